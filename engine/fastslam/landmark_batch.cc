// UpdateLandmarkBatch and LandmarkLikelihoodBatch (landmark_batch.h) in Highway vectors, one
// landmark per 64-bit lane: poses and leaves gathered into the lanes, the 2x2 algebra written out,
// the results scattered back. Compiled with -ffp-contract=off (engine/CMakeLists.txt).
#ifndef GROVE_ENGINE_FASTSLAM_LANDMARK_BATCH_CC_
#define GROVE_ENGINE_FASTSLAM_LANDMARK_BATCH_CC_

#include "engine/fastslam/landmark_batch.h"

#include <cfloat>
#include <cmath>
#include <numbers>

namespace grove::fastslam::landmark_batch_internal {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2 * std::numbers::pi;  // exactly twice kPi
const double kLogTwoPi = std::log(kTwoPi);
// WrapAngle()'s reach for one add of 2 pi (landmark_math.h).
constexpr double kOneTurn = 9.0;

// A batch's inputs: lane i's pose is poses[i * pose_step] and its observation zs[i * z_step]
// (a step of 0: one for every lane).
template <typename Leaf>
struct Batch {
  const VehiclePose* poses;
  size_t pose_step;
  const RangeBearing* zs;
  size_t z_step;
  Leaf* const* leaves;
};

}  // namespace grove::fastslam::landmark_batch_internal

#endif  // GROVE_ENGINE_FASTSLAM_LANDMARK_BATCH_CC_

// Re-includes this file once per Highway target.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "engine/fastslam/landmark_batch.cc"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

#include "concurrency/log_atan2-inl.h"

HWY_BEFORE_NAMESPACE();
namespace grove::fastslam {
namespace HWY_NAMESPACE {

namespace hn = hwy::HWY_NAMESPACE;
using grove::HWY_NAMESPACE::Atan2Vector;
using grove::HWY_NAMESPACE::LogVector;
using landmark_batch_internal::Batch;

using D = hn::ScalableTag<double>;
using VD = hn::Vec<D>;
using MD = hn::Mask<D>;

constexpr size_t kMaxLanes = hn::MaxLanes(D());

// One vector's inputs, gathered (a lane without a landmark holds a harmless stand-in).
struct Gathered {
  HWY_ALIGN double px[kMaxLanes], py[kMaxLanes], ph[kMaxLanes];
  HWY_ALIGN double lx[kMaxLanes], ly[kMaxLanes], a[kMaxLanes], b[kMaxLanes], c[kMaxLanes];
  HWY_ALIGN double range[kMaxLanes], bearing[kMaxLanes];
  size_t count;  // lanes with a landmark, the first `count`
};

// WrapAngle() in every lane: one add of 2 pi within kOneTurn, WrapAngle() itself beyond.
HWY_INLINE VD Wrap(D d, VD x) {
  namespace k = landmark_batch_internal;
  const VD pi = hn::Set(d, k::kPi);
  VD w = hn::IfThenElse(hn::Gt(x, pi), hn::Sub(x, hn::Set(d, k::kTwoPi)), x);
  w = hn::IfThenElse(hn::Le(x, hn::Neg(pi)), hn::Add(x, hn::Set(d, k::kTwoPi)), w);
  const MD far = hn::Ge(hn::Abs(x), hn::Set(d, k::kOneTurn));
  if (HWY_LIKELY(hn::AllFalse(d, far))) return w;
  HWY_ALIGN double xs[kMaxLanes], ws[kMaxLanes];
  hn::Store(x, d, xs);
  hn::Store(w, d, ws);
  for (size_t j = 0; j < hn::Lanes(d); ++j) {
    if (std::fabs(xs[j]) >= k::kOneTurn) ws[j] = WrapAngle(xs[j]);
  }
  return hn::Load(d, ws);
}

// The innovation of every lane and its covariance S = H P H^T + R.
struct Innovation {
  VD v0, v1, h00, h01, h10, h11, hp00, hp01, hp10, hp11, s00, s01, s11, det;
  MD ok;  // the landmark is off the sensor and S is positive definite
};

HWY_INLINE Innovation Innovate(D d, const Gathered& g, double r0, double r1) {
  Innovation n;
  const VD dx = hn::Sub(hn::Load(d, g.lx), hn::Load(d, g.px));
  const VD dy = hn::Sub(hn::Load(d, g.ly), hn::Load(d, g.py));
  const VD q = hn::Add(hn::Mul(dx, dx), hn::Mul(dy, dy));
  const VD r = hn::Sqrt(q);
  n.v0 = hn::Sub(hn::Load(d, g.range), r);
  const VD predicted = Wrap(d, hn::Sub(Atan2Vector(d, dy, dx), hn::Load(d, g.ph)));
  n.v1 = Wrap(d, hn::Sub(hn::Load(d, g.bearing), predicted));
  n.h00 = hn::Div(dx, r);
  n.h01 = hn::Div(dy, r);
  n.h10 = hn::Div(hn::Neg(dy), q);
  n.h11 = hn::Div(dx, q);
  const VD a = hn::Load(d, g.a), b = hn::Load(d, g.b), c = hn::Load(d, g.c);
  n.hp00 = hn::Add(hn::Mul(n.h00, a), hn::Mul(n.h01, b));
  n.hp01 = hn::Add(hn::Mul(n.h00, b), hn::Mul(n.h01, c));
  n.hp10 = hn::Add(hn::Mul(n.h10, a), hn::Mul(n.h11, b));
  n.hp11 = hn::Add(hn::Mul(n.h10, b), hn::Mul(n.h11, c));
  n.s00 = hn::Add(hn::Add(hn::Mul(n.hp00, n.h00), hn::Mul(n.hp01, n.h01)), hn::Set(d, r0));
  n.s01 = hn::Add(hn::Mul(n.hp00, n.h10), hn::Mul(n.hp01, n.h11));
  n.s11 = hn::Add(hn::Add(hn::Mul(n.hp10, n.h10), hn::Mul(n.hp11, n.h11)), hn::Set(d, r1));
  n.det = hn::Sub(hn::Mul(n.s00, n.s11), hn::Mul(n.s01, n.s01));
  n.ok = hn::And(hn::And(hn::Gt(q, hn::Zero(d)), hn::Gt(n.s00, hn::Zero(d))),
                 hn::And(hn::Ge(n.det, hn::Set(d, DBL_MIN)), hn::IsFinite(n.det)));
  return n;
}

// log N(v; 0, S) and v^T S^-1 v (through S = L D L^T: never negative).
HWY_INLINE VD LogLikelihood(D d, const Innovation& n, VD* m2) {
  namespace k = landmark_batch_internal;
  const VD t = hn::Sub(n.v1, hn::Mul(hn::Div(n.s01, n.s00), n.v0));
  *m2 = hn::Add(hn::Div(hn::Mul(n.v0, n.v0), n.s00), hn::Mul(hn::Mul(t, t), hn::Div(n.s00, n.det)));
  return hn::Sub(hn::Sub(hn::Mul(hn::Set(d, -0.5), *m2), hn::Set(d, k::kLogTwoPi)),
                 hn::Mul(hn::Set(d, 0.5), LogVector(d, n.det)));
}

// Gathers lanes [at, at + count) of the batch (count <= Lanes); a lane without a landmark, or
// past count, takes a stand-in 1 m ahead of its pose (or of lane `at`'s).
template <typename Leaf>
HWY_INLINE void Gather(D d, const Batch<Leaf>& in, size_t at, size_t count, Gathered* g) {
  g->count = count;
  for (size_t j = 0; j < hn::Lanes(d); ++j) {
    const size_t k = at + (j < count ? j : 0);
    const VehiclePose& p = in.poses[k * in.pose_step];
    const RangeBearing& z = in.zs[k * in.z_step];
    g->range[j] = z.range_m;
    g->bearing[j] = z.bearing_rad;
    const Landmark* l = j < count ? in.leaves[at + j] : nullptr;
    g->px[j] = p.x_m;
    g->py[j] = p.y_m;
    g->ph[j] = p.heading_rad;
    if (l != nullptr) {
      g->lx[j] = l->x_m;
      g->ly[j] = l->y_m;
      g->a[j] = l->xx;
      g->b[j] = l->xy;
      g->c[j] = l->yy;
    } else {
      g->lx[j] = p.x_m + 1;
      g->ly[j] = p.y_m;
      g->a[j] = g->c[j] = 1;
      g->b[j] = 0;
    }
  }
}

size_t UpdateImpl(const Batch<Landmark>& in, double r0, double r1, double* sums, size_t n) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  size_t first_failed = n;
  Gathered g;
  HWY_ALIGN double out[6][kMaxLanes];
  HWY_ALIGN uint8_t ok_bits[8];
  for (size_t at = 0; at < n; at += lanes) {
    const size_t count = n - at < lanes ? n - at : lanes;
    Gather(d, in, at, count, &g);
    const Innovation v = Innovate(d, g, r0, r1);
    const VD inv = hn::Div(hn::Set(d, 1.0), v.det);
    const VD k00 = hn::Mul(hn::Sub(hn::Mul(v.hp00, v.s11), hn::Mul(v.hp10, v.s01)), inv);
    const VD k01 = hn::Mul(hn::Sub(hn::Mul(v.hp10, v.s00), hn::Mul(v.hp00, v.s01)), inv);
    const VD k10 = hn::Mul(hn::Sub(hn::Mul(v.hp01, v.s11), hn::Mul(v.hp11, v.s01)), inv);
    const VD k11 = hn::Mul(hn::Sub(hn::Mul(v.hp11, v.s00), hn::Mul(v.hp01, v.s01)), inv);
    const VD m0 = hn::Add(hn::Load(d, g.lx), hn::Add(hn::Mul(k00, v.v0), hn::Mul(k01, v.v1)));
    const VD m1 = hn::Add(hn::Load(d, g.ly), hn::Add(hn::Mul(k10, v.v0), hn::Mul(k11, v.v1)));
    // P' = A P A^T + K R K^T, A = I - K H.
    const VD one = hn::Set(d, 1.0);
    const VD a00 = hn::Sub(one, hn::Add(hn::Mul(k00, v.h00), hn::Mul(k01, v.h10)));
    const VD a01 = hn::Neg(hn::Add(hn::Mul(k00, v.h01), hn::Mul(k01, v.h11)));
    const VD a10 = hn::Neg(hn::Add(hn::Mul(k10, v.h00), hn::Mul(k11, v.h10)));
    const VD a11 = hn::Sub(one, hn::Add(hn::Mul(k10, v.h01), hn::Mul(k11, v.h11)));
    const VD a = hn::Load(d, g.a), b = hn::Load(d, g.b), c = hn::Load(d, g.c);
    const VD ap00 = hn::Add(hn::Mul(a00, a), hn::Mul(a01, b));
    const VD ap01 = hn::Add(hn::Mul(a00, b), hn::Mul(a01, c));
    const VD ap10 = hn::Add(hn::Mul(a10, a), hn::Mul(a11, b));
    const VD ap11 = hn::Add(hn::Mul(a10, b), hn::Mul(a11, c));
    const VD vr0 = hn::Set(d, r0), vr1 = hn::Set(d, r1);
    const VD kr00 = hn::Mul(k00, vr0), kr01 = hn::Mul(k01, vr1);
    const VD kr10 = hn::Mul(k10, vr0), kr11 = hn::Mul(k11, vr1);
    const VD p00 = hn::Add(hn::Add(hn::Mul(ap00, a00), hn::Mul(ap01, a01)),
                           hn::Add(hn::Mul(kr00, k00), hn::Mul(kr01, k01)));
    const VD p11 = hn::Add(hn::Add(hn::Mul(ap10, a10), hn::Mul(ap11, a11)),
                           hn::Add(hn::Mul(kr10, k10), hn::Mul(kr11, k11)));
    const VD p01 =
        hn::Mul(hn::Set(d, 0.5), hn::Add(hn::Add(hn::Add(hn::Mul(ap00, a10), hn::Mul(ap01, a11)),
                                                 hn::Add(hn::Mul(kr00, k10), hn::Mul(kr01, k11))),
                                         hn::Add(hn::Add(hn::Mul(ap10, a00), hn::Mul(ap11, a01)),
                                                 hn::Add(hn::Mul(kr10, k00), hn::Mul(kr11, k01)))));
    VD m2;
    const VD ll = LogLikelihood(d, v, &m2);
    const MD finite = hn::And(hn::And(hn::IsFinite(m0), hn::IsFinite(m1)),
                              hn::And(hn::And(hn::IsFinite(p00), hn::IsFinite(p01)),
                                      hn::And(hn::IsFinite(p11), hn::IsFinite(ll))));
    hn::StoreMaskBits(d, hn::And(v.ok, finite), ok_bits);
    hn::Store(m0, d, out[0]);
    hn::Store(m1, d, out[1]);
    hn::Store(p00, d, out[2]);
    hn::Store(p01, d, out[3]);
    hn::Store(p11, d, out[4]);
    hn::Store(ll, d, out[5]);
    for (size_t j = 0; j < count; ++j) {
      Landmark* l = in.leaves[at + j];
      if (l == nullptr) continue;
      if (!((ok_bits[j / 8] >> (j % 8)) & 1)) {
        if (first_failed == n) first_failed = at + j;
        continue;
      }
      l->x_m = out[0][j];
      l->y_m = out[1][j];
      l->xx = out[2][j];
      l->xy = out[3][j];
      l->yy = out[4][j];
      sums[at + j] += out[5][j];
    }
  }
  return first_failed;
}

size_t LikelihoodImpl(const Batch<const Landmark>& in, double r0, double r1,
                      double* log_likelihoods, double* mahalanobis_sq, size_t n) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  size_t first_failed = n;
  Gathered g;
  HWY_ALIGN double ll_out[kMaxLanes], m2_out[kMaxLanes];
  HWY_ALIGN uint8_t ok_bits[8];
  for (size_t at = 0; at < n; at += lanes) {
    const size_t count = n - at < lanes ? n - at : lanes;
    Gather(d, in, at, count, &g);
    const Innovation v = Innovate(d, g, r0, r1);
    VD m2;
    const VD ll = LogLikelihood(d, v, &m2);
    hn::StoreMaskBits(d, hn::And(v.ok, hn::IsFinite(ll)), ok_bits);
    hn::Store(ll, d, ll_out);
    hn::Store(m2, d, m2_out);
    for (size_t j = 0; j < count; ++j) {
      if (!((ok_bits[j / 8] >> (j % 8)) & 1)) {
        if (first_failed == n) first_failed = at + j;
        continue;
      }
      log_likelihoods[at + j] = ll_out[j];
      mahalanobis_sq[at + j] = m2_out[j];
    }
  }
  return first_failed;
}

}  // namespace HWY_NAMESPACE
}  // namespace grove::fastslam
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace grove::fastslam {

HWY_EXPORT(UpdateImpl);
HWY_EXPORT(LikelihoodImpl);

size_t UpdateLandmarkBatch(const VehiclePose* poses, Landmark* const* leaves, const RangeBearing& z,
                           double r0, double r1, double* sums, size_t n) {
  const landmark_batch_internal::Batch<Landmark> in{poses, 1, &z, 0, leaves};
  return HWY_DYNAMIC_DISPATCH(UpdateImpl)(in, r0, r1, sums, n);
}

size_t LandmarkLikelihoodBatch(const VehiclePose* poses, const Landmark* const* leaves,
                               const RangeBearing& z, double r0, double r1, double* log_likelihoods,
                               double* mahalanobis_sq, size_t n) {
  const landmark_batch_internal::Batch<const Landmark> in{poses, 1, &z, 0, leaves};
  return HWY_DYNAMIC_DISPATCH(LikelihoodImpl)(in, r0, r1, log_likelihoods, mahalanobis_sq, n);
}

size_t UpdateLandmarkPairs(const VehiclePose& pose, Landmark* const* leaves, const RangeBearing* zs,
                           double r0, double r1, double* sums, size_t n) {
  const landmark_batch_internal::Batch<Landmark> in{&pose, 0, zs, 1, leaves};
  return HWY_DYNAMIC_DISPATCH(UpdateImpl)(in, r0, r1, sums, n);
}

size_t LandmarkLikelihoodPairs(const VehiclePose& pose, const Landmark* const* leaves,
                               const RangeBearing* zs, double r0, double r1,
                               double* log_likelihoods, double* mahalanobis_sq, size_t n) {
  const landmark_batch_internal::Batch<const Landmark> in{&pose, 0, zs, 1, leaves};
  return HWY_DYNAMIC_DISPATCH(LikelihoodImpl)(in, r0, r1, log_likelihoods, mahalanobis_sq, n);
}

}  // namespace grove::fastslam
#endif  // HWY_ONCE
