// FootSLAM: pedestrian simultaneous localisation and mapping from step odometry on a hexagon
// grid (Angermann and Robertson 2012; Garcia Puyol, Robertson and Heirich, "Complexity-reduced
// FootSLAM"). A Rao-Blackwellized particle filter: each particle carries a pose, odometry error
// states and a map of hexagon transition counters that it shares with its relatives.
//
//   grove::FootSlamConfig config;
//   config.particles = 30000;
//   auto slam = grove::FootSlam::Create(config);  // validates; nothing built on error
//   if (!slam.ok()) return slam.status();
//   const double steps[][3] = {{0.5, 0.70, 0.00}, {1.0, 0.68, 0.05}};  // t_s, dx_m, dy_m
//   for (const auto& s : steps) {
//     grove::Status st = (*slam)->Step(s[0], s[1], s[2]);  // on error the engine is unchanged
//     if (!st.ok()) return st;
//   }
//   grove::StatusOr<std::vector<grove::HexCounts>> map = (*slam)->CumulativeMap();
//
// Thread safety: a FootSlam is driven by one thread at a time (no two calls overlap, const
// read-outs included); it runs its own worker threads inside Step(). Two engines in one
// process share nothing.
//
// Ownership: every read-out that returns a container (maps, trajectories, landmarks, checkpoint
// bytes) returns a copy the caller owns: it stays valid after later steps and after the engine
// is destroyed. Only references returned by const methods (config(), MeanTrajectory()) live in
// the engine and change with the next step.
#ifndef GROVE_FOOTSLAM_H_
#define GROVE_FOOTSLAM_H_

#include <cstdint>
#include <memory>
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

enum class FootSlamMapKind {
  kHTree,  // per-particle persistent H-tree shared between relatives (paper §IV)
  kNaive,  // per-particle hash table copied whole at resampling (paper §III), the baseline
};

// How a step's transitions weigh a particle.
enum class FootSlamWeighting {
  // The paper's rule: w *= (C_h^e + a) / (C_h + 6a) for each crossed edge. Every crossing
  // multiplies by a number below one, so particles whose steps cross fewer edges gain weight:
  // a free step scale drifts short.
  kPaper,
  // Each crossing's probability is divided by the probability an empty map gives it (1/6):
  // w *= 6 (C_h^e + a) / (C_h + 6a). Unexplored space is neutral, so the number of crossings
  // alone no longer rewards a particle; known transitions still do.
  kPriorRatio,
};

// How far the hexagon grid reaches.
enum class FootSlamGrid {
  // The H-tree gains a level above its root when a particle leaves the area it covers, up to
  // 2^26 hexagons per side: walks of any extent run, a step costing like log of the extent.
  kGrowing,
  // The paper's fixed grid of grid_size x grid_size hexagons; a walk that leaves it stops with
  // an error. Within the grid both give the same results.
  kFixed,
};

// The filter's fields come from FilterConfig (grove/filter_config.h): particles (Default:
// 30000), seed, resampling, resample_threshold (Default: 0.5), threads and batch (Default: 512);
// island mode's from IslandConfig (islands, island_exchange_steps, island_exchange_fraction:
// above 1 island the particles form islands of whole blocks of 4,096, each resampled from its
// own weights; systematic resampling only).
struct GROVE_EXPORT FootSlamConfig : FilterConfig, IslandConfig {
  FootSlamConfig() { particles = 30000; }

  // Options that change results

  // Circumradius of the pointy-top hexagons, metres. Range: (0, 1000]. Default: 0.5.
  double hex_radius_m = 0.5;
  // Prior count a added to every edge counter (Dirichlet prior). Range: (0, 1e6]. Default: 0.8.
  double prior_count = 0.8;
  // Weighting rule, see FootSlamWeighting. Default: kPaper.
  FootSlamWeighting weighting = FootSlamWeighting::kPaper;
  // Confidence in a prior map (SetPriorMap): each of its counters, times this, is added to the
  // prior count a of its edge. 1 counts the earlier walk's weighted crossings as if this walk had
  // made them; 0 ignores the prior map. Range: [0, 1e6]. Default: 1.
  double prior_map_confidence = 1;
  // Storage of diversity (paper §VI): every 50 steps, each block of the particles' maps (a
  // square H-tree subtree, the largest no wider than this distance) farther than this from
  // every particle is folded into one weighted mean map, the stored map, and dropped from the
  // particles' trees. The stored map is a prior map from then on (confidence 1), so a particle
  // that comes back is weighted by it. 0 switches storage off. H-tree maps only, with
  // grid_size >= degree. Range: [0, 1e9] metres. Default: 0.
  double store_distance_m = 0;

  // Start pose in the map frame. Range: |start_x_m|, |start_y_m| <= 1e9 hexagon radii (the
  // grid's integer coordinates); |start_heading_rad| <= 1000. Default: origin, heading 0.
  double start_x_m = 0;
  double start_y_m = 0;
  double start_heading_rad = 0;

  // Motion model. Each particle rotates and scales the odometry step by its own error states
  // and adds white noise (the paper's P, U, E). All zero: every particle follows the odometry.
  // Sigmas are bounded so that no finite configuration can make a pose non-finite.
  // Initial spread of the heading error, radians. Range: [0, 10]. Default: 0 (start heading
  // known).
  double initial_heading_sigma_rad = 0;
  // Random-walk increment of the heading error per step, radians. Range: [0, 10]. Default: 0.01.
  double heading_drift_sigma_rad = 0.01;
  // White noise on each step's heading, radians. Range: [0, 10]. Default: 0.03.
  double heading_sigma_rad = 0.03;
  // Initial spread of the step-length scale error (scale = 1 + N(0, sigma)). Range: [0, 10].
  // Default: 0 (scale fixed: see engine/footslam/README.md on the short-step trap).
  double scale_sigma = 0;
  // Random-walk increment of the scale error per step. Range: [0, 10]. Default: 0.
  double scale_drift_sigma = 0;
  // White noise on each step's length, metres. Range: [0, 100]. Default: 0.04.
  double step_length_sigma_m = 0.04;
  // White noise on each step's end position, per axis, metres. Range: [0, 100]. Default: 0.
  double position_sigma_m = 0;

  // Map representation. Default: kHTree.
  FootSlamMapKind map = FootSlamMapKind::kHTree;
  // H-tree degree s = s_x * s_y. One of 4, 16, 64, 256. Default: 16.
  int degree = 16;
  // Hexagons per side of the square grid centred on the start (the first grid, when it grows);
  // a power of sqrt(degree) and at least sqrt(degree). Default: 256.
  int grid_size = 256;
  // Whether the grid grows when a particle leaves it. Default: kGrowing.
  FootSlamGrid grid = FootSlamGrid::kGrowing;
  // Alphabet bound T (paper §V): leaves hold one 16-bit symbol while every counter is <= T.
  // Range: 0..5; 0 switches the alphabet off. Default: 5. H-tree maps only; results identical.
  int alphabet = 5;

  // Checks every field; the message names the field, its value and the rule it breaks.
  Status Validate() const;
};

GROVE_EXPORT const char* FootSlamMapKindName(FootSlamMapKind kind);  // "htree", "naive"
GROVE_EXPORT bool ParseFootSlamMapKind(const std::string& name, FootSlamMapKind* kind);
// "paper", "prior_ratio"
GROVE_EXPORT const char* FootSlamWeightingName(FootSlamWeighting weighting);
GROVE_EXPORT bool ParseFootSlamWeighting(const std::string& name, FootSlamWeighting* weighting);

// One hexagon of a map: axial coordinates, centre and the six edge counters (weighted for a
// cumulative map, whole numbers for one particle's map).
struct HexCounts {
  int32_t q = 0;
  int32_t r = 0;
  double x_m = 0;
  double y_m = 0;
  double counts[6] = {0, 0, 0, 0, 0, 0};
};

// What a run asked for, what it used and what it cost.
struct GROVE_EXPORT FootSlamSummary : FilterSummary {
  // Weighted means over the particles after the last step: the step-length scale error state
  // (1 = the odometry's length) and the heading error state (radians).
  double mean_scale = 1;
  double mean_heading_error_rad = 0;
  MemoryUse map_memory;
  MemoryUse trajectory_memory;
  // Hexagons per side of the grid the particles' maps reach: grid_size until a particle leaves
  // the first grid, then the nested grid that holds every particle's hexagons.
  int64_t grid_size = 0;
  // Hexagons of the prior map in use, and those left out (outside the grid).
  int64_t prior_hexagons = 0;
  int64_t prior_hexagons_outside = 0;
  // Storage of diversity (store_distance_m): blocks folded into the stored map, its hexagons,
  // and the seconds it took (choosing, folding and dropping blocks).
  int64_t stored_blocks = 0;
  // Blocks whose fold lost nothing: every particle held the same counters there, so the stored
  // map weighs a return exactly as the particles' own maps would have.
  int64_t stored_blocks_exact = 0;
  int64_t stored_hexagons = 0;
  double store_s = 0;
  // One paragraph for a terminal.
  std::string BriefReport() const;
};

// Every field of FootSlamConfig: name, type, range, effect and meaning, in the struct's order.
// Validate() checks these ranges; the grove command's JSON keys, flags and --print-config and
// the checkpoint's field block come from this table.
GROVE_EXPORT const std::vector<ConfigField<FootSlamConfig>>& FootSlamConfigFields();

class Collective;

class GROVE_EXPORT FootSlam {
 public:
  // Validates `config` and builds the engine; nothing is built when the config is invalid.
  static StatusOr<std::unique_ptr<FootSlam>> Create(const FootSlamConfig& config);
  // One rank's engine of a filter whose config.particles are split over the ranks of `ranks`
  // (grove/collective.h; null: one process, as Create(config)). Every rank creates its
  // engine with the same configuration and makes the same calls in the same order: Step, and every
  // read-out, is collective, and gives every rank the whole filter's result, the same bits as
  // one process. Checkpoint() saves this rank's share (Resume with ranks reads it back).
  // Storage of diversity folds every rank's far blocks into one stored map that every rank
  // holds. Every rank needs at least one block of 4,096 particles (InvalidArgument).
  // Summary()'s memory and phase figures are this rank's.
  static StatusOr<std::unique_ptr<FootSlam>> Create(const FootSlamConfig& config,
                                                    Collective* ranks);
  // What Create(config, ranks) checks of a configuration for `ranks` ranks beyond Validate():
  // InvalidArgument naming the field when it cannot run across that many.
  static Status CheckAcrossRanks(const FootSlamConfig& config, int ranks);

  // A prediction of the peak memory, in bytes, of a run of `steps` steps: particle state, two
  // generations of maps, the path histories and a fixed overhead. Calibrated on 2-thread runs of
  // the paper walk at 30,000 to 1,000,000 particles and the bundled walk at 30,000, whose peak
  // RSS it exceeds by 7 to 22 % (engine/footslam/README.md, "Speed and memory"); the naive map
  // assumes about 1.2 new hexagons per step. REQUIRES: config.Validate() is ok.
  static int64_t EstimatePeakBytes(const FootSlamConfig& config, int64_t steps);
  virtual ~FootSlam();

  // Processes one odometry step (dx, dy in the odometry frame, metres) at time t_s.
  // Returns InvalidArgument (engine unchanged) for a value outside grove/input_rules.h's bounds
  // (|t| <= 1e12 s, |dx|, |dy| <= 1e6 m) or a time not after the previous one; OutOfRange when
  // a particle leaves a fixed grid (or the largest a growing one reaches) or a particle's step
  // crosses more than 8 x grid_size hexagons; FailedPrecondition when every weight became zero
  // (the filter degenerated). Every error but InvalidArgument stopped the engine (its message
  // says so): every later step returns FailedPrecondition.
  Status Step(double t_s, double dx_m, double dy_m);

  // Sets a prior map: the cumulative map of an earlier walk through the same area, in this
  // configuration's map frame and hexagon radius (q, r and the counts are read; x_m and y_m are
  // not). Each crossing is then weighted by (C_h^e + a + k P_h^e) / (C_h + 6a + k P_h), P the
  // prior's counters and k = prior_map_confidence: read-only, stored once for every particle, and
  // in checkpoints. Hexagons outside a fixed grid (or the largest a growing one reaches) can never
  // be crossed and are left out. A second call replaces the prior; an empty map removes it.
  // InvalidArgument naming the row for a count that is negative or not finite, or a hexagon
  // given twice (nothing changed then); FailedPrecondition after the first Step().
  Status SetPriorMap(const std::vector<HexCounts>& map);

  // Sets the time stamp of the start pose; the first step must come after it. Without it the
  // start pose takes the first step's time. InvalidArgument for a non-finite time,
  // FailedPrecondition after the first Step().
  Status SetStartTime(double t_s);

  const FootSlamConfig& config() const;
  int64_t steps() const;
  // The current pose of the heaviest particle and the weighted mean pose.
  Pose2 HeaviestPose() const;
  Pose2 MeanPose() const;
  // The heaviest particle's whole path: the start, then one pose per step. The read-outs that
  // build a container return ResourceExhausted when there is no memory for it.
  StatusOr<std::vector<StampedPose>> HeaviestTrajectory() const;
  // The weighted mean pose after each step (the start first).
  const std::vector<StampedPose>& MeanTrajectory() const;
  // The smoothed path, for offline mapping: the pose at every step (the start first) as the
  // weighted mean, under the weights after the last step, of the surviving particles' ancestral
  // poses there: fixed-interval smoothing by the ancestry, which the filtered mean (the mean of
  // each step's own particles, most of which later die) is not. At the last step it is the mean
  // pose (to the history's single precision). Visits each distinct path entry once; each step's
  // distinct poses are weighted in fixed point and summed in the order of their bits, so the
  // same bits at any thread or rank count.
  StatusOr<std::vector<StampedPose>> SmoothedTrajectory() const;
  // Eq. 5-6 of the paper: sum over particles of w_i * C_i, hexagons in key order, plus the
  // stored map (storage of diversity). Visits each distinct map node once.
  StatusOr<std::vector<HexCounts>> CumulativeMap() const;
  // The heaviest particle's own map, plus the stored map.
  StatusOr<std::vector<HexCounts>> HeaviestMap() const;
  // The stored map (store_distance_m): the weighted mean counters of every block folded so
  // far, hexagons in key order; empty when nothing was stored.
  StatusOr<std::vector<HexCounts>> StoredMap() const;
  FootSlamSummary Summary() const;
  // Walks every shared map node and path pose and checks its reference count against its links
  // (and that every live node is reached): Internal naming the broken rule. Slow (the whole
  // state); for tests and debugging.
  Status CheckInvariants() const;

  // Checkpoints

  // The whole state after the last step as the bytes of a checkpoint file (format in
  // tools/io/FORMATS.md, "Checkpoints"): every particle's pose, error states, weight, map and path,
  // with the sharing between particles kept, so the size follows the distinct map nodes.
  // `user_data` is stored as is (the grove command keeps its input position there).
  // FailedPrecondition after an error stopped the engine.
  StatusOr<std::string> Checkpoint(std::string_view user_data = {}) const;

  // An engine continuing from `checkpoint`, made by Checkpoint() under a configuration equal to
  // `config` in every field but threads and batch. Stepping it gives, bit for bit, what the
  // checkpointed engine would have given. `name` (a file name) starts every error message;
  // `user_data` (may be null) receives the stored user data.
  // Errors: InvalidArgument for an invalid `config`; DataLoss for a corrupt or truncated
  // checkpoint (naming the byte offset and the field); FailedPrecondition for a format version
  // this build cannot read or a configuration that differs (naming the field and both values).
  static StatusOr<std::unique_ptr<FootSlam>> Resume(const FootSlamConfig& config,
                                                    std::string_view checkpoint,
                                                    const std::string& name,
                                                    std::string* user_data);
  // Across ranks (collective: every rank calls it with its own file): rank q's share from the
  // checkpoint rank q wrote. FailedPrecondition on every rank when a file is another rank's or
  // of another rank count, or the ranks' files are of different steps; any rank's error reaches
  // every rank (the lowest failing rank's).
  static StatusOr<std::unique_ptr<FootSlam>> Resume(const FootSlamConfig& config,
                                                    std::string_view checkpoint,
                                                    const std::string& name, std::string* user_data,
                                                    Collective* ranks);

  class Impl;

 private:
  explicit FootSlam(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace grove

#endif  // GROVE_FOOTSLAM_H_
