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
//      PieceReleasingModel in a filter alone releases it in pieces inside the next parallel
//      loop instead: the next step's, or complete's for up to 4,096 particles);
//   4. complete (optional): a model whose weights do not depend on what it draws (FastSLAM
//      2.0) draws and updates after resampling, in parallel over batches;
//   5. population (optional): a model that needs the whole population once its particles are
//      drawn (moving them towards the best one, as differential evolution does) gets it last:
//      after complete, or for a model without it after advance (then before normalising).
// One Predict() propagates every particle without weighting (a landmark filter predicts at the
// control rate and weights only at scans); PredictRun() does several in one parallel loop. Each
// input counts as one step of the random streams.
// Sums over particles are taken over fixed blocks and every draw comes from a counter-based
// stream, so the same seed gives bit-identical weights at any thread count. A batch that fails
// returns a Status; the step's result is the failure of the lowest failing batch, so the same
// error is reported at any thread count. Across ranks (FilterOptions::collective) a
// RankResampler resamples, in island mode an IslandResampler.
//
// Thread safety: one thread drives a filter; the filter uses its WorkerPool inside a step.
#ifndef GROVE_ENGINE_FILTER_PARTICLE_FILTER_H_
#define GROVE_ENGINE_FILTER_PARTICLE_FILTER_H_

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "alloc/check.h"
#include "concurrency/worker_pool.h"
#include "engine/filter/filter_model.h"
#include "engine/filter/filter_options.h"
#include "engine/filter/island_resampler.h"
#include "engine/filter/particle_migration.h"
#include "engine/filter/rank_resampler.h"
#include "engine/filter/resampler.h"
#include "engine/io/checkpoint_io.h"
#include "engine/ranks/collective.h"
#include "grove/status.h"

namespace grove {

// Wall time spent in each phase, summed over steps (seconds).
struct PhaseTimes {
  double advance_s = 0;    // propagate, weight and update maps
  double normalize_s = 0;  // log-sum-exp and ESS
  double resample_s = 0;   // drawing parents and gathering the new generation
  double release_s = 0;    // freeing the dead generation (in advance_s when freed in pieces)
};

// RunInBatches' batch size: batch b is particles [b * size, (b + 1) * size). A whole number of
// kMeanSubBlock particles (max_batch rounded up), so a batch holds whole sub-blocks of the mean.
inline size_t BatchSize(const WorkerPool& workers, size_t n, size_t max_batch) {
  const size_t threads = static_cast<size_t>(workers.num_threads());
  size_t batch = std::max<size_t>(max_batch, 1);
  if (threads > 1) batch = std::clamp<size_t>((n + 4 * threads - 1) / (4 * threads), 1, batch);
  return (batch + kMeanSubBlock - 1) / kMeanSubBlock * kMeanSubBlock;
}

// Runs body(slot, begin, end) -> Status over [0, n) in batches of BatchSize(): max_batch
// particles, fewer when that leaves a thread under 4 batches (100 particles in batches of 64
// would keep two threads at 64 and 36), rounded up to whole sub-blocks; returns the error of the
// lowest failing batch, which is the error of the lowest failing particle whatever the batches when
// a batch stops at its first. `status` is scratch space (one entry per batch), kept by the caller
// to avoid an allocation per loop.
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
        parents_(model->size()),
        ranks_(options.collective, total_, first_, options.seed),
        islands_(options, total_, first_) {}

  // Runs one weighting step on `input`. Returns the model's error (the lowest failing batch's),
  // or FailedPrecondition when every particle weight is zero or non-finite after the update
  // (the filter has degenerated). After an error the particles are partly advanced: the
  // caller must not step again.
  template <typename Input>
  requires WeightingModel<Model, Input> Status Update(const Input& input) {
    bool unused = false;
    return Update(
        input, [](size_t, size_t) {}, &unused);
  }

  // Update() that also calls settled(begin, end) on each batch of particles once the step has
  // made them final (their poses and weights), inside the loop that completes the step: when the
  // model completes it and no population phase moves particles after (PopulationMoves()). A
  // caller's per-batch work on the final particles (the driver's mean pose) then needs no loop
  // of its own. *all_settled: whether every batch was passed to it.
  template <typename Input, typename Settled>
  requires WeightingModel<Model, Input> Status Update(const Input& input, Settled&& settled,
                                                      bool* all_settled) {
    *all_settled = false;
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
    const bool exchange = islands_.Exchanges(step_);
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
      // A generation just resampled is freed before or among the draws that copy the maps. A
      // large one whole first: freed in pieces among the draws, the dead maps and the new copies
      // would add up (Victoria Park with 10,000 particles: a fifth more peak memory). A small
      // one in pieces: whole, up to 1,024 particles are one thread's chunk.
      auto t_release = Clock::now();
      const bool in_pieces = release_pending_ && log_w_.size() <= kPiecesAmongDraws;
      if (!in_pieces) FinishRelease();
      auto t3 = Clock::now();
      times_.release_s += Seconds(t3 - t_release);
      bool final = true;
      if constexpr (PopulationModel<Model, Input>) {
        if constexpr (requires { model_->PopulationMoves(input); }) {
          final = !model_->PopulationMoves(input);
        } else {
          final = false;
        }
      }
      status = ForBatches([&](int slot, size_t begin, size_t end) {
        if constexpr (PieceReleasingModel<Model>) {
          if (in_pieces) model_->ReleaseDeadRange(DeadFrom(begin), DeadFrom(end), slot);
        }
        Status s = model_->Complete(input, step_, begin, end, slot);
        if (s.ok() && final) settled(begin, end);
        return s;
      });
      if constexpr (PieceReleasingModel<Model>) {
        if (in_pieces) model_->DeadReleased();
      }
      release_pending_ = false;
      *all_settled = final && status.ok();
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
    size_t done = 0;
    return PredictRun(
        std::span<const Input>(&input, 1), [](size_t, size_t, size_t) {}, &done);
  }

  // Predict() on each of `inputs` in turn, in one pass over the particles: each batch runs
  // through every input before it ends, so a run costs one parallel loop, not one per input.
  // after(j, begin, end) runs on a batch once input j has moved it. *done gets the inputs every
  // particle completed; on an error it is the failing input's index, the error is that of its
  // lowest failing particle (as Predict() on each in turn would return) and the particles are
  // partly advanced. Across ranks, one input at a time (the ranks agree on each step's status).
  template <typename Input, typename After>
  requires PredictingModel<Model, Input> Status PredictRun(std::span<const Input> inputs,
                                                           After&& after, size_t* done) {
    GROVE_DCHECK(options_.collective == nullptr || inputs.size() == 1);
    auto t0 = std::chrono::steady_clock::now();
    bool release = release_pending_;
    if constexpr (!PieceReleasingModel<Model>) {
      FinishRelease();
      release = false;
    }
    const size_t batch = BatchSize(*workers_, log_w_.size(), options_.batch);
    failed_input_.assign((log_w_.size() + batch - 1) / batch, inputs.size());
    Status status = ForBatches([&](int slot, size_t begin, size_t end) {
      if constexpr (PieceReleasingModel<Model>) {
        if (release) model_->ReleaseDeadRange(DeadFrom(begin), DeadFrom(end), slot);
      }
      for (size_t j = 0; j < inputs.size(); ++j) {
        Status s = model_->Predict(inputs[j], step_ + j, begin, end, slot);
        if (!s.ok()) {
          failed_input_[begin / batch] = j;
          return s;
        }
        after(j, begin, end);
      }
      return Status::Ok();
    });
    if constexpr (PieceReleasingModel<Model>) {
      if (release) model_->DeadReleased();
    }
    release_pending_ = false;
    *done = inputs.size();
    if (!status.ok()) {
      // `status` is the lowest failing batch's (moved out); the lowest failing input's lowest
      // failing batch may be a later one.
      size_t lowest = failed_input_.size(), best = 0;
      for (size_t b = 0; b < failed_input_.size(); ++b) {
        if (failed_input_[b] == inputs.size()) continue;
        if (lowest == failed_input_.size()) lowest = b;
        if (failed_input_[b] < *done) {
          *done = failed_input_[b];
          best = b;
        }
      }
      if (best != lowest) status = std::move(batch_status_[best]);
    }
    if (options_.collective != nullptr) status = AgreeStatus(*options_.collective, status);
    times_.advance_s += Seconds(std::chrono::steady_clock::now() - t0);
    step_ += status.ok() ? inputs.size() : *done + 1;
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
  uint64_t sent_bytes() const { return migration_.sent_bytes; }
  uint64_t sent_particles() const { return migration_.sent_particles; }
  // Across ranks: seconds spent writing and reading the particles that move (not sending them).
  double migrate_seconds() const { return migration_.migrate_s; }

 private:
  template <typename D>
  static double Seconds(D d) {
    return std::chrono::duration<double>(d).count();
  }

  // Runs body(slot, begin, end) -> Status over batches of about options_.batch particles
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

  // Up to this many particles a dead generation is freed in pieces among complete's draws.
  static constexpr size_t kPiecesAmongDraws = 4096;

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
      mine = islands_.Configure(MigratingModel<Model>);
    }
    if (options_.collective == nullptr) return mine;
    return AgreeFilterOptions(*options_.collective, options_, total_, log_w_.size(),
                              std::move(mine));
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
    GatherGeneration(*model_, std::span<const uint32_t>(parents_),
                     BatchSize(*workers_, parents_.size(), options_.batch), *workers_);
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

  // Resampling across ranks (RankResampler) and in island mode (IslandResampler).
  Status ResampleAcross() {
    auto t0 = std::chrono::steady_clock::now();
    if constexpr (!MigratingModel<Model>) {
      return InvalidArgumentError("the model's particles cannot move between ranks");
    } else {
      GROVE_RETURN_IF_ERROR(ranks_.Resample(step_, weights_, block_sums_, *workers_, model_,
                                            &parents_, &heaviest_, &migration_));
      TakeGeneration(t0);
      return Status::Ok();
    }
  }
  Status ResampleIslands(bool exchange) {
    auto t0 = std::chrono::steady_clock::now();
    if constexpr (!MigratingModel<Model>) {
      return InvalidArgumentError("the model's particles cannot move between islands");
    } else {
      GROVE_RETURN_IF_ERROR(islands_.Resample(step_, exchange, log_w_, *workers_, model_, &parents_,
                                              &heaviest_, &migration_));
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
  RankResampler ranks_;
  IslandResampler islands_;
  MigrationStats migration_;
  bool options_checked_ = false;
  bool release_pending_ = false;  // the dead generation waits for the next advance
  std::vector<Status> batch_status_;
  std::vector<size_t> failed_input_;  // PredictRun(): per batch, the input it failed at
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
