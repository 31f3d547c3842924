// ParticleFilter: the sequential importance resampling loop of a Rao-Blackwellized particle
// filter, generic over a model that owns the particles' state (structure of arrays).
//
// One Update():
//   1. advance: the model propagates, weights and updates the map of every particle, in parallel
//      over batches (log-domain weight increments);
//   2. normalise: log-sum-exp over fixed blocks, then the effective sample size 1 / sum(w^2);
//   3. resample when ESS / N < threshold (threshold 1 resamples every step): parents are drawn
//      (systematic by default, in parallel), the model gathers the new generation (O(1) per
//      particle: maps are shared) and releases the dead one, both in parallel (a
//      PieceReleasingModel in a filter alone releases it during the next advance instead);
//   4. complete (optional): a model whose weights do not depend on what it draws (FastSLAM
//      2.0) draws and updates after resampling, in parallel over batches;
//   5. population (optional): a model that needs the whole population once its particles are
//      drawn (moving them towards the best one, as differential evolution does) gets it last:
//      after complete, or for a model without it after advance (then before normalising).
// One Predict() propagates every particle without weighting (a landmark filter predicts at the
// control rate and weights only at scans). Both count as one step of the random streams.
// Sums over particles are taken over fixed blocks and every draw comes from a counter-based
// stream, so the same seed gives bit-identical weights at any thread count. A batch that fails
// returns a Status; the step's result is the failure of the lowest failing batch, so the same
// error is reported at any thread count.
//
// Thread safety: one thread drives a filter; the filter uses its WorkerPool inside a step.
#ifndef GROVE_ENGINE_FILTER_PARTICLE_FILTER_H_
#define GROVE_ENGINE_FILTER_PARTICLE_FILTER_H_

#include <algorithm>
#include <chrono>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "concurrency/worker_pool.h"
#include "engine/filter/resampler.h"
#include "engine/io/checkpoint_io.h"
#include "engine/ranks/collective.h"
#include "grove/status.h"

namespace grove {

struct FilterOptions {
  // Which resampling scheme draws the next generation. Default: systematic.
  ResamplingScheme resampling = ResamplingScheme::kSystematic;
  // Resample when ESS / N falls below this, in (0, 1]; 1 resamples every step. Default: 0.5.
  double resample_threshold = 0.5;
  // Particles per parallel batch, at most: fewer when that leaves a thread under 4 batches
  // (affects speed only). Default: 512.
  size_t batch = 512;
  // Seed of every random stream. Default: 1.
  uint64_t seed = 1;
  // Ranks that run this filter together (nullptr: this process holds every particle). Each
  // rank's model holds its RankShare(total_particles, ranks, rank, kSumBlock) of the particles,
  // as global particles [first, first + model size); weights are normalised and resampled over
  // all of them, and a particle whose copies belong to another rank moves there (the model
  // exports and imports it: MigratingModel). Only systematic resampling runs across ranks.
  Collective* collective = nullptr;
  // The whole filter's particle count, with a collective.
  uint64_t total_particles = 0;
  // Island mode when above 1: the particles form this many islands of whole blocks (island j
  // holds RankShare(total, islands, j, kSumBlock)), each resampled from its own weights alone,
  // after which every particle weighs 1 / N again: an island's share of the total weight is
  // dropped, the price of never moving particles at a resampling. Every `exchange_steps` steps
  // the filter resamples whatever the ESS, and island j then draws a systematic sample of
  // `exchange_fraction` of the smallest island's count from its weights and sends it to island
  // (j + 1) mod islands, where it takes the place of as many of the island's own draws. Results
  // depend on the islands, not on the ranks or threads. Across ranks, islands must be a multiple
  // of the ranks (rank q holds whole islands). Needs a MigratingModel. Default: 1 (off).
  int islands = 1;
  uint64_t exchange_steps = 10;
  double exchange_fraction = 0.1;
};

// Wall time spent in each phase, summed over steps (seconds).
struct PhaseTimes {
  double advance_s = 0;    // propagate, weight and update maps
  double normalize_s = 0;  // log-sum-exp and ESS
  double resample_s = 0;   // drawing parents and gathering the new generation
  double release_s = 0;    // freeing the dead generation (in advance_s when freed in pieces)
};

// What a model provides (checked where a filter is instantiated).
template <typename M>
concept FilterModel = requires(M& m, const M& cm, std::span<const uint32_t> parents,
                               WorkerPool& workers) {
  { cm.size() } -> std::convertible_to<size_t>;
  // The next generation: particle k copies parents[k] (nondecreasing); maps are shared.
  { m.Gather(parents, workers) } -> std::same_as<void>;
  // Frees what only the previous generation reached.
  { m.ReleaseDead(workers) } -> std::same_as<void>;
};

// A model that can free its dead generation in pieces: ReleaseDeadRange(lo, hi, slot) releases
// what the previous generation's particles [lo, min(hi, its size)) held, DeadReleased() ends
// that generation once every piece is released. The filter then frees the dead generation
// during the next advance, each batch first releasing the dead particles among its own
// particles' parents (their relatives, whose nodes it is about to touch): the release's cache
// misses overlap the motion's arithmetic, and the separate release loop and its join go.
template <typename M>
concept PieceReleasingModel = requires(M& m, size_t lo, size_t hi, int slot) {
  { m.ReleaseDeadRange(lo, hi, slot) } -> std::same_as<void>;
  { m.DeadReleased() } -> std::same_as<void>;
};

// A model whose particles can move between ranks: Export() writes particles `which` (local
// indices, increasing) with everything they share written once; Import() appends `count`
// particles so written to the model's own (size() grows by count until the next Gather(), whose
// parents may name them), checking every value, with paths no newer than `step`.
template <typename M>
concept MigratingModel = requires(const M& cm, M& m, std::span<const uint32_t> which, ByteWriter* w,
                                  ByteReader* r, size_t count, uint64_t step) {
  { cm.Export(which, w) } -> std::same_as<void>;
  { m.Import(r, count, step) } -> std::same_as<Status>;
};

// A model that weights `Input`: adds each particle's log-likelihood increment to log_w[i] for i
// in [begin, end) after propagating it; returns the first particle's error (the batch stops).
template <typename M, typename Input>
concept WeightingModel = FilterModel<M> &&
    requires(M& m, const Input& in, uint64_t step, size_t i, int slot, double* log_w) {
  { m.Advance(in, step, i, i, slot, log_w) } -> std::same_as<Status>;
};

// A model that propagates on `Input` without weighting.
template <typename M, typename Input>
concept PredictingModel = FilterModel<M> &&
    requires(M& m, const Input& in, uint64_t step, size_t i, int slot) {
  { m.Predict(in, step, i, i, slot) } -> std::same_as<Status>;
};

// A model with a population phase for `Input`, run once its particles are drawn (after
// Complete(), or after Advance() when the model has no Complete()): Population(input, step,
// workers) may move particles (not their weights) and runs its own parallel loops.
template <typename M, typename Input>
concept PopulationModel = requires(M& m, const Input& in, uint64_t step, WorkerPool& workers) {
  { m.Population(in, step, workers) } -> std::same_as<Status>;
};

// RunInBatches' batch size: batch b is particles [b * size, (b + 1) * size).
inline size_t BatchSize(const WorkerPool& workers, size_t n, size_t max_batch) {
  const size_t threads = static_cast<size_t>(workers.num_threads());
  size_t batch = std::max<size_t>(max_batch, 1);
  if (threads > 1) batch = std::clamp<size_t>((n + 4 * threads - 1) / (4 * threads), 1, batch);
  return batch;
}

// Runs body(slot, begin, end) -> Status over [0, n) in batches of at most max_batch particles,
// fewer when that leaves a thread under 4 batches (100 particles in batches of 64 would keep two
// threads at 64 and 36); returns the error of the lowest failing batch, which is the error of the
// lowest failing particle whatever the batches when a batch stops at its first. `status` is
// scratch space (one entry per batch), kept by the caller to avoid an allocation per loop.
template <typename F>
Status RunInBatches(WorkerPool& workers, size_t n, size_t max_batch, std::vector<Status>* status,
                    F&& body) {
  const size_t batch = BatchSize(workers, n, max_batch);
  status->assign((n + batch - 1) / batch, Status::Ok());
  workers.ParallelFor(n, batch, [&](int slot, size_t begin, size_t end) {
    (*status)[begin / batch] = body(slot, begin, end);
  });
  for (Status& s : *status) {
    if (!s.ok()) return std::move(s);
  }
  return Status::Ok();
}

// A model that completes its update of `Input` after resampling, over every particle:
// Complete(input, step, begin, end, slot). FastSLAM 2.0 weights a particle by its predictive
// likelihood, which does not depend on the pose it then draws, so it resamples first and draws
// after (Bailey's order): copies of one parent draw distinct poses.
template <typename M, typename Input>
concept CompletingModel = requires(M& m, const Input& in, uint64_t step, size_t i, int slot) {
  { m.Complete(in, step, i, i, slot) } -> std::same_as<Status>;
};

template <FilterModel Model>
class ParticleFilter {
 public:
  ParticleFilter(Model* model, WorkerPool* workers, const FilterOptions& options)
      : model_(model),
        workers_(workers),
        options_(options),
        total_(options.collective == nullptr ? model->size() : options.total_particles),
        first_(options.collective == nullptr ? 0
                                             : RankShare(total_, options.collective->size(),
                                                         options.collective->rank(), kSumBlock)
                                                   .first),
        log_w_(model->size(), -std::log(static_cast<double>(total_))),
        parents_(model->size()) {}

  // Runs one weighting step on `input`. Returns the model's error (the lowest failing batch's),
  // or FailedPrecondition when every particle weight is zero or non-finite after the update
  // (the filter has degenerated). After an error the particles are partly advanced: the
  // caller must not step again.
  template <typename Input>
  requires WeightingModel<Model, Input> Status Update(const Input& input) {
    using Clock = std::chrono::steady_clock;
    auto t0 = Clock::now();
    if (!options_checked_) {
      options_checked_ = true;
      GROVE_RETURN_IF_ERROR(CheckOptions());
    }
    const bool release = release_pending_;
    // Each batch also finds its heaviest particle, for Normalize(): no loop of its own.
    const size_t batch = BatchSize(*workers_, log_w_.size(), options_.batch);
    maxes_.assign((log_w_.size() + batch - 1) / batch, MaxPart{});
    Status status = ForBatches([&](int slot, size_t begin, size_t end) {
      if constexpr (PieceReleasingModel<Model>) {
        if (release) model_->ReleaseDeadRange(DeadFrom(begin), DeadFrom(end), slot);
      }
      Status s = model_->Advance(input, step_, begin, end, slot, log_w_.data());
      if (s.ok()) maxes_[begin / batch] = MaxOf(begin, end);
      return s;
    });
    if constexpr (PieceReleasingModel<Model>) {
      if (release) model_->DeadReleased();
    }
    release_pending_ = false;
    if constexpr (PopulationModel<Model, Input> && !CompletingModel<Model, Input>) {
      if (status.ok()) status = model_->Population(input, step_, *workers_);
    }
    if (options_.collective != nullptr) status = AgreeStatus(*options_.collective, status);
    auto t1 = Clock::now();
    times_.advance_s += Seconds(t1 - t0);
    if (!status.ok()) {
      ++step_;
      return status;
    }
    status = Normalize();
    auto t2 = Clock::now();
    times_.normalize_s += Seconds(t2 - t1);
    ++weight_steps_;
    if (!status.ok()) {
      ++step_;
      return status;
    }
    ess_sum_ += ess_;
    const double n = static_cast<double>(total_);
    // (CheckOptions() refused exchange_steps = 0 in island mode.)
    const bool exchange = options_.islands > 1 && (step_ + 1) % options_.exchange_steps == 0;
    if (exchange || options_.resample_threshold >= 1.0 || ess_ < options_.resample_threshold * n) {
      if (options_.islands > 1) {
        status = ResampleIslands(exchange);
      } else if (options_.collective == nullptr) {
        Resample();
      } else {
        status = ResampleAcross();
      }
      if (!status.ok()) {
        ++step_;
        return status;
      }
    }
    if constexpr (CompletingModel<Model, Input>) {
      auto t3 = Clock::now();
      status = ForBatches([&](int slot, size_t begin, size_t end) {
        return model_->Complete(input, step_, begin, end, slot);
      });
      if constexpr (PopulationModel<Model, Input>) {
        if (status.ok()) status = model_->Population(input, step_, *workers_);
      }
      times_.advance_s += Seconds(Clock::now() - t3);
    }
    ++step_;
    return status;
  }

  // Runs one predict-only step: every particle is propagated on `input`, no weight changes.
  template <typename Input>
  requires PredictingModel<Model, Input> Status Predict(const Input& input) {
    auto t0 = std::chrono::steady_clock::now();
    FinishRelease();
    Status status = ForBatches([&](int slot, size_t begin, size_t end) {
      return model_->Predict(input, step_, begin, end, slot);
    });
    if (options_.collective != nullptr) status = AgreeStatus(*options_.collective, status);
    times_.advance_s += Seconds(std::chrono::steady_clock::now() - t0);
    ++step_;
    return status;
  }

  // The filter's state between steps: step and resampling counts, ESS statistics, phase
  // times, the heaviest particle and the normalised log weights. The random streams are keyed
  // by (seed, step, particle), so the step is their whole position.
  void Save(ByteWriter* w) const {
    w->Put<uint64_t>(step_);
    w->Put<uint64_t>(weight_steps_);
    w->Put<uint64_t>(resamplings_);
    w->Put<uint64_t>(heaviest_);
    w->Put<double>(ess_);
    w->Put<double>(ess_sum_);
    w->Put(times_);
    w->Put<uint64_t>(log_w_.size());
    w->PutBytes(log_w_.data(), log_w_.size() * sizeof(double));
  }

  Status Load(ByteReader* r) {
    const size_t n = log_w_.size();
    uint64_t step = 0, weight_steps = 0, resamplings = 0, heaviest = 0, count = 0;
    double ess = 0, ess_sum = 0;
    PhaseTimes times;
    GROVE_RETURN_IF_ERROR(r->Get("step", &step));
    GROVE_RETURN_IF_ERROR(r->Get("weighting steps", &weight_steps));
    GROVE_RETURN_IF_ERROR(r->Get("resamplings", &resamplings));
    GROVE_RETURN_IF_ERROR(r->Get("heaviest particle", &heaviest));
    GROVE_RETURN_IF_ERROR(r->Get("ESS", &ess));
    GROVE_RETURN_IF_ERROR(r->Get("ESS sum", &ess_sum));
    GROVE_RETURN_IF_ERROR(r->Get("phase times", &times));
    GROVE_RETURN_IF_ERROR(r->Get("weight count", &count));
    if (weight_steps > step) return r->Error("weighting steps", "more than the steps");
    if (resamplings > weight_steps) return r->Error("resamplings", "more than the steps");
    // Across ranks the heaviest particle and the ESS are the whole filter's.
    if (heaviest >= total_) return r->Error("heaviest particle", "not a particle");
    if (!(ess >= 0 && ess <= static_cast<double>(total_) * (1 + 1e-9)) || !std::isfinite(ess_sum)) {
      return r->Error("ESS", "outside [0, particles]");
    }
    for (double t : {times.advance_s, times.normalize_s, times.resample_s, times.release_s}) {
      if (!(t >= 0 && t < 1e12)) return r->Error("phase times", "not a duration");
    }
    if (count != n) return r->Error("weight count", "does not match the particle count");
    std::vector<double> log_w(n);
    GROVE_RETURN_IF_ERROR(r->GetBytes("log weights", log_w.data(), n * sizeof(double)));
    bool any_finite = false;
    for (double v : log_w) {
      if (std::isnan(v) || v > 1e-9) return r->Error("log weights", "a weight is NaN or above 1");
      any_finite = any_finite || std::isfinite(v);
    }
    // (A rank's share alone may weigh nothing.)
    if (!any_finite && options_.collective == nullptr) {
      return r->Error("log weights", "every weight is zero");
    }
    step_ = step;
    resamplings_ = resamplings;
    heaviest_ = heaviest;
    ess_ = ess;
    ess_sum_ = ess_sum;
    weight_steps_ = weight_steps;
    times_ = times;
    log_w_.swap(log_w);
    return Status::Ok();
  }

  // Normalised log weights (log w_i, sum of w_i = 1) of this rank's particles.
  std::span<const double> log_weights() const { return log_w_; }
  // Effective sample size after the last step's update, before any resampling.
  double ess() const { return ess_; }
  // The mean ESS over the weighting steps.
  double mean_ess() const {
    return weight_steps_ == 0 ? 0 : ess_sum_ / static_cast<double>(weight_steps_);
  }
  uint64_t steps() const { return step_; }
  uint64_t resamplings() const { return resamplings_; }
  const PhaseTimes& phase_times() const { return times_; }
  const FilterOptions& options() const { return options_; }
  // The particle that was heaviest after the last update (lowest index on ties), followed
  // through resampling to its first copy: resampling equalises weights but not evidence.
  // Across ranks, a global index (it may be another rank's particle).
  size_t heaviest() const { return heaviest_; }
  // The global index of this rank's first particle and the whole filter's count.
  uint64_t first_particle() const { return first_; }
  uint64_t total_particles() const { return total_; }
  // Across ranks: the bytes of particles this rank has sent to others, and how many particles.
  uint64_t sent_bytes() const { return sent_bytes_; }
  uint64_t sent_particles() const { return sent_particles_; }
  // Across ranks: seconds spent writing and reading the particles that move (not sending them).
  double migrate_seconds() const { return migrate_s_; }

 private:
  template <typename D>
  static double Seconds(D d) {
    return std::chrono::duration<double>(d).count();
  }

  // Runs body(slot, begin, end) -> Status over batches of at most options_.batch particles
  // (RunInBatches).
  template <typename F>
  Status ForBatches(F&& body) {
    return RunInBatches(*workers_, log_w_.size(), options_.batch, &batch_status_,
                        std::forward<F>(body));
  }

  // The first particle of the previous generation whose dead references the batch starting at
  // new particle k releases: the dead among its particles' parents (and, for the first batch,
  // those before them; for the last, those after). parents_ is nondecreasing, so the batches'
  // pieces partition the previous generation.
  size_t DeadFrom(size_t k) const {
    if (k == 0) return 0;
    return k < parents_.size() ? parents_[k] : std::numeric_limits<size_t>::max();
  }

  // Releases a dead generation the next advance has not (before a step without one).
  void FinishRelease() {
    if (!release_pending_) return;
    model_->ReleaseDead(*workers_);
    release_pending_ = false;
  }

  // The heaviest of particles [begin, end) (the first on ties), and whether any weight is NaN.
  struct MaxPart {
    double max = -std::numeric_limits<double>::infinity();
    size_t argmax = 0;
    bool nan = false;
  };
  MaxPart MaxOf(size_t begin, size_t end) const {
    MaxPart p;
    for (size_t i = begin; i < end; ++i) {
      if (std::isnan(log_w_[i])) p.nan = true;
      if (log_w_[i] > p.max) {
        p.max = log_w_[i];
        p.argmax = i;
      }
    }
    return p;
  }

  // Normalises the weights from the advance's per-batch maxima (maxes_, in batch order).
  Status Normalize() {
    const size_t n = log_w_.size();
    std::vector<MaxPart>& maxes = maxes_;
    if (options_.collective != nullptr) {
      // One partial per rank, combined in rank order as the batches are: the same first maximum.
      MaxPart mine;
      for (const MaxPart& p : maxes) {
        mine.nan = mine.nan || p.nan;
        if (p.max > mine.max) {
          mine.max = p.max;
          mine.argmax = first_ + p.argmax;
        }
      }
      GROVE_RETURN_IF_ERROR(
          AllGatherValues<MaxPart>(*options_.collective, std::span(&mine, 1), &maxes));
    }
    double max = -std::numeric_limits<double>::infinity();
    for (const MaxPart& p : maxes) {
      if (p.nan) return Degenerate("a particle weight is NaN");
      if (p.max > max) {
        max = p.max;
        heaviest_ = p.argmax;
      }
    }
    if (!std::isfinite(max)) return Degenerate("every particle weight is zero or infinite");
    // The normalised weights are kept: resampling draws from them. They are the scaled weights
    // exp(log w_i - max) over their sum: one exponential per particle.
    weights_.resize(n);
    std::vector<double> sums =
        workers_->MapBlocks<double>(n, kSumBlock, [&](size_t, size_t begin, size_t end) {
          double s = 0;
          for (size_t i = begin; i < end; ++i) {
            weights_[i] = std::exp(log_w_[i] - max);
            s += weights_[i];
          }
          return s;
        });
    GROVE_RETURN_IF_ERROR(GatherBlocks(&sums));
    double total = 0;
    for (double s : sums) total += s;
    const double log_total = max + std::log(total);
    // The blocks' sums of the normalised weights come out too: resampling starts from them
    // (BlockSums(weights_), added in the same order: the same bits).
    struct Sums {
      double squares = 0, weights = 0;
    };
    std::vector<Sums> block =
        workers_->MapBlocks<Sums>(n, kSumBlock, [&](size_t, size_t begin, size_t end) {
          Sums s;
          for (size_t i = begin; i < end; ++i) {
            log_w_[i] -= log_total;
            double w = weights_[i] / total;
            weights_[i] = w;
            s.squares += w * w;
            s.weights += w;
          }
          return s;
        });
    std::vector<double> squares(block.size());
    block_sums_.resize(block.size());
    for (size_t b = 0; b < block.size(); ++b) {
      squares[b] = block[b].squares;
      block_sums_[b] = block[b].weights;
    }
    GROVE_RETURN_IF_ERROR(GatherBlocks(&squares));
    double sum_sq = 0;
    for (double s : squares) sum_sq += s;
    ess_ = 1.0 / sum_sq;
    return Status::Ok();
  }

  // Before the first weighting step: the islands fit the particles and ranks; across ranks,
  // also the scheme is systematic, every rank's model holds its share, and the ranks agree on
  // what changes results (the same error on every rank otherwise).
  Status CheckOptions() {
    Status mine;
    if (options_.resampling != ResamplingScheme::kSystematic &&
        (options_.collective != nullptr || options_.islands > 1)) {
      mine = InvalidArgumentError(
          std::string("resampling: a filter across ranks or islands resamples systematically, "
                      "not ") +
          ResamplingSchemeName(options_.resampling));
    } else {
      mine = CheckIslands();
    }
    if (options_.collective == nullptr) return mine;
    Collective& c = *options_.collective;
    if (!mine.ok()) {
      // Agreed below.
    } else if (log_w_.size() != RankShare(total_, c.size(), c.rank(), kSumBlock).count) {
      mine = InvalidArgumentError("the model holds " + std::to_string(log_w_.size()) +
                                  " particles, not this rank's share of " + std::to_string(total_));
    }
    GROVE_RETURN_IF_ERROR(AgreeStatus(c, mine));
    struct Key {
      uint64_t total, seed;
      double threshold;
      int64_t scheme, islands;
      uint64_t exchange_steps;
      double exchange_fraction;
      bool operator==(const Key&) const = default;
    };
    Key key{total_,
            options_.seed,
            options_.resample_threshold,
            static_cast<int64_t>(options_.resampling),
            options_.islands,
            options_.exchange_steps,
            options_.exchange_fraction};
    std::vector<Key> all;
    GROVE_RETURN_IF_ERROR(AllGatherValues<Key>(c, std::span(&key, 1), &all));
    for (size_t q = 1; q < all.size(); ++q) {
      if (!(all[q] == all[0])) {
        return InvalidArgumentError("rank " + std::to_string(q) +
                                    "'s filter (particles, seed, resampling, threshold, islands, "
                                    "exchange) differs from rank 0's");
      }
    }
    return Status::Ok();
  }

  // Island mode's rules (OK when it is off); sets the islands this rank holds.
  Status CheckIslands() {
    const int islands = options_.islands;
    if (islands <= 1) return Status::Ok();
    const int ranks = options_.collective == nullptr ? 1 : options_.collective->size();
    GROVE_RETURN_IF_ERROR(grove::CheckIslands(total_, islands, ranks, kSumBlock));
    if (!(options_.exchange_fraction >= 0 && options_.exchange_fraction <= 0.5)) {
      return InvalidArgumentError(
          "exchange_fraction = " + std::to_string(options_.exchange_fraction) +
          ": must be in [0, 0.5]");
    }
    if (options_.exchange_steps == 0) {
      return InvalidArgumentError("exchange_steps = 0: must be at least 1");
    }
    if constexpr (!MigratingModel<Model>) {
      return InvalidArgumentError("islands = " + std::to_string(islands) +
                                  ": the model's particles cannot move between islands");
    }
    const int me = options_.collective == nullptr ? 0 : options_.collective->rank();
    island_lo_ = me * (islands / ranks);
    island_hi_ = island_lo_ + islands / ranks;
    uint64_t smallest = total_;
    for (int j = 0; j < islands; ++j) {
      smallest = std::min(smallest, RankShare(total_, islands, j, kSumBlock).count);
    }
    migrants_ = static_cast<uint64_t>(
        std::floor(options_.exchange_fraction * static_cast<double>(smallest)));
    return Status::Ok();
  }

  // Across ranks, every rank's per-block values in block order (ranks hold whole blocks in
  // order); alone, nothing to do.
  Status GatherBlocks(std::vector<double>* blocks) {
    if (options_.collective == nullptr) return Status::Ok();
    std::vector<double> mine;
    mine.swap(*blocks);
    return AllGatherValues<double>(*options_.collective, mine, blocks);
  }

  static Status Degenerate(const char* what) {
    return FailedPreconditionError(std::string("the filter degenerated: ") + what);
  }

  void Resample() {
    using Clock = std::chrono::steady_clock;
    auto t0 = Clock::now();
    grove::Resample(options_.resampling, weights_, options_.seed, step_, *workers_, parents_,
                    block_sums_);
    // Systematic and residual resampling always copy it (its weight is at least 1/N); the
    // other schemes may not, and then its successor in index order stands in.
    heaviest_ = static_cast<size_t>(
        std::lower_bound(parents_.begin(), parents_.end(), static_cast<uint32_t>(heaviest_)) -
        parents_.begin());
    TakeGeneration(t0);
  }

  // The model gathers parents_ as its next generation and frees the dead one; every weight
  // becomes 1 / N. The resample phase is timed from t0.
  void TakeGeneration(std::chrono::steady_clock::time_point t0) {
    using Clock = std::chrono::steady_clock;
    FinishRelease();  // (an advance always comes between two resamplings)
    model_->Gather(parents_, *workers_);
    auto t1 = Clock::now();
    // Alone (parents_ then nondecreasing), a piece-releasing model frees the dead generation in
    // the next advance.
    if (PieceReleasingModel<Model> && options_.collective == nullptr && options_.islands <= 1) {
      release_pending_ = true;
    } else {
      model_->ReleaseDead(*workers_);
    }
    auto t2 = Clock::now();
    std::fill(log_w_.begin(), log_w_.end(), -std::log(static_cast<double>(total_)));
    ++resamplings_;
    times_.resample_s += Seconds(t1 - t0);
    times_.release_s += Seconds(t2 - t1);
  }

  // Systematic resampling across ranks: every rank computes its own particles' copies from the
  // gathered block sums, sends each other rank the particles whose copies it holds (once per
  // rank, with their copy counts), and gathers its new generation from its own and the received
  // ones in rank order, which is slot order.
  Status ResampleAcross() {
    using Clock = std::chrono::steady_clock;
    auto t0 = Clock::now();
    if constexpr (!MigratingModel<Model>) {
      return InvalidArgumentError("the model's particles cannot move between ranks");
    } else {
      Collective& c = *options_.collective;
      const int ranks = c.size(), me = c.rank();
      const size_t n = log_w_.size();
      std::vector<double> block_sums;
      GROVE_RETURN_IF_ERROR(
          AllGatherValues<double>(c, std::span<const double>(block_sums_), &block_sums));
      slots_.resize(n + 1);
      SystematicSlots(weights_, first_ / kSumBlock, block_sums, total_,
                      SystematicUniform(options_.seed, step_), *workers_, slots_);
      // The heaviest particle's first copy (Resample()'s lower bound), from its rank.
      uint64_t heaviest = UINT64_MAX;
      if (heaviest_ >= first_ && heaviest_ - first_ < n) heaviest = slots_[heaviest_ - first_];
      std::vector<uint64_t> heaviest_all;
      GROVE_RETURN_IF_ERROR(AllGatherValues<uint64_t>(c, std::span(&heaviest, 1), &heaviest_all));
      heaviest_ = *std::min_element(heaviest_all.begin(), heaviest_all.end());
      // Copies of local particle i that slots [lo, hi) hold.
      auto copies_in = [&](size_t i, const ParticleShare& s) {
        uint64_t lo = std::max(slots_[i], s.first), hi = std::min(slots_[i + 1], s.first + s.count);
        return hi > lo ? hi - lo : 0;
      };
      auto m0 = Clock::now();
      std::vector<std::string> to(static_cast<size_t>(ranks));
      std::vector<uint32_t> which, copies;
      for (int q = 0; q < ranks; ++q) {
        if (q == me) continue;
        const ParticleShare share = RankShare(total_, ranks, q, kSumBlock);
        which.clear();
        copies.clear();
        for (size_t i = 0; i < n; ++i) {
          if (uint64_t k = copies_in(i, share); k > 0) {
            which.push_back(static_cast<uint32_t>(i));
            copies.push_back(static_cast<uint32_t>(k));
          }
        }
        if (which.empty()) continue;
        to[static_cast<size_t>(q)] = WriteParticles(which, copies);
        sent_bytes_ += to[static_cast<size_t>(q)].size();
        sent_particles_ += which.size();
      }
      migrate_s_ += Seconds(Clock::now() - m0);
      std::vector<std::string> from;
      GROVE_RETURN_IF_ERROR(c.AllToAll(to, &from));
      auto m1 = Clock::now();
      parents_.clear();
      const ParticleShare own{first_, n};
      Status s;
      for (int q = 0; q < ranks && s.ok(); ++q) {
        if (q == me) {
          for (size_t i = 0; i < n; ++i) {
            parents_.insert(parents_.end(), copies_in(i, own), static_cast<uint32_t>(i));
          }
          continue;
        }
        if (from[static_cast<size_t>(q)].empty()) continue;
        uint64_t read = 0;
        s = ReadParticles(from[static_cast<size_t>(q)], "particles from rank " + std::to_string(q),
                          n - std::min(n, parents_.size()), &read);
      }
      if (s.ok() && parents_.size() != n) {
        s = InternalError("resampling across ranks: " + std::to_string(parents_.size()) +
                          " copies for " + std::to_string(n) + " particles");
      }
      migrate_s_ += Seconds(Clock::now() - m1);
      GROVE_RETURN_IF_ERROR(AgreeStatus(c, s));
      TakeGeneration(t0);
      return Status::Ok();
    }
  }

  // A message of particles that move: `which` (local indices) with their copy counts, then
  // the particles as the model exports them.
  std::string WriteParticles(std::span<const uint32_t> which, std::span<const uint32_t> copies) {
    ByteWriter w;
    w.Put<uint64_t>(which.size());
    w.PutBytes(copies.data(), copies.size_bytes());
    model_->Export(which, &w);
    return w.Take();
  }

  // Imports the particles of a WriteParticles() message named `name` and appends their copies
  // to parents_ (at most `limit` in all, each particle at least one); *copies_read is their sum.
  Status ReadParticles(std::string_view bytes, const std::string& name, uint64_t limit,
                       uint64_t* copies_read) {
    ByteReader r(bytes, name);
    uint64_t count = 0;
    GROVE_RETURN_IF_ERROR(r.GetCount("particle count", sizeof(uint32_t), &count));
    std::vector<uint32_t> copies(count);
    GROVE_RETURN_IF_ERROR(r.GetBytes("copies", copies.data(), count * sizeof(uint32_t)));
    const size_t base = model_->size();
    GROVE_RETURN_IF_ERROR(model_->Import(&r, count, step_ + 1));
    if (!r.at_end()) return r.Error("end", "bytes after the particles");
    uint64_t total = 0;
    for (size_t k = 0; k < count; ++k) {
      total += copies[k];
      if (copies[k] == 0 || total > limit) {
        return r.Error("copies", "more copies than the slots they fill");
      }
      parents_.insert(parents_.end(), copies[k], static_cast<uint32_t>(base + k));
    }
    *copies_read = total;
    return Status::Ok();
  }

  // Island mode: each of this rank's islands draws its next generation from its own weights;
  // with `exchange`, island j also draws migrants_ particles and sends them to island j + 1
  // (written and read back as between ranks, whichever rank holds the neighbour), where they
  // follow the island's own migrants_ fewer draws.
  Status ResampleIslands(bool exchange) {
    using Clock = std::chrono::steady_clock;
    auto t0 = Clock::now();
    if constexpr (!MigratingModel<Model>) {
      return InvalidArgumentError("the model's particles cannot move between islands");
    } else {
      const int islands = options_.islands;
      const uint64_t m = exchange ? migrants_ : 0;
      const int ranks = options_.collective == nullptr ? 1 : options_.collective->size();
      const int me = options_.collective == nullptr ? 0 : options_.collective->rank();
      const int local = island_hi_ - island_lo_;
      std::vector<std::vector<uint32_t>> own(static_cast<size_t>(local));
      std::vector<std::string> sent(static_cast<size_t>(local));
      std::vector<uint32_t> drawn, which, copies;
      Status s;
      uint64_t heaviest = UINT64_MAX;
      size_t last_sent = 0;  // distinct particles the last island sends
      for (int j = island_lo_; j < island_hi_ && s.ok(); ++j) {
        const ParticleShare island = RankShare(total_, islands, j, kSumBlock);
        const size_t begin = island.first - first_, n = island.count;
        // Weights relative to the island's heaviest: an island far behind the others may have
        // every normalised weight underflow.
        std::span<const double> log_w(log_w_.data() + begin, n);
        const double max = *std::max_element(log_w.begin(), log_w.end());
        if (!std::isfinite(max)) {
          s = Degenerate(
              ("island " + std::to_string(j) + "'s every particle weight is zero").c_str());
          break;
        }
        island_w_.resize(n);
        for (size_t i = 0; i < n; ++i) island_w_[i] = std::exp(log_w[i] - max);
        std::vector<uint32_t>& kept = own[static_cast<size_t>(j - island_lo_)];
        kept.resize(n - m);
        SystematicResample(island_w_, IslandUniform(options_.seed, step_, j, 0), *workers_, kept);
        for (uint32_t& p : kept) p += static_cast<uint32_t>(begin);
        if (heaviest_ >= island.first && heaviest_ - island.first < n) {
          // The heaviest particle's first copy, or the next one's (as Resample()).
          heaviest = island.first + (std::lower_bound(kept.begin(), kept.end(),
                                                      static_cast<uint32_t>(heaviest_ - first_)) -
                                     kept.begin());
        }
        if (m == 0) continue;
        auto m0 = Clock::now();
        drawn.resize(m);
        SystematicResample(island_w_, IslandUniform(options_.seed, step_, j, 1), *workers_, drawn);
        which.clear();
        copies.clear();
        for (uint32_t p : drawn) {
          if (which.empty() || which.back() != begin + p) {
            which.push_back(static_cast<uint32_t>(begin + p));
            copies.push_back(0);
          }
          ++copies.back();
        }
        sent[static_cast<size_t>(j - island_lo_)] = WriteParticles(which, copies);
        last_sent = which.size();
        migrate_s_ += Seconds(Clock::now() - m0);
      }
      if (options_.collective != nullptr) {
        GROVE_RETURN_IF_ERROR(AgreeStatus(*options_.collective, s));
      } else {
        GROVE_RETURN_IF_ERROR(s);
      }
      // What each of this rank's islands receives: from the island before it, here or on the
      // rank before.
      std::vector<std::string> from_rank;
      if (m > 0 && ranks > 1) {
        std::vector<std::string> to(static_cast<size_t>(ranks));
        const int next = (me + 1) % ranks;
        to[static_cast<size_t>(next)] = sent.back();
        sent_bytes_ += sent.back().size();
        sent_particles_ += last_sent;
        GROVE_RETURN_IF_ERROR(options_.collective->AllToAll(to, &from_rank));
      }
      auto m1 = Clock::now();
      parents_.clear();
      for (int j = island_lo_; j < island_hi_ && s.ok(); ++j) {
        const size_t at = static_cast<size_t>(j - island_lo_);
        parents_.insert(parents_.end(), own[at].begin(), own[at].end());
        if (m == 0) continue;
        const int before = (j + islands - 1) % islands;
        const std::string& bytes = at > 0 ? sent[at - 1]
                                   : ranks > 1
                                       ? from_rank[static_cast<size_t>((me + ranks - 1) % ranks)]
                                       : sent[static_cast<size_t>(local - 1)];
        const std::string name = "particles from island " + std::to_string(before);
        uint64_t read = 0;
        s = ReadParticles(bytes, name, m, &read);
        if (s.ok() && read != m) {
          s = DataLossError(name + ": " + std::to_string(read) + " copies for " +
                            std::to_string(m) + " migrants");
        }
      }
      if (s.ok() && parents_.size() != log_w_.size()) {
        s = InternalError("island resampling: " + std::to_string(parents_.size()) + " copies for " +
                          std::to_string(log_w_.size()) + " particles");
      }
      migrate_s_ += Seconds(Clock::now() - m1);
      if (options_.collective != nullptr) {
        GROVE_RETURN_IF_ERROR(AgreeStatus(*options_.collective, s));
        std::vector<uint64_t> all;
        GROVE_RETURN_IF_ERROR(
            AllGatherValues<uint64_t>(*options_.collective, std::span(&heaviest, 1), &all));
        heaviest = *std::min_element(all.begin(), all.end());
      } else {
        GROVE_RETURN_IF_ERROR(s);
      }
      heaviest_ = heaviest;
      TakeGeneration(t0);
      return Status::Ok();
    }
  }

  Model* model_;
  WorkerPool* workers_;
  FilterOptions options_;
  uint64_t total_;  // particles in the whole filter
  uint64_t first_;  // this rank's first particle
  std::vector<double> log_w_;
  std::vector<double> weights_;     // exp(log_w_) after the last normalisation
  std::vector<double> block_sums_;  // BlockSums(weights_) after the last normalisation
  std::vector<MaxPart> maxes_;      // the last advance's batches' heaviest particles
  std::vector<uint32_t> parents_;
  std::vector<uint64_t> slots_;   // across ranks: each particle's first copy
  std::vector<double> island_w_;  // island mode: an island's weights over its heaviest
  int island_lo_ = 0;             // island mode: this rank's islands [island_lo_, island_hi_)
  int island_hi_ = 1;
  uint64_t migrants_ = 0;  // island mode: the particles an island sends at an exchange
  uint64_t sent_bytes_ = 0;
  uint64_t sent_particles_ = 0;
  double migrate_s_ = 0;
  bool options_checked_ = false;
  bool release_pending_ = false;  // the dead generation waits for the next advance
  std::vector<Status> batch_status_;
  size_t heaviest_ = 0;
  uint64_t step_ = 0;
  uint64_t resamplings_ = 0;
  uint64_t weight_steps_ = 0;
  double ess_ = 0;
  double ess_sum_ = 0;
  PhaseTimes times_;
};

}  // namespace grove

#endif  // GROVE_ENGINE_FILTER_PARTICLE_FILTER_H_
