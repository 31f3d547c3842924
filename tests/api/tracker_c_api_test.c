/* The beacon tracker's C entry points from C: the calls every model has on a third model
 * (configuration from defaults and JSON, create, the size-query rule, summary, checkpoint and
 * resume) and its own (update, set_start_time, mean_state), with their error paths. Built as
 * C99 with -Wall -Werror -pedantic against libgrove.so. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "grove/c_api.h"
#include "tests/api/c_check.h"

#define CHECK_TRACKER(h, call, expected) \
  CHECK_STATUS_MSG(call, expected, grove_tracker_last_error(h))

enum { kUpdates = 40, kBeacons = 3 };

/* The target at update k (t = k s): moving at (0.6, 0.3) m/s from (1, -2). */
static void TargetAt(int k, double* x, double* y) {
  *x = 1 + 0.6 * k;
  *y = -2 + 0.3 * k;
}

/* Exact ranges from the target at update k to three beacons. */
static void RangesAt(int k, grove_range_measurement* z) {
  static const double beacons[kBeacons][2] = {{-30, -30}, {30, -30}, {0, 30}};
  double x, y;
  int b;
  TargetAt(k, &x, &y);
  for (b = 0; b < kBeacons; ++b) {
    z[b].beacon_x_m = beacons[b][0];
    z[b].beacon_y_m = beacons[b][1];
    z[b].range_m = hypot(x - beacons[b][0], y - beacons[b][1]);
  }
}

static void Feed(grove_tracker* h, int from, int to) {
  grove_range_measurement z[kBeacons];
  int k;
  for (k = from; k < to; ++k) {
    RangesAt(k, z);
    CHECK_TRACKER(h, grove_tracker_update(h, k, z, kBeacons), GROVE_OK);
  }
}

static void TestConfiguration(void) {
  grove_tracker_config config, back;
  grove_tracker* h = NULL;
  char error[256];
  grove_tracker_config_default(&config);
  CHECK(config.particles == 2000 && config.seed == 1 && config.range_sigma_m == 0.5);
  CHECK(config.resampling == GROVE_RESAMPLING_SYSTEMATIC && config.resample_threshold == 0.5);
  CHECK_STATUS(grove_tracker_config_from_json("{\"particles\": 300, \"range_sigma_m\": 0.2}",
                                              &config, error, sizeof error),
               GROVE_OK);
  CHECK(config.particles == 300 && config.range_sigma_m == 0.2 && config.seed == 1);
  CHECK_STATUS(grove_tracker_config_from_json("{\"range_sigma\": 1}", &config, error, sizeof error),
               GROVE_INVALID_ARGUMENT);
  CHECK(Contains(error, "range_sigma_m")); /* the nearest key */
  config.acceleration_sigma_mps2 = -1;
  CHECK_STATUS(grove_tracker_create(&config, &h, error, sizeof error), GROVE_INVALID_ARGUMENT);
  CHECK(h == NULL && Contains(error, "acceleration_sigma_mps2 = -1"));
  config.acceleration_sigma_mps2 = 0.25;
  config.threads = 1;
  CHECK_STATUS(grove_tracker_create(&config, &h, error, sizeof error), GROVE_OK);
  CHECK_TRACKER(h, grove_tracker_get_config(h, &back), GROVE_OK);
  CHECK(back.particles == 300 && back.acceleration_sigma_mps2 == 0.25 && back.threads == 1);
  grove_tracker_destroy(h);
  grove_tracker_destroy(NULL);
  CHECK(strcmp(grove_tracker_last_error(NULL), "") == 0);
}

static void TestRunAndReadOuts(void) {
  grove_tracker_config config;
  grove_tracker* h = NULL;
  grove_target_state state;
  grove_tracker_summary summary;
  grove_pose pose;
  grove_pose* path;
  grove_range_measurement z[kBeacons];
  double x, y;
  size_t count = 0;
  int64_t steps = 0;
  char error[256];
  grove_tracker_config_default(&config);
  config.particles = 2000;
  config.initial_position_sigma_m = 5;
  CHECK_STATUS(grove_tracker_create(&config, &h, error, sizeof error), GROVE_OK);
  CHECK_TRACKER(h, grove_tracker_set_start_time(h, 0), GROVE_OK);
  Feed(h, 1, kUpdates);

  /* A refused update changes nothing; a NULL array with ranges is refused. */
  RangesAt(kUpdates, z);
  z[1].range_m = -3;
  CHECK_TRACKER(h, grove_tracker_update(h, kUpdates, z, kBeacons), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(grove_tracker_last_error(h), "measurement 1"));
  CHECK_TRACKER(h, grove_tracker_update(h, kUpdates, NULL, 2), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(grove_tracker_last_error(h), "z is NULL"));
  CHECK_TRACKER(h, grove_tracker_step_count(h, &steps), GROVE_OK);
  CHECK(steps == kUpdates - 1);
  CHECK(strcmp(grove_tracker_last_error(h), "") == 0);

  CHECK_TRACKER(h, grove_tracker_mean_state(h, &state), GROVE_OK);
  TargetAt(kUpdates - 1, &x, &y);
  CHECK(state.t_s == kUpdates - 1);
  CHECK(fabs(state.x_m - x) < 0.5 && fabs(state.y_m - y) < 0.5);
  CHECK(fabs(state.vx_mps - 0.6) < 0.3 && fabs(state.vy_mps - 0.3) < 0.3);
  CHECK_TRACKER(h, grove_tracker_mean_state(h, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_TRACKER(h, grove_tracker_heaviest_pose(h, &pose), GROVE_OK);
  CHECK(fabs(pose.x_m - x) < 1 && fabs(pose.heading_rad - atan2(0.3, 0.6)) < 0.5);

  /* The size-query rule. */
  CHECK_TRACKER(h, grove_tracker_mean_trajectory(h, NULL, 0, &count), GROVE_OK);
  CHECK(count == (size_t)kUpdates); /* the prior, then every update */
  path = malloc(count * sizeof *path);
  CHECK(path != NULL);
  CHECK_TRACKER(h, grove_tracker_mean_trajectory(h, path, count - 1, &count), GROVE_OUT_OF_RANGE);
  CHECK_TRACKER(h, grove_tracker_mean_trajectory(h, path, count, &count), GROVE_OK);
  CHECK(path[0].t_s == 0 && path[count - 1].t_s == kUpdates - 1);
  free(path);

  CHECK_TRACKER(h, grove_tracker_get_summary(h, &summary), GROVE_OK);
  CHECK(summary.measurements == (kUpdates - 1) * kBeacons);
  CHECK(summary.filter.particles == 2000 && summary.filter.steps == kUpdates - 1);
  grove_tracker_destroy(h);
}

/* A checkpoint after half the updates, resumed, gives the bits of the whole run. */
static void TestCheckpointAndResume(void) {
  grove_tracker_config config;
  grove_tracker *whole = NULL, *half = NULL, *resumed = NULL;
  grove_target_state a, b;
  char error[256];
  size_t size = 0;
  void* bytes;
  grove_tracker_config_default(&config);
  config.particles = 500;
  CHECK_STATUS(grove_tracker_create(&config, &whole, error, sizeof error), GROVE_OK);
  CHECK_STATUS(grove_tracker_create_json("{\"particles\": 500}", &half, error, sizeof error),
               GROVE_OK);
  Feed(whole, 1, kUpdates);
  Feed(half, 1, kUpdates / 2);
  CHECK_TRACKER(half, grove_tracker_checkpoint(half, NULL, 0, &size), GROVE_OK);
  bytes = malloc(size);
  CHECK(bytes != NULL);
  CHECK_TRACKER(half, grove_tracker_checkpoint(half, bytes, size, &size), GROVE_OK);
  config.threads = 2; /* may differ */
  CHECK_STATUS(grove_tracker_resume(&config, bytes, size, &resumed, error, sizeof error), GROVE_OK);
  Feed(resumed, kUpdates / 2, kUpdates);
  CHECK_TRACKER(whole, grove_tracker_mean_state(whole, &a), GROVE_OK);
  CHECK_TRACKER(resumed, grove_tracker_mean_state(resumed, &b), GROVE_OK);
  CHECK(memcmp(&a, &b, sizeof a) == 0);
  config.seed = 9;
  grove_tracker_destroy(resumed);
  CHECK_STATUS(grove_tracker_resume(&config, bytes, size, &resumed, error, sizeof error),
               GROVE_FAILED_PRECONDITION);
  CHECK(resumed == NULL && Contains(error, "seed = 1"));
  free(bytes);
  grove_tracker_destroy(whole);
  grove_tracker_destroy(half);
}

int main(void) {
  TestConfiguration();
  TestRunAndReadOuts();
  TestCheckpointAndResume();
  printf("tracker C API test passed\n");
  return 0;
}
