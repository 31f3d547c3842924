/* grove's C API: FootSLAM, landmark FastSLAM and the beacon tracker behind opaque handles, for
 * C and for any language with a C foreign-function interface. C99; the same header compiles as
 * C++.
 *
 *   grove_footslam_config config;
 *   grove_footslam_config_default(&config);
 *   config.particles = 1000;
 *   grove_footslam* slam = NULL;
 *   char error[256];
 *   if (grove_footslam_create(&config, &slam, error, sizeof error) != GROVE_OK) {
 *     fprintf(stderr, "%s\n", error);
 *     return 1;
 *   }
 *   const double t[] = {0.5, 1.0}, dx[] = {0.70, 0.68}, dy[] = {0.00, 0.05};
 *   for (int i = 0; i < 2; ++i) {
 *     if (grove_footslam_step(slam, t[i], dx[i], dy[i]) != GROVE_OK) {
 *       fprintf(stderr, "%s\n", grove_footslam_last_error(slam));
 *     }
 *   }
 *   size_t count = 0;
 *   grove_footslam_cumulative_map(slam, NULL, 0, &count);     // size query
 *   grove_hex_counts* map = malloc(count * sizeof *map);
 *   if (map != NULL) grove_footslam_cumulative_map(slam, map, count, &count);  // fill
 *   free(map);
 *   grove_footslam_destroy(slam);
 *
 * Errors. Every call that can fail returns a grove_status; nothing is written to an output on
 * error unless the call says so. No C++ exception crosses this API and no input, however bad
 * (NULL pointers, out-of-range values, corrupt checkpoints), aborts the process. A call on a
 * handle records its error message in the handle: grove_*_last_error() returns it, "" after a
 * successful call. Calls that make a handle (create, create_json, resume) have no handle to
 * record in: they write the message into the caller's buffer `error` of `error_size` bytes,
 * always NUL-terminated and cut to fit (nothing is written when `error` is NULL or
 * `error_size` is 0; "" on success).
 * A step that fails with GROVE_INVALID_ARGUMENT leaves the engine unchanged. Any other failure
 * of a step (a particle left the grid, the filter degenerated, out of memory) stops the engine,
 * and its message says so: later steps and checkpoints return GROVE_FAILED_PRECONDITION; the
 * read-outs still work. The bounds of every input value are grove/input_rules.h's.
 *
 * Arrays: the size-query rule. Every call that copies a variable number of items into a
 * caller's array (trajectories, maps, landmarks, checkpoint bytes) takes (out, capacity, count):
 *   - out == NULL and capacity == 0: a size query. Returns GROVE_OK and sets *count to the
 *     number of items the fill needs; nothing else is written.
 *   - out != NULL and capacity >= that number: fills out[0 .. *count) and returns GROVE_OK.
 *   - out != NULL and capacity too small: returns GROVE_OUT_OF_RANGE, sets *count to the number
 *     needed and writes nothing into out.
 *   - out == NULL with capacity > 0, or count == NULL: GROVE_INVALID_ARGUMENT.
 * Read-outs that are computed by the call (the heaviest trajectory, the maps, the landmarks,
 * the checkpoint) are kept in the handle from a size query or a too-small fill until the next
 * successful fill of the same read-out, so the fill copies exactly what was sized. Any
 * stepping call in between (step, steps, set_start_time, control, scan; failed or not) drops
 * them: the fill then computes the read-out again, and if it grew past `capacity` returns
 * GROVE_OUT_OF_RANGE with the new size in *count. A successful fill releases the kept copy.
 *
 * Ownership. The caller owns every array and buffer it passes in, and everything copied into
 * them: it stays valid after later steps and after the handle is destroyed. A handle owns the
 * strings its last_error returns (valid until the next call on that handle or its destroy) and
 * the kept read-outs above. grove_version() and grove_status_name() return static strings.
 * A handle is released by its destroy function only (NULL is accepted and ignored).
 *
 * Thread safety. One thread at a time per handle: no two calls on one handle may overlap, not
 * even two read-only getters, nor a getter and a step (the getters update the handle's error
 * message and kept read-outs). Calls on different handles may overlap freely: handles share
 * nothing (each engine owns its worker threads, node pools and random streams). The engine runs
 * its own worker threads inside a step (config.threads). grove_version(),
 * grove_version_numbers(), grove_status_name() and the config_default functions may be called
 * from any thread at any time.
 */
#ifndef GROVE_C_API_H_
#define GROVE_C_API_H_

#include <stddef.h>
#include <stdint.h>

#include "grove/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Status and version */

/* Mirrors grove::StatusCode value for value. */
typedef enum grove_status {
  GROVE_OK = 0,
  GROVE_INVALID_ARGUMENT,    /* a configuration value, an argument or an input record is bad */
  GROVE_NOT_FOUND,           /* something that must exist does not */
  GROVE_OUT_OF_RANGE,        /* a position left the map grid; a caller's array is too small */
  GROVE_FAILED_PRECONDITION, /* not valid in the handle's state (e.g. after a fatal error) */
  GROVE_RESOURCE_EXHAUSTED,  /* out of memory */
  GROVE_DATA_LOSS,           /* a corrupt or truncated checkpoint */
  GROVE_IO_ERROR,            /* the operating system refused a read or a write */
  GROVE_INTERNAL             /* a broken invariant caught without aborting */
} grove_status;

/* "ok", "invalid argument", ...; "unknown" for a value outside the enum. Static string. */
GROVE_EXPORT const char* grove_status_name(grove_status status);

/* One line: "grove 0.3.0 (commit abc1234, GCC 12.2.0, Release; SIMD: ...)". Static string. */
GROVE_EXPORT const char* grove_version(void);
/* The library's version numbers; any pointer may be NULL. */
GROVE_EXPORT void grove_version_numbers(int* major, int* minor, int* patch);

/* Shared value types */

/* A pose in the map frame at time t_s (seconds). */
typedef struct grove_pose {
  double t_s;
  double x_m;
  double y_m;
  double heading_rad;
} grove_pose;

/* A pose's covariance, its upper triangle (x, y in m; heading in rad). */
typedef struct grove_pose_covariance {
  double xx, xy, xh, yy, yh, hh;
} grove_pose_covariance;

/* Memory of one kind of node (map, trajectory), summed over the engine's node pools. */
typedef struct grove_memory_use {
  int64_t live_nodes; /* nodes in use now */
  int64_t live_bytes;
  int64_t peak_live_nodes; /* highest seen (per node pool, summed) */
  int64_t peak_live_bytes;
  int64_t reserved_bytes; /* obtained from the system by the node pools */
} grove_memory_use;

/* What a run asked for, used and cost: every model's part of its summary. Times in seconds. */
typedef struct grove_filter_summary {
  int64_t particles;
  int threads_requested;
  int threads_used;
  int64_t steps; /* filter steps: weighting steps and predict-only steps */
  int64_t resamplings;
  double mean_ess;      /* over the weighting steps */
  double advance_s;     /* propagate, weight and update maps */
  double normalize_s;   /* log-sum-exp and effective sample size */
  double resample_s;    /* drawing parents and gathering the new generation */
  double release_s;     /* freeing the dead generation */
  double bookkeeping_s; /* weighted-mean pose per step */
  double filter_s;      /* the sum of the five phases */
} grove_filter_summary;

/* Resampling schemes (grove::ResamplingScheme). */
enum {
  GROVE_RESAMPLING_SYSTEMATIC = 0,
  GROVE_RESAMPLING_STRATIFIED = 1,
  GROVE_RESAMPLING_RESIDUAL = 2,
  GROVE_RESAMPLING_MULTINOMIAL = 3
};

/* FootSLAM */

typedef struct grove_footslam grove_footslam;

/* grove::FootSlamMapKind and grove::FootSlamWeighting. */
enum { GROVE_FOOTSLAM_MAP_HTREE = 0, GROVE_FOOTSLAM_MAP_NAIVE = 1 };
enum { GROVE_FOOTSLAM_WEIGHTING_PAPER = 0, GROVE_FOOTSLAM_WEIGHTING_PRIOR_RATIO = 1 };
enum { GROVE_FOOTSLAM_GRID_GROWING = 0, GROVE_FOOTSLAM_GRID_FIXED = 1 };

/* Every field of grove::FootSlamConfig (grove/footslam.h gives each one's meaning, unit, range
 * and default; the JSON keys are the field names). Enumerations are ints holding the constants
 * above. Start from grove_footslam_config_default(): a zeroed struct is not a valid config. */
typedef struct grove_footslam_config {
  /* Options that change results. */
  int64_t particles; /* 1..2^31; default 30000 */
  uint64_t seed;     /* default 1 */
  double hex_radius_m;
  double prior_count;
  int weighting; /* GROVE_FOOTSLAM_WEIGHTING_* */
  double start_x_m;
  double start_y_m;
  double start_heading_rad;
  double initial_heading_sigma_rad;
  double heading_drift_sigma_rad;
  double heading_sigma_rad;
  double scale_sigma;
  double scale_drift_sigma;
  double step_length_sigma_m;
  double position_sigma_m;
  int resampling; /* GROVE_RESAMPLING_* */
  double resample_threshold;
  int map; /* GROVE_FOOTSLAM_MAP_* */
  int degree;
  int grid_size;
  int grid;                    /* GROVE_FOOTSLAM_GRID_*; growing by default */
  double prior_map_confidence; /* weight of a prior map's counts; default 1 */
  int alphabet;
  double store_distance_m; /* storage of diversity: store areas this far away; 0 (default): off */
  int islands;             /* island mode: 1 (default) is off */
  int64_t island_exchange_steps;
  double island_exchange_fraction;
  /* Options that change only speed. */
  int threads; /* 0: one per hardware thread */
  int64_t batch;
} grove_footslam_config;

/* One hexagon of a map: axial coordinates, centre (m) and the six edge counters. */
typedef struct grove_hex_counts {
  int32_t q;
  int32_t r;
  double x_m;
  double y_m;
  double counts[6];
} grove_hex_counts;

typedef struct grove_footslam_summary {
  grove_filter_summary filter;
  /* Weighted means over the particles after the last step: the step-length scale error state
   * (1 = the odometry's length) and the heading error state (rad). */
  double mean_scale;
  double mean_heading_error_rad;
  grove_memory_use map_memory;
  grove_memory_use trajectory_memory;
  /* Hexagons per side of the grid the particles' maps reach (grows past grid_size when the
   * grid grows). */
  int64_t grid_size;
  /* Hexagons of the prior map in use, and those outside the grid, left out. */
  int64_t prior_hexagons;
  int64_t prior_hexagons_outside;
  /* Storage of diversity: blocks stored, hexagons of the stored map, seconds spent. */
  int64_t stored_blocks;
  int64_t stored_blocks_exact; /* folds that lost nothing: every particle held the same counts */
  int64_t stored_hexagons;
  double store_s;
} grove_footslam_summary;

/* Writes grove::FootSlamConfig's defaults into *config (nothing when config is NULL). */
GROVE_EXPORT void grove_footslam_config_default(grove_footslam_config* config);
/* Applies the keys of the JSON object `json` (the grove command's --config keys, e.g.
 * {"particles": 500, "map": "naive"}) over *config's current values, then validates the
 * result. Keys not in the text keep their values. On error (syntax, unknown or repeated key,
 * wrong type, value out of range: "config:line:column: ...", or a rule between fields) *config
 * is unchanged and the message goes to `error`. */
GROVE_EXPORT grove_status grove_footslam_config_from_json(const char* json,
                                                          grove_footslam_config* config,
                                                          char* error, size_t error_size);

/* Validates *config and makes an engine in *out (set to NULL on error; nothing built). */
GROVE_EXPORT grove_status grove_footslam_create(const grove_footslam_config* config,
                                                grove_footslam** out, char* error,
                                                size_t error_size);
/* As create, from the defaults with the keys of `json` applied (config_from_json). */
GROVE_EXPORT grove_status grove_footslam_create_json(const char* json, grove_footslam** out,
                                                     char* error, size_t error_size);
/* Releases the engine; NULL is ignored. */
GROVE_EXPORT void grove_footslam_destroy(grove_footslam* slam);
/* The message of the last failed call on `slam`, "" after a success (and for NULL). Owned by
 * the handle; valid until the next call on it. */
GROVE_EXPORT const char* grove_footslam_last_error(const grove_footslam* slam);

/* Processes one odometry step (dx, dy in the odometry frame, metres) at time t_s.
 * GROVE_INVALID_ARGUMENT (engine unchanged) for a value outside grove/input_rules.h's bounds
 * or a time not after the previous one; GROVE_OUT_OF_RANGE when a particle leaves a fixed grid or a
 * step crosses more than 8 x grid_size hexagons; GROVE_FAILED_PRECONDITION when the filter
 * degenerated or an earlier error stopped the engine. */
GROVE_EXPORT grove_status grove_footslam_step(grove_footslam* slam, double t_s, double dx_m,
                                              double dy_m);
/* Steps t_s[i], dx_m[i], dy_m[i] for i = 0 .. n-1 in order, as n calls of step; stops at the
 * first error, whose message starts "steps[i]: ". *done (may be NULL) receives the number of steps
 * taken. The arrays may be NULL only when n == 0. */
GROVE_EXPORT grove_status grove_footslam_steps(grove_footslam* slam, const double* t_s,
                                               const double* dx_m, const double* dy_m, size_t n,
                                               size_t* done);
/* Sets a prior map (grove::FootSlam::SetPriorMap): n hexagons of an earlier walk's cumulative
 * map in this engine's map frame; q, r and the counts are read, x_m and y_m are not. Each
 * crossing's counts gain prior_map_confidence times the prior's. Before the first step; n = 0
 * removes the prior (hexes may then be NULL). GROVE_INVALID_ARGUMENT naming the row for a
 * negative or non-finite count or a hexagon given twice (nothing changed then),
 * GROVE_FAILED_PRECONDITION after the first step. */
GROVE_EXPORT grove_status grove_footslam_set_prior_map(grove_footslam* slam,
                                                       const grove_hex_counts* hexes, size_t n);
/* The time of the start pose; the first step must come after it. GROVE_INVALID_ARGUMENT for a
 * non-finite time, GROVE_FAILED_PRECONDITION after the first step. */
GROVE_EXPORT grove_status grove_footslam_set_start_time(grove_footslam* slam, double t_s);
/* Steps so far. */
GROVE_EXPORT grove_status grove_footslam_step_count(grove_footslam* slam, int64_t* steps);
/* The config the engine runs (as validated at create or resume). */
GROVE_EXPORT grove_status grove_footslam_get_config(grove_footslam* slam,
                                                    grove_footslam_config* config);
/* The weighted mean pose and the heaviest particle's pose after the last step; t_s is the last
 * step's time (the start's before the first step; 0 when no time is known yet). */
GROVE_EXPORT grove_status grove_footslam_mean_pose(grove_footslam* slam, grove_pose* pose);
GROVE_EXPORT grove_status grove_footslam_heaviest_pose(grove_footslam* slam, grove_pose* pose);
/* The weighted mean pose at the start and after every step: step count + 1 poses. Size-query
 * rule (top of the file). */
GROVE_EXPORT grove_status grove_footslam_mean_trajectory(grove_footslam* slam, grove_pose* out,
                                                         size_t capacity, size_t* count);
/* The heaviest particle's whole path: the start, then one pose per step. Size-query rule;
 * computed by the call and kept between a size query and the fill. */
GROVE_EXPORT grove_status grove_footslam_heaviest_trajectory(grove_footslam* slam, grove_pose* out,
                                                             size_t capacity, size_t* count);
/* The smoothed path (grove::FootSlam::SmoothedTrajectory: the weighted mean, under the final
 * weights, of the surviving particles' ancestral poses at every step): the start, then one pose
 * per step. Size-query rule; computed by the call and kept between a size query and the fill. */
GROVE_EXPORT grove_status grove_footslam_smoothed_trajectory(grove_footslam* slam, grove_pose* out,
                                                             size_t capacity, size_t* count);
/* The cumulative map (sum over particles of weight times the particle's counters), the
 * heaviest particle's own map (both plus the stored map) and the stored map of storage of
 * diversity (store_distance_m), hexagons in key order. Size-query rule; computed by the call
 * and kept between a size query and the fill. */
GROVE_EXPORT grove_status grove_footslam_cumulative_map(grove_footslam* slam, grove_hex_counts* out,
                                                        size_t capacity, size_t* count);
GROVE_EXPORT grove_status grove_footslam_heaviest_map(grove_footslam* slam, grove_hex_counts* out,
                                                      size_t capacity, size_t* count);
GROVE_EXPORT grove_status grove_footslam_stored_map(grove_footslam* slam, grove_hex_counts* out,
                                                    size_t capacity, size_t* count);
GROVE_EXPORT grove_status grove_footslam_get_summary(grove_footslam* slam,
                                                     grove_footslam_summary* summary);
/* The whole state after the last step as checkpoint bytes (the grove command's checkpoint
 * file format, with no user data), `size` bytes. Size-query rule, counting bytes: a size query
 * builds the checkpoint and keeps it in the handle for the fill. GROVE_FAILED_PRECONDITION
 * after an error stopped the engine. */
GROVE_EXPORT grove_status grove_footslam_checkpoint(grove_footslam* slam, void* buffer,
                                                    size_t capacity, size_t* size);
/* An engine continuing from the `size` checkpoint bytes at `data` (copied; the caller keeps
 * them), made under a config equal to *config in every field but threads and batch. Stepping
 * it gives, bit for bit, what the checkpointed engine would have given.
 * GROVE_INVALID_ARGUMENT for an invalid config; GROVE_DATA_LOSS for corrupt or truncated
 * bytes; GROVE_FAILED_PRECONDITION for a format this build cannot read or a different config
 * (the message names the field and both values). */
GROVE_EXPORT grove_status grove_footslam_resume(const grove_footslam_config* config,
                                                const void* data, size_t size, grove_footslam** out,
                                                char* error, size_t error_size);

/* Landmark FastSLAM */

typedef struct grove_fastslam grove_fastslam;

/* grove::FastSlamFilter, FastSlamVehicle, FastSlamAssociation, FastSlamGateUnit and
 * FastSlamEvidence. */
enum {
  GROVE_FASTSLAM_FILTER_FASTSLAM1 = 0,
  GROVE_FASTSLAM_FILTER_FASTSLAM2 = 1,
  GROVE_FASTSLAM_FILTER_UNSCENTED = 2,
  GROVE_FASTSLAM_FILTER_SRCD = 3,
  GROVE_FASTSLAM_FILTER_SRCD_AIDED = 4,
  GROVE_FASTSLAM_FILTER_SRCD_PARTICLE = 5,
  GROVE_FASTSLAM_FILTER_DE_SRCD = 6
};
enum { GROVE_FASTSLAM_VEHICLE_BAILEY = 0, GROVE_FASTSLAM_VEHICLE_GUIVANT_NEBOT = 1 };
enum {
  GROVE_FASTSLAM_ASSOCIATION_KNOWN = 0,
  GROVE_FASTSLAM_ASSOCIATION_MAXIMUM_LIKELIHOOD = 1,
  GROVE_FASTSLAM_ASSOCIATION_EXCLUSIVE = 2,
  GROVE_FASTSLAM_ASSOCIATION_SAMPLED = 3,
  GROVE_FASTSLAM_ASSOCIATION_JCBB = 4
};
enum { GROVE_FASTSLAM_GATE_DISTANCE2 = 0, GROVE_FASTSLAM_GATE_PROBABILITY = 1 };
enum { GROVE_FASTSLAM_EVIDENCE_OFF = 0, GROVE_FASTSLAM_EVIDENCE_ON = 1 };

/* Every field of grove::FastSlamConfig (grove/fastslam.h gives each one's meaning, unit, range
 * and default). Start from grove_fastslam_config_default(). */
typedef struct grove_fastslam_config {
  /* Options that change results. */
  int64_t particles;
  uint64_t seed;
  int filter;  /* GROVE_FASTSLAM_FILTER_* */
  int vehicle; /* GROVE_FASTSLAM_VEHICLE_* */
  double wheelbase_m;
  double encoder_offset_m;
  double laser_forward_m;
  double laser_left_m;
  double sigma_speed_mps;
  double sigma_steer_rad;
  double sigma_range_m;
  double sigma_bearing_rad;
  double start_x_m;
  double start_y_m;
  double start_heading_rad;
  int resampling; /* GROVE_RESAMPLING_* */
  double resample_threshold;
  double ut_alpha;
  double ut_beta;
  double ut_kappa;
  double cd_step;
  double de_scale;
  double de_crossover;
  int64_t de_generations;
  int association; /* GROVE_FASTSLAM_ASSOCIATION_* */
  double reject_gate;
  double augment_gate;
  int gate_unit; /* GROVE_FASTSLAM_GATE_* */
  int evidence;  /* GROVE_FASTSLAM_EVIDENCE_* */
  int64_t evidence_threshold;
  double sensor_range_m;
  double sensor_fov_rad;
  double index_cell_m;
  /* Options that change only speed. */
  int threads; /* 0: one per hardware thread */
  int64_t batch;
} grove_fastslam_config;

/* One detection: range (m, >= 0), bearing (rad, in (-pi, pi], counter-clockwise from the
 * heading), the landmark's id (known association: >= 0; unknown: -1 or a truth tag). */
typedef struct grove_landmark_observation {
  double range_m;
  double bearing_rad;
  int64_t id;
} grove_landmark_observation;

/* A landmark of the heaviest particle's map: id (under unknown association its spatial key),
 * mean (m), covariance (m^2), and under unknown association the id of the observation that
 * created it (-1 for none). */
typedef struct grove_landmark_estimate {
  int64_t id;
  double x_m;
  double y_m;
  double sxx;
  double sxy;
  double syy;
  int64_t source_id;
} grove_landmark_estimate;

typedef struct grove_fastslam_summary {
  grove_filter_summary filter;
  int64_t controls;      /* control calls */
  int64_t scans;         /* scan calls */
  int64_t observations;  /* detections over all scans */
  int64_t predict_steps; /* filter steps that only predicted */
  int64_t landmarks;     /* in the heaviest particle's map */
  /* Unknown association along the heaviest particle's ancestry (grove::AssociationCounts). */
  int64_t associated, created, ignored, removed, dropped, tagged, wrong, truncated;
  /* Differential evolution (DE_SRCD): trial poses and those accepted. */
  int64_t evolution_trials, evolution_accepted;
  grove_memory_use map_memory;
  grove_memory_use trajectory_memory;
} grove_fastslam_summary;

GROVE_EXPORT void grove_fastslam_config_default(grove_fastslam_config* config);
/* As grove_footslam_config_from_json, with grove::FastSlamConfigFields()' keys
 * ({"filter": "fastslam1", "association": "ml", ...}). */
GROVE_EXPORT grove_status grove_fastslam_config_from_json(const char* json,
                                                          grove_fastslam_config* config,
                                                          char* error, size_t error_size);
GROVE_EXPORT grove_status grove_fastslam_create(const grove_fastslam_config* config,
                                                grove_fastslam** out, char* error,
                                                size_t error_size);
GROVE_EXPORT grove_status grove_fastslam_create_json(const char* json, grove_fastslam** out,
                                                     char* error, size_t error_size);
GROVE_EXPORT void grove_fastslam_destroy(grove_fastslam* slam);
GROVE_EXPORT const char* grove_fastslam_last_error(const grove_fastslam* slam);

/* A control (speed m/s, steering angle rad) from t_s on: predicts from the last time to t_s
 * with the control held so far (the first control sets the start time), then holds this one.
 * GROVE_INVALID_ARGUMENT, engine unchanged, for a value outside grove/input_rules.h's bounds
 * or a time not after the previous control's or before the last scan's. The prediction runs
 * with the next scan or read-out, all the controls' predictions since the last scan in one
 * pass (grove/fastslam.h, FastSlam::Control()): an error inside it is returned there, or after
 * a read-out that returns no status by the next call that returns one. */
GROVE_EXPORT grove_status grove_fastslam_control(grove_fastslam* slam, double t_s, double speed_mps,
                                                 double steer_rad);
/* A scan at t_s: predicts to t_s with the held control, then updates with the n observations
 * (obs may be NULL only when n == 0; copied, the caller keeps them). GROVE_INVALID_ARGUMENT,
 * engine unchanged, before the first control, for a time outside the bounds, before the last
 * or equal to the previous scan's, or an observation outside the bounds (named by its index);
 * GROVE_FAILED_PRECONDITION when the filter degenerated or an earlier error stopped the engine. */
GROVE_EXPORT grove_status grove_fastslam_scan(grove_fastslam* slam, double t_s,
                                              const grove_landmark_observation* obs, size_t n);
/* Filter steps so far: one per prediction and one per scan update. */
GROVE_EXPORT grove_status grove_fastslam_step_count(grove_fastslam* slam, int64_t* steps);
GROVE_EXPORT grove_status grove_fastslam_get_config(grove_fastslam* slam,
                                                    grove_fastslam_config* config);
/* Poses after the last step; t_s as for FootSLAM. */
GROVE_EXPORT grove_status grove_fastslam_mean_pose(grove_fastslam* slam, grove_pose* pose);
GROVE_EXPORT grove_status grove_fastslam_heaviest_pose(grove_fastslam* slam, grove_pose* pose);
/* The weighted covariance of the particles' poses about their mean after the last step. */
GROVE_EXPORT grove_status grove_fastslam_pose_covariance(grove_fastslam* slam,
                                                         grove_pose_covariance* covariance);
/* The weighted mean pose at the start, after every scan and after every control but the first;
 * the heaviest particle's path at the same times. Not step count + 1 poses: a scan's own
 * prediction adds none. Size-query rule. */
GROVE_EXPORT grove_status grove_fastslam_mean_trajectory(grove_fastslam* slam, grove_pose* out,
                                                         size_t capacity, size_t* count);
GROVE_EXPORT grove_status grove_fastslam_heaviest_trajectory(grove_fastslam* slam, grove_pose* out,
                                                             size_t capacity, size_t* count);
/* The heaviest particle's landmarks in id order. Size-query rule. */
GROVE_EXPORT grove_status grove_fastslam_landmarks(grove_fastslam* slam,
                                                   grove_landmark_estimate* out, size_t capacity,
                                                   size_t* count);
GROVE_EXPORT grove_status grove_fastslam_get_summary(grove_fastslam* slam,
                                                     grove_fastslam_summary* summary);
/* As grove_footslam_checkpoint and grove_footslam_resume. */
GROVE_EXPORT grove_status grove_fastslam_checkpoint(grove_fastslam* slam, void* buffer,
                                                    size_t capacity, size_t* size);
GROVE_EXPORT grove_status grove_fastslam_resume(const grove_fastslam_config* config,
                                                const void* data, size_t size, grove_fastslam** out,
                                                char* error, size_t error_size);

/* Range-only beacon tracking (grove/tracking.h) */

typedef struct grove_tracker grove_tracker;

/* Every field of grove::TrackerConfig (grove/tracking.h gives each one's meaning, unit, range and
 * default). Start from grove_tracker_config_default(). */
typedef struct grove_tracker_config {
  /* Options that change results. */
  int64_t particles;
  uint64_t seed;
  double start_x_m;
  double start_y_m;
  double start_vx_mps;
  double start_vy_mps;
  double initial_position_sigma_m;
  double initial_velocity_sigma_mps;
  double acceleration_sigma_mps2;
  double range_sigma_m;
  int resampling; /* GROVE_RESAMPLING_* */
  double resample_threshold;
  /* Options that change only speed. */
  int threads; /* 0: one per hardware thread */
  int64_t batch;
} grove_tracker_config;

/* One range: the beacon's position (m) and the measured distance to it (m, >= 0). */
typedef struct grove_range_measurement {
  double beacon_x_m;
  double beacon_y_m;
  double range_m;
} grove_range_measurement;

/* The target's weighted mean position (m) and velocity (m/s) at time t_s. */
typedef struct grove_target_state {
  double t_s;
  double x_m;
  double y_m;
  double vx_mps;
  double vy_mps;
} grove_target_state;

typedef struct grove_tracker_summary {
  grove_filter_summary filter;
  int64_t measurements; /* ranges over all updates */
} grove_tracker_summary;

/* The calls every model has, declared for the model whose handle is `prefix` and whose
 * configuration and summary are prefix##_config and prefix##_summary: config_default,
 * config_from_json, create, create_json, destroy, last_error, step_count, get_config,
 * mean_pose, heaviest_pose, mean_trajectory, get_summary, checkpoint and resume, each as
 * grove_footslam's (which documents them). */
#define GROVE_C_MODEL_API(prefix)                                                                 \
  GROVE_EXPORT void prefix##_config_default(prefix##_config* config);                             \
  GROVE_EXPORT grove_status prefix##_config_from_json(const char* json, prefix##_config* config,  \
                                                      char* error, size_t error_size);            \
  GROVE_EXPORT grove_status prefix##_create(const prefix##_config* config, prefix** out,          \
                                            char* error, size_t error_size);                      \
  GROVE_EXPORT grove_status prefix##_create_json(const char* json, prefix** out, char* error,     \
                                                 size_t error_size);                              \
  GROVE_EXPORT void prefix##_destroy(prefix* h);                                                  \
  GROVE_EXPORT const char* prefix##_last_error(const prefix* h);                                  \
  GROVE_EXPORT grove_status prefix##_step_count(prefix* h, int64_t* steps);                       \
  GROVE_EXPORT grove_status prefix##_get_config(prefix* h, prefix##_config* config);              \
  GROVE_EXPORT grove_status prefix##_mean_pose(prefix* h, grove_pose* pose);                      \
  GROVE_EXPORT grove_status prefix##_heaviest_pose(prefix* h, grove_pose* pose);                  \
  GROVE_EXPORT grove_status prefix##_mean_trajectory(prefix* h, grove_pose* out, size_t capacity, \
                                                     size_t* count);                              \
  GROVE_EXPORT grove_status prefix##_get_summary(prefix* h, prefix##_summary* summary);           \
  GROVE_EXPORT grove_status prefix##_checkpoint(prefix* h, void* buffer, size_t capacity,         \
                                                size_t* size);                                    \
  GROVE_EXPORT grove_status prefix##_resume(const prefix##_config* config, const void* data,      \
                                            size_t size, prefix** out, char* error,               \
                                            size_t error_size);

/* grove_tracker_config_default ... grove_tracker_resume. The poses' heading is the direction of
 * motion; step_count counts updates. */
GROVE_C_MODEL_API(grove_tracker)

/* Moves every particle to t_s, then weights it by the n ranges (z may be NULL only when n == 0;
 * copied). GROVE_INVALID_ARGUMENT, tracker unchanged, for a time not finite or not after the
 * previous one, or a range not finite or negative (named by its index);
 * GROVE_FAILED_PRECONDITION when the filter degenerated or an earlier error stopped it. */
GROVE_EXPORT grove_status grove_tracker_update(grove_tracker* tracker, double t_s,
                                               const grove_range_measurement* z, size_t n);
/* The time of the prior, before the first update (grove_footslam_set_start_time's rules). */
GROVE_EXPORT grove_status grove_tracker_set_start_time(grove_tracker* tracker, double t_s);
/* The weighted mean position and velocity after the last update. */
GROVE_EXPORT grove_status grove_tracker_mean_state(grove_tracker* tracker,
                                                   grove_target_state* state);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* GROVE_C_API_H_ */
