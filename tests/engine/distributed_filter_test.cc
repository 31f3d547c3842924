// One FootSLAM filter across K ranks (threads of this process, joined by InProcessCollective)
// gives, bit for bit, what one filter holding every particle gives: weights, poses, paths and
// maps of every particle, the heaviest particle and the resampling count.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "concurrency/worker_pool.h"
#include "engine/filter/particle_filter.h"
#include "engine/filter/resampler.h"
#include "engine/footslam/alphabet.h"
#include "engine/footslam/alphabet_htree_map.h"
#include "engine/footslam/footslam_model.h"
#include "engine/footslam/hex_grid.h"
#include "engine/footslam/htree_layout.h"
#include "engine/footslam/htree_map.h"
#include "engine/footslam/naive_map.h"
#include "engine/io/checkpoint_io.h"
#include "engine/ranks/collective.h"
#include "grove/footslam.h"

namespace grove::footslam {
namespace {

// Laps of a 12 m x 6 m corridor loop in 0.7 m steps: enough revisits that weights differ and
// the filter resamples often.
std::vector<StepInput> Loop(int steps) {
  std::vector<StepInput> out;
  const double legs[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
  const int leg_steps[4] = {17, 9, 17, 9};
  for (int k = 0, leg = 0, done = 0; k < steps; ++k) {
    out.push_back({0.7 * legs[leg][0], 0.7 * legs[leg][1]});
    if (++done == leg_steps[leg]) {
      done = 0;
      leg = (leg + 1) % 4;
    }
  }
  return out;
}

// What one rank ends with: its particles' state written out in order, one record each, and
// the filter's counters.
struct RankResult {
  Status status;
  std::vector<double> log_w;
  std::vector<std::string> particles;  // pose, errors, path, map
  uint64_t heaviest = 0;
  uint64_t resamplings = 0;
  double mean_ess = 0;
  uint64_t sent_bytes = 0;
  Status counts;  // CheckCounts() after the run
};

template <typename Map>
RankResult RunRank(FootSlamConfig config, const std::vector<StepInput>& steps,
                   Collective* collective, int threads, uint64_t seed_on_rank_1 = 0) {
  if (seed_on_rank_1 != 0 && collective != nullptr && collective->rank() == 1) {
    config.seed = seed_on_rank_1;
  }
  RankResult out;
  const int ranks = collective == nullptr ? 1 : collective->size();
  const int rank = collective == nullptr ? 0 : collective->rank();
  const ParticleShare share =
      RankShare(static_cast<uint64_t>(config.particles), ranks, rank, kSumBlock);
  HexGrid grid(config.hex_radius_m);
  HTreeLayout layout = *HTreeLayout::Create(config.grid_size, config.degree);
  Alphabet alphabet = *Alphabet::Create(config.alphabet);
  WorkerPool workers(threads);
  Map map(layout, threads, share.count, &alphabet);
  FootSlamModel<Map> model(config, &grid, &layout, &map, threads, share);
  EXPECT_TRUE(model.Init());
  FilterOptions options;
  options.seed = config.seed;
  options.batch = 512;
  options.collective = collective;
  options.total_particles = static_cast<uint64_t>(config.particles);
  options.islands = config.islands;
  options.exchange_steps = static_cast<uint64_t>(config.island_exchange_steps);
  options.exchange_fraction = config.island_exchange_fraction;
  ParticleFilter<FootSlamModel<Map>> filter(&model, &workers, options);
  for (const StepInput& in : steps) {
    out.status = filter.Update(in);
    if (!out.status.ok()) return out;
  }
  out.log_w.assign(filter.log_weights().begin(), filter.log_weights().end());
  for (size_t i = 0; i < model.size(); ++i) {
    ByteWriter w;
    w.Put(model.x(i));
    w.Put(model.y(i));
    w.Put(model.heading(i));
    w.Put(model.heading_error(i));
    w.Put(model.scale(i));
    for (const auto* n : PoseHistory::Path(model.history(i))) {
      w.Put(n->step);
      w.Put(n->value);
    }
    model.map().ForEachHex(i, [&](uint64_t key, const Htc& h) {
      w.Put(key);
      w.Put(h);
    });
    out.particles.push_back(w.Take());
  }
  out.heaviest = filter.heaviest();
  out.resamplings = filter.resamplings();
  out.mean_ess = filter.mean_ess();
  out.sent_bytes = filter.sent_bytes();
  out.counts = model.CheckCounts();
  return out;
}

template <typename Map>
std::vector<RankResult> RunRanks(const FootSlamConfig& config, const std::vector<StepInput>& steps,
                                 int ranks, int threads, uint64_t seed_on_rank_1 = 0) {
  std::vector<RankResult> results(static_cast<size_t>(ranks));
  std::vector<std::unique_ptr<Collective>> endpoints = InProcessCollective::Create(ranks);
  std::vector<std::thread> pool;
  for (int r = 0; r < ranks; ++r) {
    pool.emplace_back([&, r] {
      results[static_cast<size_t>(r)] = RunRank<Map>(
          config, steps, endpoints[static_cast<size_t>(r)].get(), threads, seed_on_rank_1);
    });
  }
  for (std::thread& t : pool) t.join();
  return results;
}

FootSlamConfig TestConfig() {
  FootSlamConfig config;
  // Three whole blocks and part of a fourth: the last rank's share ends mid-block.
  config.particles = 3 * static_cast<int64_t>(kSumBlock) + 517;
  config.grid_size = 64;
  config.seed = 7;
  return config;
}

template <typename Map>
void ExpectSameAsOneProcess(int ranks, int threads, const FootSlamConfig& config = TestConfig()) {
  SCOPED_TRACE(std::to_string(ranks) + " ranks, " + std::to_string(threads) + " threads each, " +
               std::to_string(config.islands) + " islands");
  const std::vector<StepInput> steps = Loop(120);
  RankResult one = RunRank<Map>(config, steps, nullptr, 1);
  ASSERT_TRUE(one.status.ok()) << one.status.message();
  ASSERT_TRUE(one.counts.ok()) << one.counts.message();
  ASSERT_GT(one.resamplings, 10u);  // the exchange is exercised
  std::vector<RankResult> parts = RunRanks<Map>(config, steps, ranks, threads);
  std::vector<double> log_w;
  std::vector<std::string> particles;
  uint64_t sent = 0;
  for (const RankResult& p : parts) {
    ASSERT_TRUE(p.status.ok()) << p.status.message();
    ASSERT_TRUE(p.counts.ok()) << p.counts.message();
    EXPECT_EQ(p.heaviest, one.heaviest);
    EXPECT_EQ(p.resamplings, one.resamplings);
    EXPECT_EQ(std::memcmp(&p.mean_ess, &one.mean_ess, sizeof(double)), 0);
    log_w.insert(log_w.end(), p.log_w.begin(), p.log_w.end());
    particles.insert(particles.end(), p.particles.begin(), p.particles.end());
    sent += p.sent_bytes;
  }
  ASSERT_EQ(log_w.size(), one.log_w.size());
  EXPECT_EQ(std::memcmp(log_w.data(), one.log_w.data(), log_w.size() * sizeof(double)), 0);
  ASSERT_EQ(particles.size(), one.particles.size());
  size_t differ = 0;
  for (size_t i = 0; i < particles.size(); ++i) differ += particles[i] != one.particles[i];
  EXPECT_EQ(differ, 0u);
  if (ranks > 1) {
    EXPECT_GT(sent, 0u);  // particles did move
  }
}

TEST(DistributedFilterTest, HTreeAcrossRanksIsBitIdentical) {
  ExpectSameAsOneProcess<HTreeMap<4>>(2, 1);
  ExpectSameAsOneProcess<HTreeMap<4>>(3, 2);
}

TEST(DistributedFilterTest, AlphabetHTreeAcrossRanksIsBitIdentical) {
  ExpectSameAsOneProcess<AlphabetHTreeMap<4>>(2, 2);
  ExpectSameAsOneProcess<AlphabetHTreeMap<4>>(4, 1);
}

TEST(DistributedFilterTest, NaiveAcrossRanksIsBitIdentical) {
  ExpectSameAsOneProcess<NaiveMap>(3, 1);
}

// Island mode: the islands, not the ranks, decide the results.
TEST(DistributedFilterTest, IslandsGiveTheSameResultsAtAnyRankCount) {
  FootSlamConfig config = TestConfig();
  config.islands = 4;  // four blocks: one each, the last of 517 particles
  config.island_exchange_steps = 7;
  config.island_exchange_fraction = 0.2;
  ExpectSameAsOneProcess<AlphabetHTreeMap<4>>(2, 2, config);
  ExpectSameAsOneProcess<AlphabetHTreeMap<4>>(4, 1, config);
  // Not the global mode's results.
  const std::vector<StepInput> steps = Loop(120);
  RankResult islands = RunRank<AlphabetHTreeMap<4>>(config, steps, nullptr, 2);
  RankResult global = RunRank<AlphabetHTreeMap<4>>(TestConfig(), steps, nullptr, 2);
  ASSERT_EQ(islands.particles.size(), global.particles.size());
  size_t differ = 0;
  for (size_t i = 0; i < islands.particles.size(); ++i) {
    differ += islands.particles[i] != global.particles[i];
  }
  EXPECT_GT(differ, islands.particles.size() / 2);
}

// Islands must be whole on every rank: 3 islands over 2 ranks stop both, with one error.
TEST(DistributedFilterTest, IslandsThatDoNotDivideAmongTheRanksStopEveryRank) {
  FootSlamConfig config = TestConfig();
  config.islands = 3;
  for (const RankResult& p : RunRanks<HTreeMap<4>>(config, Loop(5), 2, 1)) {
    EXPECT_EQ(p.status.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(p.status.message().find("islands = 3: must be a multiple of the ranks (2)"),
              std::string::npos)
        << p.status.message();
  }
}

TEST(DistributedFilterTest, RankSharesAreWholeBlocksInOrder) {
  for (uint64_t total : {uint64_t{1}, uint64_t{4096}, uint64_t{12805}, uint64_t{1000000}}) {
    for (int ranks : {1, 2, 3, 4, 7}) {
      uint64_t next = 0;
      for (int r = 0; r < ranks; ++r) {
        ParticleShare s = RankShare(total, ranks, r, kSumBlock);
        EXPECT_EQ(s.first, next);
        if (s.first + s.count < total) {
          EXPECT_EQ(s.count % kSumBlock, 0u);
        }
        next = s.first + s.count;
      }
      EXPECT_EQ(next, total);
    }
  }
}

// Too few particles for the ranks: the refusal says why blocks exist and what count works.
TEST(DistributedFilterTest, TooFewParticlesForTheRanksNameTheSmallestCountThatWorks) {
  Status s = CheckRankShares(2000, 2, kSumBlock);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("same result at any rank count"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("2 ranks need particles >= 4097 (2000 particles run on at most 1 "
                             "rank)"),
            std::string::npos)
      << s.message();
  s = CheckRankShares(8192, 3, kSumBlock);
  EXPECT_NE(s.message().find("3 ranks need particles >= 8193 (8192 particles run on at most 2 "
                             "ranks)"),
            std::string::npos)
      << s.message();
  EXPECT_TRUE(CheckRankShares(4097, 2, kSumBlock).ok());
  EXPECT_TRUE(CheckRankShares(2000, 1, kSumBlock).ok());
}

// A failure on one rank reaches every rank as the same error, and no rank is left waiting.
TEST(DistributedFilterTest, AFailureOnOneRankStopsEveryRank) {
  FootSlamConfig config = TestConfig();
  config.grid = FootSlamGrid::kFixed;
  config.grid_size = 16;  // about 14 m across, centred on the start: the loop leaves it
  std::vector<RankResult> parts = RunRanks<HTreeMap<4>>(config, Loop(40), 3, 1);
  RankResult one = RunRank<HTreeMap<4>>(config, Loop(40), nullptr, 1);
  ASSERT_FALSE(one.status.ok());
  ASSERT_NE(one.status.message().find("left the"), std::string::npos) << one.status.message();
  for (size_t r = 0; r < parts.size(); ++r) {
    // Rank 0 holds the lowest failing particle, the one a single process names.
    const Status& s = parts[r].status;
    EXPECT_EQ(s.code(), one.status.code());
    EXPECT_EQ(s.message(), (r == 0 ? "" : "rank 0: ") + one.status.message());
  }
}

// Particles written by one rank are read back whole by another; any truncation of the message is
// an error naming the field, and leaks nothing (the sanitizer build checks).
TEST(DistributedFilterTest, ATruncatedParticleMessageIsAnErrorNotACrash) {
  FootSlamConfig config = TestConfig();
  config.particles = 64;
  HexGrid grid(config.hex_radius_m);
  HTreeLayout layout = *HTreeLayout::Create(config.grid_size, config.degree);
  Alphabet alphabet = *Alphabet::Create(config.alphabet);
  WorkerPool workers(1);
  AlphabetHTreeMap<4> map(layout, 1, 64, &alphabet);
  FootSlamModel<AlphabetHTreeMap<4>> model(config, &grid, &layout, &map, 1);
  ASSERT_TRUE(model.Init());
  FilterOptions options;
  options.seed = config.seed;
  ParticleFilter<FootSlamModel<AlphabetHTreeMap<4>>> filter(&model, &workers, options);
  for (const StepInput& in : Loop(30)) ASSERT_TRUE(filter.Update(in).ok());
  const std::vector<uint32_t> which = {0, 5, 6, 40, 63};
  ByteWriter w;
  model.Export(which, &w);
  const std::string message = w.Take();
  auto receiver = [&](AlphabetHTreeMap<4>* m) {
    return FootSlamModel<AlphabetHTreeMap<4>>(config, &grid, &layout, m, 1, {64, 64});
  };
  {
    AlphabetHTreeMap<4> m(layout, 1, 64, &alphabet);
    auto other = receiver(&m);
    ASSERT_TRUE(other.Init());
    ByteReader r(message, "message");
    Status s = other.Import(&r, which.size(), 30);
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_TRUE(r.at_end());
    ASSERT_EQ(other.size(), 64 + which.size());
    for (size_t k = 0; k < which.size(); ++k) {
      EXPECT_EQ(other.x(64 + k), model.x(which[k]));
      EXPECT_EQ(other.heading(64 + k), model.heading(which[k]));
      EXPECT_EQ(PoseHistory::Path(other.history(64 + k)).size(),
                PoseHistory::Path(model.history(which[k])).size());
    }
    // Steps newer than the receiver's step are refused.
    ByteReader early(message, "message");
    AlphabetHTreeMap<4> m2(layout, 1, 64, &alphabet);
    auto again = receiver(&m2);
    ASSERT_TRUE(again.Init());
    EXPECT_FALSE(again.Import(&early, which.size(), 29).ok());
  }
  for (size_t cut = 0; cut < message.size(); cut += 1 + message.size() / 97) {
    AlphabetHTreeMap<4> m(layout, 1, 64, &alphabet);
    auto other = receiver(&m);
    ASSERT_TRUE(other.Init());
    ByteReader r(std::string_view(message).substr(0, cut), "message");
    Status s = other.Import(&r, which.size(), 30);
    ASSERT_FALSE(s.ok()) << "cut at " << cut;
    EXPECT_EQ(s.code(), StatusCode::kDataLoss) << s.message();
    EXPECT_NE(s.message().find("message: byte"), std::string::npos) << s.message();
  }
}

// Ranks that disagree on what changes results all stop before the first step, with one error.
TEST(DistributedFilterTest, RanksThatDisagreeAllStop) {
  std::vector<RankResult> parts = RunRanks<HTreeMap<4>>(TestConfig(), Loop(5), 3, 1, 8);
  for (const RankResult& p : parts) {
    EXPECT_EQ(p.status.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(p.status.message().find("rank 1's filter"), std::string::npos) << p.status.message();
  }
}

// Stratified, residual and multinomial resampling run in one process only.
TEST(DistributedFilterTest, OnlySystematicResamplingRunsAcrossRanks) {
  std::vector<std::unique_ptr<Collective>> endpoints = InProcessCollective::Create(1);
  FootSlamConfig config = TestConfig();
  HexGrid grid(config.hex_radius_m);
  HTreeLayout layout = *HTreeLayout::Create(config.grid_size, config.degree);
  WorkerPool workers(1);
  HTreeMap<4> map(layout, 1, static_cast<size_t>(config.particles), nullptr);
  FootSlamModel<HTreeMap<4>> model(config, &grid, &layout, &map, 1);
  ASSERT_TRUE(model.Init());
  FilterOptions options;
  options.resampling = ResamplingScheme::kMultinomial;
  options.resample_threshold = 1.0;
  options.collective = endpoints[0].get();
  options.total_particles = static_cast<uint64_t>(config.particles);
  ParticleFilter<FootSlamModel<HTreeMap<4>>> filter(&model, &workers, options);
  Status s = filter.Update(StepInput{0.7, 0});
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("systematic"), std::string::npos) << s.message();
}

}  // namespace
}  // namespace grove::footslam
