// Differential evolution in DE-SRCD-FastSLAM (FastSlamModel::Population): its moves never lower
// a particle's fitness, what F = 0 and Cr = 0 do, and nothing moves without generations or with
// fewer than 3 particles. (Same seed, same result at 1, 2 and 4 threads:
// ByFilterAndAssociation.SameResultAtAnyThreadCount/de_srcd_* in fastslam_test.cc.)
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "concurrency/worker_pool.h"
#include "engine/fastslam/fastslam_model.h"
#include "grove/fastslam.h"

namespace grove::fastslam {
namespace {

constexpr double kPi = std::numbers::pi;

// A de_srcd model taken by hand to the moment Population() runs at its second scan: the first
// scan maps four landmarks from the start, then 16 noisy predictions spread the particles'
// proposals, and the second scan's Advance() and Complete() draw distinct poses.
class Evolution {
 public:
  explicit Evolution(FastSlamConfig config, int threads = 1)
      : config_(Config(config)), workers_(threads), model_(config_, workers_.num_slots()) {
    log_w_.assign(model_.size(), 0);
    uint64_t step = 0;
    Scan(step++);
    EXPECT_TRUE(model_.Population(ScanStep{first_}, step - 1, workers_).ok());
    for (int k = 0; k < 16; ++k) {
      const PredictStep c{{3.0, 0.05, 0.025}, /*starts_segment=*/k == 0};
      EXPECT_TRUE(model_.Predict(c, step++, 0, model_.size(), 0).ok());
    }
    step_ = step;
    Scan(step_);
  }

  static FastSlamConfig Config(FastSlamConfig c) {
    c.filter = FastSlamFilter::kDeSrcd;
    c.sigma_speed_mps = 1.0;
    c.sigma_steer_rad = 10 * kPi / 180;
    c.sigma_range_m = 0.2;
    c.sigma_bearing_rad = 2 * kPi / 180;
    return c;
  }

  ScanStep second() const { return ScanStep{second_}; }
  uint64_t step() const { return step_; }
  FastSlamModel<3>& model() { return model_; }
  WorkerPool& workers() { return workers_; }

  std::vector<VehiclePose> Poses() const {
    std::vector<VehiclePose> p;
    for (size_t i = 0; i < model_.size(); ++i) p.push_back(model_.pose(i));
    return p;
  }
  std::vector<double> Fitness() const {
    std::vector<double> f;
    for (size_t i = 0; i < model_.size(); ++i)
      f.push_back(model_.Fitness(second(), i, model_.pose(i), /*slot=*/0));
    return f;
  }

 private:
  void Scan(uint64_t step) {
    const ScanStep scan{step == 0 ? std::span<const LandmarkObservation>(first_)
                                  : std::span<const LandmarkObservation>(second_)};
    model_.NoteScan(scan);
    EXPECT_TRUE(model_.Advance(scan, step, 0, model_.size(), 0, log_w_.data()).ok());
    EXPECT_TRUE(model_.Complete(scan, step, 0, model_.size(), 0).ok());
  }

  // Four landmarks around (20, 0), seen from the start and again from about 1.2 m on.
  const LandmarkObservation first_[4] = {
      {20.0, 0.0, 0}, {22.36, 0.4636, 1}, {22.36, -0.4636, 2}, {30.0, 0.1, 3}};
  const LandmarkObservation second_[4] = {
      {18.8, 0.02, 0}, {21.3, 0.49, 1}, {21.2, -0.46, 2}, {28.8, 0.11, 3}};
  FastSlamConfig config_;
  WorkerPool workers_;
  FastSlamModel<3> model_;
  std::vector<double> log_w_;
  uint64_t step_ = 0;
};

TEST(DifferentialEvolution, MovesNeverLowerAParticlesFitness) {
  FastSlamConfig config;
  config.particles = 40;
  Evolution e(config);
  const std::vector<double> before = e.Fitness();
  const std::vector<VehiclePose> poses_before = e.Poses();
  ASSERT_TRUE(e.model().Population(e.second(), e.step(), e.workers()).ok());
  const std::vector<double> after = e.Fitness();
  int improved = 0;
  for (size_t i = 0; i < before.size(); ++i) {
    EXPECT_GE(after[i], before[i]) << "particle " << i;
    if (after[i] > before[i]) {
      ++improved;
    } else {
      EXPECT_EQ(e.model().pose(i).x_m, poses_before[i].x_m) << "a move without a gain";
    }
  }
  // The draws are spread (sigma_v = 1 m/s, sigma_G = 10 degrees), so DE finds better poses.
  EXPECT_GT(improved, 10);
  const EvolutionCounts& counts = e.model().evolution_counts();
  EXPECT_EQ(counts.trials, 40 * config.de_generations);
  EXPECT_GT(counts.accepted, 10);
  EXPECT_LE(counts.accepted, counts.trials);
}

// DE/best/1/bin with F = 0 and Cr = 0: the mutant is the best particle's pose and binomial
// crossover still takes coordinate j_rand from it (the seed's Eq. 31: "or j = j_rand"), so each
// trial is the particle's pose with one coordinate replaced by the best's. It is not "the
// particle unchanged": a trial that gains fitness is kept. What stays unchanged is every other
// coordinate, and the best particle itself.
TEST(DifferentialEvolution, ZeroScaleAndCrossoverCopyOneCoordinateOfTheBest) {
  FastSlamConfig config;
  config.particles = 30;
  config.de_scale = 0;
  config.de_crossover = 0;
  config.de_generations = 1;
  Evolution e(config);
  const std::vector<double> fitness = e.Fitness();
  const std::vector<VehiclePose> before = e.Poses();
  size_t best = 0;
  for (size_t i = 1; i < fitness.size(); ++i) {
    if (fitness[i] > fitness[best]) best = i;
  }
  ASSERT_TRUE(e.model().Population(e.second(), e.step(), e.workers()).ok());
  int moved = 0;
  for (size_t i = 0; i < before.size(); ++i) {
    const VehiclePose& a = before[i];
    const VehiclePose& b = e.model().pose(i);
    const int changed = (a.x_m != b.x_m) + (a.y_m != b.y_m) + (a.heading_rad != b.heading_rad);
    EXPECT_LE(changed, 1) << "particle " << i;
    if (changed == 1) {
      ++moved;
      const VehiclePose& x = before[best];
      EXPECT_TRUE(b.x_m == x.x_m || b.y_m == x.y_m || b.heading_rad == x.heading_rad) << i;
    }
  }
  EXPECT_EQ(e.model().pose(best).x_m, before[best].x_m);
  EXPECT_GT(moved, 0);
}

TEST(DifferentialEvolution, NothingMovesWithoutGenerationsOrWithFewerThanThreeParticles) {
  for (auto [particles, generations] : {std::pair{20, 0}, std::pair{2, 10}}) {
    FastSlamConfig config;
    config.particles = particles;
    config.de_generations = generations;
    Evolution e(config);
    const std::vector<VehiclePose> before = e.Poses();
    ASSERT_TRUE(e.model().Population(e.second(), e.step(), e.workers()).ok());
    for (size_t i = 0; i < before.size(); ++i) {
      EXPECT_EQ(e.model().pose(i).x_m, before[i].x_m);
      EXPECT_EQ(e.model().pose(i).heading_rad, before[i].heading_rad);
    }
    EXPECT_EQ(e.model().evolution_counts().accepted, 0);
  }
}

TEST(DifferentialEvolution, SameMovesAtAnyThreadCount) {
  std::vector<VehiclePose> first;
  for (int threads : {1, 2, 4}) {
    FastSlamConfig config;
    config.particles = 64;
    config.batch = 5;
    Evolution e(config, threads);
    ASSERT_TRUE(e.model().Population(e.second(), e.step(), e.workers()).ok());
    const std::vector<VehiclePose> p = e.Poses();
    if (threads == 1) {
      first = p;
      continue;
    }
    for (size_t i = 0; i < p.size(); ++i) {
      ASSERT_EQ(p[i].x_m, first[i].x_m) << threads << " threads, particle " << i;
      ASSERT_EQ(p[i].y_m, first[i].y_m) << threads << " threads, particle " << i;
      ASSERT_EQ(p[i].heading_rad, first[i].heading_rad) << threads << " threads, particle " << i;
    }
  }
}

}  // namespace
}  // namespace grove::fastslam
