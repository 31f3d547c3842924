#include "engine/fastslam/joint_compatibility.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "alloc/check.h"

namespace grove::fastslam {
namespace {

// exp(-y) sum_{i<k} y^i / i!, the terms summed in logarithms (no overflow of y^i or i!).
double EvenTail(int k, double y) {
  if (y <= 0) return 1;
  const double log_y = std::log(y);
  double log_term = -y, sum = 0;
  for (int i = 0; i < k; ++i) {
    if (i > 0) log_term += log_y - std::log(static_cast<double>(i));
    sum += std::exp(log_term);
  }
  return sum;
}

}  // namespace

double ChiSquareEvenQuantile(int k, double alpha) {
  double lo = 0, hi = k + 1.0;
  while (EvenTail(k, hi) > alpha) hi *= 2;
  for (int it = 0; it < 200 && hi - lo > 1e-12 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (EvenTail(k, mid) > alpha ? lo : hi) = mid;
  }
  return lo + hi;  // x = 2y at the midpoint
}

void ExtendJointGates(double reject_gate, size_t k_max, std::vector<double>* gates) {
  const double alpha = std::exp(-0.5 * reject_gate);
  if (gates->empty() && k_max > 0) gates->push_back(reject_gate);
  while (gates->size() < k_max) {
    gates->push_back(ChiSquareEvenQuantile(static_cast<int>(gates->size()) + 1, alpha));
  }
}

bool JointCompatibility::Decide(std::span<Match> matches, size_t detections, double reject_gate,
                                std::span<const double> gates, int64_t node_budget,
                                std::vector<Decision>* out) {
  // Unpaired: new unless some landmark lies within the augment gate.
  out->assign(detections, Decision{});
  for (const Match& m : matches) (*out)[m.detection].kind = Decision::kIgnored;
  cand_.clear();
  for (const Match& m : matches) {
    if (m.d2 < reject_gate) cand_.push_back(m);
  }
  std::sort(cand_.begin(), cand_.end(), [](const Match& a, const Match& b) {
    if (a.detection != b.detection) return a.detection < b.detection;
    if (a.d2 != b.d2) return a.d2 < b.d2;
    return a.key < b.key;
  });
  first_.clear();
  for (size_t c = 0; c < cand_.size(); ++c) {
    if (c == 0 || cand_[c].detection != cand_[c - 1].detection) {
      first_.push_back(static_cast<uint32_t>(c));
    }
  }
  const size_t levels = first_.size();
  first_.push_back(static_cast<uint32_t>(cand_.size()));
  GROVE_CHECK(gates.size() >= levels);
  chosen_.assign(levels, -1);
  best_ = chosen_;
  used_.clear();
  gates_ = gates;
  best_pairs_ = -1;
  best_d2_ = std::numeric_limits<double>::infinity();
  nodes_ = 0;
  budget_ = node_budget;
  const bool complete = Search(0, 0, 0.0);
  for (size_t l = 0; l < levels; ++l) {
    if (best_[l] < 0) continue;
    const Match& m = cand_[best_[l]];
    (*out)[m.detection] = Decision{Decision::kAssociated, m.key, m.log_likelihood};
  }
  return !complete;
}

bool JointCompatibility::Search(size_t level, int pairs, double d2) {
  if (nodes_ == budget_) return false;
  ++nodes_;
  const size_t levels = first_.size() - 1;
  if (level == levels) {
    if (pairs > best_pairs_ || (pairs == best_pairs_ && d2 < best_d2_)) {
      best_ = chosen_;
      best_pairs_ = pairs;
      best_d2_ = d2;
    }
    return true;
  }
  // The most pairs any hypothesis below can reach, and whether one with `reach` pairs at joint
  // distance `at` could still beat the best.
  const int reach = pairs + static_cast<int>(levels - level);
  auto may_beat = [&](int most, double at) {
    return most > best_pairs_ || (most == best_pairs_ && at < best_d2_);
  };
  for (uint32_t c = first_[level]; c < first_[level + 1]; ++c) {
    const Match& m = cand_[c];
    const double next = d2 + m.d2;
    // Candidates come by increasing d2: once one fails the gate or the bound, all later do.
    if (!(next < gates_[pairs]) || !may_beat(reach, next)) break;
    if (std::find(used_.begin(), used_.end(), m.key) != used_.end()) continue;
    chosen_[level] = static_cast<int32_t>(c);
    used_.push_back(m.key);
    const bool ok = Search(level + 1, pairs + 1, next);
    used_.pop_back();
    if (!ok) return false;
  }
  chosen_[level] = -1;
  if (!may_beat(reach - 1, d2)) return true;
  return Search(level + 1, pairs, d2);
}

}  // namespace grove::fastslam
