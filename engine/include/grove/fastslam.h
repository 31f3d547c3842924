// Landmark FastSLAM: a vehicle driving among point landmarks, observed by a range-bearing sensor
// (Montemerlo et al., "FastSLAM", AAAI 2002, and "FastSLAM 2.0", IJCAI 2003). A
// Rao-Blackwellized particle filter: each particle carries a vehicle path and a map of landmark
// Gaussians, kept in a persistent tree that it shares with its relatives (log-N updates, O(1)
// copies, freed by reference counts).
//
//   grove::FastSlamConfig config;                     // FastSLAM 2.0, 100 particles, Bailey
//   auto slam = grove::FastSlam::Create(config);       // validates; nothing built on error
//   if (!slam.ok()) return slam.status();
//   GROVE_RETURN_IF_ERROR((*slam)->Control(0.0, 3.0, 0.0));  // speed, steering from t = 0 on
//   grove::LandmarkObservation z[] = {{12.5, 0.3, 7}};  // range, bearing, landmark id
//   GROVE_RETURN_IF_ERROR((*slam)->Scan(0.2, z));      // predicts to t = 0.2, then updates
//   auto landmarks = (*slam)->HeaviestLandmarks();     // a StatusOr: fails without memory
//
// Time: the first Control() sets the start time (the start pose is at it). A control holds
// from its time until the next control's (zero-order hold); every call predicts from the last
// time to its own with the held control, one Euler step per call. Scan() then updates.
// Predictions are deferred: Control() checks its input and records the step; the next Scan()
// or read-out runs every recorded prediction in one pass over the particles (one parallel loop
// for the controls between two scans, not one per control), with the same result as running
// each at once.
//
// Thread safety: a FastSlam is driven by one thread at a time (no two calls overlap, const
// read-outs included); it runs its own worker threads inside each call. Two engines in one
// process share nothing.
//
// Ownership: every read-out that returns a container (maps, trajectories, landmarks, checkpoint
// bytes) returns a copy the caller owns: it stays valid after later steps and after the engine
// is destroyed. Only references returned by const methods (config(), MeanTrajectory()) live in
// the engine and change with the next step.
#ifndef GROVE_FASTSLAM_H_
#define GROVE_FASTSLAM_H_

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "grove/config_fields.h"
#include "grove/export.h"
#include "grove/filter_config.h"
#include "grove/resampling.h"
#include "grove/status.h"
#include "grove/types.h"

namespace grove {

enum class FastSlamFilter {
  // Proposal from the motion model: each particle draws its own noisy control; the weight is the
  // likelihood of the scan's innovations; each observed landmark gets an EKF update.
  kFastSlam1,
  // Proposal that uses the scan (Montemerlo et al. 2003), applied observation by observation as
  // Bailey's sample_proposal: between scans each particle predicts a pose mean and covariance
  // from the control and its noise; at a scan the observations of known landmarks refine them,
  // the pose is drawn from the result, and the weight is the product of each observation's
  // predictive likelihood.
  kFastSlam2,
  // The seed's family (Ankışhan et al., 2016; engine/fastslam/sigma_point_filters.h and
  // engine/fastslam/README.md give every reading). Each draws its pose after resampling (as
  // kFastSlam2) unless said.
  // U-FastSLAM (Kim, Sakthivel, Chung 2008): the scaled unscented transform for the vehicle's
  // prediction and proposal, the landmark updates and the weights (ut_alpha, ut_beta, ut_kappa).
  kUnscented,
  // SRCD-FastSLAM (the seed's Section 3.1): square-root central-difference Kalman filters
  // (cd_step h) for the vehicle, the landmarks (Cholesky factors in the leaves) and the weights.
  kSrcd,
  // SRCD-aided FastSLAM (grove's reading of the seed's Table 1): FastSLAM 2.0's EKF proposal and
  // weight for the vehicle; the square-root central-difference filter for the landmarks.
  kSrcdAided,
  // SRCD particle-filter FastSLAM (grove's reading: van der Merwe's sigma-point particle filter
  // with the SR-CDKF): the SR-CDKF proposal for the vehicle, drawn before the weight; the weight
  // is the importance ratio p(z | x) p(x | prediction) / q(x) at the drawn pose; EKF landmarks.
  kSrcdParticle,
  // DE-SRCD-FastSLAM (the seed's Section 3.2): kSrcd, and after each scan's draw differential
  // evolution DE/best/1/bin (de_scale F, de_crossover Cr, de_generations) moves the drawn poses
  // towards a higher fitness (Eq. 32) before they update their maps.
  kDeSrcd,
};

enum class FastSlamVehicle {
  // Bailey's simulator: x += V dt cos(G + phi), y += V dt sin(G + phi),
  // phi += V dt sin(G) / wheelbase_m.
  kBailey,
  // Guivant and Nebot's Ackermann model of the Victoria Park vehicle: the speed is measured at
  // the rear left wheel (encoder_offset_m from the axle centre) and the state is the laser's
  // position (laser_forward_m ahead of the rear axle, laser_left_m to the side).
  kGuivantNebot,
};

enum class FastSlamAssociation {
  // Each observation names its landmark (LandmarkObservation::id).
  kKnown,
  // Unknown association, per particle: maximum likelihood inside the reject gate, a new
  // landmark beyond the augment gate of every landmark, the detection ignored in between
  // (engine/fastslam/data_association.h). Observation ids, when given (>= 0), only tag the
  // landmarks they create, for the association error rate.
  kMaximumLikelihood,
  // As kMaximumLikelihood, and within a scan one landmark per detection and one detection per
  // landmark (greedy by likelihood).
  kExclusive,
  // Unknown association, per particle: each detection's association drawn in proportion to its
  // likelihoods, a new landmark (p0) included, and weighted by their sum
  // (engine/fastslam/association_sampling.h).
  kSampled,
  // Unknown association, per particle and scan: joint compatibility branch and bound (Neira and
  // Tardós 2001): the most detections paired with distinct landmarks inside their reject gates
  // whose summed d2 passes the chi-square test of 2k degrees of freedom at the reject gate's
  // confidence; the others new or ignored as under kMaximumLikelihood
  // (engine/fastslam/joint_compatibility.h).
  kJointCompatibility,
};

// How the gates are given.
enum class FastSlamGateUnit {
  kDistance2,    // squared Mahalanobis distances (Bailey's 4 and 25)
  kProbability,  // chi-square (2 degrees of freedom) probabilities: d2 = -2 ln(1 - p)
};

enum class FastSlamEvidence { kOff, kOn };

// The filter's fields come from FilterConfig (grove/filter_config.h): particles (Default: 100,
// Bailey's NPARTICLES), seed, resampling, resample_threshold (resample after a scan when ESS / N
// is below it; Default: 0.75, Bailey's NEFFECTIVE = 0.75 * NPARTICLES), threads and batch
// (Default: 64).
struct GROVE_EXPORT FastSlamConfig : FilterConfig {
  FastSlamConfig() {
    particles = 100;
    resample_threshold = 0.75;
    batch = 64;
  }

  // Options that change results

  // The filter. Default: kFastSlam2.
  FastSlamFilter filter = FastSlamFilter::kFastSlam2;
  // The vehicle model. Default: kBailey.
  FastSlamVehicle vehicle = FastSlamVehicle::kBailey;
  // Distance between the axles, metres (B of the Bailey model, L of Guivant-Nebot's).
  // Range: (0, 100]. Default: 4 (Bailey's WHEELBASE).
  double wheelbase_m = 4.0;
  // Guivant-Nebot only: encoder offset H, laser offsets a (forward) and b (to the side), metres.
  // Range: [-100, 100]. Defaults: the Victoria Park vehicle's H = 0.76, a = 3.78, b = 0.50.
  double encoder_offset_m = 0.76;
  double laser_forward_m = 3.78;
  double laser_left_m = 0.50;
  // Control noise: standard deviations of the speed (m/s) and the steering angle (rad) the
  // filter assumes. Range: [0, 100] and [0, pi]. Defaults: Bailey's sigmaV = 0.3 m/s and
  // sigmaG = 3 degrees.
  double sigma_speed_mps = 0.3;
  double sigma_steer_rad = 0.052359877559830;
  // Sensor noise: standard deviations of range (m) and bearing (rad). Range: [0, 1e4] and
  // [0, pi]. Defaults: Bailey's sigmaR = 0.1 m and sigmaB = 1 degree.
  double sigma_range_m = 0.1;
  double sigma_bearing_rad = 0.017453292519943;
  // Start pose. Range: |x|, |y| <= 1e9 m, |heading| <= 1000 rad. Default: (0, 0, 0).
  double start_x_m = 0;
  double start_y_m = 0;
  double start_heading_rad = 0;

  // The seed's family (filter kUnscented ... kDeSrcd)

  // U-FastSLAM's scaled unscented transform. Ranges: alpha (0, 10], beta [0, 100],
  // kappa (-4, 100]. Defaults: Kim's 0.9, 2, 0.
  double ut_alpha = 0.9;
  double ut_beta = 2;
  double ut_kappa = 0;
  // The central-difference half-step h of the SRCD filters. Range: [1, 10]. Default: sqrt(3),
  // optimal for Gaussian variables.
  double cd_step = 1.7320508075688772;
  // Differential evolution (kDeSrcd): scale factor F, crossover probability Cr, and the number
  // of generations per scan. Ranges: [0, 2], [0, 1], 0..255 (each generation draws from a random
  // stream of its own). Defaults: the seed's F = 0.4, Cr = 0.8; 10 generations (the seed gives
  // no number).
  double de_scale = 0.4;
  double de_crossover = 0.8;
  int64_t de_generations = 10;

  // Unknown data association (association != kKnown)

  // Default: kKnown.
  FastSlamAssociation association = FastSlamAssociation::kKnown;
  // Gates, in gate_unit. Range: (0, 1e6] (probabilities: (0, 1)); augment >= reject.
  // Defaults: Bailey's 4 and 25 (squared Mahalanobis distances). Under kJointCompatibility the
  // reject gate is each pair's individual gate, and its chi-square confidence the joint test's.
  double reject_gate = 4.0;
  double augment_gate = 25.0;
  FastSlamGateUnit gate_unit = FastSlamGateUnit::kDistance2;
  // Landmark existence evidence (Montemerlo): a new landmark starts at 1, gains 1 at each scan
  // that associates it and loses 1 at each scan that has it in view (range <= sensor_range_m,
  // |bearing| <= sensor_fov_rad / 2, from the pose the association used: FastSLAM 2.0's
  // predicted mean) without a detection inside its augment gate; it is removed when its
  // evidence falls below evidence_threshold. Default: on (measured: on Victoria Park it halves
  // the map and lowers the GPS error; engine/fastslam/README.md), threshold 0.
  FastSlamEvidence evidence = FastSlamEvidence::kOn;
  int64_t evidence_threshold = 0;
  // The sensor's view for the evidence. Range: (0, 1e6] m and (0, 2 pi]. Defaults: Bailey's
  // MAX_RANGE 30 m and the front half-plane.
  double sensor_range_m = 30;
  double sensor_fov_rad = 3.141592653589793;
  // Side of the spatial index's cells, metres (at most 8 landmarks a cell: a ninth is dropped
  // and counted). Range: [0.05, 1e4]. Default: 5.
  double index_cell_m = 5;

  // Checks every field; the message names the field, its value and the rule it breaks.
  Status Validate() const;
};

// A gate as a squared Mahalanobis distance.
GROVE_EXPORT double FastSlamGateDistance2(double gate, FastSlamGateUnit unit);

// "fastslam1", "fastslam2", "ufastslam", "srcd", "srcd_aided", "srcd_pf", "de_srcd".
GROVE_EXPORT const char* FastSlamFilterName(FastSlamFilter filter);
// The filter named `name` (FastSlamFilterName's names); false for another name.
GROVE_EXPORT bool FastSlamFilterFromName(std::string_view name, FastSlamFilter* filter);
GROVE_EXPORT const char* FastSlamVehicleName(FastSlamVehicle vehicle);  // "bailey", "guivant_nebot"

// Every field of FastSlamConfig: name, type, range, effect and meaning, in the struct's order.
GROVE_EXPORT const std::vector<ConfigField<FastSlamConfig>>& FastSlamConfigFields();

// One detection of a scan: range (m, in [0, 1e6]), bearing (rad, in (-pi, pi], counter-clockwise
// from the heading) and the landmark's id (known association: in [0, 2^31); unknown: -1 for
// none, or a simulator's truth below 2^31 that only tags the landmarks it creates). The bounds
// are grove/input_rules.h's.
struct LandmarkObservation {
  double range_m = 0;
  double bearing_rad = 0;
  int64_t id = 0;
};

// A landmark of a particle's map: its id (under unknown association its spatial key), mean (m)
// and covariance (m^2), and under unknown association the id the observation that created it
// carried (-1 for none).
struct LandmarkEstimate {
  int64_t id = 0;
  double x_m = 0;
  double y_m = 0;
  double sxx = 0;
  double sxy = 0;
  double syy = 0;
  int64_t source_id = -1;
};

// What unknown association did along one particle's ancestry, over the whole run.
struct AssociationCounts {
  int64_t associated = 0;  // detections that updated a landmark
  int64_t created = 0;     // detections that started a landmark
  int64_t ignored = 0;     // detections between the gates
  int64_t removed = 0;     // landmarks removed by their existence evidence
  int64_t dropped = 0;     // landmarks not stored: their cell of the index was full
  int64_t tagged = 0;      // associations of a detection and a landmark that both carry an id
  int64_t wrong = 0;       // ... whose ids differ
  int64_t truncated = 0;   // scans whose joint compatibility search stopped at its node budget
};

// What differential evolution did (kDeSrcd), over the whole run.
struct EvolutionCounts {
  int64_t trials = 0;    // trial poses evaluated
  int64_t accepted = 0;  // ... that replaced their particle's pose (a strictly higher fitness)
};

struct GROVE_EXPORT FastSlamSummary : FilterSummary {
  int64_t controls = 0;           // Control() calls
  int64_t scans = 0;              // Scan() calls
  int64_t observations = 0;       // detections over all scans
  int64_t predict_steps = 0;      // filter steps that only predicted
  int64_t landmarks = 0;          // in the heaviest particle's map
  AssociationCounts association;  // the heaviest particle's (unknown association)
  EvolutionCounts evolution;      // kDeSrcd
  MemoryUse map_memory;
  MemoryUse trajectory_memory;
  // One paragraph for a terminal.
  std::string BriefReport() const;
};

// What a run will give an engine: the figures FastSlam::EstimatePeakBytes() predicts from.
struct FastSlamWorkload {
  int64_t controls = 0;      // Control() calls
  int64_t scans = 0;         // Scan() calls
  int64_t observations = 0;  // detections over all scans
};

class Collective;

class GROVE_EXPORT FastSlam {
 public:
  // Validates `config` and builds the engine; nothing is built when the config is invalid.
  static StatusOr<std::unique_ptr<FastSlam>> Create(const FastSlamConfig& config);
  // One rank's engine of a filter whose config.particles are split over the ranks of `ranks`
  // (grove/collective.h; null: one process, as Create(config)), as FootSlam's: every rank
  // creates its engine with the same configuration and makes the same calls in the same order;
  // Control, Scan and every read-out are collective and give every rank the whole filter's
  // result, the same bits as one process. Checkpoint() saves this rank's share. Every rank needs
  // at least one block of 4,096 particles (InvalidArgument). Summary()'s memory and phase
  // figures are this rank's.
  static StatusOr<std::unique_ptr<FastSlam>> Create(const FastSlamConfig& config,
                                                    Collective* ranks);
  // What Create(config, ranks) checks of a configuration for `ranks` ranks beyond Validate().
  static Status CheckAcrossRanks(const FastSlamConfig& config, int ranks);
  // A prediction of the peak memory, in bytes, of a process running an engine of `config` fed
  // `work`: a fixed part, the particles' state and the map paths each scan copies (in two
  // generations, growing with the detections a scan holds), and the per-step records. It stays
  // above the peak RSS of `grove fastslam victoria-park` and of the webmap's `run`
  // (engine/fastslam/README.md gives the runs). Across ranks, of a rank holding
  // config.particles particles. REQUIRES: config.Validate() is ok.
  static int64_t EstimatePeakBytes(const FastSlamConfig& config, const FastSlamWorkload& work);
  virtual ~FastSlam();

  // A control (speed m/s, steering angle rad) from time t_s on: predicts from the last time to
  // t_s with the control held so far (the first call sets the start time), then holds this one.
  // InvalidArgument, the engine unchanged, for a value outside grove/input_rules.h's bounds
  // (CheckInput, CheckSteering) or a time not after the previous control's and not at or after
  // the last scan's. The prediction itself runs with the next Scan() or read-out (see Time
  // above): an error inside it (a particle's pose not finite, its noisy steering outside what
  // the vehicle model can use) stops the engine and is returned, with the step and time it
  // happened at, by that Scan() or read-out, or, when the read-out returns no status (MeanPose(),
  // MeanTrajectory(), Summary(), ...), by the next call that returns one. Every later step
  // returns FailedPrecondition.
  Status Control(double t_s, double speed_mps, double steer_rad);

  // A scan at t_s (at or after the last time): predicts to t_s with the held control, then
  // updates every particle with the observations. InvalidArgument, the engine unchanged, before
  // the first control, for a bad time (outside grove/input_rules.h's bounds, before the last, or
  // the time of the scan just before: one time's detections are one scan), or for an observation
  // outside the bounds (CheckInput, CheckLandmarkId; the message names its index).
  // FailedPrecondition when the filter degenerated: that and any other error stopped the engine
  // (its message says so), and every later step returns FailedPrecondition.
  Status Scan(double t_s, std::span<const LandmarkObservation> observations);

  const FastSlamConfig& config() const;
  // Filter steps so far: one per prediction and one per scan update.
  int64_t steps() const;
  Pose2 MeanPose() const;
  Pose2 HeaviestPose() const;
  // The weighted mean pose at the start and after every step.
  const std::vector<StampedPose>& MeanTrajectory() const;
  // The covariance of the particles' poses about their weighted mean after the last step
  // (weighted; heading differences wrapped to (-pi, pi]); the particles' own Gaussians between
  // scans are not added. After a scan every particle holds a drawn pose, so this is the filter's
  // estimate of its pose uncertainty there (the pose NEES uses it).
  Pose2Covariance PoseCovariance() const;
  // The heaviest particle's path at the same times, traced through its ancestry.
  StatusOr<std::vector<StampedPose>> HeaviestTrajectory() const;
  // The heaviest particle's landmarks in id order.
  StatusOr<std::vector<LandmarkEstimate>> HeaviestLandmarks() const;
  FastSlamSummary Summary() const;
  // Walks every shared map node and path entry and checks its reference count (tests).
  Status CheckInvariants() const;

  // Checkpoints (as FootSlam's)
  StatusOr<std::string> Checkpoint(std::string_view user_data = {}) const;
  static StatusOr<std::unique_ptr<FastSlam>> Resume(const FastSlamConfig& config,
                                                    std::string_view checkpoint,
                                                    const std::string& name,
                                                    std::string* user_data);
  // Across ranks (collective: every rank calls it with its own file), as FootSlam's.
  static StatusOr<std::unique_ptr<FastSlam>> Resume(const FastSlamConfig& config,
                                                    std::string_view checkpoint,
                                                    const std::string& name, std::string* user_data,
                                                    Collective* ranks);

  class Impl;

 private:
  explicit FastSlam(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace grove

#endif  // GROVE_FASTSLAM_H_
