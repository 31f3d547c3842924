// Data association sampling (`association = sampled`): each particle draws each detection's
// association instead of taking the most likely one (Montemerlo's thesis, ch. 4, "data
// association sampling"; Nieto, Guivant, Nebot and Thrun, "Real time data association for
// FastSLAM", 2003).
//
// For detection z the hypotheses are every landmark whose d2 lies within the augment gate
// (Match::log_likelihood l_k) and a new landmark, whose likelihood is the new-feature p0 of
// data_association.h. The draw takes hypothesis k with probability q_k = L_k / T, T = sum of the
// L's (p0 included): there is no ignored band and no reject gate. A landmark beyond the augment
// gate is not a hypothesis: its likelihood is then below about 2 p0 (S >= R against p0's 2R) and
// the candidate query (SearchRadius) does not reach it.
//
// Weight. The draw is a proposal, so the importance weight of detection z is L_k / q_k = T, the
// same for every draw: the sum of the hypotheses' likelihoods (their marginal). A filter whose
// detection term is L_k (FastSLAM 1.0: l_k; the new landmark: p0) adds log T - log L_k to reach
// it (Decision::log_likelihood holds log L_k, so the correction is exact); FastSLAM 2.0 adds the
// same correction to its proposal step's predictive likelihood, which replaces l_k (the two
// differ by the pose covariance of one scan's prediction).
//
// The draw uses RandomStream(seed, step + 1, particle, kAssociation), one uniform per detection
// in the detections' order, so a particle's associations are the same at any thread or rank
// count and across checkpoints.
#ifndef GROVE_ENGINE_FASTSLAM_ASSOCIATION_SAMPLING_H_
#define GROVE_ENGINE_FASTSLAM_ASSOCIATION_SAMPLING_H_

#include <cstddef>
#include <span>
#include <vector>

#include "concurrency/random_stream.h"
#include "engine/fastslam/data_association.h"

namespace grove::fastslam {

// The sampled decisions of `detections` detections from their matches (every pair with
// d2 <= augment_gate, in any order; reordered by detection and key), each kAssociated or kNew;
// *log_correction gets the sum over detections of log T - log L_drawn (see above). `rs` gives
// one uniform per detection.
void SampleDecisions(std::span<Match> matches, size_t detections, double log_p0, RandomStream* rs,
                     std::vector<Decision>* out, double* log_correction);

}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_ASSOCIATION_SAMPLING_H_
