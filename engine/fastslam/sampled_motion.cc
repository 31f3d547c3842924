// MoveSampled (sampled_motion.h): FastSLAM 1.0's particle steps in Highway vectors, one particle
// per 64-bit lane, poses and unit vectors loaded from their arrays of structures. Compiled with
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

// One vector of particles at poses[0 ..] and units[0 ..] (arrays of structures), their
// normals at nv and ng (nullptr: that sigma is 0). Sets *failed to the lanes whose step failed
// and *steering to those that failed for the steering; returns whether a lane needs WrapOne()
// (its unwrapped heading is then left in raw[lane]).
template <bool kGuivantNebot>
HWY_INLINE bool MoveVector(D d, const SampledControl& u, const double* nv, const double* ng,
                           bool units_from_headings, double* poses, double* units, double* raw,
                           MD* failed, MD* steering) {
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

template <bool kGuivantNebot>
MotionResult MoveAll(const SampledControl& u, const double* const* noise, bool units_from_headings,
                     VehiclePose* poses, HeadingUnit* units, size_t n) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  const int normals = u.normals();
  const double* nv = u.sigma_speed_mps > 0 ? noise[0] : nullptr;
  const double* ng = u.sigma_steer_rad > 0 ? noise[normals - 1] : nullptr;
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
    const bool wrap = MoveVector<kGuivantNebot>(
        d, u, nv == nullptr ? nullptr : nv + i, ng == nullptr ? nullptr : ng + i,
        units_from_headings, reinterpret_cast<double*>(poses + i),
        reinterpret_cast<double*>(units + i), raw, &failed, &steering);
    finish(i, lanes, wrap, failed, steering, poses + i, units + i);
  }
  if (i < n) {
    // The last partial vector through the same code: its particles copied into full vectors
    // (padded with copies of the first), moved, and copied back.
    constexpr size_t kMax = hn::MaxLanes(D());
    VehiclePose p[kMax];
    HeadingUnit q[kMax];
    HWY_ALIGN double tv[kMax], tg[kMax];
    const size_t valid = n - i;
    for (size_t j = 0; j < lanes; ++j) {
      const size_t from = i + (j < valid ? j : 0);
      p[j] = poses[from];
      q[j] = units[from];
      if (nv != nullptr) tv[j] = nv[from];
      if (ng != nullptr) tg[j] = ng[from];
    }
    MD failed, steering;
    const bool wrap = MoveVector<kGuivantNebot>(
        d, u, nv == nullptr ? nullptr : tv, ng == nullptr ? nullptr : tg, units_from_headings,
        reinterpret_cast<double*>(p), reinterpret_cast<double*>(q), raw, &failed, &steering);
    finish(i, valid, wrap, failed, steering, p, q);
    std::copy(p, p + valid, poses + i);
    std::copy(q, q + valid, units + i);
  }
  return result;
}

MotionResult MoveSampledImpl(const SampledControl& u, const double* const* noise,
                             bool units_from_headings, VehiclePose* poses, HeadingUnit* units,
                             size_t n) {
  if (u.geometry.kind == FastSlamVehicle::kBailey) {
    return MoveAll<false>(u, noise, units_from_headings, poses, units, n);
  }
  return MoveAll<true>(u, noise, units_from_headings, poses, units, n);
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

}  // namespace grove::fastslam
#endif  // HWY_ONCE
