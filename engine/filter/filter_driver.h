// FilterDriver: what every model's engine does around its ParticleFilter, written once: the
// failure latch, the time of every step, the weighted-mean pose after every step, the
// summary's counters and the generic part of a checkpoint body. A model's facade owns one (with
// its model and worker pool) and adds only what is its own: inputs, maps and read-outs.
//
// The model is a PosedModel: a FilterModel with the pose of each particle after a step.
//
// Errors: a step with a bad time (grove/input_rules.h, or out of order) returns InvalidArgument
// and changes nothing; a step the model or the filter fails (its message prefixed with
// "step K (t = T s): "), and any exception or allocation failure inside one (ResourceExhausted,
// Internal), latches the driver failed: the message ends with kStoppedNote, an InvalidArgument
// becomes FailedPrecondition (that code promises an unchanged engine), every later step returns
// FailedPrecondition and the state may not be checkpointed.
//
// Thread safety: one thread drives an engine (see ParticleFilter).
#ifndef GROVE_ENGINE_FILTER_FILTER_DRIVER_H_
#define GROVE_ENGINE_FILTER_FILTER_DRIVER_H_

#include <fmt/format.h>
#include <oneapi/tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <memory>
#include <new>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "alloc/check.h"
#include "concurrency/worker_pool.h"
#include "engine/filter/filter_model.h"
#include "engine/filter/filter_options.h"
#include "engine/filter/particle_filter.h"
#include "engine/filter/resampler.h"
#include "engine/io/checkpoint_io.h"
#include "grove/input_rules.h"
#include "grove/status.h"
#include "grove/types.h"

namespace grove {

// Runs f() -> StatusOr<T> or Status, turning an escaping exception into a status: what every
// facade call that builds a container wraps itself in.
template <typename F>
auto NoThrow(F&& f) noexcept -> decltype(f()) {
  try {
    return f();
  } catch (const std::bad_alloc&) {
    return ResourceExhaustedError("out of memory");
  } catch (const std::exception& e) {
    return InternalError(std::string("unexpected exception: ") + e.what());
  } catch (...) {
    return InternalError("unexpected exception");
  }
}

enum class TimeOrder {
  kIncreasing,     // every step after the one before (FootSLAM's steps)
  kNonDecreasing,  // a step may share the time of the one before (an update after a prediction)
};

// What the message of an error that stopped an engine ends with.
inline constexpr char kStoppedNote[] = " (the engine stopped here: every later step fails)";

template <PosedModel Model>
class FilterDriver {
 public:
  FilterDriver(Model* model, WorkerPool* workers, const FilterOptions& options,
               int threads_requested, const Pose2& start, TimeOrder order)
      : model_(model),
        workers_(workers),
        filter_(model, workers, options),
        threads_requested_(threads_requested),
        order_(order) {
    times_.push_back(0.0);
    mean_.push_back({0.0, start});
  }

  // A weighting step on `input` at time t_s. Alone (not across ranks), each batch of the loop
  // that completes the step sums its own sub-blocks of the mean pose when the filter lets it
  // (ParticleFilter::Update with a per-batch call), so the mean needs no pass of its own on the
  // driving thread; the same sums, added in the same order, as ComputeMeanPose().
  template <typename Input>
  Status Update(double t_s, const Input& input) {
    weights_current_ = false;
    if (filter_.options().collective != nullptr) {
      return Step(t_s, [&] { return filter_.Update(input); });
    }
    return Step(t_s, [&] {
      settled_mean_.reset();
      const size_t n = model_->size();
      weights_.resize(n);
      sub_sums_.resize(SubBlocks(n));
      bool summed = false;
      Status s = filter_.Update(
          input,
          [&](size_t begin, size_t end) {
            FillWeights(filter_.log_weights(), begin, end);
            SumSubBlocks(begin, end, sub_sums_.data());
          },
          &summed);
      if (s.ok() && summed) {
        std::vector<Sum> sums((n + kSumBlock - 1) / kSumBlock);
        AddSubBlocks(sub_sums_.data(), sub_sums_.size(), sums.data());
        settled_mean_ = PoseOf(sums);
        weights_current_ = true;
      }
      return s;
    });
  }
  // A predict-only step on `input` at time t_s.
  template <typename Input>
  Status Predict(double t_s, const Input& input) {
    return Step(t_s, [&] { return filter_.Predict(input); });
  }

  // Predict(times[j], inputs[j]) for each j in turn, with the same state, times, mean poses and
  // errors, in one pass over the particles (ParticleFilter::PredictRun): what a facade uses for
  // the predictions between two weighting steps. Each batch keeps the sums of its sub-blocks of
  // the mean pose after each input, in runs of at most kRunSumBytes of them; where a run would
  // hold one input (beyond about 3 million particles), and across ranks, input by input.
  // InvalidArgument, nothing changed, for a bad time (as Predict()).
  template <typename Input>
  Status PredictRun(std::span<const double> times, std::span<const Input> inputs) {
    GROVE_DCHECK(times.size() == inputs.size());
    const size_t n = model_->size();
    const size_t per_run = workers_->num_threads() == 1
                               ? inputs.size()
                               : std::max<size_t>(1, kRunSumBytes / (sizeof(Sum) * SubBlocks(n)));
    if (filter_.options().collective != nullptr || inputs.size() == 1 || per_run == 1) {
      for (size_t j = 0; j < inputs.size(); ++j) {
        GROVE_RETURN_IF_ERROR(Predict(times[j], inputs[j]));
      }
      return Status::Ok();
    }
    for (size_t j = 0; j < times.size(); ++j) {
      GROVE_RETURN_IF_ERROR(CheckTime(times[j], j == 0 ? times_.back() : times[j - 1],
                                      steps() + 1 + static_cast<int64_t>(j)));
    }
    GROVE_RETURN_IF_ERROR(CheckNotFailed("cannot be stepped again"));
    return Guarded([&]() -> Status {
      for (size_t first = 0; first < inputs.size(); first += per_run) {
        const size_t count = std::min(per_run, inputs.size() - first);
        GROVE_RETURN_IF_ERROR(RunPart(times.subspan(first, count), inputs.subspan(first, count)));
      }
      return Status::Ok();
    });
  }

  // Sets the time of the start pose; the first step must not come before it. Without it the
  // start takes the first step's time. InvalidArgument for a non-finite time,
  // FailedPrecondition after the first step.
  Status SetStartTime(double t_s) {
    if (Status s = CheckInput(InputField::kTime, t_s); !s.ok()) {
      return InvalidArgumentError("start time: " + s.message());
    }
    if (filter_.steps() > 0) {
      return FailedPreconditionError("the start time must be set before the first step");
    }
    start_time_unset_ = false;
    times_.front() = t_s;
    mean_.front().t_s = t_s;
    return Status::Ok();
  }

  // Runs f() -> Status, turning an exception escaping it into a status and latching the driver
  // failed: no exception leaves the engine.
  template <typename F>
  Status Guarded(F&& f) noexcept {
    try {
      return f();
    } catch (const std::bad_alloc&) {
      return Stop(ResourceExhaustedError("out of memory"));
    } catch (const std::exception& e) {
      return Stop(InternalError(std::string("unexpected exception: ") + e.what()));
    } catch (...) {
      return Stop(InternalError("unexpected exception"));
    }
  }

  // Runs f() -> Status between steps (a model's housekeeping on the state a step left); an error
  // or an exception stops the engine as a failed step does.
  template <typename F>
  Status AfterStep(F&& f) noexcept {
    Status status = Guarded(f);
    if (!status.ok() && !failed_) return Stop(status);
    return status;
  }

  bool failed() const { return failed_; }
  // Whether the start time is known: set by SetStartTime() or by the first step.
  bool start_time_set() const { return !start_time_unset_; }
  // FailedPrecondition after an error stopped the engine.
  Status CheckNotFailed(const char* what) const {
    if (!failed_) return Status::Ok();
    return FailedPreconditionError(std::string("the engine stopped at an earlier error and ") +
                                   what);
  }

  int64_t steps() const { return static_cast<int64_t>(filter_.steps()); }
  // times()[k]: the time of the state after step k (k = 0: the start).
  const std::vector<double>& times() const { return times_; }
  const std::vector<StampedPose>& mean_trajectory() const { return mean_; }
  const ParticleFilter<Model>& filter() const { return filter_; }

  FilterSummary Summary() const {
    FilterSummary s;
    s.particles = static_cast<int64_t>(filter_.total_particles());
    s.threads_requested = threads_requested_;
    // oneTBB never runs more threads than the process may use, whatever the arena asks for.
    s.threads_used = std::min(workers_->num_threads(), tbb::info::default_concurrency());
    s.steps = steps();
    s.resamplings = static_cast<int64_t>(filter_.resamplings());
    s.mean_ess = filter_.mean_ess();
    const PhaseTimes& t = filter_.phase_times();
    s.advance_s = t.advance_s;
    s.normalize_s = t.normalize_s;
    s.resample_s = t.resample_s;
    s.release_s = t.release_s;
    s.bookkeeping_s = bookkeeping_s_;
    s.sent_particles = static_cast<int64_t>(filter_.sent_particles());
    s.sent_bytes = static_cast<int64_t>(filter_.sent_bytes());
    s.migrate_s = filter_.migrate_seconds();
    const WorkerPool::Usage usage = workers_->usage();
    s.loop_s = usage.loop_s;
    s.loop_busy_s = usage.busy_s;
    s.loops = static_cast<int64_t>(usage.loops);
    return s;
  }

  // The generic state: times, mean poses, bookkeeping time, the start flag and the filter.
  void Save(ByteWriter* w) const {
    w->Put<uint64_t>(times_.size());
    w->PutBytes(times_.data(), times_.size() * sizeof(double));
    w->Put<uint64_t>(mean_.size());
    for (const StampedPose& p : mean_) {
      w->Put(p.t_s);
      w->Put(p.pose.x_m);
      w->Put(p.pose.y_m);
      w->Put(p.pose.heading_rad);
    }
    w->Put<double>(bookkeeping_s_);
    w->Put<uint8_t>(start_time_unset_ ? 1 : 0);
    filter_.Save(w);
  }

  // Reads what Save() wrote into a new driver; checks counts, order and finiteness.
  Status Load(ByteReader* r) {
    uint64_t count = 0;
    GROVE_RETURN_IF_ERROR(r->GetCount("time count", sizeof(double), &count));
    std::vector<double> times(count);
    GROVE_RETURN_IF_ERROR(r->GetBytes("times", times.data(), count * sizeof(double)));
    GROVE_RETURN_IF_ERROR(r->GetCount("mean pose count", 4 * sizeof(double), &count));
    std::vector<StampedPose> mean(count);
    for (StampedPose& p : mean) {
      double v[4];
      GROVE_RETURN_IF_ERROR(r->GetBytes("mean pose", v, sizeof(v)));
      p = {v[0], Pose2{v[1], v[2], v[3]}};
    }
    double bookkeeping_s = 0;
    uint8_t unset = 0;
    GROVE_RETURN_IF_ERROR(r->Get("bookkeeping time", &bookkeeping_s));
    GROVE_RETURN_IF_ERROR(r->Get("start time unset", &unset));
    if (!(bookkeeping_s >= 0 && bookkeeping_s < 1e12)) {
      return r->Error("bookkeeping time", "not a duration");
    }
    GROVE_RETURN_IF_ERROR(filter_.Load(r));
    const uint64_t steps = filter_.steps();
    if (times.size() != steps + 1 || mean.size() != steps + 1) {
      return r->Error("times", "not one per pose (" + std::to_string(steps + 1) + ")");
    }
    for (size_t k = 0; k < times.size(); ++k) {
      bool ordered =
          k == 0 || (k == 1 || order_ == TimeOrder::kNonDecreasing ? times[k] >= times[k - 1]
                                                                   : times[k] > times[k - 1]);
      if (!std::isfinite(times[k]) || !ordered || mean[k].t_s != times[k]) {
        return r->Error("times", "not finite and increasing");
      }
      const Pose2& p = mean[k].pose;
      if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !std::isfinite(p.heading_rad)) {
        return r->Error("mean pose", "not finite");
      }
    }
    if (unset > 1 || (unset == 1 && steps > 0)) return r->Error("start time unset", "invalid");
    times_.swap(times);
    mean_.swap(mean);
    weights_current_ = false;
    bookkeeping_s_ = bookkeeping_s;
    start_time_unset_ = unset == 1;
    return Status::Ok();
  }

 private:
  // A particle's pose, for the mean pose.
  struct PoseSample {
    double x, y, c, s;
  };
  // PredictRun(): the most bytes of sub-block sums a run keeps.
  static constexpr size_t kRunSumBytes = size_t{8} << 20;
  static size_t SubBlocks(size_t n) { return (n + kMeanSubBlock - 1) / kMeanSubBlock; }

  // InvalidArgument unless step `step`'s time t_s is finite and in order after `previous`.
  Status CheckTime(double t_s, double previous, int64_t step) const {
    if (Status s = CheckInput(InputField::kTime, t_s); !s.ok()) {
      return InvalidArgumentError(fmt::format("step {}: {}", step, s.message()));
    }
    if (start_time_unset_ && step == steps() + 1) return Status::Ok();
    const bool ok = order_ == TimeOrder::kIncreasing ? t_s > previous : t_s >= previous;
    if (ok) return Status::Ok();
    return InvalidArgumentError(
        fmt::format("step {}: t = {} is {} the previous time {}: times must be {}", step, t_s,
                    order_ == TimeOrder::kIncreasing ? "not after" : "before", previous,
                    order_ == TimeOrder::kIncreasing ? "strictly increasing" : "non-decreasing"));
  }

  // Before `count` steps from time t_s on: the start time if it was unset, and room for their
  // times and mean poses (growing geometrically), so that nothing after fails half-way for want
  // of memory.
  void StartStepping(double t_s, size_t count) {
    if (start_time_unset_) {
      times_.front() = t_s;
      mean_.front().t_s = t_s;
      start_time_unset_ = false;
    }
    if (times_.size() + count > times_.capacity()) {
      times_.reserve(std::max(2 * times_.size() + 16, times_.size() + count));
    }
    if (mean_.size() + count > mean_.capacity()) {
      mean_.reserve(std::max(2 * mean_.size() + 16, mean_.size() + count));
    }
  }

  // One part of PredictRun(): the filter's run, then the times and mean poses of the inputs it
  // completed (and the time of a failed one, as Step()). Each batch (whole sub-blocks of the
  // mean: BatchSize()) sums its own sub-blocks after each input, on its thread; the blocks'
  // sums add them in order, as SumOf() does: as the run goes with one thread (the batches run
  // in particle order), afterwards with more.
  template <typename Input>
  Status RunPart(std::span<const double> times, std::span<const Input> inputs) {
    StartStepping(times.front(), times.size());
    const size_t n = model_->size();
    const size_t blocks = (n + kSumBlock - 1) / kSumBlock;
    const size_t subs = SubBlocks(n);
    const bool in_order = workers_->num_threads() == 1;
    std::vector<Sum> sums(inputs.size() * blocks);
    if (!in_order) sub_sums_.resize(inputs.size() * subs);
    const bool current = weights_current_ && weights_.size() == n;
    std::span<const double> lw = filter_.log_weights();
    weights_.resize(n);
    size_t done = 0;
    Status status = filter_.PredictRun(
        inputs,
        [&](size_t j, size_t begin, size_t end) {
          if (j == 0 && !current) FillWeights(lw, begin, end);
          if (!in_order) {
            SumSubBlocks(begin, end, &sub_sums_[j * subs]);
            return;
          }
          auto sub = [&](size_t b) {
            return SubBlockSum(b, std::min(end, b + kMeanSubBlock),
                               [&](size_t i) { return SampleOf(i); });
          };
          // In a local per block: the compiler keeps the chain of adds in registers.
          for (size_t b = begin; b < end;) {
            const size_t e = std::min(end, (b / kSumBlock + 1) * kSumBlock);
            Sum& total = sums[j * blocks + b / kSumBlock];
            Sum local = total;
            for (; b < e; b += kMeanSubBlock) AddSum(&local, sub(b));
            total = local;
          }
        },
        &done);
    sums.resize(done * blocks);
    // A failed first input leaves batches without weights.
    weights_current_ = current || done > 0;
    auto t0 = std::chrono::steady_clock::now();
    for (size_t j = 0; !in_order && j < done; ++j) {
      AddSubBlocks(&sub_sums_[j * subs], subs, &sums[j * blocks]);
    }
    for (size_t j = 0; j < done; ++j) {
      times_.push_back(times[j]);
      mean_.push_back({times[j], PoseOf(std::span<const Sum>(sums).subspan(j * blocks, blocks))});
    }
    bookkeeping_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (status.ok()) return Status::Ok();
    times_.push_back(times[done]);
    return Stop(Status(status.code(), fmt::format("step {} (t = {} s): {}", filter_.steps(),
                                                  times[done], status.message())));
  }

  template <typename Run>
  Status Step(double t_s, Run&& run) {
    GROVE_RETURN_IF_ERROR(CheckNotFailed("cannot be stepped again"));
    GROVE_RETURN_IF_ERROR(CheckTime(t_s, times_.back(), steps() + 1));
    return Guarded([&]() -> Status {
      StartStepping(t_s, 1);
      Status status = run();
      times_.push_back(t_s);
      if (!status.ok()) {
        return Stop(Status(status.code(), fmt::format("step {} (t = {} s): {}", filter_.steps(),
                                                      t_s, status.message())));
      }
#ifdef GROVE_EXPENSIVE_CHECKS
      // Debug builds walk every shared node after every step (mimalloc's expensive level).
      if constexpr (requires { model_->CheckCounts(); }) {
        Status counts = model_->CheckCounts();
        if (!counts.ok()) std::fprintf(stderr, "%s\n", counts.ToString().c_str());
        GROVE_CHECK(counts.ok());
      }
#endif
      auto t0 = std::chrono::steady_clock::now();
      StatusOr<Pose2> mean = settled_mean_.has_value() ? *settled_mean_ : ComputeMeanPose();
      settled_mean_.reset();
      if (!mean.ok()) return Stop(mean.status());
      mean_.push_back({t_s, *mean});
      bookkeeping_s_ +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      return Status::Ok();
    });
  }

  // Latches the driver failed and returns `s` saying so. InvalidArgument promises an unchanged
  // engine, which a half-done step is not: it becomes FailedPrecondition.
  Status Stop(const Status& s) {
    if (failed_) return s;
    failed_ = true;
    const StatusCode code =
        s.code() == StatusCode::kInvalidArgument ? StatusCode::kFailedPrecondition : s.code();
    return Status(code, s.message() + kStoppedNote);
  }

  // Weighted mean pose over fixed blocks (circular mean for the heading); across ranks, every
  // rank's blocks in rank order, which is block order. The weights exp(log w_i) are kept from one
  // step to the next until a weighting step changes them (a prediction does not).
  struct Sum {
    double w = 0, x = 0, y = 0, c = 0, s = 0;
  };
  StatusOr<Pose2> ComputeMeanPose() {
    auto lw = filter_.log_weights();
    const bool current = weights_current_ && weights_.size() == lw.size();
    weights_.resize(lw.size());
    std::vector<Sum> sums = workers_->template MapBlocks<Sum>(
        model_->size(), kSumBlock, [&](size_t, size_t b, size_t e) {
          if (!current) FillWeights(lw, b, e);
          return SumOf(b, e, [&](size_t i) { return SampleOf(i); });
        });
    weights_current_ = true;
    if (Collective* ranks = filter_.options().collective; ranks != nullptr) {
      std::vector<Sum> all;
      GROVE_RETURN_IF_ERROR(AllGatherValues<Sum>(*ranks, sums, &all));
      sums.swap(all);
    }
    return PoseOf(sums);
  }

  // weights_[i] = exp(lw[i]) for i in [b, e); after resampling every weight is the same: one
  // exp, not one per particle. (The same values however [b, e) is cut.)
  void FillWeights(std::span<const double> lw, size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      weights_[i] = i == b || lw[i] != lw[i - 1] ? std::exp(lw[i]) : weights_[i - 1];
    }
  }

  PoseSample SampleOf(size_t i) const {
    return {model_->x(i), model_->y(i), model_->cos_heading(i), model_->sin_heading(i)};
  }
  static void Add(Sum* s, double w, const PoseSample& p) {
    s->w += w;
    s->x += w * p.x;
    s->y += w * p.y;
    s->c += w * p.c;
    s->s += w * p.s;
  }
  static void AddSum(Sum* total, const Sum& s) {
    total->w += s.w;
    total->x += s.x;
    total->y += s.y;
    total->c += s.c;
    total->s += s.s;
  }
  // The weighted sums of the particles of one sub-block [b, e), added in index order; pose(i)
  // gives a PoseSample. In a local: the compiler keeps the chain of adds in registers.
  template <typename PoseOfParticle>
  Sum SubBlockSum(size_t b, size_t e, PoseOfParticle&& pose) const {
    Sum s;
    for (size_t i = b; i < e; ++i) Add(&s, weights_[i], pose(i));
    return s;
  }
  // The sums of the sub-blocks of particles [begin, end) as they are now (begin a multiple of
  // kMeanSubBlock), into subs[b / kMeanSubBlock] for each sub-block starting at b: one batch's
  // part of a step's mean, on its thread.
  void SumSubBlocks(size_t begin, size_t end, Sum* subs) const {
    for (size_t b = begin; b < end; b += kMeanSubBlock) {
      subs[b / kMeanSubBlock] =
          SubBlockSum(b, std::min(end, b + kMeanSubBlock), [&](size_t i) { return SampleOf(i); });
    }
  }
  // Adds `count` sub-block sums, in order, to the sums of their blocks of kSumBlock particles:
  // the blocks' sums as SumOf() adds them.
  static void AddSubBlocks(const Sum* subs, size_t count, Sum* blocks) {
    for (size_t k = 0; k < count; ++k) AddSum(&blocks[k * kMeanSubBlock / kSumBlock], subs[k]);
  }
  // The weighted sums of block [b, e) (b a multiple of kMeanSubBlock): its sub-blocks' sums,
  // added in order.
  template <typename PoseOfParticle>
  Sum SumOf(size_t b, size_t e, PoseOfParticle&& pose) const {
    Sum s;
    for (size_t k = b; k < e; k += kMeanSubBlock) {
      AddSum(&s, SubBlockSum(k, std::min(e, k + kMeanSubBlock), pose));
    }
    return s;
  }

  // The mean pose of the blocks' sums, added in block order.
  static Pose2 PoseOf(std::span<const Sum> sums) {
    Sum total;
    for (const Sum& s : sums) AddSum(&total, s);
    return Pose2{total.x / total.w, total.y / total.w, std::atan2(total.s, total.c)};
  }

  Model* model_;
  WorkerPool* workers_;
  ParticleFilter<Model> filter_;
  int threads_requested_;
  TimeOrder order_;
  std::vector<double> times_;  // times_[k]: time of the state after step k (k = 0: the start)
  std::vector<StampedPose> mean_;
  double bookkeeping_s_ = 0;
  std::vector<double> weights_;        // exp of the log weights, for the mean pose
  std::vector<Sum> sub_sums_;          // PredictRun(): each input's sub-block sums in a part
  std::optional<Pose2> settled_mean_;  // Update(): the step's mean, summed in its batches
  bool weights_current_ = false;       // weights_ holds the filter's weights now
  bool start_time_unset_ = true;
  bool failed_ = false;
};

}  // namespace grove

#endif  // GROVE_ENGINE_FILTER_FILTER_DRIVER_H_
