#include "engine/particle_filter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <vector>

#include "concurrency/random_stream.h"
#include "engine/persistent_trie.h"

namespace grove {
namespace {

struct Count {
  uint32_t n;
};
using Trie = PersistentTrie<Count, 4>;

// A toy model: a 1-D random walk whose map counts visits per cell; revisits are rewarded, so
// weights, resampling and map sharing all matter.
class ToyModel {
 public:
  ToyModel(size_t n, int slots) : trie_(4, slots), x_(n, 0.0), roots_(n, nullptr) {}
  ~ToyModel() {
    for (auto r : roots_) trie_.Release(r, 0);
    for (auto r : dead_) trie_.Release(r, 0);
  }
  size_t size() const { return x_.size(); }

  void Advance(const double& drift, uint64_t step, size_t begin, size_t end, int slot,
               double* log_w) {
    for (size_t i = begin; i < end; ++i) {
      RandomStream rs(123, step, static_cast<uint32_t>(i));
      x_[i] += drift + rs.NextNormal();
      uint64_t cell = static_cast<uint64_t>(std::floor(x_[i]) + 30000) & 0xFFFF;
      uint32_t seen = 0;
      roots_[i] = trie_.Update(roots_[i], cell, slot, [&](Count& c, bool) { seen = c.n++; });
      log_w[i] += std::log((seen + 1.0) / (step + 2.0));
    }
  }
  void Gather(std::span<const uint32_t> parents, WorkerPool& workers) {
    std::vector<double> x(parents.size());
    std::vector<Trie::Root> roots(parents.size());
    workers.ParallelFor(parents.size(), 64, [&](int, size_t b, size_t e) {
      for (size_t k = b; k < e; ++k) {
        x[k] = x_[parents[k]];
        roots[k] = Trie::Share(roots_[parents[k]]);
      }
    });
    x_.swap(x);
    dead_.swap(roots_);
    roots_.swap(roots);
  }
  void ReleaseDead(WorkerPool& workers) {
    workers.ParallelFor(dead_.size(), 64, [&](int slot, size_t b, size_t e) {
      for (size_t k = b; k < e; ++k) trie_.Release(dead_[k], slot);
    });
    dead_.clear();
  }

  std::vector<std::map<uint64_t, uint32_t>> Maps() const {
    std::vector<std::map<uint64_t, uint32_t>> maps(roots_.size());
    for (size_t i = 0; i < roots_.size(); ++i) {
      trie_.ForEach(roots_[i], [&](uint64_t k, const Count& c) { maps[i][k] = c.n; });
    }
    return maps;
  }
  const std::vector<double>& x() const { return x_; }
  const std::vector<Trie::Root>& roots() const { return roots_; }
  Trie& trie() { return trie_; }

 private:
  Trie trie_;
  std::vector<double> x_;
  std::vector<Trie::Root> roots_;
  std::vector<Trie::Root> dead_;
};

struct RunResult {
  std::vector<double> log_w;
  std::vector<double> x;
  std::vector<std::map<uint64_t, uint32_t>> maps;
  uint64_t resamplings;
};

RunResult RunToy(int threads, ResamplingScheme scheme, double threshold) {
  WorkerPool workers(threads);
  ToyModel model(3000, workers.num_slots());
  FilterOptions options;
  options.resampling = scheme;
  options.resample_threshold = threshold;
  options.batch = 37;
  options.seed = 5;
  ParticleFilter<ToyModel> filter(&model, &workers, options);
  for (int step = 0; step < 60; ++step) {
    double drift = step % 20 < 10 ? 0.7 : -0.7;  // back and forth: revisits
    EXPECT_TRUE(filter.Step(drift).ok());
  }
  auto lw = filter.log_weights();
  return {std::vector<double>(lw.begin(), lw.end()), model.x(), model.Maps(), filter.resamplings()};
}

TEST(ParticleFilterTest, SameSeedIsBitIdenticalAtAnyThreadCount) {
  for (ResamplingScheme scheme : {ResamplingScheme::kSystematic, ResamplingScheme::kResidual}) {
    for (double threshold : {0.5, 1.0}) {
      SCOPED_TRACE(testing::Message() << ResamplingSchemeName(scheme) << " " << threshold);
      RunResult one = RunToy(1, scheme, threshold);
      EXPECT_GT(one.resamplings, 0u);
      for (int threads : {2, 4}) {
        RunResult other = RunToy(threads, scheme, threshold);
        EXPECT_EQ(other.log_w, one.log_w) << "threads " << threads;
        EXPECT_EQ(other.x, one.x) << "threads " << threads;
        EXPECT_EQ(other.maps, one.maps) << "threads " << threads;
        EXPECT_EQ(other.resamplings, one.resamplings);
      }
    }
  }
}

TEST(ParticleFilterTest, WeightsAreNormalisedAndThresholdOneResamplesEveryStep) {
  RunResult r = RunToy(2, ResamplingScheme::kSystematic, 1.0);
  EXPECT_EQ(r.resamplings, 60u);
  double total = 0;
  for (double lw : r.log_w) total += std::exp(lw);
  EXPECT_NEAR(total, 1.0, 1e-9);
}

class DegenerateModel {
 public:
  size_t size() const { return 10; }
  void Advance(const int&, uint64_t, size_t b, size_t e, int, double* log_w) {
    for (size_t i = b; i < e; ++i) log_w[i] = -INFINITY;
  }
  void Gather(std::span<const uint32_t>, WorkerPool&) {}
  void ReleaseDead(WorkerPool&) {}
};

TEST(ParticleFilterTest, AllZeroWeightsReportDegeneracyWithStep) {
  WorkerPool workers(1);
  DegenerateModel model;
  ParticleFilter<DegenerateModel> filter(&model, &workers, FilterOptions{});
  Status s = filter.Step(0);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(s.message().find("step 0"), std::string::npos) << s.message();
}

TEST(ParticleFilterTest, MapsOfResampledParticlesAreSharedNotCopied) {
  WorkerPool workers(2);
  ToyModel model(2000, workers.num_slots());
  FilterOptions options;
  options.resample_threshold = 1.0;
  ParticleFilter<ToyModel> filter(&model, &workers, options);
  for (int step = 0; step < 40; ++step) ASSERT_TRUE(filter.Step(0.5).ok());
  // Each particle owns the path it updated last; the rest of its map is shared with relatives.
  int64_t owned_or_shared = 0;
  for (const auto& r : model.roots()) owned_or_shared += model.trie().CountNodes(r);
  EXPECT_LT(model.trie().live_nodes() * 2, owned_or_shared);
}

}  // namespace
}  // namespace grove
