#include "bench/ranks/ranks_benchmark.h"

#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <span>
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
#include "engine/io/checkpoint_io.h"
#include "grove/checksum.h"
#include "grove/footslam.h"
#include "grove/version.h"
#include "tools/io/atomic_file.h"
#include "tools/run/run_loop.h"
#include "tools/sim/walk_simulator.h"

namespace grove::tools {
namespace {

using Clock = std::chrono::steady_clock;
using footslam::AlphabetHTreeMap;
using footslam::FootSlamModel;
using Model = FootSlamModel<AlphabetHTreeMap<4>>;

double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// A Collective that times its calls and counts the bytes this rank hands to them.
class TimedCollective : public Collective {
 public:
  explicit TimedCollective(Collective* inner) : inner_(inner) {}
  int rank() const override { return inner_->rank(); }
  int size() const override { return inner_->size(); }
  Status AllGather(const std::string& mine, std::vector<std::string>* all) override {
    auto t0 = Clock::now();
    Status s = inner_->AllGather(mine, all);
    seconds_ += Seconds(Clock::now() - t0);
    ++calls_;
    bytes_ += mine.size();
    return s;
  }
  Status AllToAll(const std::vector<std::string>& to, std::vector<std::string>* from) override {
    auto t0 = Clock::now();
    Status s = inner_->AllToAll(to, from);
    seconds_ += Seconds(Clock::now() - t0);
    ++calls_;
    for (const std::string& m : to) bytes_ += m.size();
    return s;
  }
  double seconds() const { return seconds_; }
  uint64_t calls() const { return calls_; }
  uint64_t bytes() const { return bytes_; }

 private:
  Collective* inner_;
  double seconds_ = 0;
  uint64_t calls_ = 0;
  uint64_t bytes_ = 0;
};

// One CRC per particle of everything that particle is: its normalised log weight, pose, error
// states, path and map.
std::vector<uint32_t> ParticleDigests(const Model& model, std::span<const double> log_w) {
  std::vector<uint32_t> out;
  out.reserve(model.size());
  for (size_t i = 0; i < model.size(); ++i) {
    ByteWriter w;
    w.Put(log_w[i]);
    for (double v :
         {model.x(i), model.y(i), model.heading(i), model.heading_error(i), model.scale(i)}) {
      w.Put(v);
    }
    for (const auto* n = model.history(i); n != nullptr; n = n->parent) {
      w.Put(n->step);
      w.Put(n->value);
    }
    model.map().ForEachHex(i, [&](uint64_t key, const footslam::Htc& h) {
      w.Put(key);
      w.Put(h);
    });
    out.push_back(Crc32(w.Take()));
  }
  return out;
}

// What each rank reports to rank 0.
struct RankReport {
  uint64_t particles;
  int32_t threads;
  double run_s;
  double collective_s;
  uint64_t collective_calls;
  uint64_t collective_bytes;
  uint64_t sent_particles;
  uint64_t sent_particle_bytes;
  double migrate_s;
  PhaseTimes phases;
};

}  // namespace

int RanksBenchCommand(const RanksBenchOptions& options, Collective& world) {
  const int ranks = world.size(), rank = world.rank();
  // Every check is made alike on every rank: all fail together, none waits for another.
  FootSlamConfig config;
  config.particles = options.particles;
  config.threads = options.threads > 0 ? options.threads : UsableCpus();
  config.map = FootSlamMapKind::kHTree;
  config.degree = 16;
  config.grid_size = 256;
  config.grid = FootSlamGrid::kFixed;
  config.alphabet = 5;
  config.seed = options.seed;
  config.islands = options.islands;
  config.island_exchange_steps = options.exchange_steps;
  config.island_exchange_fraction = options.exchange_fraction;
  if (Status s = config.Validate(); !s.ok()) return Fail(kExitUsage, s.message());
  const uint64_t total = static_cast<uint64_t>(options.particles);
  if (Status s = FootSlam::CheckAcrossRanks(config, ranks); !s.ok()) {
    return Fail(kExitUsage, s.message());
  }
  // The ranks must run the same walk and filter (an MPMD launch could give them other options).
  std::vector<std::string> all_options;
  const std::string given = fmt::format(
      "--particles {} --minutes {} --seed {} --islands {} --exchange-steps {} "
      "--exchange-fraction {}",
      options.particles, options.minutes, options.seed, options.islands, options.exchange_steps,
      options.exchange_fraction);
  if (Status s = world.AllGather(given, &all_options); !s.ok()) {
    return Fail(kExitInternal, s.message());
  }
  for (size_t q = 1; q < all_options.size(); ++q) {
    if (all_options[q] != all_options[0]) {
      return Fail(kExitUsage, fmt::format("rank {} was given {}, rank 0 {}", q, all_options[q],
                                          all_options[0]));
    }
  }
  StatusOr<std::vector<StepRecord>> walk = PaperWalk(options.minutes);
  if (!walk.ok()) return Fail(kExitUsage, walk.status().message());
  Status dir = rank == 0 ? EnsureDirectory(options.out_dir) : Status::Ok();
  if (Status s = AgreeStatus(world, dir); !s.ok()) return Fail(kExitOutput, s.message());

  const ParticleShare share = RankShare(total, ranks, rank, kSumBlock);
  footslam::HexGrid grid(config.hex_radius_m);
  StatusOr<footslam::HTreeLayout> layout =
      footslam::HTreeLayout::Create(config.grid_size, config.degree);
  StatusOr<footslam::Alphabet> alphabet = footslam::Alphabet::Create(config.alphabet);
  if (!layout.ok() || !alphabet.ok()) return Fail(kExitInternal, "the paper configuration");
  WorkerPool workers(config.threads);
  AlphabetHTreeMap<4> map(*layout, config.threads, share.count, &*alphabet);
  Model model(config, &grid, &*layout, &map, config.threads, share);
  if (!model.Init()) return Fail(kExitMemory, "out of memory");
  TimedCollective timed(&world);
  FilterOptions filter_options;
  filter_options.seed = config.seed;
  filter_options.batch = static_cast<size_t>(config.batch);
  filter_options.resample_threshold = config.resample_threshold;
  filter_options.islands = config.islands;
  filter_options.exchange_steps = static_cast<uint64_t>(config.island_exchange_steps);
  filter_options.exchange_fraction = config.island_exchange_fraction;
  // One rank runs the filter of one process: the reference the others must match.
  filter_options.collective = ranks > 1 ? &timed : nullptr;
  filter_options.total_particles = total;
  ParticleFilter<Model> filter(&model, &workers, filter_options);
  auto t0 = Clock::now();
  for (const StepRecord& step : *walk) {
    Status s = filter.Update(footslam::StepInput{step.dx_m, step.dy_m});
    if (!s.ok()) return Fail(kExitRun, s.message());
  }
  const double run_s = Seconds(Clock::now() - t0);

  std::vector<uint32_t> digests;
  Status s =
      AllGatherValues<uint32_t>(world, ParticleDigests(model, filter.log_weights()), &digests);
  RankReport mine{share.count,
                  config.threads,
                  run_s,
                  timed.seconds(),
                  timed.calls(),
                  timed.bytes(),
                  filter.sent_particles(),
                  filter.sent_bytes(),
                  filter.migrate_seconds(),
                  filter.phase_times()};
  std::vector<RankReport> reports;
  if (s.ok()) s = AllGatherValues<RankReport>(world, std::span(&mine, 1), &reports);
  if (!s.ok()) return Fail(kExitInternal, s.message());
  if (rank != 0) return kExitOk;

  const uint32_t digest = Crc32(std::string_view(reinterpret_cast<const char*>(digests.data()),
                                                 digests.size() * sizeof(uint32_t)));
  double slowest = 0;
  uint64_t sent_bytes = 0, sent_particles = 0;
  nlohmann::ordered_json per_rank = nlohmann::ordered_json::array();
  for (const RankReport& r : reports) {
    slowest = std::max(slowest, r.run_s);
    sent_bytes += r.sent_particle_bytes;
    sent_particles += r.sent_particles;
    per_rank.push_back({{"particles", r.particles},
                        {"threads", r.threads},
                        {"run_s", r.run_s},
                        {"collective_s", r.collective_s},
                        {"own_work_s", r.run_s - r.collective_s},
                        {"collective_calls", r.collective_calls},
                        {"collective_bytes", r.collective_bytes},
                        {"sent_particles", r.sent_particles},
                        {"sent_particle_bytes", r.sent_particle_bytes},
                        {"migrate_s", r.migrate_s},
                        {"phases_s",
                         {{"advance", r.phases.advance_s},
                          {"normalize", r.phases.normalize_s},
                          {"resample", r.phases.resample_s},
                          {"release", r.phases.release_s}}}});
  }
  const double steps = static_cast<double>(walk->size());
  const double resamplings = static_cast<double>(filter.resamplings());
  nlohmann::ordered_json j = {
      {"grove", VersionString()},
      {"ranks", ranks},
      {"particles", options.particles},
      {"steps", walk->size()},
      {"seed", options.seed},
      {"islands", options.islands},
      {"exchange_steps", options.islands > 1 ? options.exchange_steps : 0},
      {"exchange_fraction", options.islands > 1 ? options.exchange_fraction : 0.0},
      {"sent_bytes_per_step", sent_bytes / steps},
      {"run_s", slowest},
      {"ns_per_particle_step", slowest * 1e9 / (steps * static_cast<double>(total))},
      {"resamplings", filter.resamplings()},
      {"mean_ess", filter.mean_ess()},
      {"sent_particles_per_resampling", resamplings > 0 ? sent_particles / resamplings : 0.0},
      {"sent_bytes_per_resampling", resamplings > 0 ? sent_bytes / resamplings : 0.0},
      {"digest", fmt::format("{:08x}", digest)},
      {"per_rank", per_rank}};
  if (Status w = WriteFileAtomically(options.out_dir + "/ranks.json", j.dump(2) + "\n"); !w.ok()) {
    return Fail(kExitOutput, w.message());
  }
  std::printf(
      "ranks %d, %lld particles, %zu steps: %.3f s, %.1f ns per particle-step, %.0f bytes "
      "sent per resampling, digest %08x\n",
      ranks, static_cast<long long>(options.particles), walk->size(), slowest,
      slowest * 1e9 / (steps * static_cast<double>(total)),
      resamplings > 0 ? sent_bytes / resamplings : 0.0, digest);
  return kExitOk;
}

}  // namespace grove::tools
