// MoveSampled and MoveLinearized (sampled_motion.h): FastSLAM's particle steps in Highway
// vectors, one particle per 64-bit lane, poses and unit vectors loaded from their arrays of
// structures, covariances through a buffer from theirs. Compiled with
// -ffp-contract=off (engine/CMakeLists.txt): no multiply and add are fused, so every target and
// the scalar fix-ups round alike. foreach_target.h compiles the HWY_NAMESPACE part once per
// target; HWY_DYNAMIC_DISPATCH picks one at run time.
#ifndef GROVE_ENGINE_FASTSLAM_SAMPLED_MOTION_CC_
#define GROVE_ENGINE_FASTSLAM_SAMPLED_MOTION_CC_

#include "engine/fastslam/sampled_motion.h"

#include <algorithm>
#include <cstring>
#include <numbers>
#include <type_traits>

#include "concurrency/sin_cos.h"

namespace grove::fastslam {
namespace {

static_assert(sizeof(VehiclePose) == 3 * sizeof(double) && std::is_standard_layout_v<VehiclePose>);
static_assert(sizeof(HeadingUnit) == 2 * sizeof(double) && std::is_standard_layout_v<HeadingUnit>);
static_assert(sizeof(PoseCovariance) == 6 * sizeof(double) &&
              std::is_standard_layout_v<PoseCovariance>);

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2 * std::numbers::pi;  // exactly twice kPi
// Within +-kWrapReach a heading is wrapped by one exact add of kTwoPi (Sterbenz: x - 2 pi is
// exact for x in [pi, 4 pi]), which is what WrapAngle()'s remainder gives for |x| < 3 pi.
constexpr double kWrapReach = 9.0;

// A heading beyond kWrapReach: WrapAngle() and the unit vector of the result, in scalar.
void WrapOne(double raw, VehiclePose* p, HeadingUnit* u) {
  p->heading_rad = WrapAngle(raw);
  SinCosReference(&p->heading_rad, 1, &u->s, &u->c);
}

}  // namespace
}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_SAMPLED_MOTION_CC_

// Re-includes this file once per Highway target.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "engine/fastslam/sampled_motion.cc"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

#include "concurrency/sin_cos-inl.h"

HWY_BEFORE_NAMESPACE();
namespace grove::fastslam {
namespace HWY_NAMESPACE {

namespace hn = hwy::HWY_NAMESPACE;
using grove::HWY_NAMESPACE::SinCosVector;

using D = hn::ScalableTag<double>;
using VD = hn::Vec<D>;
using MD = hn::Mask<D>;

// The step's Jacobians in a vector of particles: Gv's heading column (ax, ay, 1) and Gu's
// columns (v0, v1, v2) for the speed and (g0, g1, g2) for the steering.
struct StepJacobian {
  VD ax, ay, v0, v1, v2, g0, g1, g2;
};

// One vector of particles at poses[0 ..] and units[0 ..] (arrays of structures), their
// normals at nv and ng (nullptr: that sigma is 0). Sets *failed to the lanes whose step failed
// and *steering to those that failed for the steering, and with kJacobian *jac; returns whether
// a lane needs WrapOne() (its unwrapped heading is then left in raw[lane]).
template <bool kGuivantNebot, bool kJacobian = false>
HWY_INLINE bool MoveVector(D d, const SampledControl& u, const double* nv, const double* ng,
                           bool units_from_headings, double* poses, double* units, double* raw,
                           MD* failed, MD* steering, StepJacobian* jac = nullptr) {
  VD x, y, h, c, s;
  hn::LoadInterleaved3(d, poses, x, y, h);
  if (units_from_headings) {
    SinCosVector(d, h, s, c);
  } else {
    hn::LoadInterleaved2(d, units, c, s);
  }
  VD v = hn::Set(d, u.v_mps);
  VD g = hn::Set(d, u.steer_rad);
  if (nv != nullptr) v = hn::Add(v, hn::Mul(hn::Set(d, u.sigma_speed_mps), hn::LoadU(d, nv)));
  if (ng != nullptr) g = hn::Add(g, hn::Mul(hn::Set(d, u.sigma_steer_rad), hn::LoadU(d, ng)));
  VD sg, cg;
  SinCosVector(d, g, sg, cg);
  const VD dt = hn::Set(d, u.dt_s);
  VD turn;
  MD bad_steering;
  if constexpr (!kGuivantNebot) {
    bad_steering = hn::Not(hn::IsFinite(g));
    const VD vdt = hn::Mul(v, dt);
    const VD ca = hn::Sub(hn::Mul(cg, c), hn::Mul(sg, s));  // cos(G + phi)
    const VD sa = hn::Add(hn::Mul(sg, c), hn::Mul(cg, s));  // sin(G + phi)
    x = hn::Add(x, hn::Mul(vdt, ca));
    y = hn::Add(y, hn::Mul(vdt, sa));
    turn = hn::Mul(hn::Mul(vdt, sg), hn::Set(d, 1 / u.geometry.wheelbase_m));
    if constexpr (kJacobian) {
      const VD l = hn::Set(d, u.geometry.wheelbase_m);
      jac->ax = hn::Neg(hn::Mul(vdt, sa));
      jac->ay = hn::Mul(vdt, ca);
      jac->v0 = hn::Mul(dt, ca);
      jac->v1 = hn::Mul(dt, sa);
      jac->v2 = hn::Div(hn::Mul(dt, sg), l);
      jac->g0 = jac->ax;
      jac->g1 = jac->ay;
      jac->g2 = hn::Div(hn::Mul(vdt, cg), l);
    }
  } else {
    const VD l = hn::Set(d, u.geometry.wheelbase_m);
    const VD a = hn::Set(d, u.geometry.laser_forward_m);
    const VD b = hn::Set(d, u.geometry.laser_left_m);
    const VD tg = hn::Div(sg, cg);
    const VD k =
        hn::Sub(hn::Set(d, 1.0), hn::Div(hn::Mul(tg, hn::Set(d, u.geometry.encoder_offset_m)), l));
    bad_steering =
        hn::Not(hn::And(hn::Lt(hn::Abs(g), hn::Set(d, kPi / 2)), hn::Gt(k, hn::Zero(d))));
    const VD vc = hn::Div(v, k);
    const VD rate = hn::Mul(hn::Div(vc, l), tg);
    x = hn::Add(x, hn::Mul(dt, hn::Sub(hn::Mul(vc, c),
                                       hn::Mul(rate, hn::Add(hn::Mul(a, s), hn::Mul(b, c))))));
    y = hn::Add(y, hn::Mul(dt, hn::Add(hn::Mul(vc, s),
                                       hn::Mul(rate, hn::Sub(hn::Mul(a, c), hn::Mul(b, s))))));
    turn = hn::Mul(dt, rate);
    if constexpr (kJacobian) {
      // x' = x + dt vc A, y' = y + dt vc B, phi' = phi + dt vc tan(G) / L with vc = V / k.
      const VD one = hn::Set(d, 1.0);
      const VD fore = hn::Add(hn::Mul(a, s), hn::Mul(b, c));
      const VD side = hn::Sub(hn::Mul(a, c), hn::Mul(b, s));
      const VD big_a = hn::Sub(c, hn::Mul(hn::Div(tg, l), fore));
      const VD big_b = hn::Add(s, hn::Mul(hn::Div(tg, l), side));
      const VD sec2 = hn::Add(one, hn::Mul(tg, tg));
      const VD dvc_dv = hn::Div(one, k);
      const VD dvc_dg = hn::Div(
          hn::Mul(hn::Mul(v, hn::Set(d, u.geometry.encoder_offset_m / u.geometry.wheelbase_m)),
                  sec2),
          hn::Mul(k, k));
      const VD da_dg = hn::Neg(hn::Mul(hn::Div(sec2, l), fore));
      const VD db_dg = hn::Mul(hn::Div(sec2, l), side);
      const VD dt_vc = hn::Mul(dt, vc);
      jac->ax = hn::Neg(hn::Mul(dt_vc, big_b));
      jac->ay = hn::Mul(dt_vc, big_a);
      jac->v0 = hn::Mul(hn::Mul(dt, dvc_dv), big_a);
      jac->v1 = hn::Mul(hn::Mul(dt, dvc_dv), big_b);
      jac->v2 = hn::Div(hn::Mul(hn::Mul(dt, dvc_dv), tg), l);
      jac->g0 = hn::Mul(dt, hn::Add(hn::Mul(dvc_dg, big_a), hn::Mul(vc, da_dg)));
      jac->g1 = hn::Mul(dt, hn::Add(hn::Mul(dvc_dg, big_b), hn::Mul(vc, db_dg)));
      jac->g2 = hn::Div(hn::Mul(dt, hn::Add(hn::Mul(dvc_dg, tg), hn::Mul(vc, sec2))), l);
    }
  }
  const VD heading = hn::Add(h, turn);
  const VD pi = hn::Set(d, kPi);
  const VD two_pi = hn::Set(d, kTwoPi);
  const MD above = hn::Gt(heading, pi);
  const MD below = hn::Le(heading, hn::Neg(pi));
  const VD wrapped = hn::IfThenElse(above, hn::Sub(heading, two_pi),
                                    hn::IfThenElse(below, hn::Add(heading, two_pi), heading));
  const MD far = hn::Gt(hn::Abs(heading), hn::Set(d, kWrapReach));
  SinCosVector(d, wrapped, s, c);
  const MD finite = hn::And(hn::And(hn::IsFinite(x), hn::IsFinite(y)), hn::IsFinite(wrapped));
  *steering = bad_steering;
  *failed = hn::Or(bad_steering, hn::Not(finite));
  hn::StoreInterleaved3(x, y, wrapped, d, poses);
  hn::StoreInterleaved2(c, s, d, units);
  if (HWY_LIKELY(hn::AllFalse(d, far))) return false;
  hn::StoreU(heading, d, raw);
  return true;
}

// The covariances of one vector of particles at covs (an array of PoseCovariance) carried
// through the step: Gv = I + a e_h^T with a = (ax, ay, 0) and c = Sigma e_h make Gv Sigma Gv^T
// = Sigma + a c^T + c a^T + Sigma_hh a a^T; Gu Q Gu^T = q_v g_v g_v^T + q_g g_g g_g^T. The six
// terms are moved between the structures and the lanes through a buffer (cheaper than gathers
// and scatters).
HWY_INLINE void PropagateVector(D d, const StepJacobian& j, double q_speed, double q_steer,
                                PoseCovariance* covs) {
  constexpr size_t kMax = hn::MaxLanes(D());
  HWY_ALIGN double t[6][kMax];
  const size_t lanes = hn::Lanes(d);
  for (size_t k = 0; k < lanes; ++k) {
    const PoseCovariance& c = covs[k];
    t[0][k] = c.xx;
    t[1][k] = c.xy;
    t[2][k] = c.xh;
    t[3][k] = c.yy;
    t[4][k] = c.yh;
    t[5][k] = c.hh;
  }
  const VD xx = hn::Load(d, t[0]), xy = hn::Load(d, t[1]), xh = hn::Load(d, t[2]);
  const VD yy = hn::Load(d, t[3]), yh = hn::Load(d, t[4]), hh = hn::Load(d, t[5]);
  const VD qv = hn::Set(d, q_speed), qg = hn::Set(d, q_steer), two = hn::Set(d, 2.0);
  // q_v a_r a_c + q_g b_r b_c for the control's two columns.
  auto control = [&](VD vr, VD vc, VD gr, VD gc) {
    return hn::Add(hn::Mul(hn::Mul(qv, vr), vc), hn::Mul(hn::Mul(qg, gr), gc));
  };
  hn::Store(hn::Add(hn::Add(hn::Add(xx, hn::Mul(hn::Mul(two, j.ax), xh)),
                            hn::Mul(hn::Mul(hh, j.ax), j.ax)),
                    control(j.v0, j.v0, j.g0, j.g0)),
            d, t[0]);
  hn::Store(hn::Add(hn::Add(hn::Add(hn::Add(xy, hn::Mul(j.ax, yh)), hn::Mul(xh, j.ay)),
                            hn::Mul(hn::Mul(hh, j.ax), j.ay)),
                    control(j.v0, j.v1, j.g0, j.g1)),
            d, t[1]);
  hn::Store(hn::Add(hn::Add(xh, hn::Mul(j.ax, hh)), control(j.v0, j.v2, j.g0, j.g2)), d, t[2]);
  hn::Store(hn::Add(hn::Add(hn::Add(yy, hn::Mul(hn::Mul(two, j.ay), yh)),
                            hn::Mul(hn::Mul(hh, j.ay), j.ay)),
                    control(j.v1, j.v1, j.g1, j.g1)),
            d, t[3]);
  hn::Store(hn::Add(hn::Add(yh, hn::Mul(j.ay, hh)), control(j.v1, j.v2, j.g1, j.g2)), d, t[4]);
  hn::Store(hn::Add(hh, control(j.v2, j.v2, j.g2, j.g2)), d, t[5]);
  for (size_t k = 0; k < lanes; ++k) {
    covs[k] = PoseCovariance{t[0][k], t[1][k], t[2][k], t[3][k], t[4][k], t[5][k]};
  }
}

// MoveSampled(), or with kLinearized MoveLinearized() (noise is then nullptr; covs may be).
template <bool kGuivantNebot, bool kLinearized>
MotionResult MoveAll(const SampledControl& u, const double* const* noise, bool units_from_headings,
                     VehiclePose* poses, HeadingUnit* units, size_t n, double q_speed = 0,
                     double q_steer = 0, PoseCovariance* covs = nullptr) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  const int normals = kLinearized ? 0 : u.normals();
  const double* nv = normals > 0 && u.sigma_speed_mps > 0 ? noise[0] : nullptr;
  const double* ng = normals > 0 && u.sigma_steer_rad > 0 ? noise[normals - 1] : nullptr;
  // Moves the vector at p, q (and its covariances at r).
  auto move = [&](const double* v, const double* g, VehiclePose* p, HeadingUnit* q,
                  PoseCovariance* r, double* raw, MD* failed, MD* steering) {
    StepJacobian jac;
    const bool wrap = MoveVector<kGuivantNebot, kLinearized>(
        d, u, v, g, units_from_headings, reinterpret_cast<double*>(p), reinterpret_cast<double*>(q),
        raw, failed, steering, &jac);
    if (kLinearized && r != nullptr) {
      PropagateVector(d, jac, q_speed, q_steer, r);
    }
    return wrap;
  };
  MotionResult result{n, MotionFailure::kNone};
  HWY_ALIGN double raw[hn::MaxLanes(D())];
  // Notes lane failures and wraps of the vector at particle `at` (of `valid` particles) whose
  // poses and units are p and q.
  auto finish = [&](size_t at, size_t valid, bool wrap, MD failed, MD steering, VehiclePose* p,
                    HeadingUnit* q) {
    if (wrap) {
      for (size_t j = 0; j < valid; ++j) {
        if (std::fabs(raw[j]) > kWrapReach) WrapOne(raw[j], &p[j], &q[j]);
      }
    }
    if (HWY_LIKELY(hn::AllFalse(d, failed)) || result.first_failed < n) return;
    const intptr_t lane = hn::FindFirstTrue(d, failed);
    if (lane < 0 || static_cast<size_t>(lane) >= valid) return;
    result.first_failed = at + static_cast<size_t>(lane);
    uint8_t bits[8] = {};
    hn::StoreMaskBits(d, steering, bits);
    const bool bad = (bits[lane / 8] >> (lane % 8)) & 1;
    result.why = bad ? MotionFailure::kSteering : MotionFailure::kNotFinite;
  };
  size_t i = 0;
  for (; i + lanes <= n; i += lanes) {
    MD failed, steering;
    const bool wrap =
        move(nv == nullptr ? nullptr : nv + i, ng == nullptr ? nullptr : ng + i, poses + i,
             units + i, covs == nullptr ? nullptr : covs + i, raw, &failed, &steering);
    finish(i, lanes, wrap, failed, steering, poses + i, units + i);
  }
  if (i < n) {
    // The last partial vector through the same code: its particles copied into full vectors
    // (padded with copies of the first), moved, and copied back.
    constexpr size_t kMax = hn::MaxLanes(D());
    VehiclePose p[kMax];
    HeadingUnit q[kMax];
    PoseCovariance r[kMax];
    HWY_ALIGN double tv[kMax], tg[kMax];
    const size_t valid = n - i;
    for (size_t j = 0; j < lanes; ++j) {
      const size_t from = i + (j < valid ? j : 0);
      p[j] = poses[from];
      q[j] = units[from];
      if (covs != nullptr) r[j] = covs[from];
      if (nv != nullptr) tv[j] = nv[from];
      if (ng != nullptr) tg[j] = ng[from];
    }
    MD failed, steering;
    const bool wrap = move(nv == nullptr ? nullptr : tv, ng == nullptr ? nullptr : tg, p, q,
                           covs == nullptr ? nullptr : r, raw, &failed, &steering);
    finish(i, valid, wrap, failed, steering, p, q);
    std::copy(p, p + valid, poses + i);
    std::copy(q, q + valid, units + i);
    if (covs != nullptr) std::copy(r, r + valid, covs + i);
  }
  return result;
}

MotionResult MoveSampledImpl(const SampledControl& u, const double* const* noise,
                             bool units_from_headings, VehiclePose* poses, HeadingUnit* units,
                             size_t n) {
  if (u.geometry.kind == FastSlamVehicle::kBailey) {
    return MoveAll<false, false>(u, noise, units_from_headings, poses, units, n);
  }
  return MoveAll<true, false>(u, noise, units_from_headings, poses, units, n);
}

MotionResult MoveLinearizedImpl(const SampledControl& u, double q_speed, double q_steer,
                                bool units_from_headings, VehiclePose* poses, HeadingUnit* units,
                                PoseCovariance* covs, size_t n) {
  if (u.geometry.kind == FastSlamVehicle::kBailey) {
    return MoveAll<false, true>(u, nullptr, units_from_headings, poses, units, n, q_speed, q_steer,
                                covs);
  }
  return MoveAll<true, true>(u, nullptr, units_from_headings, poses, units, n, q_speed, q_steer,
                             covs);
}

}  // namespace HWY_NAMESPACE
}  // namespace grove::fastslam
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace grove::fastslam {

HWY_EXPORT(MoveSampledImpl);

MotionResult MoveSampled(const SampledControl& u, const double* const* noise,
                         bool units_from_headings, VehiclePose* poses, HeadingUnit* units,
                         size_t n) {
  return HWY_DYNAMIC_DISPATCH(MoveSampledImpl)(u, noise, units_from_headings, poses, units, n);
}

HWY_EXPORT(MoveLinearizedImpl);

MotionResult MoveLinearized(const SampledControl& u, double q_speed, double q_steer,
                            bool units_from_headings, VehiclePose* poses, HeadingUnit* units,
                            PoseCovariance* covs, size_t n) {
  return HWY_DYNAMIC_DISPATCH(MoveLinearizedImpl)(u, q_speed, q_steer, units_from_headings, poses,
                                                  units, covs, n);
}

}  // namespace grove::fastslam
#endif  // HWY_ONCE
