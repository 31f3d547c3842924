/* The foot IMU front end's C API from C (grove/c_api_foot_imu.h): every call and error path, and
 * a synthetic walk whose steps are known. Built as C99 with -Wall -Werror -pedantic against
 * libgrove.so; the checks cannot be compiled out. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "grove/c_api_foot_imu.h"
#include "tests/api/c_checks.h"

#define CHECK_STATUS(call, expected, message) CHECK_STATUS_MSG(call, expected, message)
#define CHECK_IMU(h, call, expected) CHECK_STATUS(call, expected, grove_foot_imu_last_error(h))

enum { kRateHz = 200, kSteps = 6 };
static const double kGravity = 9.80665;
static const double kStepM = 0.7;
static const double kSwingS = 0.5;
static const double kStanceS = 0.6;
static const double kRollRad = 0.5;
static const double kPi = 3.14159265358979323846;

static int Contains(const char* text, const char* part) { return strstr(text, part) != NULL; }

/* A sensor walking along x: stances, then swings whose position follows a minimum-jerk profile
 * over kStepM while the sensor rolls about its x axis by kRollRad sin^2(pi u) and back (a foot
 * that never turns is still to SHOE at mid-swing, where its acceleration passes zero). With the
 * roll phi, the specific force in the sensor frame is (x'', g sin phi, g cos phi). */
static size_t MakeWalk(grove_imu_sample* out, size_t capacity) {
  const int stance = (int)(kStanceS * kRateHz), swing = (int)(kSwingS * kRateHz);
  size_t n = 0;
  int step, k;
  for (step = 0; step <= kSteps; ++step) {
    const int moving = step < kSteps;
    for (k = 0; k < stance + (moving ? swing : 0); ++k) {
      grove_imu_sample s;
      double ax = 0, roll = 0, roll_rate = 0;
      memset(&s, 0, sizeof s);
      if (k >= stance) {
        const double u = (double)(k - stance) / swing;
        ax = kStepM / (kSwingS * kSwingS) * (60 * u - 180 * u * u + 120 * u * u * u);
        roll = kRollRad * sin(kPi * u) * sin(kPi * u);
        roll_rate = kRollRad * kPi / kSwingS * sin(2 * kPi * u);
      }
      CHECK(n < capacity);
      s.t_s = (double)n / kRateHz;
      s.accel_mps2[0] = ax;
      s.accel_mps2[1] = kGravity * sin(roll);
      s.accel_mps2[2] = kGravity * cos(roll);
      s.gyro_radps[0] = roll_rate;
      out[n++] = s;
    }
  }
  return n;
}

static grove_foot_imu* NewImu(void) {
  grove_foot_imu_config c;
  grove_foot_imu* h = NULL;
  char error[512];
  grove_foot_imu_config_default(&c);
  c.gravity_mps2 = kGravity;
  CHECK_STATUS(grove_foot_imu_create(&c, &h, error, sizeof error), GROVE_OK, error);
  CHECK(h != NULL);
  CHECK(error[0] == '\0');
  return h;
}

static void TestConfig(void) {
  grove_foot_imu_config c, before;
  grove_foot_imu* h = (grove_foot_imu*)&c; /* must be set to NULL on error */
  char error[512];
  grove_foot_imu_config_default(&c);
  CHECK(c.detector == GROVE_DETECTOR_SHOE);
  CHECK(c.detector_window == 5);
  CHECK(c.zupt_sigma_mps == 0.01);
  grove_foot_imu_config_default(NULL); /* does nothing */

  CHECK_STATUS(grove_foot_imu_config_from_json("{\"detector\": \"are\", \"detector_window\": 9}",
                                               &c, error, sizeof error),
               GROVE_OK, error);
  CHECK(c.detector == GROVE_DETECTOR_ARE);
  CHECK(c.detector_window == 9);
  before = c;
  CHECK_STATUS(grove_foot_imu_config_from_json("{\"detector_windwo\": 3}", &c, error, sizeof error),
               GROVE_INVALID_ARGUMENT, "an unknown key");
  CHECK(Contains(error, "detector_window")); /* the nearest key is suggested */
  CHECK(memcmp(&c, &before, sizeof c) == 0);
  CHECK_STATUS(grove_foot_imu_config_from_json(NULL, &c, error, sizeof error),
               GROVE_INVALID_ARGUMENT, "NULL json");
  CHECK_STATUS(grove_foot_imu_config_from_json("{}", NULL, error, sizeof error),
               GROVE_INVALID_ARGUMENT, "NULL config");

  c.detector_window = 0;
  CHECK_STATUS(grove_foot_imu_create(&c, &h, error, sizeof error), GROVE_INVALID_ARGUMENT,
               "window 0");
  CHECK(h == NULL);
  CHECK(Contains(error, "detector_window"));
  c.detector_window = 5;
  c.detector = 17;
  CHECK_STATUS(grove_foot_imu_create(&c, &h, error, sizeof error), GROVE_INVALID_ARGUMENT,
               "detector 17");
  CHECK(Contains(error, "detector"));
  CHECK_STATUS(grove_foot_imu_create(NULL, &h, error, sizeof error), GROVE_INVALID_ARGUMENT,
               "NULL config");
  CHECK_STATUS(grove_foot_imu_create(&c, NULL, error, sizeof error), GROVE_INVALID_ARGUMENT,
               "NULL out");
  CHECK_STATUS(grove_foot_imu_create_json("{\"zupt_sigma_mps\": -1}", &h, error, sizeof error),
               GROVE_INVALID_ARGUMENT, "a negative sigma");
  CHECK(Contains(error, "zupt_sigma_mps"));
  CHECK(h == NULL);
  CHECK_STATUS(grove_foot_imu_create_json("{\"detector\": \"mv\"}", &h, error, sizeof error),
               GROVE_OK, error);
  grove_foot_imu_destroy(h);
  grove_foot_imu_destroy(NULL);
}

static void TestNullHandle(void) {
  grove_imu_sample s;
  size_t count = 0;
  memset(&s, 0, sizeof s);
  CHECK(grove_foot_imu_add_sample(NULL, &s) == GROVE_INVALID_ARGUMENT);
  CHECK(grove_foot_imu_add_samples(NULL, &s, 1, &count) == GROVE_INVALID_ARGUMENT);
  CHECK(grove_foot_imu_finish(NULL) == GROVE_INVALID_ARGUMENT);
  CHECK(grove_foot_imu_take_steps(NULL, NULL, 0, &count) == GROVE_INVALID_ARGUMENT);
  CHECK(strcmp(grove_foot_imu_last_error(NULL), "") == 0);
}

static void TestBadSamples(void) {
  grove_foot_imu* h = NewImu();
  grove_imu_sample s;
  grove_foot_imu_summary summary;
  memset(&s, 0, sizeof s);
  s.accel_mps2[2] = kGravity;
  s.t_s = 1.0;
  CHECK_IMU(h, grove_foot_imu_add_sample(h, &s), GROVE_OK);
  s.t_s = 1.0; /* not after the previous sample */
  CHECK_IMU(h, grove_foot_imu_add_sample(h, &s), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(grove_foot_imu_last_error(h), "not after the previous sample"));
  s.t_s = 1.005;
  s.gyro_radps[1] = NAN;
  CHECK_IMU(h, grove_foot_imu_add_sample(h, &s), GROVE_INVALID_ARGUMENT);
  s.gyro_radps[1] = 0;
  s.accel_mps2[0] = 1000; /* beyond the 16 g range: saturated */
  CHECK_IMU(h, grove_foot_imu_add_sample(h, &s), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(grove_foot_imu_last_error(h), "satur"));
  s.accel_mps2[0] = 0;
  s.t_s = 2.0; /* a gap longer than max_sample_interval_s */
  CHECK_IMU(h, grove_foot_imu_add_sample(h, &s), GROVE_INVALID_ARGUMENT);
  CHECK_IMU(h, grove_foot_imu_add_sample(h, NULL), GROVE_INVALID_ARGUMENT);
  /* The engine is unchanged: one sample, and the next good one is taken. */
  CHECK_IMU(h, grove_foot_imu_get_summary(h, &summary), GROVE_OK);
  CHECK(summary.samples == 1);
  s.t_s = 1.005;
  CHECK_IMU(h, grove_foot_imu_add_sample(h, &s), GROVE_OK);
  CHECK(strcmp(grove_foot_imu_last_error(h), "") == 0);
  CHECK_IMU(h, grove_foot_imu_add_samples(h, NULL, 3, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_IMU(h, grove_foot_imu_finish(h), GROVE_OK);
  s.t_s = 1.010;
  CHECK_IMU(h, grove_foot_imu_add_sample(h, &s), GROVE_FAILED_PRECONDITION);
  CHECK_IMU(h, grove_foot_imu_finish(h), GROVE_OK); /* a second finish does nothing */
  CHECK_IMU(h, grove_foot_imu_get_state(h, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_IMU(h, grove_foot_imu_get_summary(h, NULL), GROVE_INVALID_ARGUMENT);
  grove_foot_imu_destroy(h);
}

static void TestWalk(void) {
  const size_t capacity = (size_t)((kSteps + 1) * (kStanceS + kSwingS) * kRateHz) + 10;
  grove_imu_sample* samples = malloc(capacity * sizeof *samples);
  grove_foot_step steps[kSteps + 1];
  grove_foot_step one;
  grove_foot_imu_summary summary;
  grove_foot_imu_state state;
  grove_foot_imu* h = NewImu();
  size_t n, added = 0, count = 0, taken = 0, i;
  CHECK(samples != NULL);
  n = MakeWalk(samples, capacity);
  /* Half the walk, then the steps so far; then the rest. */
  CHECK_IMU(h, grove_foot_imu_add_samples(h, samples, n / 2, &added), GROVE_OK);
  CHECK(added == n / 2);
  CHECK_IMU(h, grove_foot_imu_take_steps(h, NULL, 0, &count), GROVE_OK);
  CHECK(count >= 1 && count < kSteps);
  CHECK_IMU(h, grove_foot_imu_take_steps(h, NULL, 2, &count), GROVE_INVALID_ARGUMENT);
  CHECK_IMU(h, grove_foot_imu_take_steps(h, steps, 0, NULL), GROVE_INVALID_ARGUMENT);
  if (count > 1) { /* too small a fill keeps the steps */
    CHECK_IMU(h, grove_foot_imu_take_steps(h, &one, 1, &count), GROVE_OUT_OF_RANGE);
  }
  CHECK_IMU(h, grove_foot_imu_take_steps(h, steps, kSteps + 1, &count), GROVE_OK);
  taken = count;
  CHECK_IMU(h, grove_foot_imu_take_steps(h, NULL, 0, &count), GROVE_OK);
  CHECK(count == 0); /* handed out */
  CHECK_IMU(h, grove_foot_imu_add_samples(h, samples + n / 2, n - n / 2, &added), GROVE_OK);
  CHECK_IMU(h, grove_foot_imu_finish(h), GROVE_OK);
  CHECK_IMU(h, grove_foot_imu_take_steps(h, steps + taken, kSteps + 1 - taken, &count), GROVE_OK);
  taken += count;
  CHECK(taken == kSteps);
  for (i = 0; i < taken; ++i) {
    const grove_foot_step* s = &steps[i];
    if (fabs(s->dx_m - kStepM) > 0.005 || fabs(s->dy_m) > 0.005 || fabs(s->dheading_rad) > 1e-3) {
      fprintf(stderr, "step %d: dx %.6f dy %.6f dheading %.6f\n", (int)i, s->dx_m, s->dy_m,
              s->dheading_rad);
      exit(1);
    }
    CHECK(s->covariance.xx > 0 && s->covariance.yy > 0 && s->covariance.hh >= 0);
    CHECK(s->stance_begin_s < s->t_s && s->t_s < s->stance_end_s);
    CHECK(i == 0 || s->t_s > steps[i - 1].t_s);
  }
  CHECK_IMU(h, grove_foot_imu_get_summary(h, &summary), GROVE_OK);
  CHECK(summary.samples == (int64_t)n);
  CHECK(summary.aligned == 1 && summary.has_origin == 1);
  CHECK(summary.steps == kSteps);
  CHECK(fabs(summary.distance_m - kSteps * kStepM) < 0.03);
  CHECK(summary.gravity_mps2 == kGravity);
  CHECK_IMU(h, grove_foot_imu_get_state(h, &state), GROVE_OK);
  CHECK(fabs(state.position_m[0] - kSteps * kStepM) < 0.03);
  CHECK(fabs(state.velocity_mps[0]) < 1e-3);
  CHECK(state.still == 1);
  grove_foot_imu_destroy(h);
  free(samples);
}

int main(void) {
  TestConfig();
  TestNullHandle();
  TestBadSamples();
  TestWalk();
  printf("foot_imu_c_api_test: ok\n");
  return 0;
}
