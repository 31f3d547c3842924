/* The C API from C: every call, every error path, and real runs of FootSLAM (a square loop
 * walked ten times) and landmark FastSLAM (a circle among known landmarks). Built as C99 with
 * -Wall -Werror -pedantic against libgrove.so; the checks cannot be compiled out. */
#include "grove/c_api.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tests/api/c_check.h"

/* For calls on a handle: the message is the handle's last error. */
#define CHECK_FOOT(h, call, expected) CHECK_STATUS_MSG(call, expected, grove_footslam_last_error(h))
#define CHECK_FAST(h, call, expected) CHECK_STATUS_MSG(call, expected, grove_fastslam_last_error(h))

static const double kPi = 3.14159265358979323846;

static int PoseFinite(const grove_pose* p) {
  return isfinite(p->t_s) && isfinite(p->x_m) && isfinite(p->y_m) && isfinite(p->heading_rad);
}

/* The FootSLAM walk: a 4 m square, 0.5 m steps, walked anticlockwise ten times */

enum { kSquareSide = 8, kLoopSteps = 4 * kSquareSide, kWalkSteps = 10 * kLoopSteps };

typedef struct Walk {
  double t[kWalkSteps];
  double dx[kWalkSteps];
  double dy[kWalkSteps];
} Walk;

static void MakeWalk(Walk* w) {
  int k;
  for (k = 0; k < kWalkSteps; ++k) {
    const int side = (k / kSquareSide) % 4;
    const double heading = side * kPi / 2;
    w->t[k] = 0.5 * (k + 1);
    /* A 1 % scale error, as odometry has. */
    w->dx[k] = 0.505 * cos(heading);
    w->dy[k] = 0.505 * sin(heading);
  }
}

static grove_footslam_config FootConfig(void) {
  grove_footslam_config c;
  grove_footslam_config_default(&c);
  c.particles = 200;
  c.seed = 7;
  c.threads = 1;
  c.batch = 64;
  return c;
}

static grove_footslam* NewFoot(const grove_footslam_config* c) {
  grove_footslam* h = NULL;
  char error[512];
  CHECK_STATUS_MSG(grove_footslam_create(c, &h, error, sizeof error), GROVE_OK, error);
  CHECK(h != NULL);
  CHECK(error[0] == '\0');
  return h;
}

/* Mean or heaviest trajectory into a new array of *count poses (free()d by the caller). */
static grove_pose* FootTrajectory(grove_footslam* h, int heaviest, size_t* count) {
  grove_pose* out;
  size_t n = 0, filled = 0;
  if (heaviest) {
    CHECK_FOOT(h, grove_footslam_heaviest_trajectory(h, NULL, 0, &n), GROVE_OK);
  } else {
    CHECK_FOOT(h, grove_footslam_mean_trajectory(h, NULL, 0, &n), GROVE_OK);
  }
  out = (grove_pose*)malloc((n + 1) * sizeof *out);
  CHECK(out != NULL);
  if (heaviest) {
    CHECK_FOOT(h, grove_footslam_heaviest_trajectory(h, out, n, &filled), GROVE_OK);
  } else {
    CHECK_FOOT(h, grove_footslam_mean_trajectory(h, out, n, &filled), GROVE_OK);
  }
  CHECK(filled == n);
  *count = n;
  return out;
}

static grove_hex_counts* FootMap(grove_footslam* h, int heaviest, size_t* count) {
  grove_hex_counts* out;
  size_t n = 0, filled = 0;
  if (heaviest) {
    CHECK_FOOT(h, grove_footslam_heaviest_map(h, NULL, 0, &n), GROVE_OK);
  } else {
    CHECK_FOOT(h, grove_footslam_cumulative_map(h, NULL, 0, &n), GROVE_OK);
  }
  out = (grove_hex_counts*)malloc((n + 1) * sizeof *out);
  CHECK(out != NULL);
  if (heaviest) {
    CHECK_FOOT(h, grove_footslam_heaviest_map(h, out, n, &filled), GROVE_OK);
  } else {
    CHECK_FOOT(h, grove_footslam_cumulative_map(h, out, n, &filled), GROVE_OK);
  }
  CHECK(filled == n);
  *count = n;
  return out;
}

/* Checkpoint bytes into a new buffer of *size bytes. */
static unsigned char* FootCheckpoint(grove_footslam* h, size_t* size) {
  unsigned char* out;
  size_t n = 0, filled = 0;
  CHECK_FOOT(h, grove_footslam_checkpoint(h, NULL, 0, &n), GROVE_OK);
  CHECK(n > 0);
  out = (unsigned char*)malloc(n);
  CHECK(out != NULL);
  CHECK_FOOT(h, grove_footslam_checkpoint(h, out, n, &filled), GROVE_OK);
  CHECK(filled == n);
  *size = n;
  return out;
}

static void TestVersionAndStatus(void) {
  int major = -1, minor = -1, patch = -1;
  char numbers[64];
  const char* v = grove_version();
  CHECK(v != NULL);
  CHECK(strncmp(v, "grove ", 6) == 0);
  CHECK(v == grove_version()); /* one static string */
  grove_version_numbers(&major, &minor, &patch);
  CHECK(major >= 0 && minor >= 0 && patch >= 0);
  snprintf(numbers, sizeof numbers, "%d.%d.%d", major, minor, patch);
  CHECK(Contains(v, numbers));
  grove_version_numbers(NULL, NULL, NULL); /* NULLs are fine */
  CHECK(strcmp(grove_status_name(GROVE_OK), "ok") == 0);
  CHECK(strcmp(grove_status_name(GROVE_INVALID_ARGUMENT), "invalid argument") == 0);
  CHECK(strcmp(grove_status_name(GROVE_DATA_LOSS), "data loss") == 0);
  CHECK(strcmp(grove_status_name(GROVE_INTERNAL), "internal") == 0);
  CHECK(strcmp(grove_status_name((grove_status)99), "unknown") == 0);
  CHECK(strcmp(grove_status_name((grove_status)-1), "unknown") == 0);
  printf("ok: version \"%s\" and status names\n", v);
}

static void TestFootNullHandle(void) {
  grove_pose pose;
  grove_footslam_summary summary;
  grove_footslam_config config;
  int64_t steps = 0;
  size_t n = 0, done = 7;
  double t = 1, d = 0;
  grove_hex_counts hex;
  unsigned char byte;
  CHECK_STATUS(grove_footslam_step(NULL, 1, 0, 0), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_footslam_steps(NULL, &t, &d, &d, 1, &done), GROVE_INVALID_ARGUMENT);
  CHECK(done == 0);
  CHECK_STATUS(grove_footslam_set_start_time(NULL, 0), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_footslam_set_prior_map(NULL, &hex, 1), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_footslam_step_count(NULL, &steps), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_footslam_get_config(NULL, &config), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_footslam_mean_pose(NULL, &pose), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_footslam_heaviest_pose(NULL, &pose), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_footslam_mean_trajectory(NULL, &pose, 1, &n), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_footslam_heaviest_trajectory(NULL, &pose, 1, &n), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_footslam_cumulative_map(NULL, &hex, 1, &n), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_footslam_heaviest_map(NULL, &hex, 1, &n), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_footslam_get_summary(NULL, &summary), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_footslam_checkpoint(NULL, &byte, 1, &n), GROVE_INVALID_ARGUMENT);
  CHECK(strcmp(grove_footslam_last_error(NULL), "") == 0);
  grove_footslam_destroy(NULL);
  printf("ok: footslam calls on a NULL handle\n");
}

static void TestFootCreateErrors(void) {
  grove_footslam_config c = FootConfig(), before;
  grove_footslam* h = (grove_footslam*)&c; /* any non-NULL value: create must reset it */
  char error[512];
  char small[8];

  CHECK_STATUS(grove_footslam_create(NULL, &h, error, sizeof error), GROVE_INVALID_ARGUMENT);
  CHECK(h == NULL);
  CHECK(Contains(error, "config is NULL"));
  CHECK_STATUS(grove_footslam_create(&c, NULL, error, sizeof error), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(error, "out is NULL"));

  c.particles = 0; /* out of range */
  CHECK_STATUS(grove_footslam_create(&c, &h, error, sizeof error), GROVE_INVALID_ARGUMENT);
  CHECK(h == NULL);
  CHECK(Contains(error, "particles"));
  /* The message is cut to the buffer and NUL-terminated; no buffer is fine. */
  memset(small, 'x', sizeof small);
  CHECK_STATUS(grove_footslam_create(&c, &h, small, sizeof small), GROVE_INVALID_ARGUMENT);
  CHECK(strlen(small) == sizeof small - 1);
  CHECK_STATUS(grove_footslam_create(&c, &h, NULL, 0), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_footslam_create(&c, &h, small, 0), GROVE_INVALID_ARGUMENT);

  c = FootConfig();
  c.weighting = 7; /* not an enumerator */
  CHECK_STATUS(grove_footslam_create(&c, &h, error, sizeof error), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(error, "weighting"));
  c = FootConfig();
  c.map = -1;
  CHECK_STATUS(grove_footslam_create(&c, &h, error, sizeof error), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(error, "map"));
  c = FootConfig();
  c.hex_radius_m = NAN;
  CHECK_STATUS(grove_footslam_create(&c, &h, error, sizeof error), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(error, "hex_radius_m"));
  c = FootConfig();
  c.grid_size = 100; /* not a power of sqrt(degree): a rule between fields */
  CHECK_STATUS(grove_footslam_create(&c, &h, error, sizeof error), GROVE_INVALID_ARGUMENT);
  CHECK(error[0] != '\0');
  CHECK(h == NULL);

  /* JSON: syntax, unknown key, range, type, a rule between fields, NULL. */
  CHECK_STATUS(grove_footslam_create_json("{\"particles\": ", &h, error, sizeof error),
               GROVE_INVALID_ARGUMENT);
  CHECK(Contains(error, "config:1:"));
  CHECK_STATUS(grove_footslam_create_json("{\"particlez\": 5}", &h, error, sizeof error),
               GROVE_INVALID_ARGUMENT);
  CHECK(Contains(error, "particlez"));
  CHECK(Contains(error, "particles")); /* the suggestion */
  CHECK_STATUS(grove_footslam_create_json("{\n  \"particles\": 0\n}", &h, error, sizeof error),
               GROVE_INVALID_ARGUMENT);
  CHECK(Contains(error, "config:2:"));
  CHECK(Contains(error, "particles"));
  CHECK_STATUS(grove_footslam_create_json("{\"particles\": \"many\"}", &h, error, sizeof error),
               GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_footslam_create_json("{\"map\": \"quadtree\"}", &h, error, sizeof error),
               GROVE_INVALID_ARGUMENT);
  CHECK(Contains(error, "htree"));
  CHECK_STATUS(grove_footslam_create_json("{\"grid_size\": 100}", &h, error, sizeof error),
               GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_footslam_create_json("[1, 2]", &h, error, sizeof error),
               GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_footslam_create_json("{\"seed\": 1, \"seed\": 2}", &h, error, sizeof error),
               GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_footslam_create_json(NULL, &h, error, sizeof error), GROVE_INVALID_ARGUMENT);
  CHECK(h == NULL);
  CHECK_STATUS(grove_footslam_create_json("{}", NULL, error, sizeof error), GROVE_INVALID_ARGUMENT);

  /* config_from_json keeps the fields the text leaves out and changes nothing on error. */
  c = FootConfig();
  CHECK_STATUS_MSG(grove_footslam_config_from_json("{\"particles\": 123, \"map\": \"naive\"}", &c,
                                                   error, sizeof error),
                   GROVE_OK, error);
  CHECK(error[0] == '\0');
  CHECK(c.particles == 123 && c.map == GROVE_FOOTSLAM_MAP_NAIVE && c.seed == 7 && c.threads == 1);
  before = c;
  CHECK_STATUS(
      grove_footslam_config_from_json("{\"particles\": 5, \"bogus\": 1}", &c, error, sizeof error),
      GROVE_INVALID_ARGUMENT);
  CHECK(memcmp(&before, &c, sizeof c) == 0);
  CHECK_STATUS(grove_footslam_config_from_json("{}", NULL, error, sizeof error),
               GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_footslam_config_from_json(NULL, &c, error, sizeof error),
               GROVE_INVALID_ARGUMENT);

  /* A good JSON config: the engine runs exactly it. */
  CHECK_STATUS_MSG(grove_footslam_create_json(
                       "{\"particles\": 50, \"map\": \"naive\", \"seed\": 9, \"threads\": 1}", &h,
                       error, sizeof error),
                   GROVE_OK, error);
  CHECK(h != NULL);
  CHECK_FOOT(h, grove_footslam_get_config(h, &c), GROVE_OK);
  CHECK(c.particles == 50 && c.map == GROVE_FOOTSLAM_MAP_NAIVE && c.seed == 9);
  grove_footslam_config_default(&before);
  CHECK(c.hex_radius_m == before.hex_radius_m && c.degree == before.degree);
  CHECK_FOOT(h, grove_footslam_step(h, 0.5, 0.5, 0), GROVE_OK);
  grove_footslam_destroy(h);
  grove_footslam_config_default(NULL);
  printf("ok: footslam create, create_json and config_from_json errors\n");
}

/* Step errors on a live handle: each leaves the engine unchanged. */
static void TestFootStepErrors(void) {
  grove_footslam_config c = FootConfig();
  grove_footslam* h = NewFoot(&c);
  grove_pose pose, out[4];
  grove_footslam_summary summary;
  int64_t steps = -1;
  size_t n = 99, done = 99;
  double t[3] = {3, 4, 5}, dx[3] = {0.5, 0.5, 0.5}, dy[3] = {0, NAN, 0};
  unsigned char byte;

  CHECK_FOOT(h, grove_footslam_set_start_time(h, NAN), GROVE_INVALID_ARGUMENT);
  CHECK(grove_footslam_last_error(h)[0] != '\0');
  CHECK_FOOT(h, grove_footslam_set_start_time(h, 0), GROVE_OK);
  CHECK(strcmp(grove_footslam_last_error(h), "") == 0);
  CHECK_FOOT(h, grove_footslam_step(h, 1, 0.5, 0), GROVE_OK);
  CHECK_FOOT(h, grove_footslam_set_start_time(h, 0), GROVE_FAILED_PRECONDITION);

  CHECK_FOOT(h, grove_footslam_step(h, NAN, 0.5, 0), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_step(h, 2, NAN, 0), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_step(h, 2, 0, INFINITY), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_step(h, 1, 0.5, 0), GROVE_INVALID_ARGUMENT); /* same time */
  CHECK(grove_footslam_last_error(h)[0] != '\0');
  CHECK_FOOT(h, grove_footslam_step(h, 0.5, 0.5, 0), GROVE_INVALID_ARGUMENT); /* earlier */
  CHECK_FOOT(h, grove_footslam_step_count(h, &steps), GROVE_OK);
  CHECK(steps == 1);
  CHECK(strcmp(grove_footslam_last_error(h), "") == 0);

  /* The array call stops at the first bad step, naming its index. */
  CHECK_FOOT(h, grove_footslam_steps(h, t, dx, dy, 3, &done), GROVE_INVALID_ARGUMENT);
  CHECK(done == 1);
  CHECK(Contains(grove_footslam_last_error(h), "steps[1]: "));
  CHECK_FOOT(h, grove_footslam_step_count(h, &steps), GROVE_OK);
  CHECK(steps == 2);
  CHECK_FOOT(h, grove_footslam_steps(h, NULL, dx, dy, 3, &done), GROVE_INVALID_ARGUMENT);
  CHECK(done == 0);
  CHECK_FOOT(h, grove_footslam_steps(h, t, NULL, dy, 1, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_steps(h, t, dx, NULL, 1, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_steps(h, NULL, NULL, NULL, 0, &done), GROVE_OK);
  CHECK(done == 0);
  CHECK_FOOT(h, grove_footslam_step_count(h, &steps), GROVE_OK);
  CHECK(steps == 2);

  /* NULL outputs and bad (out, capacity) pairs. */
  CHECK_FOOT(h, grove_footslam_step_count(h, NULL), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(grove_footslam_last_error(h), "steps is NULL"));
  CHECK_FOOT(h, grove_footslam_get_config(h, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_mean_pose(h, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_heaviest_pose(h, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_get_summary(h, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_mean_trajectory(h, out, 4, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_mean_trajectory(h, NULL, 4, &n), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_heaviest_trajectory(h, out, 4, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_heaviest_trajectory(h, NULL, 4, &n), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_cumulative_map(h, NULL, 1, &n), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_heaviest_map(h, NULL, 1, &n), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_cumulative_map(h, NULL, 0, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_checkpoint(h, NULL, 1, &n), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_checkpoint(h, &byte, 1, NULL), GROVE_INVALID_ARGUMENT);

  /* A too-small array: the size comes back, nothing is written. */
  memset(out, 0x5a, sizeof out);
  CHECK_FOOT(h, grove_footslam_mean_trajectory(h, out, 2, &n), GROVE_OUT_OF_RANGE);
  CHECK(n == 3);
  CHECK(((unsigned char*)out)[0] == 0x5a && ((unsigned char*)out)[sizeof out - 1] == 0x5a);
  CHECK(Contains(grove_footslam_last_error(h), "capacity 2 < 3"));
  CHECK_FOOT(h, grove_footslam_heaviest_trajectory(h, out, 1, &n), GROVE_OUT_OF_RANGE);
  CHECK(n == 3);
  CHECK_FOOT(h, grove_footslam_checkpoint(h, &byte, 1, &n), GROVE_OUT_OF_RANGE);
  CHECK(n > 1);
  CHECK_FOOT(h, grove_footslam_mean_trajectory(h, out, 4, &n), GROVE_OK);
  CHECK(n == 3);
  CHECK(out[0].t_s == 0 && out[1].t_s == 1 && out[2].t_s == 3);
  CHECK_FOOT(h, grove_footslam_mean_pose(h, &pose), GROVE_OK);
  CHECK(pose.t_s == 3 && PoseFinite(&pose));
  CHECK_FOOT(h, grove_footslam_get_summary(h, &summary), GROVE_OK);
  CHECK(summary.filter.steps == 2);
  grove_footslam_destroy(h);
  printf("ok: footslam step errors leave the engine unchanged\n");
}

/* A walk that leaves a small grid stops the engine: later steps and checkpoints fail, the
 * read-outs still work. */
static void TestFootFatalError(void) {
  grove_footslam_config c = FootConfig();
  grove_footslam* h;
  grove_pose pose;
  size_t n = 0;
  int64_t steps = 0;
  int k;
  grove_status s = GROVE_OK;
  c.grid_size = 16;
  c.grid = GROVE_FOOTSLAM_GRID_FIXED;
  c.degree = 16;
  h = NewFoot(&c);
  for (k = 1; k <= 100 && s == GROVE_OK; ++k) s = grove_footslam_step(h, k, 1.0, 0);
  CHECK_STATUS_MSG(s, GROVE_OUT_OF_RANGE, grove_footslam_last_error(h));
  CHECK(Contains(grove_footslam_last_error(h), "the engine stopped here"));
  CHECK_FOOT(h, grove_footslam_step(h, 1000, 0.1, 0), GROVE_FAILED_PRECONDITION);
  CHECK_FOOT(h, grove_footslam_checkpoint(h, NULL, 0, &n), GROVE_FAILED_PRECONDITION);
  CHECK_FOOT(h, grove_footslam_mean_pose(h, &pose), GROVE_OK);
  CHECK(PoseFinite(&pose));
  CHECK_FOOT(h, grove_footslam_step_count(h, &steps), GROVE_OK);
  CHECK_FOOT(h, grove_footslam_mean_trajectory(h, NULL, 0, &n), GROVE_OK);
  /* The engine counts the failed step in its step count but not in its mean trajectory. */
  CHECK(steps == k - 1);
  CHECK(n >= (size_t)steps && n <= (size_t)steps + 1);
  grove_footslam_destroy(h);
  printf("ok: footslam use after a fatal error (left the grid at step %d)\n", (int)steps);
}

static void CheckMaps(grove_footslam* h) {
  size_t n_cum = 0, n_heavy = 0, i, j, n = 0;
  grove_hex_counts* cum = FootMap(h, 0, &n_cum);
  grove_hex_counts* heavy = FootMap(h, 1, &n_heavy);
  double total = 0;
  CHECK(n_cum > 10 && n_heavy > 10);
  for (i = 0; i < n_cum; ++i) {
    CHECK(isfinite(cum[i].x_m) && isfinite(cum[i].y_m));
    CHECK(fabs(cum[i].x_m) < 50 && fabs(cum[i].y_m) < 50);
    for (j = 0; j < 6; ++j) {
      CHECK(isfinite(cum[i].counts[j]) && cum[i].counts[j] >= 0);
      total += cum[i].counts[j];
    }
  }
  CHECK(total > 0);
  for (i = 0; i < n_heavy; ++i) {
    for (j = 0; j < 6; ++j) {
      CHECK(heavy[i].counts[j] >= 0 && heavy[i].counts[j] == floor(heavy[i].counts[j]));
    }
  }
  /* Too small: the size again, the buffer untouched. */
  memset(cum, 0x5a, sizeof *cum);
  CHECK_FOOT(h, grove_footslam_cumulative_map(h, cum, n_cum - 1, &n), GROVE_OUT_OF_RANGE);
  CHECK(n == n_cum);
  CHECK(((unsigned char*)cum)[0] == 0x5a);
  CHECK_FOOT(h, grove_footslam_heaviest_map(h, heavy, 0, &n), GROVE_OUT_OF_RANGE);
  CHECK(n == n_heavy);
  free(cum);
  free(heavy);
}

/* Ten loops one step at a time; the same through the array call; the same with a checkpoint
 * and a resume (on two threads) halfway. All three must agree bit for bit. */
static void TestFootRuns(void) {
  static Walk walk;
  const grove_footslam_config c = FootConfig();
  grove_footslam_config resume_config = c;
  grove_footslam *a = NewFoot(&c), *b = NewFoot(&c), *d = NewFoot(&c), *e = NULL;
  grove_pose *mean_a, *mean_b, *mean_e, *heavy_a, *heavy_b, *heavy_e, pose;
  grove_hex_counts *map_a, *map_e;
  size_t n_mean_a, n_mean_b, n_mean_e, n_heavy_a, n_heavy_b, n_heavy_e, n_map_a, n_map_e;
  size_t i, done = 0, size = 0;
  unsigned char* checkpoint;
  char error[512];
  int64_t steps = 0;
  grove_footslam_summary summary;
  const size_t half = kWalkSteps / 2;

  MakeWalk(&walk);
  CHECK_FOOT(a, grove_footslam_set_start_time(a, 0), GROVE_OK);
  CHECK_FOOT(b, grove_footslam_set_start_time(b, 0), GROVE_OK);
  CHECK_FOOT(d, grove_footslam_set_start_time(d, 0), GROVE_OK);
  for (i = 0; i < kWalkSteps; ++i) {
    CHECK_FOOT(a, grove_footslam_step(a, walk.t[i], walk.dx[i], walk.dy[i]), GROVE_OK);
  }
  CHECK_FOOT(b, grove_footslam_steps(b, walk.t, walk.dx, walk.dy, kWalkSteps, &done), GROVE_OK);
  CHECK(done == kWalkSteps);

  CHECK_FOOT(a, grove_footslam_step_count(a, &steps), GROVE_OK);
  CHECK(steps == kWalkSteps);
  mean_a = FootTrajectory(a, 0, &n_mean_a);
  heavy_a = FootTrajectory(a, 1, &n_heavy_a);
  CHECK(n_mean_a == kWalkSteps + 1 && n_heavy_a == kWalkSteps + 1);
  for (i = 0; i < n_mean_a; ++i) {
    CHECK(PoseFinite(&mean_a[i]) && PoseFinite(&heavy_a[i]));
    CHECK(mean_a[i].t_s == (i == 0 ? 0 : walk.t[i - 1]));
    CHECK(heavy_a[i].t_s == mean_a[i].t_s);
    CHECK(fabs(mean_a[i].x_m) < 20 && fabs(mean_a[i].y_m) < 20);
  }
  CHECK_FOOT(a, grove_footslam_mean_pose(a, &pose), GROVE_OK);
  CHECK(memcmp(&pose, &mean_a[kWalkSteps], sizeof pose) == 0);
  CHECK_FOOT(a, grove_footslam_heaviest_pose(a, &pose), GROVE_OK);
  /* The path stores poses in single precision. */
  CHECK(pose.t_s == heavy_a[kWalkSteps].t_s && fabs(pose.x_m - heavy_a[kWalkSteps].x_m) < 1e-5);
  CHECK(fabs(pose.y_m - heavy_a[kWalkSteps].y_m) < 1e-5);
  CHECK(fabs(pose.heading_rad - heavy_a[kWalkSteps].heading_rad) < 1e-5);
  {
    /* The smoothed path: one pose per step and the start, ending at the mean pose. */
    size_t n_smoothed = 0, filled = 0;
    grove_pose* smoothed;
    CHECK_FOOT(a, grove_footslam_smoothed_trajectory(a, NULL, 0, &n_smoothed), GROVE_OK);
    CHECK(n_smoothed == kWalkSteps + 1);
    smoothed = (grove_pose*)malloc(n_smoothed * sizeof *smoothed);
    CHECK(smoothed != NULL);
    CHECK_FOOT(a, grove_footslam_smoothed_trajectory(a, smoothed, 1, &filled), GROVE_OUT_OF_RANGE);
    CHECK(filled == n_smoothed);
    CHECK_FOOT(a, grove_footslam_smoothed_trajectory(a, smoothed, n_smoothed, &filled), GROVE_OK);
    CHECK(filled == n_smoothed && smoothed[kWalkSteps].t_s == mean_a[kWalkSteps].t_s);
    CHECK(fabs(smoothed[kWalkSteps].x_m - mean_a[kWalkSteps].x_m) < 1e-4);
    CHECK(fabs(smoothed[kWalkSteps].y_m - mean_a[kWalkSteps].y_m) < 1e-4);
    for (i = 0; i < n_smoothed; ++i) CHECK(PoseFinite(&smoothed[i]));
    CHECK_STATUS(grove_footslam_smoothed_trajectory(NULL, smoothed, 1, &filled),
                 GROVE_INVALID_ARGUMENT);
    free(smoothed);
  }
  CheckMaps(a);
  CHECK_FOOT(a, grove_footslam_get_summary(a, &summary), GROVE_OK);
  CHECK(summary.filter.particles == c.particles);
  CHECK(summary.filter.steps == kWalkSteps);
  CHECK(summary.filter.threads_used == 1);
  CHECK(summary.filter.resamplings >= 1 && summary.filter.resamplings <= kWalkSteps);
  CHECK(summary.filter.mean_ess > 0 && summary.filter.mean_ess <= (double)c.particles);
  CHECK(summary.filter.filter_s >= 0 && summary.filter.advance_s >= 0);
  CHECK(summary.map_memory.live_bytes > 0 && summary.map_memory.live_nodes > 0);
  CHECK(summary.trajectory_memory.live_bytes >= 0);
  CHECK(isfinite(summary.mean_scale) && isfinite(summary.mean_heading_error_rad));
  printf("ok: footslam %d steps of a square loop: finite poses, %d-pose trajectories, maps\n",
         kWalkSteps, (int)n_mean_a);

  mean_b = FootTrajectory(b, 0, &n_mean_b);
  heavy_b = FootTrajectory(b, 1, &n_heavy_b);
  CHECK(n_mean_b == n_mean_a && n_heavy_b == n_heavy_a);
  CHECK(memcmp(mean_a, mean_b, n_mean_a * sizeof *mean_a) == 0);
  CHECK(memcmp(heavy_a, heavy_b, n_heavy_a * sizeof *heavy_a) == 0);
  printf("ok: footslam array steps equal single steps bit for bit\n");

  /* Checkpoint halfway, resume under another thread count, finish. */
  CHECK_FOOT(d, grove_footslam_steps(d, walk.t, walk.dx, walk.dy, half, &done), GROVE_OK);
  checkpoint = FootCheckpoint(d, &size);
  grove_footslam_destroy(d);
  resume_config.threads = 2;
  resume_config.batch = 16;
  CHECK_STATUS_MSG(grove_footslam_resume(&resume_config, checkpoint, size, &e, error, sizeof error),
                   GROVE_OK, error);
  CHECK_FOOT(e, grove_footslam_step_count(e, &steps), GROVE_OK);
  CHECK(steps == (int64_t)half);
  CHECK_FOOT(e,
             grove_footslam_steps(e, walk.t + half, walk.dx + half, walk.dy + half,
                                  kWalkSteps - half, &done),
             GROVE_OK);
  mean_e = FootTrajectory(e, 0, &n_mean_e);
  heavy_e = FootTrajectory(e, 1, &n_heavy_e);
  CHECK(n_mean_e == n_mean_a && n_heavy_e == n_heavy_a);
  CHECK(memcmp(mean_a, mean_e, n_mean_a * sizeof *mean_a) == 0);
  CHECK(memcmp(heavy_a, heavy_e, n_heavy_a * sizeof *heavy_a) == 0);
  map_a = FootMap(a, 0, &n_map_a);
  map_e = FootMap(e, 0, &n_map_e);
  CHECK(n_map_a == n_map_e);
  CHECK(memcmp(map_a, map_e, n_map_a * sizeof *map_a) == 0);
  free(map_a);
  free(map_e);
  printf("ok: footslam checkpoint (%d bytes) -> resume on 2 threads -> continue is bit-identical\n",
         (int)size);

  /* Corrupt, truncated, empty and foreign checkpoints; a different or invalid config. */
  {
    grove_footslam* r = (grove_footslam*)&resume_config;
    grove_footslam_config other = c;
    unsigned char* bad = (unsigned char*)malloc(size);
    CHECK(bad != NULL);
    memcpy(bad, checkpoint, size);
    bad[size / 2] ^= 0x40;
    CHECK_STATUS(grove_footslam_resume(&c, bad, size, &r, error, sizeof error), GROVE_DATA_LOSS);
    CHECK(r == NULL);
    CHECK(error[0] != '\0');
    CHECK_STATUS(grove_footslam_resume(&c, checkpoint, size / 2, &r, error, sizeof error),
                 GROVE_DATA_LOSS);
    CHECK_STATUS(grove_footslam_resume(&c, checkpoint, size - 1, &r, error, sizeof error),
                 GROVE_DATA_LOSS);
    CHECK_STATUS(grove_footslam_resume(&c, NULL, 0, &r, error, sizeof error), GROVE_DATA_LOSS);
    memset(bad, 0, size);
    CHECK_STATUS(grove_footslam_resume(&c, bad, size, &r, error, sizeof error), GROVE_DATA_LOSS);
    CHECK_STATUS(grove_footslam_resume(&c, NULL, 10, &r, error, sizeof error),
                 GROVE_INVALID_ARGUMENT);
    CHECK_STATUS(grove_footslam_resume(NULL, checkpoint, size, &r, error, sizeof error),
                 GROVE_INVALID_ARGUMENT);
    CHECK_STATUS(grove_footslam_resume(&c, checkpoint, size, NULL, error, sizeof error),
                 GROVE_INVALID_ARGUMENT);
    other.seed = 8;
    CHECK_STATUS(grove_footslam_resume(&other, checkpoint, size, &r, error, sizeof error),
                 GROVE_FAILED_PRECONDITION);
    CHECK(Contains(error, "seed"));
    other = c;
    other.hex_radius_m = 0.6;
    CHECK_STATUS(grove_footslam_resume(&other, checkpoint, size, &r, error, sizeof error),
                 GROVE_FAILED_PRECONDITION);
    CHECK(Contains(error, "hex_radius_m"));
    other = c;
    other.particles = -3;
    CHECK_STATUS(grove_footslam_resume(&other, checkpoint, size, &r, error, sizeof error),
                 GROVE_INVALID_ARGUMENT);
    CHECK(r == NULL);
    free(bad);
    printf("ok: footslam resume refuses corrupt bytes and a different config\n");
  }

  /* Size query, then steps into new ground, then the fill with the old size: the map grew, so
   * the fill reports the new size instead of writing past the caller's array. */
  {
    size_t n_before = 0, n_after = 0, n_cp = 0, n_cp_after = 0;
    grove_hex_counts* map;
    unsigned char* cp;
    CHECK_FOOT(e, grove_footslam_cumulative_map(e, NULL, 0, &n_before), GROVE_OK);
    CHECK_FOOT(e, grove_footslam_checkpoint(e, NULL, 0, &n_cp), GROVE_OK);
    map = (grove_hex_counts*)malloc(n_before * sizeof *map);
    cp = (unsigned char*)malloc(n_cp);
    CHECK(map != NULL && cp != NULL);
    for (i = 1; i <= 30; ++i) {
      CHECK_FOOT(e, grove_footslam_step(e, walk.t[kWalkSteps - 1] + 0.5 * i, 0.5, 0), GROVE_OK);
    }
    CHECK_FOOT(e, grove_footslam_cumulative_map(e, map, n_before, &n_after), GROVE_OUT_OF_RANGE);
    CHECK(n_after > n_before);
    /* The checkpoint changed too: it fits (and is the new one) or its new size comes back. */
    if (grove_footslam_checkpoint(e, cp, n_cp, &n_cp_after) == GROVE_OK) {
      CHECK(n_cp_after <= n_cp);
    } else {
      CHECK(n_cp_after > n_cp);
      CHECK(Contains(grove_footslam_last_error(e), "capacity"));
    }
    free(map);
    free(cp);
  }
  grove_footslam_destroy(e);
  grove_footslam_destroy(a);
  grove_footslam_destroy(b);
  free(checkpoint);
  free(mean_a);
  free(mean_b);
  free(mean_e);
  free(heavy_a);
  free(heavy_b);
  free(heavy_e);
  printf("ok: footslam read-outs that changed between size query and fill are re-sized\n");
}

/* Landmark FastSLAM: Bailey's vehicle on a circle of radius 10 m among 8 landmarks */

enum { kLandmarks = 8, kScans = 300, kControlEvery = 50, kMaxObs = kLandmarks };
static const double kSpeed = 3.0, kDt = 0.1, kWheelbase = 4.0;

typedef struct Scenario {
  double lx[kLandmarks], ly[kLandmarks];
  int seen[kLandmarks];
  double steer;
  int observations;
} Scenario;

static double Wrap(double a) {
  while (a > kPi) a -= 2 * kPi;
  while (a <= -kPi) a += 2 * kPi;
  return a;
}

static void MakeScenario(Scenario* s) {
  int i;
  memset(s, 0, sizeof *s);
  s->steer = asin(kWheelbase / 10.0); /* turning radius B / sin(G) = 10 m */
  for (i = 0; i < kLandmarks; ++i) {
    const double a = 2 * kPi * i / kLandmarks, r = i % 2 == 0 ? 15.0 : 5.0;
    s->lx[i] = r * cos(a);
    s->ly[i] = 10 + r * sin(a);
  }
}

/* The noise-free detections from pose (x, y, phi): landmarks within 30 m in the front
 * half-plane, ids known. */
static size_t Observe(Scenario* s, double x, double y, double phi,
                      grove_landmark_observation* obs) {
  size_t n = 0;
  int i;
  for (i = 0; i < kLandmarks; ++i) {
    const double dx = s->lx[i] - x, dy = s->ly[i] - y;
    const double range = sqrt(dx * dx + dy * dy), bearing = Wrap(atan2(dy, dx) - phi);
    if (range <= 30 && fabs(bearing) <= kPi / 2) {
      obs[n].range_m = range;
      obs[n].bearing_rad = bearing;
      obs[n].id = i;
      ++n;
    }
  }
  return n;
}

/* Drives scans first .. last-1 (scan k at t = k dt, k >= 1) on `h`; the truth follows the
 * filter's Euler model. A control at t = 0 (first == 1) and after every kControlEvery-th scan. */
static void DriveFast(grove_fastslam* h, Scenario* s, int first, int last) {
  grove_landmark_observation obs[kMaxObs];
  double x = 0, y = 0, phi = 0;
  int k;
  if (first == 1) CHECK_FAST(h, grove_fastslam_control(h, 0, kSpeed, s->steer), GROVE_OK);
  /* The truth up to scan first-1. */
  for (k = 1; k < first; ++k) {
    x += kSpeed * kDt * cos(s->steer + phi);
    y += kSpeed * kDt * sin(s->steer + phi);
    phi += kSpeed * kDt * sin(s->steer) / kWheelbase;
  }
  for (k = first; k < last; ++k) {
    size_t n, i;
    const double t = k * kDt;
    x += kSpeed * kDt * cos(s->steer + phi);
    y += kSpeed * kDt * sin(s->steer + phi);
    phi += kSpeed * kDt * sin(s->steer) / kWheelbase;
    n = Observe(s, x, y, phi, obs);
    for (i = 0; i < n; ++i) s->seen[obs[i].id] = 1;
    s->observations += (int)n;
    CHECK_FAST(h, grove_fastslam_scan(h, t, obs, n), GROVE_OK);
    if (k % kControlEvery == 0) {
      CHECK_FAST(h, grove_fastslam_control(h, t, kSpeed, s->steer), GROVE_OK);
    }
  }
}

static grove_fastslam_config FastConfig(void) {
  grove_fastslam_config c;
  grove_fastslam_config_default(&c);
  c.particles = 50;
  c.seed = 3;
  c.threads = 1;
  c.batch = 16;
  return c;
}

static grove_fastslam* NewFast(const grove_fastslam_config* c) {
  grove_fastslam* h = NULL;
  char error[512];
  CHECK_STATUS_MSG(grove_fastslam_create(c, &h, error, sizeof error), GROVE_OK, error);
  CHECK(h != NULL);
  return h;
}

static grove_pose* FastTrajectory(grove_fastslam* h, int heaviest, size_t* count) {
  grove_pose* out;
  size_t n = 0, filled = 0;
  if (heaviest) {
    CHECK_FAST(h, grove_fastslam_heaviest_trajectory(h, NULL, 0, &n), GROVE_OK);
  } else {
    CHECK_FAST(h, grove_fastslam_mean_trajectory(h, NULL, 0, &n), GROVE_OK);
  }
  out = (grove_pose*)malloc((n + 1) * sizeof *out);
  CHECK(out != NULL);
  if (heaviest) {
    CHECK_FAST(h, grove_fastslam_heaviest_trajectory(h, out, n, &filled), GROVE_OK);
  } else {
    CHECK_FAST(h, grove_fastslam_mean_trajectory(h, out, n, &filled), GROVE_OK);
  }
  CHECK(filled == n);
  *count = n;
  return out;
}

static grove_landmark_estimate* FastLandmarks(grove_fastslam* h, size_t* count) {
  grove_landmark_estimate* out;
  size_t n = 0, filled = 0;
  CHECK_FAST(h, grove_fastslam_landmarks(h, NULL, 0, &n), GROVE_OK);
  out = (grove_landmark_estimate*)malloc((n + 1) * sizeof *out);
  CHECK(out != NULL);
  CHECK_FAST(h, grove_fastslam_landmarks(h, out, n, &filled), GROVE_OK);
  CHECK(filled == n);
  *count = n;
  return out;
}

static void TestFastNullHandle(void) {
  grove_pose pose;
  grove_pose_covariance cov;
  grove_fastslam_summary summary;
  grove_fastslam_config config;
  grove_landmark_observation obs = {1, 0, 0};
  grove_landmark_estimate est;
  int64_t steps;
  size_t n;
  unsigned char byte;
  CHECK_STATUS(grove_fastslam_control(NULL, 0, 1, 0), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_fastslam_scan(NULL, 1, &obs, 1), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_fastslam_step_count(NULL, &steps), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_fastslam_get_config(NULL, &config), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_fastslam_mean_pose(NULL, &pose), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_fastslam_heaviest_pose(NULL, &pose), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_fastslam_pose_covariance(NULL, &cov), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_fastslam_mean_trajectory(NULL, &pose, 1, &n), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_fastslam_heaviest_trajectory(NULL, &pose, 1, &n), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_fastslam_landmarks(NULL, &est, 1, &n), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_fastslam_get_summary(NULL, &summary), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_fastslam_checkpoint(NULL, &byte, 1, &n), GROVE_INVALID_ARGUMENT);
  CHECK(strcmp(grove_fastslam_last_error(NULL), "") == 0);
  grove_fastslam_destroy(NULL);
  grove_fastslam_config_default(NULL);
  printf("ok: fastslam calls on a NULL handle\n");
}

static void TestFastErrors(void) {
  grove_fastslam_config c = FastConfig();
  grove_fastslam* h = NULL;
  grove_landmark_observation obs[2] = {{10, 0.1, 0}, {12, -0.2, 1}};
  grove_pose pose;
  grove_pose_covariance cov;
  grove_fastslam_summary summary;
  grove_landmark_estimate est;
  int64_t steps = -1, steps_before;
  size_t n;
  char error[512];

  /* Creation. */
  c.particles = 0;
  CHECK_STATUS(grove_fastslam_create(&c, &h, error, sizeof error), GROVE_INVALID_ARGUMENT);
  CHECK(h == NULL && Contains(error, "particles"));
  c = FastConfig();
  c.filter = 42;
  CHECK_STATUS(grove_fastslam_create(&c, &h, error, sizeof error), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(error, "filter"));
  c = FastConfig();
  c.reject_gate = 30; /* above augment_gate */
  CHECK_STATUS(grove_fastslam_create(&c, &h, error, sizeof error), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_fastslam_create(NULL, &h, error, sizeof error), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_fastslam_create(&c, NULL, error, sizeof error), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_fastslam_create_json("{\"filter\": \"fastslam3\"}", &h, error, sizeof error),
               GROVE_INVALID_ARGUMENT);
  CHECK(Contains(error, "fastslam3"));
  CHECK_STATUS(grove_fastslam_create_json("{\"partcles\": 5}", &h, error, sizeof error),
               GROVE_INVALID_ARGUMENT);
  CHECK(Contains(error, "partcles"));
  CHECK_STATUS(grove_fastslam_create_json("{\"sigma_bearing_rad\": 4}", &h, error, sizeof error),
               GROVE_INVALID_ARGUMENT);
  CHECK(Contains(error, "sigma_bearing_rad"));
  CHECK_STATUS(grove_fastslam_create_json("{", &h, error, sizeof error), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_fastslam_create_json(NULL, &h, error, sizeof error), GROVE_INVALID_ARGUMENT);
  CHECK(h == NULL);
  c = FastConfig();
  CHECK_STATUS_MSG(
      grove_fastslam_config_from_json("{\"association\": \"ml\"}", &c, error, sizeof error),
      GROVE_OK, error);
  CHECK(c.association == GROVE_FASTSLAM_ASSOCIATION_MAXIMUM_LIKELIHOOD && c.particles == 50);
  CHECK_STATUS_MSG(
      grove_fastslam_config_from_json("{\"association\": \"jcbb\"}", &c, error, sizeof error),
      GROVE_OK, error);
  CHECK(c.association == GROVE_FASTSLAM_ASSOCIATION_JCBB);
  h = NewFast(&c); /* and back: the engine reports the association it was given */
  c = FastConfig();
  CHECK_FAST(h, grove_fastslam_get_config(h, &c), GROVE_OK);
  CHECK(c.association == GROVE_FASTSLAM_ASSOCIATION_JCBB);
  grove_fastslam_destroy(h);
  h = NULL;
  CHECK_STATUS(grove_fastslam_config_from_json("{}", NULL, error, sizeof error),
               GROVE_INVALID_ARGUMENT);
  CHECK_STATUS_MSG(
      grove_fastslam_create_json("{\"filter\": \"fastslam1\", \"particles\": 30, \"threads\": 1}",
                                 &h, error, sizeof error),
      GROVE_OK, error);
  CHECK_FAST(h, grove_fastslam_get_config(h, &c), GROVE_OK);
  CHECK(c.filter == GROVE_FASTSLAM_FILTER_FASTSLAM1 && c.particles == 30);
  CHECK(c.vehicle == GROVE_FASTSLAM_VEHICLE_BAILEY && c.evidence == GROVE_FASTSLAM_EVIDENCE_ON);
  grove_fastslam_destroy(h);

  /* Calls out of order and bad input: each leaves the engine unchanged. */
  c = FastConfig();
  h = NewFast(&c);
  CHECK_FAST(h, grove_fastslam_scan(h, 0.1, obs, 2), GROVE_INVALID_ARGUMENT); /* no control */
  CHECK(grove_fastslam_last_error(h)[0] != '\0');
  CHECK_FAST(h, grove_fastslam_control(h, NAN, 1, 0), GROVE_INVALID_ARGUMENT);
  CHECK_FAST(h, grove_fastslam_control(h, 0, INFINITY, 0), GROVE_INVALID_ARGUMENT);
  CHECK_FAST(h, grove_fastslam_control(h, 0, 2, 0), GROVE_OK);
  CHECK(strcmp(grove_fastslam_last_error(h), "") == 0);
  CHECK_FAST(h, grove_fastslam_scan(h, 0.1, obs, 2), GROVE_OK);
  CHECK_FAST(h, grove_fastslam_step_count(h, &steps_before), GROVE_OK);
  CHECK_FAST(h, grove_fastslam_scan(h, 0.1, obs, 2), GROVE_INVALID_ARGUMENT);  /* same time */
  CHECK_FAST(h, grove_fastslam_scan(h, 0.05, obs, 2), GROVE_INVALID_ARGUMENT); /* earlier */
  CHECK_FAST(h, grove_fastslam_control(h, 0.05, 2, 0), GROVE_INVALID_ARGUMENT);
  CHECK_FAST(h, grove_fastslam_scan(h, NAN, obs, 2), GROVE_INVALID_ARGUMENT);
  obs[1].range_m = -1;
  CHECK_FAST(h, grove_fastslam_scan(h, 0.2, obs, 2), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(grove_fastslam_last_error(h), "1"));
  obs[1].range_m = 12;
  obs[1].bearing_rad = 4;
  CHECK_FAST(h, grove_fastslam_scan(h, 0.2, obs, 2), GROVE_INVALID_ARGUMENT);
  obs[1].bearing_rad = NAN;
  CHECK_FAST(h, grove_fastslam_scan(h, 0.2, obs, 2), GROVE_INVALID_ARGUMENT);
  obs[1].bearing_rad = -0.2;
  obs[1].id = -1; /* known association needs an id */
  CHECK_FAST(h, grove_fastslam_scan(h, 0.2, obs, 2), GROVE_INVALID_ARGUMENT);
  obs[1].id = 1;
  CHECK_FAST(h, grove_fastslam_scan(h, 0.2, NULL, 2), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(grove_fastslam_last_error(h), "obs is NULL"));
  CHECK_FAST(h, grove_fastslam_step_count(h, &steps), GROVE_OK);
  CHECK(steps == steps_before);
  CHECK_FAST(h, grove_fastslam_scan(h, 0.2, NULL, 0), GROVE_OK); /* an empty scan */

  /* NULL outputs, bad (out, capacity) pairs, too-small arrays. */
  CHECK_FAST(h, grove_fastslam_step_count(h, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_FAST(h, grove_fastslam_get_config(h, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_FAST(h, grove_fastslam_mean_pose(h, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_FAST(h, grove_fastslam_heaviest_pose(h, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_FAST(h, grove_fastslam_pose_covariance(h, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_FAST(h, grove_fastslam_get_summary(h, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_FAST(h, grove_fastslam_mean_trajectory(h, &pose, 1, NULL), GROVE_INVALID_ARGUMENT);
  CHECK_FAST(h, grove_fastslam_heaviest_trajectory(h, NULL, 1, &n), GROVE_INVALID_ARGUMENT);
  CHECK_FAST(h, grove_fastslam_landmarks(h, NULL, 3, &n), GROVE_INVALID_ARGUMENT);
  CHECK_FAST(h, grove_fastslam_checkpoint(h, NULL, 3, &n), GROVE_INVALID_ARGUMENT);
  CHECK_FAST(h, grove_fastslam_landmarks(h, &est, 1, &n), GROVE_OUT_OF_RANGE);
  CHECK(n == 2);
  CHECK_FAST(h, grove_fastslam_mean_trajectory(h, &pose, 1, &n), GROVE_OUT_OF_RANGE);
  CHECK_FAST(h, grove_fastslam_step_count(h, &steps), GROVE_OK);
  /* The start and one pose per scan (steps also counts the scans' predictions). */
  CHECK(n == 3 && steps == 4);
  CHECK_FAST(h, grove_fastslam_pose_covariance(h, &cov), GROVE_OK);
  CHECK_FAST(h, grove_fastslam_get_summary(h, &summary), GROVE_OK);
  CHECK(summary.controls == 1 && summary.scans == 2 && summary.observations == 2);
  grove_fastslam_destroy(h);
  printf("ok: fastslam create, control and scan errors leave the engine unchanged\n");
}

/* Regression: values outside grove/input_rules.h's bounds (a huge finite range made a landmark
 * of infinite covariance, a control at t = 1e300 blocked every later call, an id of INT64_MAX
 * and any steering angle passed) are refused with GROVE_INVALID_ARGUMENT naming the value, and
 * the engine is exactly as before: step count, mean pose and time; the next good call works. */
static void TestFastBoundsLeaveEngineUnchanged(void) {
  grove_fastslam_config c = FastConfig();
  grove_fastslam* h = NewFast(&c);
  grove_landmark_observation obs[2] = {{10, 0.1, 0}, {12, -0.2, 1}};
  grove_pose before, after;
  int64_t steps_before = -1, steps = -1;
  size_t poses_before = 0, poses = 0;
  CHECK_FAST(h, grove_fastslam_control(h, 0, 2, 0), GROVE_OK);
  CHECK_FAST(h, grove_fastslam_scan(h, 0.1, obs, 2), GROVE_OK);
  CHECK_FAST(h, grove_fastslam_step_count(h, &steps_before), GROVE_OK);
  CHECK_FAST(h, grove_fastslam_mean_pose(h, &before), GROVE_OK);
  CHECK_FAST(h, grove_fastslam_mean_trajectory(h, NULL, 0, &poses_before), GROVE_OK);

  obs[1].range_m = 1e300;
  CHECK_FAST(h, grove_fastslam_scan(h, 0.2, obs, 2), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(grove_fastslam_last_error(h), "observation 1: range = 1e+300: must be in"));
  obs[1].range_m = 1e12;
  CHECK_FAST(h, grove_fastslam_scan(h, 0.2, obs, 2), GROVE_INVALID_ARGUMENT);
  obs[1].range_m = 12;
  obs[1].id = INT64_MAX;
  CHECK_FAST(h, grove_fastslam_scan(h, 0.2, obs, 2), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(grove_fastslam_last_error(h), "id = 9223372036854775807"));
  obs[1].id = 1;
  CHECK_FAST(h, grove_fastslam_scan(h, 1e300, obs, 2), GROVE_INVALID_ARGUMENT);
  CHECK_FAST(h, grove_fastslam_control(h, 1e300, 2, 0), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(grove_fastslam_last_error(h), "t = 1e+300: must be within +-1e12 s"));
  CHECK_FAST(h, grove_fastslam_control(h, 0.15, 1e30, 0), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(grove_fastslam_last_error(h), "speed = 1e+30: must be within +-1000 m/s"));
  CHECK_FAST(h, grove_fastslam_control(h, 0.15, 2, 4), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(grove_fastslam_last_error(h), "steering = 4: must be in (-pi/2, pi/2) rad"));
  CHECK_FAST(h, grove_fastslam_control(h, 0.15, 2, 1e10), GROVE_INVALID_ARGUMENT);

  CHECK_FAST(h, grove_fastslam_step_count(h, &steps), GROVE_OK);
  CHECK_FAST(h, grove_fastslam_mean_pose(h, &after), GROVE_OK);
  CHECK_FAST(h, grove_fastslam_mean_trajectory(h, NULL, 0, &poses), GROVE_OK);
  CHECK(steps == steps_before && poses == poses_before);
  CHECK(memcmp(&before, &after, sizeof before) == 0);
  /* Not latched: the engine takes the next good control and scan. */
  CHECK_FAST(h, grove_fastslam_control(h, 0.15, 2, 0.1), GROVE_OK);
  CHECK_FAST(h, grove_fastslam_scan(h, 0.2, obs, 2), GROVE_OK);
  grove_fastslam_destroy(h);
  printf("ok: fastslam values outside the input bounds leave the engine unchanged\n");
}

/* Regression: FootSLAM's steps keep the same bounds (|t| <= 1e12 s, |dx|, |dy| <= 1e6 m). */
static void TestFootBoundsLeaveEngineUnchanged(void) {
  grove_footslam_config c = FootConfig();
  grove_footslam* h = NewFoot(&c);
  int64_t steps = -1;
  CHECK_FOOT(h, grove_footslam_step(h, 1, 0.5, 0), GROVE_OK);
  CHECK_FOOT(h, grove_footslam_step(h, 1e300, 0.5, 0), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(grove_footslam_last_error(h), "t = 1e+300: must be within +-1e12 s"));
  CHECK_FOOT(h, grove_footslam_step(h, 2, 1e7, 0), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(grove_footslam_last_error(h), "dx = 10000000: must be within +-1e6 m"));
  CHECK_FOOT(h, grove_footslam_step(h, 2, 0, -1e300), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_step_count(h, &steps), GROVE_OK);
  CHECK(steps == 1);
  CHECK_FOOT(h, grove_footslam_step(h, 2, 0.5, 0), GROVE_OK);
  grove_footslam_destroy(h);
  h = NewFoot(&c);
  CHECK_FOOT(h, grove_footslam_set_start_time(h, -1e13), GROVE_INVALID_ARGUMENT);
  CHECK_FOOT(h, grove_footslam_set_start_time(h, 0), GROVE_OK);
  grove_footslam_destroy(h);
  printf("ok: footslam values outside the input bounds leave the engine unchanged\n");
}

static void TestFastRuns(void) {
  Scenario s, s2;
  const grove_fastslam_config c = FastConfig();
  grove_fastslam_config resume_config = c;
  grove_fastslam *a = NewFast(&c), *d = NewFast(&c), *e = NULL, *r = NULL;
  grove_pose *mean_a, *heavy_a, *mean_e, *heavy_e, pose;
  grove_landmark_estimate *lm_a, *lm_e;
  grove_pose_covariance cov;
  grove_fastslam_summary summary;
  size_t n_mean_a, n_heavy_a, n_mean_e, n_heavy_e, n_lm_a, n_lm_e, i, size = 0, filled = 0;
  size_t expected_landmarks = 0;
  int64_t steps = 0;
  unsigned char* checkpoint;
  char error[512];
  int j;

  MakeScenario(&s);
  DriveFast(a, &s, 1, kScans + 1);
  for (j = 0; j < kLandmarks; ++j) expected_landmarks += (size_t)s.seen[j];
  CHECK(expected_landmarks >= 4);

  CHECK_FAST(a, grove_fastslam_step_count(a, &steps), GROVE_OK);
  /* A prediction and an update per scan, a prediction per control but the first. */
  CHECK(steps == 2 * kScans + kScans / kControlEvery);
  mean_a = FastTrajectory(a, 0, &n_mean_a);
  heavy_a = FastTrajectory(a, 1, &n_heavy_a);
  /* The start, one pose per scan and one per control but the first. */
  CHECK(n_mean_a == 1 + kScans + kScans / kControlEvery && n_heavy_a == n_mean_a);
  for (i = 0; i < n_mean_a; ++i) {
    CHECK(PoseFinite(&mean_a[i]) && PoseFinite(&heavy_a[i]));
    CHECK(heavy_a[i].t_s == mean_a[i].t_s);
    CHECK(i == 0 || mean_a[i].t_s >= mean_a[i - 1].t_s);
    CHECK(fabs(mean_a[i].x_m) < 30 && fabs(mean_a[i].y_m - 10) < 30);
  }
  CHECK(mean_a[n_mean_a - 1].t_s == kScans * kDt);
  CHECK_FAST(a, grove_fastslam_mean_pose(a, &pose), GROVE_OK);
  CHECK(memcmp(&pose, &mean_a[n_mean_a - 1], sizeof pose) == 0);
  CHECK_FAST(a, grove_fastslam_heaviest_pose(a, &pose), GROVE_OK);
  CHECK(PoseFinite(&pose));
  CHECK_FAST(a, grove_fastslam_pose_covariance(a, &cov), GROVE_OK);
  CHECK(isfinite(cov.xx) && isfinite(cov.xy) && isfinite(cov.hh));
  CHECK(cov.xx >= 0 && cov.yy >= 0 && cov.hh >= 0);

  lm_a = FastLandmarks(a, &n_lm_a);
  CHECK(n_lm_a == expected_landmarks);
  for (i = 0; i < n_lm_a; ++i) {
    const int64_t id = lm_a[i].id;
    CHECK(id >= 0 && id < kLandmarks && s.seen[id]);
    CHECK(i == 0 || lm_a[i].id > lm_a[i - 1].id);
    CHECK(isfinite(lm_a[i].x_m) && isfinite(lm_a[i].y_m));
    CHECK(hypot(lm_a[i].x_m - s.lx[id], lm_a[i].y_m - s.ly[id]) < 2.0);
    CHECK(lm_a[i].sxx > 0 && lm_a[i].syy > 0);
    CHECK(lm_a[i].sxx * lm_a[i].syy - lm_a[i].sxy * lm_a[i].sxy > 0);
  }
  CHECK_FAST(a, grove_fastslam_get_summary(a, &summary), GROVE_OK);
  CHECK(summary.filter.particles == c.particles && summary.filter.steps == steps);
  CHECK(summary.scans == kScans && summary.controls == 1 + kScans / kControlEvery);
  CHECK(summary.observations == s.observations);
  CHECK(summary.landmarks == (int64_t)n_lm_a);
  CHECK(summary.filter.mean_ess > 0 && summary.filter.mean_ess <= (double)c.particles);
  CHECK(summary.map_memory.live_bytes > 0 && summary.trajectory_memory.live_bytes >= 0);
  printf(
      "ok: fastslam %d scans of a circle: finite poses, %d-pose trajectories, %d landmarks "
      "within 2 m\n",
      kScans, (int)n_mean_a, (int)n_lm_a);

  /* Checkpoint after 150 scans, resume on two threads, finish: bit for bit the uninterrupted
   * run. */
  MakeScenario(&s2);
  DriveFast(d, &s2, 1, kScans / 2 + 1);
  CHECK_FAST(d, grove_fastslam_checkpoint(d, NULL, 0, &size), GROVE_OK);
  checkpoint = (unsigned char*)malloc(size);
  CHECK(checkpoint != NULL);
  CHECK_FAST(d, grove_fastslam_checkpoint(d, checkpoint, size - 1, &filled), GROVE_OUT_OF_RANGE);
  CHECK(filled == size);
  CHECK_FAST(d, grove_fastslam_checkpoint(d, checkpoint, size, &filled), GROVE_OK);
  CHECK(filled == size);
  grove_fastslam_destroy(d);
  resume_config.threads = 2;
  CHECK_STATUS_MSG(grove_fastslam_resume(&resume_config, checkpoint, size, &e, error, sizeof error),
                   GROVE_OK, error);
  DriveFast(e, &s2, kScans / 2 + 1, kScans + 1);
  mean_e = FastTrajectory(e, 0, &n_mean_e);
  heavy_e = FastTrajectory(e, 1, &n_heavy_e);
  lm_e = FastLandmarks(e, &n_lm_e);
  CHECK(n_mean_e == n_mean_a && n_heavy_e == n_heavy_a && n_lm_e == n_lm_a);
  CHECK(memcmp(mean_a, mean_e, n_mean_a * sizeof *mean_a) == 0);
  CHECK(memcmp(heavy_a, heavy_e, n_heavy_a * sizeof *heavy_a) == 0);
  CHECK(memcmp(lm_a, lm_e, n_lm_a * sizeof *lm_a) == 0);
  printf("ok: fastslam checkpoint (%d bytes) -> resume on 2 threads -> continue is bit-identical\n",
         (int)size);

  /* Bad checkpoints and configs. */
  checkpoint[size / 3] ^= 0x01;
  CHECK_STATUS(grove_fastslam_resume(&c, checkpoint, size, &r, error, sizeof error),
               GROVE_DATA_LOSS);
  CHECK(r == NULL && error[0] != '\0');
  checkpoint[size / 3] ^= 0x01;
  CHECK_STATUS(grove_fastslam_resume(&c, checkpoint, size - 8, &r, error, sizeof error),
               GROVE_DATA_LOSS);
  CHECK_STATUS(grove_fastslam_resume(&c, NULL, 0, &r, error, sizeof error), GROVE_DATA_LOSS);
  CHECK_STATUS(grove_fastslam_resume(&c, NULL, 5, &r, error, sizeof error), GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_fastslam_resume(NULL, checkpoint, size, &r, error, sizeof error),
               GROVE_INVALID_ARGUMENT);
  CHECK_STATUS(grove_fastslam_resume(&c, checkpoint, size, NULL, error, sizeof error),
               GROVE_INVALID_ARGUMENT);
  resume_config = c;
  resume_config.sigma_range_m = 0.2;
  CHECK_STATUS(grove_fastslam_resume(&resume_config, checkpoint, size, &r, error, sizeof error),
               GROVE_FAILED_PRECONDITION);
  CHECK(Contains(error, "sigma_range_m"));
  {
    /* A FootSLAM checkpoint is not a FastSLAM one. */
    grove_footslam_config fc = FootConfig();
    grove_footslam* f = NewFoot(&fc);
    size_t fsize = 0;
    unsigned char* fbytes;
    CHECK_FOOT(f, grove_footslam_step(f, 1, 0.5, 0), GROVE_OK);
    fbytes = FootCheckpoint(f, &fsize);
    CHECK(grove_fastslam_resume(&c, fbytes, fsize, &r, error, sizeof error) != GROVE_OK);
    CHECK(r == NULL);
    CHECK(error[0] != '\0');
    grove_footslam_destroy(f);
    free(fbytes);
  }
  CHECK(r == NULL);
  printf("ok: fastslam resume refuses corrupt bytes and a different config\n");

  grove_fastslam_destroy(a);
  grove_fastslam_destroy(e);
  free(checkpoint);
  free(mean_a);
  free(heavy_a);
  free(mean_e);
  free(heavy_e);
  free(lm_a);
  free(lm_e);
}

/* A prior map: bad rows and a NULL array are refused naming the problem; a good one is counted in
 * the summary and changes the run; after the first step it can no longer be set. */
static void TestFootPriorMap(void) {
  grove_footslam_config c = FootConfig();
  grove_footslam *first, *with, *without;
  grove_footslam_summary summary;
  grove_hex_counts* map;
  grove_pose a, b;
  size_t n = 0;
  int k;
  first = NewFoot(&c);
  for (k = 1; k <= 60; ++k) CHECK_FOOT(first, grove_footslam_step(first, k, 0.7, 0), GROVE_OK);
  map = FootMap(first, 0, &n);
  CHECK(n > 10);
  with = NewFoot(&c);
  without = NewFoot(&c);
  CHECK_FOOT(with, grove_footslam_set_prior_map(with, NULL, 3), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(grove_footslam_last_error(with), "hexes"));
  map[1].counts[4] = -2;
  CHECK_FOOT(with, grove_footslam_set_prior_map(with, map, n), GROVE_INVALID_ARGUMENT);
  CHECK(Contains(grove_footslam_last_error(with), "prior map row 1 "));
  map[1].counts[4] = 0;
  CHECK_FOOT(with, grove_footslam_set_prior_map(with, map, n), GROVE_OK);
  CHECK_FOOT(with, grove_footslam_get_summary(with, &summary), GROVE_OK);
  CHECK(summary.prior_hexagons == (int64_t)n);
  CHECK(summary.prior_hexagons_outside == 0);
  for (k = 1; k <= 60; ++k) {
    double turn = 0.3 * k;
    CHECK_FOOT(with, grove_footslam_step(with, k, 0.7 * cos(turn), 0.7 * sin(turn)), GROVE_OK);
    CHECK_FOOT(without, grove_footslam_step(without, k, 0.7 * cos(turn), 0.7 * sin(turn)),
               GROVE_OK);
  }
  CHECK_FOOT(with, grove_footslam_mean_pose(with, &a), GROVE_OK);
  CHECK_FOOT(without, grove_footslam_mean_pose(without, &b), GROVE_OK);
  CHECK(a.x_m != b.x_m || a.y_m != b.y_m);
  CHECK_FOOT(with, grove_footslam_set_prior_map(with, map, n), GROVE_FAILED_PRECONDITION);
  free(map);
  grove_footslam_destroy(first);
  grove_footslam_destroy(with);
  grove_footslam_destroy(without);
  printf("ok: footslam prior map\n");
}

static void TestFootStorage(void) {
  grove_footslam_config c = FootConfig();
  grove_footslam* h;
  grove_footslam_summary summary;
  grove_hex_counts* stored;
  size_t n = 0, filled = 0;
  int k;
  c.store_distance_m = 10;
  h = NewFoot(&c);
  /* Out 42 m and back: the start's area is stored on the way out. */
  for (k = 1; k <= 120; ++k) {
    CHECK_FOOT(h, grove_footslam_step(h, k, k <= 60 ? 0.7 : -0.7, 0), GROVE_OK);
  }
  CHECK_FOOT(h, grove_footslam_get_summary(h, &summary), GROVE_OK);
  CHECK(summary.stored_blocks > 0);
  CHECK(summary.stored_blocks_exact <= summary.stored_blocks);
  CHECK_FOOT(h, grove_footslam_stored_map(h, NULL, 0, &n), GROVE_OK);
  CHECK(n > 0 && (int64_t)n == summary.stored_hexagons);
  stored = (grove_hex_counts*)malloc(n * sizeof *stored);
  CHECK(stored != NULL);
  CHECK_FOOT(h, grove_footslam_stored_map(h, stored, n, &filled), GROVE_OK);
  CHECK(filled == n);
  free(stored);
  grove_footslam_destroy(h);
  c.map = GROVE_FOOTSLAM_MAP_NAIVE;
  {
    char error[512];
    CHECK_STATUS_MSG(grove_footslam_create(&c, &h, error, sizeof error), GROVE_INVALID_ARGUMENT,
                     error);
    CHECK(Contains(error, "store_distance_m = 10"));
  }
  printf("ok: footslam storage of diversity\n");
}

int main(void) {
  setvbuf(stdout, NULL, _IONBF, 0); /* keep the lines in order with a failure on stderr */
  TestVersionAndStatus();
  TestFootNullHandle();
  TestFootCreateErrors();
  TestFootStepErrors();
  TestFootBoundsLeaveEngineUnchanged();
  TestFootFatalError();
  TestFootRuns();
  TestFootPriorMap();
  TestFootStorage();
  TestFastNullHandle();
  TestFastErrors();
  TestFastBoundsLeaveEngineUnchanged();
  TestFastRuns();
  printf("c_api_test: all passed\n");
  return 0;
}
