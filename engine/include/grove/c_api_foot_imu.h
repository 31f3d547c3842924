/* grove's C API for the foot IMU front end (grove/foot_imu.h): a foot-mounted IMU's samples to
 * the steps FootSLAM walks on. C99; the same header compiles as C++. Errors, ownership,
 * threads and the size-query rule of arrays are those of grove/c_api.h.
 *
 *   grove_foot_imu_config config;
 *   grove_foot_imu_config_default(&config);
 *   grove_foot_imu* imu = NULL;
 *   char error[256];
 *   if (grove_foot_imu_create(&config, &imu, error, sizeof error) != GROVE_OK) return 1;
 *   for (int k = 0; k < 400; ++k) {  // 2 s of a still, level sensor
 *     const grove_imu_sample s = {0.005 * k, {0.0, 0.0, 9.80665}, {0.0, 0.0, 0.0}};
 *     if (grove_foot_imu_add_sample(imu, &s) != GROVE_OK) {
 *       grove_foot_imu_destroy(imu);
 *       return 1;
 *     }
 *   }
 *   grove_foot_imu_finish(imu);
 *   size_t count = 0;
 *   grove_foot_imu_take_steps(imu, NULL, 0, &count);  // size query: 0 steps here
 *   grove_foot_step* steps = malloc((count + 1) * sizeof *steps);
 *   if (steps != NULL) grove_foot_imu_take_steps(imu, steps, count + 1, &count);  // fill
 *   free(steps);
 *   grove_foot_imu_destroy(imu);
 *
 * Steps. Every finished step is kept in the handle until a successful fill of
 * grove_foot_imu_take_steps hands it out (a size query or a too-small fill keeps them); the
 * fill then holds every step finished so far, oldest first.
 */
#ifndef GROVE_C_API_FOOT_IMU_H_
#define GROVE_C_API_FOOT_IMU_H_

#include <stddef.h>
#include <stdint.h>

#include "grove/c_api.h"
#include "grove/export.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct grove_foot_imu grove_foot_imu;

/* grove::ZeroVelocityDetector. */
enum {
  GROVE_DETECTOR_SHOE = 0,
  GROVE_DETECTOR_ARE = 1,
  GROVE_DETECTOR_MV = 2,
  GROVE_DETECTOR_MAG = 3
};

/* Every field of grove::FootImuConfig (grove/foot_imu.h gives each one's meaning, unit, range
 * and default; the JSON keys are the field names). Start from grove_foot_imu_config_default():
 * a zeroed struct is not a valid config. */
typedef struct grove_foot_imu_config {
  int detector; /* GROVE_DETECTOR_* */
  int detector_window;
  double detector_threshold; /* 0: the detector's default */
  double detector_accel_sigma_mps2;
  double detector_gyro_sigma_radps;
  int stance_gap_samples;
  int min_stance_samples;
  double min_step_m;
  double accel_noise_mps2_per_sqrt_hz;
  double gyro_noise_radps_per_sqrt_hz;
  double accel_bias_walk_mps3_per_sqrt_hz;
  double gyro_bias_walk_radps2_per_sqrt_hz;
  double zupt_sigma_mps;
  double zaru_sigma_radps; /* 0: no zero-angular-rate updates */
  double alignment_s;
  double alignment_heading_rad;
  double alignment_tilt_sigma_rad;
  double alignment_heading_sigma_rad;
  double initial_accel_bias_sigma_mps2;
  double initial_gyro_bias_sigma_radps;
  double gravity_mps2; /* 0: normal gravity at latitude_deg and height_m */
  double latitude_deg;
  double height_m;
  double accel_range_mps2;
  double gyro_range_radps;
  double max_sample_interval_s;
} grove_foot_imu_config;

/* One sample: time (s), specific force (m/s^2) and angular rate (rad/s) in the sensor frame. */
typedef struct grove_imu_sample {
  double t_s;
  double accel_mps2[3];
  double gyro_radps[3];
} grove_imu_sample;

/* One step (grove::FootStep): odometry frame, metres and radians. */
typedef struct grove_foot_step {
  double t_s; /* the middle of the stance that ends the step */
  double dx_m;
  double dy_m;
  double dz_m;
  double dheading_rad;
  grove_pose_covariance covariance; /* of (dx, dy, dheading) */
  double stance_begin_s;
  double stance_end_s;
  int64_t stance_end_sample;
} grove_foot_step;

/* The navigation state after the last processed sample (grove::FootImuState). */
typedef struct grove_foot_imu_state {
  double t_s;
  double position_m[3];
  double velocity_mps[3];
  double roll_rad;
  double pitch_rad;
  double heading_rad;
  double accel_bias_mps2[3];
  double gyro_bias_radps[3];
  int still; /* 1 when the detector found the sample still */
} grove_foot_imu_state;

/* grove::FootImuSummary. */
typedef struct grove_foot_imu_summary {
  int64_t samples;
  int64_t processed_samples;
  int64_t still_samples;
  int64_t stances;
  int64_t steps;
  int aligned;
  double alignment_t_s;
  int has_origin;
  double origin_t_s; /* the odometry's start time, once has_origin */
  double gravity_mps2;
  double distance_m;
  double seconds;
} grove_foot_imu_summary;

/* Writes grove::FootImuConfig's defaults into *config (nothing when config is NULL). */
GROVE_EXPORT void grove_foot_imu_config_default(grove_foot_imu_config* config);
/* Applies the keys of the JSON object `json` (e.g. {"detector": "are"}) over *config, then
 * validates it; on error *config is unchanged and the message goes to `error`. */
GROVE_EXPORT grove_status grove_foot_imu_config_from_json(const char* json,
                                                          grove_foot_imu_config* config,
                                                          char* error, size_t error_size);
/* Validates *config and makes an engine in *out (set to NULL on error; nothing built). */
GROVE_EXPORT grove_status grove_foot_imu_create(const grove_foot_imu_config* config,
                                                grove_foot_imu** out, char* error,
                                                size_t error_size);
/* The same from a JSON object of configuration keys over the defaults. */
GROVE_EXPORT grove_status grove_foot_imu_create_json(const char* json, grove_foot_imu** out,
                                                     char* error, size_t error_size);
GROVE_EXPORT void grove_foot_imu_destroy(grove_foot_imu* imu);
/* The message of the last failed call on `imu`, "" after a successful one. */
GROVE_EXPORT const char* grove_foot_imu_last_error(const grove_foot_imu* imu);

/* grove::FootImu::AddSample: GROVE_INVALID_ARGUMENT (engine unchanged) for a bad sample,
 * GROVE_FAILED_PRECONDITION after finish. */
GROVE_EXPORT grove_status grove_foot_imu_add_sample(grove_foot_imu* imu,
                                                    const grove_imu_sample* sample);
/* Adds samples[0 .. n) in order, stopping at the first error; *added (may be NULL) counts the
 * samples taken. */
GROVE_EXPORT grove_status grove_foot_imu_add_samples(grove_foot_imu* imu,
                                                     const grove_imu_sample* samples, size_t n,
                                                     size_t* added);
/* grove::FootImu::Finish: the end of the recording. */
GROVE_EXPORT grove_status grove_foot_imu_finish(grove_foot_imu* imu);
/* The steps finished and not yet handed out, under the size-query rule (see above). */
GROVE_EXPORT grove_status grove_foot_imu_take_steps(grove_foot_imu* imu, grove_foot_step* out,
                                                    size_t capacity, size_t* count);
GROVE_EXPORT grove_status grove_foot_imu_get_state(grove_foot_imu* imu, grove_foot_imu_state* out);
GROVE_EXPORT grove_status grove_foot_imu_get_summary(grove_foot_imu* imu,
                                                     grove_foot_imu_summary* out);

#ifdef __cplusplus
}
#endif

#endif /* GROVE_C_API_FOOT_IMU_H_ */
