// Times FasterSLAM's optimised FastSLAM 1.0 (`fastslam1_sim_active`) in process: one call on the
// map file, for a particle count, printing seconds. Built by fasterslam_rounds.py against a
// FasterSLAM build; usage: fasterslam_timer MAP.mat PARTICLES
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "configfile.h"
#include "fastslam1_sim.h"
#include "fastslam1_utils.h"
#include "particle.h"
#include "read_input_file.h"

int main(int argc, char** argv) {
  if (argc != 3) return 2;
  double* lm;
  double* wp;
  size_t lm_rows, wp_rows;
  read_input_file(argv[1], &lm, &wp, lm_rows, wp_rows);
  NPARTICLES = static_cast<unsigned>(std::atoi(argv[2]));
  Particle* particles;
  double* weights;
  const auto start = std::chrono::steady_clock::now();
  fastslam1_sim_active(lm, lm_rows, 2, wp, wp_rows, 2, &particles, &weights);
  const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
  std::printf("%.6f\n", took.count());
  cleanup_particles_and_pose(&particles, &weights, &xv, &Pv, NPARTICLES);
  std::free(lm);
  std::free(wp);
}
