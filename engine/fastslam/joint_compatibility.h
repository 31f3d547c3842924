// Joint compatibility branch and bound (`association = jcbb`; Neira and Tardós, "Data
// association in stochastic mapping using the joint compatibility test", IEEE T-RA 17(6), 2001),
// per particle and scan.
//
// A hypothesis pairs some of the scan's detections with distinct landmarks, each pair inside
// its individual gate (d2 < reject_gate). The search takes the hypothesis of most pairs whose
// joint Mahalanobis distance D2 lies below chi2(2k, 1 - alpha), k its pairs; ties go to the
// smaller D2, then to the first found (detections in order, each one's landmarks by d2, then
// key). alpha is the reject gate's own: the chi-square (2 degrees of freedom) tail beyond it,
// exp(-reject_gate / 2), so a single pair passes exactly when it passes the individual gate.
//
// Joint distance. D2 = v^T C^-1 v over the stacked innovations v of the k pairs, with C their
// joint covariance. In EKF-SLAM C couples the pairs through the shared pose and the map's
// cross-covariances. In FastSLAM a particle's pose is a sample (FastSLAM 2.0 decides from its
// predicted mean, data_association.h) and its landmarks are independent given that pose, so C is
// block diagonal, C = diag(S_1, ..., S_k), and D2 is the sum of the pairs' individual d2. The
// pose uncertainty of FastSLAM 2.0's proposal is not included: the particles' spread carries it.
// The joint test then rules out sets whose distances are each near the individual gate (the
// sum outgrows chi2(2k)), and the branch and bound keeps one landmark per detection and one
// detection per landmark with the most pairs, where nearest neighbour takes each detection's
// nearest landmark on its own.
//
// Detections without a pair: new when no landmark lies within their augment gate, ignored
// otherwise (as under ml). The search visits at most node_budget nodes and then keeps the best
// hypothesis found so far (the first, greedy descent comes first: nearest landmark still free
// for each detection in order, as long as the joint test holds).
#ifndef GROVE_ENGINE_FASTSLAM_JOINT_COMPATIBILITY_H_
#define GROVE_ENGINE_FASTSLAM_JOINT_COMPATIBILITY_H_

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "engine/fastslam/data_association.h"

namespace grove::fastslam {

// The x with P(chi2 with 2k degrees of freedom > x) = alpha, for k >= 1 and 0 < alpha < 1
// (the even-degree tail, exp(-x/2) sum_{i<k} (x/2)^i / i!, solved by bisection).
double ChiSquareEvenQuantile(int k, double alpha);

// The joint gates chi2(2k, 1 - alpha) for k = 1..*gates' size, alpha that of `reject_gate`
// (above); (*gates)[0] is reject_gate itself. Extends *gates to `k_max` entries.
void ExtendJointGates(double reject_gate, size_t k_max, std::vector<double>* gates);

// Thread safety: one instance per worker slot (it holds the search's buffers).
class JointCompatibility {
 public:
  // The visits per scan after which the search stops (10,000: a scan of Victoria Park or the
  // webmap needs far fewer).
  static constexpr int64_t kDefaultNodeBudget = 10000;

  // The decisions for `detections` detections from their matches (every pair with
  // d2 <= augment_gate, in any order; reordered); `gates` as ExtendJointGates() gives, at least
  // one per detection that has a pair inside the reject gate. Returns true when the search
  // stopped at node_budget (the decisions then the best hypothesis found before).
  bool Decide(std::span<Match> matches, size_t detections, double reject_gate,
              std::span<const double> gates, int64_t node_budget, std::vector<Decision>* out);

  // The nodes the last Decide() visited (at most its budget).
  int64_t nodes() const { return nodes_; }

 private:
  // The subtree below `level` (the levels before it decided), `pairs` pairs so far at joint
  // distance d2. Returns false when the budget ran out.
  bool Search(size_t level, int pairs, double d2);

  // Candidates inside the reject gate, by detection, then d2, then key; level l's are
  // cand_[first_[l] .. first_[l + 1]).
  std::vector<Match> cand_;
  std::vector<uint32_t> first_;
  std::vector<int32_t> chosen_, best_;  // per level: the candidate taken, or -1
  std::vector<uint64_t> used_;          // the landmarks paired on the current path
  std::span<const double> gates_;
  int best_pairs_ = 0;
  double best_d2_ = 0;
  int64_t nodes_ = 0;
  int64_t budget_ = 0;
};

}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_JOINT_COMPATIBILITY_H_
