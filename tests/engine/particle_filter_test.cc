#include "engine/filter/particle_filter.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "concurrency/random_stream.h"
#include "engine/filter/filter_driver.h"
#include "engine/filter/generation.h"
#include "engine/io/checkpoint_io.h"
#include "engine/persistent/persistent_trie.h"
#include "engine/persistent/version_set.h"

namespace grove {
namespace {

struct Count {
  uint32_t n;
};
using Trie = PersistentTrie<Count, 4>;
struct Shift {
  double dx;
};

// A toy model: a 1-D random walk whose map counts visits per cell; revisits are rewarded, so
// weights, resampling and map sharing all matter.
class ToyModel {
 public:
  ToyModel(size_t n, int slots) : trie_(4, slots), x_(n, 0.0), roots_(&trie_, n) {}
  size_t size() const { return x_.size(); }

  Status Advance(const double& drift, uint64_t step, size_t begin, size_t end, int slot,
                 double* log_w) {
    for (size_t i = begin; i < end; ++i) {
      RandomStream rs(123, step, static_cast<uint32_t>(i));
      x_[i] += drift + rs.NextNormal();
      uint64_t cell = static_cast<uint64_t>(std::floor(x_[i]) + 30000) & 0xFFFF;
      uint32_t seen = 0;
      if (!trie_.Update(&roots_[i], cell, slot, [&](Count& c, bool) { seen = c.n++; })) {
        return ResourceExhaustedError("out of memory");
      }
      log_w[i] += std::log((seen + 1.0) / (step + 2.0));
    }
    return Status::Ok();
  }
  // A prediction moves without weighting or mapping.
  Status Predict(const Shift& shift, uint64_t step, size_t begin, size_t end, int) {
    for (size_t i = begin; i < end; ++i) {
      RandomStream rs(123, step, static_cast<uint32_t>(i));
      x_[i] += shift.dx + 0.1 * rs.NextNormal();
    }
    return Status::Ok();
  }
  void Gather(std::span<const uint32_t> parents, WorkerPool& workers) {
    std::vector<double> x(parents.size());
    workers.ParallelFor(parents.size(), 64, [&](int, size_t b, size_t e) {
      for (size_t k = b; k < e; ++k) x[k] = x_[parents[k]];
    });
    x_.swap(x);
    roots_.Gather(parents, workers);
  }
  void ReleaseDead(WorkerPool& workers) { roots_.ReleaseDead(workers); }

  std::vector<std::map<uint64_t, uint32_t>> Maps() const {
    std::vector<std::map<uint64_t, uint32_t>> maps(roots_.size());
    for (size_t i = 0; i < roots_.size(); ++i) {
      trie_.ForEach(roots_[i], [&](uint64_t k, const Count& c) { maps[i][k] = c.n; });
    }
    return maps;
  }
  const std::vector<double>& x() const { return x_; }
  std::span<Trie::Root const> roots() const { return roots_.roots(); }
  Trie& trie() { return trie_; }
  Status CheckCounts() const { return trie_.CheckCounts(roots_.AllReferences()); }

 protected:
  Trie trie_;
  std::vector<double> x_;
  VersionSet<Trie> roots_;
};

// The toy model freeing its dead generation in pieces (PieceReleasingModel), which it checks:
// every generation's pieces must partition it, each piece released once.
class PieceToyModel : public ToyModel {
 public:
  using ToyModel::ToyModel;
  void ReleaseDeadRange(size_t lo, size_t hi, int slot) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      pieces_.emplace_back(lo, hi);
    }
    roots_.ReleaseDeadRange(lo, hi, slot);
  }
  void DeadReleased() {
    std::sort(pieces_.begin(), pieces_.end());
    size_t next = 0;
    for (const auto& [lo, hi] : pieces_) {
      if (lo != next || hi < lo) ++bad_partitions_;
      next = hi;
    }
    if (pieces_.empty() || next < size()) ++bad_partitions_;
    pieces_.clear();
    ++generations_;
    roots_.DeadReleased();
  }
  void ReleaseDead(WorkerPool& workers) {
    ++whole_releases_;
    ToyModel::ReleaseDead(workers);
  }
  int bad_partitions_ = 0;
  int generations_ = 0;  // released in pieces
  int whole_releases_ = 0;

 private:
  std::mutex mu_;
  std::vector<std::pair<size_t, size_t>> pieces_;
};

struct RunResult {
  std::vector<double> log_w;
  std::vector<double> x;
  std::vector<std::map<uint64_t, uint32_t>> maps;
  uint64_t resamplings;
};

template <typename Model = ToyModel>
RunResult RunToy(int threads, ResamplingScheme scheme, double threshold) {
  WorkerPool workers(threads);
  Model model(3000, workers.num_slots());
  FilterOptions options;
  options.resampling = scheme;
  options.resample_threshold = threshold;
  options.batch = 37;
  options.seed = 5;
  ParticleFilter<Model> filter(&model, &workers, options);
  for (int step = 0; step < 60; ++step) {
    double drift = step % 20 < 10 ? 0.7 : -0.7;  // back and forth: revisits
    EXPECT_TRUE(filter.Update(drift).ok());
  }
  auto lw = filter.log_weights();
  EXPECT_TRUE(model.CheckCounts().ok()) << model.CheckCounts().ToString();
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

// Freeing the dead generation in pieces during the next advance changes what is shared when,
// never the results.
TEST(ParticleFilterTest, ReleasingInPiecesGivesTheSameResults) {
  for (ResamplingScheme scheme : {ResamplingScheme::kSystematic, ResamplingScheme::kResidual,
                                  ResamplingScheme::kMultinomial}) {
    for (double threshold : {0.5, 1.0}) {
      SCOPED_TRACE(testing::Message() << ResamplingSchemeName(scheme) << " " << threshold);
      RunResult whole = RunToy(1, scheme, threshold);
      for (int threads : {1, 2, 4}) {
        RunResult pieces = RunToy<PieceToyModel>(threads, scheme, threshold);
        EXPECT_EQ(pieces.log_w, whole.log_w) << "threads " << threads;
        EXPECT_EQ(pieces.x, whole.x) << "threads " << threads;
        EXPECT_EQ(pieces.maps, whole.maps) << "threads " << threads;
        EXPECT_EQ(pieces.resamplings, whole.resamplings);
      }
    }
  }
}

// Each batch of the next advance releases a piece; the pieces partition the dead generation.
// Between steps the dead generation is still held (and counted); a prediction releases it in
// pieces as a weighting step does.
TEST(ParticleFilterTest, TheNextAdvanceReleasesTheDeadGenerationInPieces) {
  WorkerPool workers(2);
  PieceToyModel model(2000, workers.num_slots());
  FilterOptions options;
  options.resample_threshold = 1.0;
  options.batch = 64;
  ParticleFilter<PieceToyModel> filter(&model, &workers, options);
  for (int step = 0; step < 20; ++step) {
    ASSERT_TRUE(filter.Update(0.5).ok());
    ASSERT_TRUE(model.CheckCounts().ok()) << model.CheckCounts().ToString();
  }
  EXPECT_EQ(model.generations_, 19);  // the 20th waits for the next advance
  EXPECT_EQ(model.whole_releases_, 0);
  EXPECT_EQ(model.bad_partitions_, 0);
  // A prediction is an advance too: it releases the 20th in pieces.
  ASSERT_TRUE(filter.Predict(Shift{1.0}).ok());
  EXPECT_EQ(model.generations_, 20);
  EXPECT_EQ(model.whole_releases_, 0);
  EXPECT_EQ(model.bad_partitions_, 0);
  ASSERT_TRUE(model.CheckCounts().ok()) << model.CheckCounts().ToString();
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
  Status Advance(const int&, uint64_t, size_t b, size_t e, int, double* log_w) {
    for (size_t i = b; i < e; ++i) log_w[i] = -INFINITY;
    return Status::Ok();
  }
  void Gather(std::span<const uint32_t>, WorkerPool&) {}
  void ReleaseDead(WorkerPool&) {}
};

TEST(ParticleFilterTest, AllZeroWeightsReportDegeneracyWithStep) {
  WorkerPool workers(1);
  DegenerateModel model;
  ParticleFilter<DegenerateModel> filter(&model, &workers, FilterOptions{});
  Status s = filter.Update(0);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(s.message().find("degenerated"), std::string::npos) << s.message();
}

// Predict-only steps move particles, leave weights alone and count as steps of the streams.
TEST(ParticleFilterTest, PredictMovesWithoutWeightingOrResampling) {
  WorkerPool workers(2);
  ToyModel model(1000, workers.num_slots());
  FilterOptions options;
  options.resample_threshold = 1.0;
  ParticleFilter<ToyModel> filter(&model, &workers, options);
  ASSERT_TRUE(filter.Update(0.5).ok());
  const std::vector<double> weights(filter.log_weights().begin(), filter.log_weights().end());
  const std::vector<double> before = model.x();
  ASSERT_TRUE(filter.Predict(Shift{2.0}).ok());
  EXPECT_EQ(filter.steps(), 2u);
  EXPECT_EQ(filter.resamplings(), 1u);
  EXPECT_EQ(std::vector<double>(filter.log_weights().begin(), filter.log_weights().end()), weights);
  double moved = 0;
  for (size_t i = 0; i < before.size(); ++i) moved += model.x()[i] - before[i];
  EXPECT_NEAR(moved / before.size(), 2.0, 0.05);
  EXPECT_TRUE(model.CheckCounts().ok()) << model.CheckCounts().ToString();
}

// A run of predictions in one pass gives the state and step count of one Predict() per input,
// and calls after(j, ...) once per input on batches that cover every particle.
TEST(ParticleFilterTest, PredictRunEqualsOnePredictPerInput) {
  const std::vector<Shift> shifts = {{0.5}, {-1.0}, {2.0}, {0.25}};
  std::vector<double> x_each;
  for (int threads : {1, 2}) {
    WorkerPool workers(threads);
    ToyModel a(1000, workers.num_slots()), b(1000, workers.num_slots());
    FilterOptions options;
    options.resample_threshold = 1.0;
    ParticleFilter<ToyModel> each(&a, &workers, options), run(&b, &workers, options);
    ASSERT_TRUE(each.Update(0.5).ok());
    ASSERT_TRUE(run.Update(0.5).ok());
    for (const Shift& s : shifts) ASSERT_TRUE(each.Predict(s).ok());
    std::vector<size_t> covered(shifts.size(), 0);
    std::mutex mu;
    size_t done = 0;
    ASSERT_TRUE(run.PredictRun(
                       std::span<const Shift>(shifts),
                       [&](size_t j, size_t begin, size_t end) {
                         std::lock_guard<std::mutex> lock(mu);
                         covered[j] += end - begin;
                       },
                       &done)
                    .ok());
    EXPECT_EQ(done, shifts.size());
    EXPECT_EQ(run.steps(), each.steps());
    EXPECT_EQ(b.x(), a.x()) << threads << " threads";
    EXPECT_EQ(covered, std::vector<size_t>(shifts.size(), 1000));
    if (threads == 1) x_each = a.x();
    EXPECT_EQ(b.x(), x_each) << "the run depends on the thread count";
    EXPECT_TRUE(b.CheckCounts().ok()) << b.CheckCounts().ToString();
  }
}

// A run's error is the lowest failing input's, of its lowest failing particle, as one Predict()
// per input would return it, whatever the batches.
class FailingPredictModel {
 public:
  size_t size() const { return 3000; }
  Status Advance(const int&, uint64_t, size_t, size_t, int, double*) { return Status::Ok(); }
  // Input j fails at particles i with i % 1000 == fail_at[j] (none if negative).
  Status Predict(const std::vector<int>& fail_at, uint64_t step, size_t b, size_t e, int) {
    const int f = fail_at[step % fail_at.size()];
    for (size_t i = b; i < e; ++i) {
      if (f >= 0 && static_cast<int>(i % 1000) == f) {
        return OutOfRangeError("step " + std::to_string(step) + " particle " + std::to_string(i));
      }
    }
    return Status::Ok();
  }
  void Gather(std::span<const uint32_t>, WorkerPool&) {}
  void ReleaseDead(WorkerPool&) {}
};

TEST(ParticleFilterTest, PredictRunReportsTheLowestFailingInputAndParticle) {
  // Input 1 fails late in the particles, input 2 early: the run stops at input 1's particle 900.
  const std::vector<int> fail_at = {-1, 900, 5, -1};
  std::vector<std::vector<int>> inputs(4, fail_at);
  for (int threads : {1, 2}) {
    for (size_t batch : {64, 4096}) {
      WorkerPool workers(threads);
      FailingPredictModel model;
      FilterOptions options;
      options.batch = batch;
      ParticleFilter<FailingPredictModel> filter(&model, &workers, options);
      size_t done = 0;
      Status s = filter.PredictRun(
          std::span<const std::vector<int>>(inputs), [](size_t, size_t, size_t) {}, &done);
      EXPECT_EQ(s.message(), "step 1 particle 900") << threads << " threads, batch " << batch;
      EXPECT_EQ(done, 1u);
      EXPECT_EQ(filter.steps(), 2u);  // the failed step counts, as Predict()'s does
    }
  }
}

// A model whose particles fail in several batches: the step reports the lowest failing
// particle's error, whatever the thread count and batch size.
class FailingModel {
 public:
  size_t size() const { return 5000; }
  Status Advance(const int&, uint64_t, size_t b, size_t e, int, double*) {
    for (size_t i = b; i < e; ++i) {
      if (i % 1777 == 1234) return OutOfRangeError("particle " + std::to_string(i));
    }
    return Status::Ok();
  }
  void Gather(std::span<const uint32_t>, WorkerPool&) {}
  void ReleaseDead(WorkerPool&) {}
};

TEST(ParticleFilterTest, ReportsTheLowestFailingBatchAtAnyThreadCount) {
  for (int threads : {1, 2, 4}) {
    for (size_t batch : {1, 7, 512, 100000}) {
      WorkerPool workers(threads);
      FailingModel model;
      FilterOptions options;
      options.batch = batch;
      ParticleFilter<FailingModel> filter(&model, &workers, options);
      Status s = filter.Update(0);
      EXPECT_EQ(s.code(), StatusCode::kOutOfRange);
      EXPECT_EQ(s.message(), "particle 1234") << threads << " threads, batch " << batch;
    }
  }
}

// The population phase runs once the particles are drawn and sees all of them: after Advance
// (before normalising) for a model without Complete, after resampling and Complete for one with
// it.
template <bool kCompletes>
class PhaseOrderModel {
 public:
  size_t size() const { return 100; }
  Status Advance(const int&, uint64_t, size_t b, size_t e, int, double* log_w) {
    for (size_t i = b; i < e; ++i) {
      log_w[i] += static_cast<double>(i % 3);
      drawn_[i] = 1;
    }
    return Status::Ok();
  }
  Status Complete(const int&, uint64_t, size_t b, size_t e, int) requires kCompletes {
    for (size_t i = b; i < e; ++i) drawn_[i] = 2;
    return Status::Ok();
  }
  Status Population(const int&, uint64_t, WorkerPool&) {
    seen_ = drawn_;
    events_.push_back("population");
    return Status::Ok();
  }
  void Gather(std::span<const uint32_t>, WorkerPool&) { events_.push_back("gather"); }
  void ReleaseDead(WorkerPool&) {}
  std::vector<std::string> events_;
  std::vector<int> drawn_ = std::vector<int>(100, 0), seen_;
};

TEST(ParticleFilterTest, PopulationPhaseRunsAfterTheDraw) {
  WorkerPool workers(2);
  FilterOptions options;
  options.resample_threshold = 1.0;  // resample every step
  {
    PhaseOrderModel<false> model;
    ParticleFilter<PhaseOrderModel<false>> filter(&model, &workers, options);
    ASSERT_TRUE(filter.Update(0).ok());
    EXPECT_EQ(model.events_, (std::vector<std::string>{"population", "gather"}));
    EXPECT_EQ(model.seen_, std::vector<int>(100, 1));
  }
  {
    PhaseOrderModel<true> model;
    ParticleFilter<PhaseOrderModel<true>> filter(&model, &workers, options);
    ASSERT_TRUE(filter.Update(0).ok());
    EXPECT_EQ(model.events_, (std::vector<std::string>{"gather", "population"}));
    EXPECT_EQ(model.seen_, std::vector<int>(100, 2));
  }
}

// GatherShared over lists whose runs of copies end inside a chunk, exactly at a chunk's end,
// cross one chunk's edge and span whole chunks (2,048 particles each), on 1, 2 and 4 threads:
// every copy refers to its parent's handle, a parent with c copies is shared c - 1 times, and
// exactly the parents no copy names are left behind.
TEST(GenerationTest, GatherSharedLeavesExactlyTheDeadHandles) {
  const size_t n = 3 * 2048 + 100;
  std::vector<std::vector<uint32_t>> lists;
  std::vector<uint32_t> parents(n);
  for (size_t k = 0; k < n; ++k) parents[k] = static_cast<uint32_t>(k / 3 * 3);
  lists.push_back(parents);  // runs of 3, some crossing a chunk's edge
  for (size_t k = 0; k < n; ++k) parents[k] = static_cast<uint32_t>(k < 2048 ? k / 2 * 2 : 2048);
  lists.push_back(parents);  // a run ending at a chunk's end, then one over two whole chunks
  for (size_t k = 0; k < n; ++k) parents[k] = 7;
  lists.push_back(parents);  // one parent
  RandomStream rng(5, 0, 0, StreamPurpose::kMotion);
  uint32_t p = 0;
  for (size_t k = 0; k < n; ++k) {
    if (rng.NextUniform() < 0.4) p += 1 + static_cast<uint32_t>(rng.NextUniform() * 3);
    parents[k] = std::min<uint32_t>(p, static_cast<uint32_t>(n - 1));
  }
  lists.push_back(parents);  // random gaps
  for (const std::vector<uint32_t>& list : lists) {
    for (int threads : {1, 2, 4}) {
      WorkerPool workers(threads);
      std::vector<int> handles(n);
      std::vector<int*> current(n), next;
      for (size_t i = 0; i < n; ++i) current[i] = &handles[i];
      std::atomic<int> shares{0};
      GatherShared(
          list, &current, workers,
          [&](int* h) {
            shares.fetch_add(1);
            return h;
          },
          &next);
      std::set<uint32_t> named(list.begin(), list.end());
      ASSERT_EQ(next.size(), n);
      for (size_t k = 0; k < n; ++k) ASSERT_EQ(next[k], &handles[list[k]]) << k;
      EXPECT_EQ(shares.load(), static_cast<int>(n - named.size())) << threads;
      for (size_t i = 0; i < n; ++i) {
        ASSERT_EQ(current[i], named.count(static_cast<uint32_t>(i)) ? nullptr : &handles[i])
            << i << " on " << threads << " threads";
      }
    }
  }
}

// GatherShared in parts (GatherSharedRange on each chunk, GatherSharedSeams after), as a model
// that gathers in its own loop runs it: with chunks of 64, 100 and 2,048 particles on 1 and 2
// threads, the same copies, shares and dead handles as the whole GatherShared.
TEST(GenerationTest, GatherSharedInChunksMatchesTheWhole) {
  const size_t n = 1000;
  std::vector<uint32_t> parents(n);
  RandomStream rng(6, 0, 0, StreamPurpose::kMotion);
  uint32_t p = 0;
  for (size_t k = 0; k < n; ++k) {
    if (rng.NextUniform() < 0.3) p += 1 + static_cast<uint32_t>(rng.NextUniform() * 3);
    parents[k] = std::min<uint32_t>(p, static_cast<uint32_t>(n - 1));
  }
  for (size_t k = 60; k < 200; ++k) parents[k] = parents[60];  // a run over chunks' edges
  std::vector<int> handles(n);
  auto fresh = [&] {
    std::vector<int*> current(n);
    for (size_t i = 0; i < n; ++i) current[i] = &handles[i];
    return current;
  };
  WorkerPool one(1);
  std::vector<int*> whole_current = fresh(), whole_next;
  GatherShared(
      parents, &whole_current, one, [](int* h) { return h; }, &whole_next);
  for (int threads : {1, 2}) {
    for (size_t grain : {64, 100, 2048}) {
      WorkerPool workers(threads);
      std::vector<int*> current = fresh(), next(n);
      std::atomic<int> shares{0};
      auto share = [&](int* h) {
        shares.fetch_add(1);
        return h;
      };
      workers.ParallelFor(n, grain, [&](int, size_t b, size_t e) {
        GatherSharedRange(std::span<const uint32_t>(parents), &current, share, &next, b, e);
      });
      GatherSharedSeams(std::span<const uint32_t>(parents), grain, &current);
      std::set<uint32_t> named(parents.begin(), parents.end());
      EXPECT_EQ(next, whole_next) << grain << " on " << threads;
      EXPECT_EQ(current, whole_current) << grain << " on " << threads;
      EXPECT_EQ(shares.load(), static_cast<int>(n - named.size()));
    }
  }
}

// A model that gathers in chunks: values 0 .. n-1 to start, weights that favour some particles.
class ChunkGatherModel {
 public:
  explicit ChunkGatherModel(size_t n) : value_(n) {
    for (size_t i = 0; i < n; ++i) value_[i] = static_cast<double>(i);
  }
  size_t size() const { return value_.size(); }
  Status Advance(const int&, uint64_t, size_t begin, size_t end, int, double* log_w) {
    for (size_t i = begin; i < end; ++i) log_w[i] += -0.3 * static_cast<double>(i % 7);
    std::lock_guard<std::mutex> lock(mu_);
    batches_.emplace_back(begin, end);
    return Status::Ok();
  }
  void GatherBegin(std::span<const uint32_t> parents) { next_.assign(parents.size(), -1); }
  void GatherRange(std::span<const uint32_t> parents, size_t b, size_t e) {
    for (size_t k = b; k < e; ++k) next_[k] = value_[parents[k]];
    std::lock_guard<std::mutex> lock(mu_);
    chunks_.emplace_back(b, e);
  }
  void GatherEnd(std::span<const uint32_t> parents, size_t grain) {
    parents_.assign(parents.begin(), parents.end());
    grain_ = grain;
    value_.swap(next_);
  }
  void ReleaseDead(WorkerPool&) {}

  std::vector<double> value_, next_;
  std::vector<uint32_t> parents_;
  size_t grain_ = 0;
  std::mutex mu_;
  std::vector<std::pair<size_t, size_t>> batches_, chunks_;
};

// The filter gathers a chunk-gathering model in one loop whose chunks are the advance's batches
// (so each particle's new values are written where it is advanced next), and each particle gets
// its parent's value, on 1 to 3 threads and with batches that do and do not divide the count.
TEST(ParticleFilterTest, ChunkGatheringModelGathersInItsBatches) {
  for (int threads : {1, 2, 3}) {
    for (size_t batch : {16, 24, 512}) {
      WorkerPool workers(threads);
      ChunkGatherModel model(100);
      FilterOptions options;
      options.batch = batch;
      options.resample_threshold = 1.0;  // resample at every step
      ParticleFilter<ChunkGatherModel> filter(&model, &workers, options);
      ASSERT_TRUE(filter.Update(0).ok());
      std::sort(model.batches_.begin(), model.batches_.end());
      std::sort(model.chunks_.begin(), model.chunks_.end());
      EXPECT_EQ(model.chunks_, model.batches_) << batch << " on " << threads;
      EXPECT_EQ(model.grain_, BatchSize(workers, 100, batch));
      ASSERT_EQ(model.parents_.size(), 100u);
      EXPECT_NE(model.parents_.front(), model.parents_.back());  // a real resampling
      for (size_t k = 0; k < 100; ++k) ASSERT_EQ(model.value_[k], model.parents_[k]) << k;
    }
  }
}

TEST(GenerationTest, GatherValuesTogetherMatchesOneAtATime) {
  const size_t n = 10000;
  std::vector<uint32_t> parents(n);
  for (size_t k = 0; k < n; ++k) parents[k] = static_cast<uint32_t>(k / 4 * 4 + 1);
  for (int threads : {1, 2}) {
    WorkerPool workers(threads);
    std::vector<double> a(n), a_one, spare_a;
    std::vector<uint64_t> b(n), b_one, spare_b;
    for (size_t i = 0; i < n; ++i) {
      a[i] = 0.5 * static_cast<double>(i);
      b[i] = 3 * i + 1;
    }
    a_one = a;
    b_one = b;
    GatherValues(parents, workers, &a_one);
    GatherValues(parents, workers, &b_one);
    GatherValuesTogether(parents, workers, Gathered<double>{&a, &spare_a},
                         Gathered<uint64_t>{&b, &spare_b});
    EXPECT_EQ(a, a_one);
    EXPECT_EQ(b, b_one);
    EXPECT_EQ(a[6], 2.5);  // particle 6 copies particle 5 (4 + 1)
  }
}

TEST(ParticleFilterTest, MapsOfResampledParticlesAreSharedNotCopied) {
  WorkerPool workers(2);
  ToyModel model(2000, workers.num_slots());
  FilterOptions options;
  options.resample_threshold = 1.0;
  ParticleFilter<ToyModel> filter(&model, &workers, options);
  for (int step = 0; step < 40; ++step) ASSERT_TRUE(filter.Update(0.5).ok());
  // Each particle owns the path it updated last; the rest of its map is shared with relatives.
  int64_t owned_or_shared = 0;
  for (const auto& r : model.roots()) owned_or_shared += model.trie().CountNodes(r);
  EXPECT_LT(model.trie().live_nodes() * 2, owned_or_shared);
  EXPECT_TRUE(model.CheckCounts().ok()) << model.CheckCounts().ToString();
}

// Island mode on a model whose particles carry the island they started in: particles move
// between islands only at exchanges, and then only to the next island.
class OriginModel {
 public:
  OriginModel(size_t n, size_t island) : origin_(n), value_(n, 0.0) {
    for (size_t i = 0; i < n; ++i) origin_[i] = static_cast<uint32_t>(i / island);
  }
  size_t size() const { return origin_.size(); }
  Status Advance(const double&, uint64_t step, size_t begin, size_t end, int, double* log_w) {
    for (size_t i = begin; i < end; ++i) {
      RandomStream rs(9, step, static_cast<uint32_t>(i));
      value_[i] += rs.NextNormal();
      log_w[i] += -0.5 * value_[i] * value_[i] * 0.01;
    }
    return Status::Ok();
  }
  void Gather(std::span<const uint32_t> parents, WorkerPool&) {
    // Each parent's copies are adjacent, and no parent appears twice.
    for (size_t k = 1; k < parents.size(); ++k) {
      if (parents[k] != parents[k - 1]) {
        EXPECT_TRUE(seen_.insert(parents[k]).second) << k;
      }
    }
    seen_.clear();
    std::vector<uint32_t> origin(parents.size());
    std::vector<double> value(parents.size());
    for (size_t k = 0; k < parents.size(); ++k) {
      origin[k] = origin_[parents[k]];
      value[k] = value_[parents[k]];
    }
    origin_.swap(origin);
    value_.swap(value);
  }
  void ReleaseDead(WorkerPool&) {}
  void Export(std::span<const uint32_t> which, ByteWriter* w) const {
    for (uint32_t i : which) {
      w->Put(origin_[i]);
      w->Put(value_[i]);
    }
  }
  Status Import(ByteReader* r, size_t count, uint64_t) {
    for (size_t k = 0; k < count; ++k) {
      uint32_t origin = 0;
      double value = 0;
      GROVE_RETURN_IF_ERROR(r->Get("origin", &origin));
      GROVE_RETURN_IF_ERROR(r->Get("value", &value));
      origin_.push_back(origin);
      value_.push_back(value);
    }
    return Status::Ok();
  }
  const std::vector<uint32_t>& origin() const { return origin_; }
  const std::vector<double>& value() const { return value_; }

 private:
  std::vector<uint32_t> origin_;
  std::vector<double> value_;
  std::set<uint32_t> seen_;
};

// Island mode (whose exchanges put migrants among an island's own copies, so parents are not one
// nondecreasing list) releases the dead generation whole even for a model that could take it in
// pieces.
class PieceOriginModel : public OriginModel {
 public:
  using OriginModel::OriginModel;
  void ReleaseDead(WorkerPool&) { ++whole_releases_; }
  void ReleaseDeadRange(size_t, size_t, int) { ++pieces_; }
  void DeadReleased() {}
  int whole_releases_ = 0;
  std::atomic<int> pieces_{0};
};

TEST(ParticleFilterTest, IslandsReleaseTheDeadGenerationWhole) {
  WorkerPool workers(2);
  PieceOriginModel model(4 * kSumBlock, kSumBlock);
  FilterOptions options;
  options.resample_threshold = 1.0;
  options.islands = 4;
  ParticleFilter<PieceOriginModel> filter(&model, &workers, options);
  for (int step = 0; step < 5; ++step) ASSERT_TRUE(filter.Update(0.0).ok());
  EXPECT_EQ(model.whole_releases_, 5);
  EXPECT_EQ(model.pieces_.load(), 0);
}

struct IslandRun {
  Status status;
  std::vector<uint32_t> origin;
  std::vector<double> value;
  uint64_t resamplings = 0;
};

IslandRun RunIslands(int threads, int steps, double fraction, uint64_t exchange_steps,
                     int islands = 4) {
  constexpr size_t kIsland = kSumBlock;
  WorkerPool workers(threads);
  OriginModel model(4 * kIsland, kIsland);
  FilterOptions options;
  options.resample_threshold = 0.9;
  options.islands = islands;
  options.exchange_fraction = fraction;
  options.exchange_steps = exchange_steps;
  ParticleFilter<OriginModel> filter(&model, &workers, options);
  IslandRun run;
  for (int k = 0; k < steps && run.status.ok(); ++k) run.status = filter.Update(0.0);
  run.origin = model.origin();
  run.value = model.value();
  run.resamplings = filter.resamplings();
  return run;
}

TEST(ParticleFilterTest, IslandsWithoutExchangeKeepTheirLineages) {
  IslandRun run = RunIslands(2, 30, 0.0, 5);
  ASSERT_TRUE(run.status.ok()) << run.status.message();
  EXPECT_GE(run.resamplings, 6u);  // every 5 steps at least
  for (size_t i = 0; i < run.origin.size(); ++i) {
    ASSERT_EQ(run.origin[i], i / kSumBlock) << "particle " << i;
  }
}

TEST(ParticleFilterTest, AnExchangeSendsASampleToTheNextIsland) {
  // Steps 0 to 3: the exchange is the fourth step's; before it nothing left its island.
  IslandRun run = RunIslands(2, 4, 0.25, 4);
  ASSERT_TRUE(run.status.ok()) << run.status.message();
  const size_t m = kSumBlock / 4;
  for (size_t j = 0; j < 4; ++j) {
    for (size_t k = 0; k < kSumBlock; ++k) {
      // An island's own draws first, then the previous island's migrants.
      const uint32_t want = k < kSumBlock - m ? j : (j + 3) % 4;
      ASSERT_EQ(run.origin[j * kSumBlock + k], want) << "island " << j << " slot " << k;
    }
  }
}

TEST(ParticleFilterTest, IslandsAreBitIdenticalAtAnyThreadCount) {
  IslandRun one = RunIslands(1, 40, 0.1, 3);
  ASSERT_TRUE(one.status.ok()) << one.status.message();
  IslandRun two = RunIslands(2, 40, 0.1, 3);
  EXPECT_EQ(two.origin, one.origin);
  EXPECT_EQ(two.value, one.value);
  std::set<uint32_t> origins_of_island_0(one.origin.begin(), one.origin.begin() + kSumBlock);
  EXPECT_GT(origins_of_island_0.size(), 1u);  // particles did move
}

TEST(ParticleFilterTest, IslandsNeedWholeBlocksAndSystematicResampling) {
  IslandRun run = RunIslands(1, 1, 0.1, 3, 5);
  EXPECT_EQ(run.status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(run.status.message().find("islands = 5: an island needs a block"), std::string::npos)
      << run.status.message();
  WorkerPool workers(1);
  OriginModel model(2 * kSumBlock, kSumBlock);
  FilterOptions options;
  options.islands = 2;
  options.resampling = ResamplingScheme::kResidual;
  ParticleFilter<OriginModel> filter(&model, &workers, options);
  Status s = filter.Update(0.0);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("systematically"), std::string::npos) << s.message();
}

// A posed model for FilterDriver: particle i at (i, step)-dependent poses, weighted unevenly.
class PosedToy {
 public:
  explicit PosedToy(size_t n) : x_(n), y_(n), h_(n) {
    for (size_t i = 0; i < n; ++i) Move(i, 0);
  }
  size_t size() const { return x_.size(); }
  Status Advance(const double&, uint64_t, size_t begin, size_t end, int, double* log_w) {
    for (size_t i = begin; i < end; ++i) log_w[i] += -0.001 * static_cast<double>(i % 97);
    return Status::Ok();
  }
  Status Predict(const Shift& shift, uint64_t step, size_t begin, size_t end, int) {
    for (size_t i = begin; i < end; ++i) Move(i, step + 1, shift.dx);
    return Status::Ok();
  }
  void Gather(std::span<const uint32_t>, WorkerPool&) {}
  void ReleaseDead(WorkerPool&) {}
  double x(size_t i) const { return x_[i]; }
  double y(size_t i) const { return y_[i]; }
  double cos_heading(size_t i) const { return std::cos(h_[i]); }
  double sin_heading(size_t i) const { return std::sin(h_[i]); }

 protected:
  void Nudge(size_t i, double dx) { x_[i] += dx; }

 private:
  void Move(size_t i, uint64_t step, double dx = 0) {
    RandomStream rs(9, step, static_cast<uint32_t>(i));
    x_[i] += dx + rs.NextNormal();
    y_[i] = 1000 * rs.NextNormal();
    h_[i] = rs.NextNormal();
  }
  std::vector<double> x_, y_, h_;
};

// PosedToy whose update ends after resampling (Complete() moves every particle), then runs a
// population phase that moves them again when `population_moves`.
class CompletingToy : public PosedToy {
 public:
  CompletingToy(size_t n, bool population_moves) : PosedToy(n), moves_(population_moves) {}
  Status Complete(const double&, uint64_t, size_t begin, size_t end, int) {
    for (size_t i = begin; i < end; ++i) Nudge(i, 0.125 * static_cast<double>(i % 7));
    return Status::Ok();
  }
  bool PopulationMoves(const double&) const { return moves_; }
  Status Population(const double&, uint64_t, WorkerPool&) {
    if (!moves_) return Status::Ok();
    for (size_t i = 0; i < size(); ++i) Nudge(i, -0.5 * static_cast<double>(i % 5));
    return Status::Ok();
  }

 private:
  bool moves_;
};

// The documented mean pose: per block of kSumBlock particles, the sums of its sub-blocks of
// kMeanSubBlock (each added in index order) added in order; the blocks added in order.
Pose2 ReferenceMean(const PosedToy& m, std::span<const double> lw) {
  double w = 0, x = 0, y = 0, c = 0, s = 0;
  for (size_t b = 0; b < m.size(); b += kSumBlock) {
    double bw = 0, bx = 0, by = 0, bc = 0, bs = 0;
    for (size_t k = b; k < std::min(m.size(), b + kSumBlock); k += kMeanSubBlock) {
      double sw = 0, sx = 0, sy = 0, sc = 0, ss = 0;
      for (size_t i = k; i < std::min(m.size(), k + kMeanSubBlock); ++i) {
        const double wi = std::exp(lw[i]);
        sw += wi;
        sx += wi * m.x(i);
        sy += wi * m.y(i);
        sc += wi * m.cos_heading(i);
        ss += wi * m.sin_heading(i);
      }
      bw += sw, bx += sx, by += sy, bc += sc, bs += ss;
    }
    w += bw, x += bx, y += by, c += bc, s += bs;
  }
  return Pose2{x / w, y / w, std::atan2(s, c)};
}

// Bit for bit.
void ExpectSamePose(const Pose2& got, const Pose2& want) {
  EXPECT_EQ(got.x_m, want.x_m);
  EXPECT_EQ(got.y_m, want.y_m);
  EXPECT_EQ(got.heading_rad, want.heading_rad);
}

// Mean poses after an update and over a run of predictions: the documented sums, bit for bit,
// at any thread count and batch size (5,000 particles: two blocks, a partial sub-block).
TEST(FilterDriverTest, MeanPoseIsTheSumOfFixedSubBlocksAtAnyThreadCount) {
  constexpr size_t kN = 5000;
  for (int threads : {1, 2, 3}) {
    for (size_t batch : {1, 50, 512}) {
      SCOPED_TRACE(testing::Message() << threads << " threads, batch " << batch);
      WorkerPool workers(threads);
      PosedToy model(kN);
      FilterOptions options;
      options.batch = batch;
      options.resample_threshold = 1e-9;  // keep the uneven weights
      FilterDriver<PosedToy> driver(&model, &workers, options, threads, Pose2{},
                                    TimeOrder::kNonDecreasing);
      ASSERT_TRUE(driver.Update(1.0, 0.0).ok());
      const std::vector<double> times = {2.0, 3.0, 4.0};
      const std::vector<Shift> shifts = {{0.5}, {-0.25}, {1.0}};
      const Pose2 after_update = ReferenceMean(model, driver.filter().log_weights());
      ASSERT_TRUE(
          driver.PredictRun(std::span<const double>(times), std::span<const Shift>(shifts)).ok());
      const Pose2 after_run = ReferenceMean(model, driver.filter().log_weights());
      const std::vector<StampedPose>& mean = driver.mean_trajectory();
      ASSERT_EQ(mean.size(), 5u);
      ExpectSamePose(mean[1].pose, after_update);
      ExpectSamePose(mean[4].pose, after_run);
    }
  }
}

// An update's mean pose is the documented sum of the particles as the whole step left them:
// summed in the batches of the loop that completes it when nothing moves them after, on the
// driving thread after a population phase that does.
TEST(FilterDriverTest, UpdateMeanPoseCountsWhatCompletesTheStep) {
  constexpr size_t kN = 5000;
  for (bool population_moves : {false, true}) {
    for (int threads : {1, 2, 3}) {
      for (size_t batch : {1, 50, 512}) {
        SCOPED_TRACE(testing::Message() << "population moves " << population_moves << ", "
                                        << threads << " threads, batch " << batch);
        WorkerPool workers(threads);
        CompletingToy model(kN, population_moves);
        FilterOptions options;
        options.batch = batch;
        options.resample_threshold = 1e-9;  // keep the uneven weights
        FilterDriver<CompletingToy> driver(&model, &workers, options, threads, Pose2{},
                                           TimeOrder::kNonDecreasing);
        const double x0 = model.x(6);
        ASSERT_TRUE(driver.Update(1.0, 0.0).ok());
        ASSERT_EQ(model.x(6), x0 + 0.75 + (population_moves ? -0.5 : 0.0));
        const Pose2 want = ReferenceMean(model, driver.filter().log_weights());
        const std::vector<StampedPose>& mean = driver.mean_trajectory();
        ASSERT_EQ(mean.size(), 2u);
        ExpectSamePose(mean[1].pose, want);
      }
    }
  }
}

}  // namespace
}  // namespace grove
