#include "engine/fastslam/data_association.h"

#include <algorithm>
#include <numbers>

namespace grove::fastslam {

double NewLandmarkLogLikelihood(const SensorNoise& noise, double augment_gate) {
  const Eigen::Matrix2d r = SensorCovariance(noise);
  // det(2R) = 4 r00 r11 for the diagonal R.
  return -0.5 * augment_gate - std::log(2 * std::numbers::pi) -
         0.5 * std::log(4 * r(0, 0) * r(1, 1));
}

double InitCovarianceBound(double range_m, const SensorNoise& noise, double init_cd_h) {
  const Eigen::Matrix2d r = SensorCovariance(noise);
  const double sr2 = r(0, 0), sb2 = r(1, 1);
  const double across = range_m * range_m * sb2;
  if (init_cd_h <= 0) return std::max(sr2, across);
  return std::max(sr2 + across * sb2 * (init_cd_h * init_cd_h - 1) / 4, across);
}

double SearchRadius(double range_m, double max_range_m, const SensorNoise& noise,
                    double augment_gate, double init_cd_h) {
  const Eigen::Matrix2d r = SensorCovariance(noise);
  const double sr2 = r(0, 0), sb2 = r(1, 1);
  const double k = 2 * augment_gate;
  const double a = k * sb2;
  if (!(a < 1)) return std::numeric_limits<double>::infinity();
  const double rmax = std::max(range_m, max_range_m);
  const double lp = InitCovarianceBound(rmax, noise, init_cd_h);
  const double c = a * range_m * range_m + k * (lp + sr2);
  const double root = (a * range_m + std::sqrt(a * a * range_m * range_m + (1 - a) * c)) / (1 - a);
  // A margin of 1e-6 relative and 1e-9 m for the round-off of the distances compared with it.
  return root * (1 + 1e-6) + 1e-9;
}

void Decide(std::span<Match> matches, size_t detections, const AssociationParams& params,
            std::vector<Decision>* out) {
  // New unless some landmark lies within the augment gate; associations override below.
  out->assign(detections, Decision{});
  for (const Match& m : matches) (*out)[m.detection].kind = Decision::kIgnored;
  auto better = [](const Match& a, const Match& b) {
    if (a.log_likelihood != b.log_likelihood) return a.log_likelihood > b.log_likelihood;
    if (a.detection != b.detection) return a.detection < b.detection;
    return a.key < b.key;
  };
  if (!params.exclusive) {
    for (const Match& m : matches) {
      if (!(m.d2 < params.reject_gate)) continue;
      Decision& d = (*out)[m.detection];
      const bool first = d.kind != Decision::kAssociated;
      if (first || better(m, Match{m.detection, d.key, d.log_likelihood, 0})) {
        d = Decision{Decision::kAssociated, m.key, m.log_likelihood};
      }
    }
  } else {
    std::sort(matches.begin(), matches.end(), better);
    std::vector<uint64_t> taken;
    for (const Match& m : matches) {
      if (!(m.d2 < params.reject_gate)) continue;
      Decision& d = (*out)[m.detection];
      if (d.kind == Decision::kAssociated) continue;
      if (std::find(taken.begin(), taken.end(), m.key) != taken.end()) continue;
      taken.push_back(m.key);
      d = Decision{Decision::kAssociated, m.key, m.log_likelihood};
    }
  }
}

}  // namespace grove::fastslam
