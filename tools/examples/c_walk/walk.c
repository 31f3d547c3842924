/* Runs FootSLAM through grove's C API on a step file (t,dx,dy per line after one header line),
 * fed in one array call, and prints the last mean pose and the size of the cumulative map.
 *   cc -std=c99 walk.c $(pkg-config --cflags --libs grove) -o walk && ./walk steps.csv */
#include <grove/c_api.h>
#include <stdio.h>
#include <stdlib.h>

int main(int argc, char** argv) {
  FILE* in;
  char header[256];
  double *t = NULL, *dx = NULL, *dy = NULL;
  size_t n = 0, capacity = 0, done = 0, hexagons = 0;
  grove_footslam* slam = NULL;
  grove_pose pose;
  char error[512];
  int ok = 0;

  if (argc != 2) {
    fprintf(stderr, "usage: %s STEPS.csv\n", argv[0]);
    return 2;
  }
  printf("%s\n", grove_version());
  in = fopen(argv[1], "r");
  if (in == NULL || fgets(header, sizeof header, in) == NULL) {
    fprintf(stderr, "%s: cannot read\n", argv[1]);
    return 1;
  }
  for (;;) {
    double a, b, c;
    if (fscanf(in, "%lf,%lf,%lf", &a, &b, &c) != 3) break;
    if (n == capacity) {
      capacity = capacity ? 2 * capacity : 1024;
      t = realloc(t, capacity * sizeof *t);
      dx = realloc(dx, capacity * sizeof *dx);
      dy = realloc(dy, capacity * sizeof *dy);
      if (t == NULL || dx == NULL || dy == NULL) return 1;
    }
    t[n] = a;
    dx[n] = b;
    dy[n] = c;
    ++n;
  }
  fclose(in);

  if (grove_footslam_create_json("{\"particles\": 2000}", &slam, error, sizeof error) != GROVE_OK) {
    fprintf(stderr, "%s\n", error);
    return 1;
  }
  if (grove_footslam_steps(slam, t, dx, dy, n, &done) != GROVE_OK) {
    fprintf(stderr, "%s: %s\n", argv[1], grove_footslam_last_error(slam));
  } else if (grove_footslam_mean_pose(slam, &pose) == GROVE_OK &&
             grove_footslam_cumulative_map(slam, NULL, 0, &hexagons) == GROVE_OK) {
    printf("%zu steps; mean pose x %.3f m, y %.3f m, heading %.4f rad; %zu hexagons mapped\n", done,
           pose.x_m, pose.y_m, pose.heading_rad, hexagons);
    ok = done == n && hexagons > 0;
  }
  grove_footslam_destroy(slam);
  free(t);
  free(dx);
  free(dy);
  return ok ? 0 : 1;
}
