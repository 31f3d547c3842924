#include "engine/fastslam/association_sampling.h"

#include <algorithm>
#include <cmath>

namespace grove::fastslam {

void SampleDecisions(std::span<Match> matches, size_t detections, double log_p0, RandomStream* rs,
                     std::vector<Decision>* out, double* log_correction) {
  std::sort(matches.begin(), matches.end(), [](const Match& a, const Match& b) {
    return a.detection != b.detection ? a.detection < b.detection : a.key < b.key;
  });
  out->assign(detections, Decision{});
  *log_correction = 0;
  size_t m = 0;
  for (size_t j = 0; j < detections; ++j) {
    const size_t begin = m;
    while (m < matches.size() && matches[m].detection == j) ++m;
    const std::span<const Match> hyp(matches.data() + begin, m - begin);
    // T = sum of exp(l) over the landmarks and p0, scaled by the largest term.
    double top = log_p0;
    for (const Match& h : hyp) top = std::max(top, h.log_likelihood);
    double total = std::exp(log_p0 - top);
    for (const Match& h : hyp) total += std::exp(h.log_likelihood - top);
    const double u = rs->NextUniform() * total;
    // The new landmark is the last hypothesis: it takes whatever the landmarks leave.
    Decision d;  // kNew
    double drawn = log_p0;
    double below = 0;
    for (const Match& h : hyp) {
      below += std::exp(h.log_likelihood - top);
      if (u < below) {
        d = Decision{Decision::kAssociated, h.key, h.log_likelihood};
        drawn = h.log_likelihood;
        break;
      }
    }
    (*out)[j] = d;
    *log_correction += top + std::log(total) - drawn;
  }
}

}  // namespace grove::fastslam
