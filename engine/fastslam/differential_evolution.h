// DifferentialEvolution: the population step of DE-SRCD-FastSLAM (kDeSrcd) over the poses drawn
// at a scan.
//
// DE/best/1/bin (Storn and Price; the seed's Eqs. 29-31): for each generation, each particle i
// forms the trial u from the mutant v = x_best + F (x_r1 - x_r2) (r1, r2 distinct and not i) by
// binomial crossover (coordinate j from v when a uniform draw is below Cr or j = j_rand, else
// from x_i), and u replaces x_i when its fitness is strictly higher. The fitness (Eq. 32,
// FastSlamModel::Fitness()) is log exp(-1/2 sum_j v_j^T R^-1 v_j) over the scan's observations of
// landmarks in particle i's own map (its associations under unknown association),
// v_j = z_j - h(x, landmark mean). Generations are synchronous (every trial is formed from the
// generation's poses), every draw comes from the stream (seed, step, particle,
// kDifferentialEvolution + 256 generation): the same at any thread count. With fewer than 3
// particles there are no r1, r2, and without an observation of a mapped landmark no fitness:
// then nothing moves. Across ranks the best pose and the population are the whole filter's.
#ifndef GROVE_ENGINE_FASTSLAM_DIFFERENTIAL_EVOLUTION_H_
#define GROVE_ENGINE_FASTSLAM_DIFFERENTIAL_EVOLUTION_H_

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <span>
#include <vector>

#include "concurrency/random_stream.h"
#include "concurrency/worker_pool.h"
#include "engine/fastslam/landmark_math.h"
#include "engine/filter/particle_filter.h"
#include "engine/io/checkpoint_io.h"
#include "engine/ranks/collective.h"
#include "grove/fastslam.h"
#include "grove/status.h"

namespace grove::fastslam {

class DifferentialEvolution {
 public:
  // The evolution of `n` particles, particle 0 here being the filter's particle `first` of
  // config.particles (across `ranks` when not null). Keeps no fitness when not `enabled`.
  DifferentialEvolution(const FastSlamConfig& config, bool enabled, size_t n, uint64_t first,
                        Collective* ranks)
      : seed_(config.seed),
        scale_(config.de_scale),
        crossover_(config.de_crossover),
        generations_(config.de_generations),
        batch_(static_cast<size_t>(config.batch)),
        first_(first),
        total_(static_cast<uint64_t>(config.particles)),
        ranks_(ranks),
        fitness_(enabled ? n : 0) {}

  const EvolutionCounts& counts() const { return counts_; }

  // Runs the generations of filter step `step` over `poses`, every particle's pose here, moving
  // those whose trial is fitter. fitness(i, pose, slot, terms) -> double: particle i's fitness at
  // `pose`, from worker slot `slot`; *terms (when not null) gets the observations summed.
  template <typename Fitness>
  Status Evolve(uint64_t step, WorkerPool& workers, std::span<VehiclePose> poses,
                const Fitness& fitness) {
    const size_t n = poses.size();
    std::atomic<bool> evidence{false};
    GROVE_RETURN_IF_ERROR(
        RunInBatches(workers, n, batch_, &batch_status_, [&](int slot, size_t b, size_t e) {
          for (size_t i = b; i < e; ++i) {
            int terms = 0;
            fitness_[i] = fitness(i, poses[i], slot, &terms);
            // Relaxed: read after the loop's join.
            if (terms > 0) evidence.store(true, std::memory_order_relaxed);
          }
          return Status::Ok();
        }));
    // Without an observation of a mapped landmark every fitness is 0 and there is nothing to
    // improve. Across ranks every rank decides alike, from every rank's evidence.
    bool any = evidence.load(std::memory_order_relaxed);
    if (ranks_ != nullptr) {
      std::vector<uint8_t> all;
      const uint8_t mine = any ? 1 : 0;
      GROVE_RETURN_IF_ERROR(AllGatherValues<uint8_t>(*ranks_, std::span(&mine, 1), &all));
      any = std::find(all.begin(), all.end(), uint8_t{1}) != all.end();
    }
    if (total_ < 3 || !any) return Status::Ok();
    std::vector<VehiclePose> trial(n);
    std::vector<double> trial_fitness(n);
    std::vector<VehiclePose> everyone;  // across ranks: every particle's pose, in order
    for (int64_t g = 0; g < generations_; ++g) {
      VehiclePose x_best;
      GROVE_RETURN_IF_ERROR(BestPose(poses, &x_best));
      std::span<const VehiclePose> population = poses;
      if (ranks_ != nullptr) {
        GROVE_RETURN_IF_ERROR(AllGatherValues<VehiclePose>(*ranks_, population, &everyone));
        population = everyone;
      }
      const uint32_t purpose =
          StreamPurpose::kDifferentialEvolution + 256 * static_cast<uint32_t>(g);
      GROVE_RETURN_IF_ERROR(
          RunInBatches(workers, n, batch_, &batch_status_, [&](int slot, size_t b, size_t e) {
            for (size_t i = b; i < e; ++i) {
              RandomStream rs(seed_, step + 1, static_cast<uint32_t>(first_ + i), purpose);
              trial[i] = TrialPose(first_ + i, population, x_best, &rs);
              trial_fitness[i] = fitness(i, trial[i], slot, nullptr);
            }
            return Status::Ok();
          }));
      for (size_t i = 0; i < n; ++i) {
        ++counts_.trials;
        if (trial_fitness[i] > fitness_[i]) {
          ++counts_.accepted;
          poses[i] = trial[i];
          fitness_[i] = trial_fitness[i];
        }
      }
    }
    return Status::Ok();
  }

  // The checkpoint's part: the counts.
  void Save(ByteWriter* w) const {
    w->Put<int64_t>(counts_.trials);
    w->Put<int64_t>(counts_.accepted);
  }
  static Status ReadCounts(ByteReader* r, EvolutionCounts* out) {
    GROVE_RETURN_IF_ERROR(r->Get("evolution trials", &out->trials));
    GROVE_RETURN_IF_ERROR(r->Get("evolution accepted", &out->accepted));
    if (!(out->accepted >= 0 && out->accepted <= out->trials)) {
      return r->Error("evolution counts", "negative, or more accepted than tried");
    }
    return Status::Ok();
  }
  void Restore(const EvolutionCounts& counts) { counts_ = counts; }

 private:
  // The pose of the first particle of highest fitness (across ranks, the whole filter's).
  Status BestPose(std::span<const VehiclePose> poses, VehiclePose* best) const {
    struct Best {
      double fitness;
      VehiclePose pose;
    };
    const size_t k = static_cast<size_t>(
        std::max_element(fitness_.begin(),
                         fitness_.begin() + static_cast<ptrdiff_t>(poses.size())) -
        fitness_.begin());
    Best mine{fitness_[k], poses[k]};
    if (ranks_ == nullptr) {
      *best = mine.pose;
      return Status::Ok();
    }
    std::vector<Best> all;
    GROVE_RETURN_IF_ERROR(AllGatherValues<Best>(*ranks_, std::span(&mine, 1), &all));
    // The first strict maximum in rank order is the first in particle order.
    size_t q = 0;
    for (size_t r = 1; r < all.size(); ++r) {
      if (all[r].fitness > all[q].fitness) q = r;
    }
    *best = all[q].pose;
    return Status::Ok();
  }

  // The trial pose of the filter's particle i (DE/best/1/bin), from `population`, every
  // particle's pose in the filter's order. REQUIRES: total_ >= 3.
  VehiclePose TrialPose(size_t i, std::span<const VehiclePose> population, const VehiclePose& best,
                        RandomStream* rs) const {
    const size_t n = population.size();
    auto other = [&](size_t a, size_t b) {
      for (;;) {
        const size_t k = static_cast<size_t>(rs->NextUniform() * static_cast<double>(n));
        if (k < n && k != a && k != b) return k;
      }
    };
    const size_t r1 = other(i, i);
    const size_t r2 = other(i, r1);
    const int j_rand = std::min(2, static_cast<int>(rs->NextUniform() * 3));
    const VehiclePose& a = population[r1];
    const VehiclePose& b = population[r2];
    const double mutant[3] = {best.x_m + scale_ * (a.x_m - b.x_m),
                              best.y_m + scale_ * (a.y_m - b.y_m),
                              best.heading_rad + scale_ * WrapAngle(a.heading_rad - b.heading_rad)};
    const double target[3] = {population[i].x_m, population[i].y_m, population[i].heading_rad};
    double u[3];
    for (int j = 0; j < 3; ++j) {
      const bool cross = rs->NextUniform() < crossover_ || j == j_rand;
      u[j] = cross ? mutant[j] : target[j];
    }
    return VehiclePose{u[0], u[1], WrapAngle(u[2])};
  }

  const uint64_t seed_;
  const double scale_;      // F
  const double crossover_;  // Cr
  const int64_t generations_;
  const size_t batch_;           // particles per parallel batch, at most
  const uint64_t first_;         // the filter's index of particle 0 here
  const uint64_t total_;         // the filter's particles
  Collective* const ranks_;      // null: one process
  std::vector<double> fitness_;  // per particle
  EvolutionCounts counts_;
  std::vector<Status> batch_status_;  // RunInBatches' scratch
};

}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_DIFFERENTIAL_EVOLUTION_H_
