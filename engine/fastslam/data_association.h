// Unknown data association for landmark FastSLAM, per particle and scan: maximum likelihood
// with a reject and an augment gate (Bailey's data_associate; Montemerlo's thesis, ch. 4).
//
// For detection z and a landmark of the particle's map, v = z - h(landmark) from the particle's
// pose, S = Hl P Hl^T + R, d2 = v^T S^-1 v and l = log N(v; 0, S) (ObservationLogLikelihood).
//   - Associated: among the landmarks with d2 < reject_gate, the one of largest l.
//   - New: d2 > augment_gate for every landmark; the detection starts a landmark.
//   - Ignored: otherwise (an ambiguous detection updates nothing).
// Exclusive association (optional): one landmark per detection and one detection per landmark
// within a scan, pairs inside the reject gate taken greedily by l (ties: detection, then key).
//
// Weight. A detection that updates no landmark (new or ignored) contributes the new-feature
// likelihood p0 to the particle's weight (Montemerlo's p0, the threshold for a new feature):
// the density of a detection at the augment gate of a landmark just created from it, whose
// innovation covariance is S = Hl (G R G^T) Hl^T + R = 2R:
//   log p0 = -augment_gate / 2 - log(2 pi) - log(det(2R)) / 2.
//
// Candidates. The landmarks compared with a detection come from the particle's spatial trie
// (spatial_key.h): those whose mean lies within SearchRadius() of the detection's point. The
// radius is a bound, not a tuning: every landmark with d2 <= augment_gate lies inside it, so the
// decisions equal those of a scan over the whole map (tested). Derivation, with D the distance
// between the detection's point and the landmark's mean, r_l the landmark's range, dr and db the
// innovation's range and bearing parts: D <= |dr| + r_l |db| (an arc then a radial segment);
// with T = diag(1, r_l), T S T = Rot P Rot^T + diag(sr^2, r_l^2 sb^2), so
// d2 >= (dr^2 + r_l^2 db^2) / (lP + sr^2 + r_l^2 sb^2) >= D^2 / (2 (lP + sr^2 + r_l^2 sb^2)),
// where lP bounds the largest eigenvalue of any landmark's P. An EKF update never grows P, and
// a landmark starts at G R G^T, whose eigenvalues are sr^2 and (r sb)^2 for its first range r;
// so lP = max(sr^2, (r_max sb)^2) with r_max the longest range of any detection so far (the
// unscented and central-difference updates never grow P either; a central-difference
// initialisation, whose second-order term lengthens the ray, gives lP = InitCovarianceBound()
// instead). With
// r_l <= r + D and k = 2 augment_gate, d2 > augment_gate whenever
//   (1 - a) D^2 - 2 a r D - a r^2 - k (lP + sr^2) > 0,   a = k sb^2,
// i.e. beyond the positive root of that quadratic. When a >= 1 there is no such bound and the
// radius is infinite (every landmark is a candidate).
#ifndef GROVE_ENGINE_FASTSLAM_DATA_ASSOCIATION_H_
#define GROVE_ENGINE_FASTSLAM_DATA_ASSOCIATION_H_

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "engine/fastslam/landmark_math.h"
#include "engine/fastslam/spatial_key.h"
#include "grove/fastslam.h"
#include "grove/status.h"

namespace grove::fastslam {

struct AssociationParams {
  double reject_gate = 4;    // squared Mahalanobis distance
  double augment_gate = 25;  // squared Mahalanobis distance, >= reject_gate
  bool exclusive = false;
  double cell_m = 5;  // the spatial keys' cell side
  SensorNoise noise;
  // The map's leaves hold square-root factors (the SRCD filters), not covariances.
  bool square_root_leaves = false;
  // New landmarks come from a central-difference initialisation with this h (0: the EKF's).
  double init_cd_h = 0;
};

// The largest eigenvalue a new landmark's covariance can have when its first range was at most
// range_m: max(sr^2, r^2 sb^2) for the EKF's G R G^T; for a central-difference initialisation
// (init_cd_h = h > 0), whose factor has the columns sr and a second-order term
// s <= r sb^2 sqrt(h^2 - 1) / 2 along the ray and r sin(h sb) / h <= r sb across it,
// max(sr^2 + r^2 sb^4 (h^2 - 1) / 4, r^2 sb^2).
double InitCovarianceBound(double range_m, const SensorNoise& noise, double init_cd_h);

// log p0 above.
double NewLandmarkLogLikelihood(const SensorNoise& noise, double augment_gate);

// The candidate radius above for a detection at range_m, when no detection so far had a range
// beyond max_range_m; +infinity when the bound does not exist.
double SearchRadius(double range_m, double max_range_m, const SensorNoise& noise,
                    double augment_gate, double init_cd_h = 0);

// A detection and a landmark within its augment gate.
struct Match {
  uint32_t detection = 0;
  uint64_t key = 0;
  double log_likelihood = 0;
  double d2 = 0;
};

struct Decision {
  enum Kind : uint8_t { kAssociated, kNew, kIgnored };
  Kind kind = kNew;
  uint64_t key = 0;           // kAssociated: the landmark
  double log_likelihood = 0;  // kAssociated: its l
};

// The decisions for `detections` detections from their matches (every pair with
// d2 <= augment_gate, in any order; reordered).
void Decide(std::span<Match> matches, size_t detections, const AssociationParams& params,
            std::vector<Decision>* out);

// The detection's point in the plane from `pose`.
inline void DetectionPoint(const VehiclePose& pose, const LandmarkObservation& z, double* x,
                           double* y) {
  const double a = pose.heading_rad + z.bearing_rad;
  *x = pose.x_m + z.range_m * std::cos(a);
  *y = pose.y_m + z.range_m * std::sin(a);
}

// The sensor's view for the existence evidence: range <= sqrt(range2) and |bearing| <= fov / 2,
// tested as: the component along the heading is at least |d| cos(fov / 2) (no angle computed).
struct SensorView {  // FastSlamConfig's sensor_range_m and sensor_fov_rad
  SensorView(double range_m, double fov_rad)
      : range_m(range_m),
        fov_rad(fov_rad),
        cos_half(std::cos(0.5 * fov_rad)),
        sin_half(std::sin(0.5 * fov_rad)) {}
  double range_m;
  double fov_rad;
  double cos_half, sin_half;  // of fov / 2
};

// Whether the point (lx, ly) relative to a sensor facing (hc, hs) (a unit vector) is in its view:
// lx^2 + ly^2 <= range2 and the angle to the heading at most the half view whose cosine is
// cos_half.
inline bool InView(double lx, double ly, double hc, double hs, double range2, double cos_half) {
  const double d2 = lx * lx + ly * ly;
  const double along = lx * hc + ly * hs;
  return d2 <= range2 && (cos_half >= 0 ? along >= 0 && along * along >= d2 * cos_half * cos_half
                                        : along >= 0 || along * along <= d2 * cos_half * cos_half);
}

// A box [x0, x1] x [y0, y1] holding the view of a sensor at (x, y) facing (hc, hs) (a unit
// vector), cos_half and sin_half those of fov / 2: the apex, the arc's ends and the arc's points
// furthest along each axis that lie in the view, widened by a millionth of the range so that
// rounding never leaves out a point InView() admits.
struct ViewBox {
  double x0, x1, y0, y1;
};
inline ViewBox ViewBoxOf(double x, double y, double hc, double hs, double range_m, double cos_half,
                         double sin_half) {
  ViewBox b{x, x, y, y};
  auto add = [&](double ux, double uy) {
    b.x0 = std::min(b.x0, x + range_m * ux);
    b.x1 = std::max(b.x1, x + range_m * ux);
    b.y0 = std::min(b.y0, y + range_m * uy);
    b.y1 = std::max(b.y1, y + range_m * uy);
  };
  add(hc * cos_half + hs * sin_half, hs * cos_half - hc * sin_half);
  add(hc * cos_half - hs * sin_half, hs * cos_half + hc * sin_half);
  if (hc >= cos_half) add(1, 0);
  if (-hc >= cos_half) add(-1, 0);
  if (hs >= cos_half) add(0, 1);
  if (-hs >= cos_half) add(0, -1);
  const double pad = 1e-6 * range_m;
  return ViewBox{b.x0 - pad, b.x1 + pad, b.y0 - pad, b.y1 + pad};
}

// A detection's point in the plane and its squared candidate radius.
struct DetectionProbe {
  double x, y, radius2;
};

// FindMatches' buffers, kept by the caller (per worker) between calls: the probes and the
// (detection, landmark) pairs whose likelihoods are computed together.
struct MatchScratch {
  std::vector<DetectionProbe> probes;
  std::vector<uint32_t> detection;
  std::vector<uint64_t> key;
  std::vector<Landmark> leaf;
  std::vector<const Landmark*> leaf_ptr;
  std::vector<RangeBearing> z;
  std::vector<double> log_likelihood, d2;
};

// Appends the matches of every detection of `scan` against the map `root` of `trie` (keyed by
// SpatialKey) seen from `pose`; with `view`, also the keys of the landmarks in view, in
// increasing order, to *in_view (the same range query). use_index: candidates from the spatial
// range query; false: from every landmark of the map, unfiltered (the reference the index and the
// radius are tested against). Errors: those of ObservationLogLikelihood for the first pair of
// the query that fails, naming the detection and the landmark.
template <typename Trie>
Status FindMatches(const Trie& trie, const typename Trie::Node* root, const VehiclePose& pose,
                   std::span<const LandmarkObservation> scan, const AssociationParams& params,
                   double max_range_m, bool use_index, std::vector<Match>* out,
                   MatchScratch* scratch, const SensorView* view = nullptr,
                   std::vector<uint64_t>* in_view = nullptr) {
  const Eigen::Matrix2d r = SensorCovariance(params.noise);
  const double sr2 = r(0, 0), sb2 = r(1, 1);
  // Each detection's point and candidate radius, and the box around all of them (and the
  // view): one range query per scan, each landmark in it tested against every detection.
  std::vector<DetectionProbe>& probes = scratch->probes;
  probes.clear();
  scratch->detection.clear();
  scratch->key.clear();
  scratch->leaf.clear();
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  bool bounded = true;
  for (const LandmarkObservation& z : scan) {
    DetectionProbe p;
    DetectionPoint(pose, z, &p.x, &p.y);
    const double radius =
        SearchRadius(z.range_m, max_range_m, params.noise, params.augment_gate, params.init_cd_h);
    bounded = bounded && std::isfinite(radius) && std::isfinite(p.x) && std::isfinite(p.y);
    p.radius2 = radius * radius;
    probes.push_back(p);
    x0 = std::min(x0, p.x - radius);
    x1 = std::max(x1, p.x + radius);
    y0 = std::min(y0, p.y - radius);
    y1 = std::max(y1, p.y + radius);
  }
  double view_range2 = 0, cos_half = 0, hc = 0, hs = 0;
  if (view != nullptr) {
    view_range2 = view->range_m * view->range_m;
    cos_half = view->cos_half;
    hc = std::cos(pose.heading_rad);
    hs = std::sin(pose.heading_rad);
    const ViewBox box =
        ViewBoxOf(pose.x_m, pose.y_m, hc, hs, view->range_m, cos_half, view->sin_half);
    x0 = std::min(x0, box.x0);
    x1 = std::max(x1, box.x1);
    y0 = std::min(y0, box.y0);
    y1 = std::max(y1, box.y1);
  }
  // The range query hands over every landmark of the nodes it admits, some beyond the box (a
  // node spans several cells): with the index and a bounded box, those, neither in view nor
  // within a radius, are passed over first. The box is widened by a millionth of its size so that
  // rounding never passes over a landmark the tests below would take.
  const double pad = 1e-6 * std::max(x1 - x0, y1 - y0);
  const double bx0 = x0 - pad, bx1 = x1 + pad, by0 = y0 - pad, by1 = y1 + pad;
  // The range query notes the pairs to test; their likelihoods follow in SIMD lanes.
  auto note = [&](uint64_t key, const Landmark& leaf) {
    const Landmark l = params.square_root_leaves ? WithCovariance(leaf) : leaf;
    const double lx = l.x_m - pose.x_m, ly = l.y_m - pose.y_m;
    if (view != nullptr && InView(lx, ly, hc, hs, view_range2, cos_half)) in_view->push_back(key);
    // The bound of the file comment with this landmark's own range and largest eigenvalue:
    // d2 >= D^2 / (2 (lP + sr^2 + r_l^2 sb^2)); beyond the augment gate it rules the pair out
    // without the likelihood. Computed for the first detection within the radius.
    double reach2 = -1;
    for (size_t j = 0; j < scan.size(); ++j) {
      const DetectionProbe& p = probes[j];
      const double dx = l.x_m - p.x, dy = l.y_m - p.y;
      const double d2 = dx * dx + dy * dy;
      if (use_index) {
        if (!(d2 <= p.radius2)) continue;
        if (reach2 < 0) {
          const double half_trace = 0.5 * (l.xx + l.yy), half_diff = 0.5 * (l.xx - l.yy);
          const double lp = half_trace + std::sqrt(half_diff * half_diff + l.xy * l.xy);
          reach2 = 2 * params.augment_gate * (lp + sr2 + (lx * lx + ly * ly) * sb2);
        }
        if (d2 > reach2) continue;
      }
      scratch->detection.push_back(static_cast<uint32_t>(j));
      scratch->key.push_back(key);
      scratch->leaf.push_back(l);
    }
  };
  // The range query's: the box test inline in the walk, the rest a call.
  auto consider = [&](uint64_t key, const Landmark& leaf) {
    if (leaf.x_m < bx0 || leaf.x_m > bx1 || leaf.y_m < by0 || leaf.y_m > by1) return;
    note(key, leaf);
  };
  if (scan.empty() && view == nullptr) return Status::Ok();
  if (use_index && bounded) {
    // One rectangle around them all: testing each node against every detection's rectangle
    // costs more than the landmarks it would skip (measured on Victoria Park: 8 % more
    // instructions).
    const CellRect rect = CellsBetween(x0, x1, y0, y1, params.cell_m);
    trie.ForEachIf(
        root, [&](uint64_t lo, uint64_t hi) { return KeyRangeMayHit(lo, hi, rect); }, consider);
  } else {
    trie.ForEach(root, note);
  }
  // The pairs' likelihoods (ObservationLogLikelihoods()), the matches in the order noted.
  const size_t n = scratch->key.size();
  scratch->leaf_ptr.resize(n);
  scratch->z.resize(n);
  scratch->log_likelihood.resize(n);
  scratch->d2.resize(n);
  for (size_t k = 0; k < n; ++k) {
    const LandmarkObservation& z = scan[scratch->detection[k]];
    scratch->leaf_ptr[k] = &scratch->leaf[k];
    scratch->z[k] = RangeBearing{z.range_m, z.bearing_rad};
  }
  size_t failed = n;
  Status s =
      ObservationLogLikelihoods(pose, scratch->z.data(), scratch->leaf_ptr.data(), params.noise,
                                scratch->log_likelihood.data(), scratch->d2.data(), n, &failed);
  if (!s.ok()) {
    return Status(s.code(), fmt::format("detection {}, landmark {}: {}", scratch->detection[failed],
                                        scratch->key[failed], s.message()));
  }
  for (size_t k = 0; k < n; ++k) {
    if (scratch->d2[k] <= params.augment_gate) {
      out->push_back(Match{scratch->detection[k], scratch->key[k], scratch->log_likelihood[k],
                           scratch->d2[k]});
    }
  }
  return Status::Ok();
}

}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_DATA_ASSOCIATION_H_
