// FastSlam::Impl, the run behind the landmark FastSLAM facade, and its implementation ImplOf
// over a model type. The facade (fastslam.cc) picks the model by the association; each model is
// instantiated in a translation unit of its own (fastslam_id_keyed.cc, fastslam_cell_keyed.cc),
// so that the compiler inlines each one's code as it would if it were the only one.
#ifndef GROVE_ENGINE_FASTSLAM_FASTSLAM_IMPL_H_
#define GROVE_ENGINE_FASTSLAM_FASTSLAM_IMPL_H_

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "concurrency/worker_pool.h"
#include "engine/fastslam/fastslam_model.h"
#include "engine/filter/filter_driver.h"
#include "engine/filter/filter_facade.h"
#include "engine/io/checkpoint_io.h"
#include "engine/ranks/collective.h"
#include "grove/fastslam.h"
#include "grove/input_rules.h"

namespace grove {

// A run behind the facade, whatever its model's map layout (ImplOf).
class FastSlam::Impl {
 public:
  virtual ~Impl() = default;
  virtual Status Control(double t_s, double v, double g) = 0;
  virtual Status Scan(double t_s, std::span<const LandmarkObservation> z) = 0;
  // Runs the deferred predictions; an error stops the engine (ImplOf::Settle()).
  virtual Status Settle() = 0;
  virtual void SettleQuietly() = 0;
  virtual const FastSlamConfig& config() const = 0;
  virtual int64_t steps() const = 0;
  virtual Pose2 MeanPose() const = 0;
  virtual Pose2 HeaviestPose() const = 0;
  virtual const std::vector<StampedPose>& MeanTrajectory() const = 0;
  virtual Pose2Covariance PoseCovariance() const = 0;
  virtual StatusOr<std::vector<StampedPose>> HeaviestTrajectory() const = 0;
  virtual StatusOr<std::vector<LandmarkEstimate>> HeaviestLandmarks() const = 0;
  virtual FastSlamSummary Summary() const = 0;
  virtual Status CheckInvariants() const = 0;
  virtual StatusOr<std::string> Checkpoint(std::string_view user_data) const = 0;
  virtual Status Load(ByteReader* r) = 0;
};

namespace fastslam_facade {

using fastslam::ControlStep;
using fastslam::PredictStep;
using fastslam::ScanStep;
using fastslam::SegmentHistory;
using fastslam::VehiclePose;

// FastSLAM's checkpoints. The body layout's version is bumped whenever it changes.
// Version 3: the seed's filters (their configuration fields, evolution counts).
// Version 4: the rank and rank count of the share it holds.
// Version 5: the association counts' truncated joint-compatibility searches; no segment flag
// (the step records say where a path segment starts).
// Version 6: under unknown association, bottom nodes of 2^kLog2CellsPerBottom cells
// (fastslam_model.h).
inline constexpr CheckpointFormat kFastSlamCheckpoint = {"grove fastslam", "FastSLAM", 6};

// What each filter step was: the replay of paths and the reported trajectory need it.
enum StepKind : uint8_t {
  kControlPredict = 0,  // a Control(): reported
  kScanPredict = 1,     // the prediction to a scan's time: not reported
  kScanUpdate = 2,      // a scan's update: reported
};

struct StepRecord {
  ControlStep control;  // for the predictions
  uint8_t kind = 0;
  uint8_t unused[7] = {};
};

// Observation k of a scan against grove/input_rules.h.
inline Status CheckObservation(size_t k, const LandmarkObservation& z, bool known) {
  Status s = CheckInput(InputField::kRange, z.range_m);
  if (s.ok()) s = CheckInput(InputField::kBearing, z.bearing_rad);
  if (s.ok()) s = CheckLandmarkId(z.id, known);
  if (!s.ok()) return InvalidArgumentError(fmt::format("observation {}: {}", k, s.message()));
  return Status::Ok();
}

template <typename Model>
class ImplOf final : public FastSlam::Impl {
 public:
  ImplOf(const FastSlamConfig& config, int threads, Collective* ranks)
      : config_(config),
        ranks_(ranks),
        share_(ShareOf(static_cast<uint64_t>(config.particles), ranks, kSumBlock)),
        workers_(threads),
        model_(config, workers_.num_slots(), share_, ranks),
        driver_(&model_, &workers_, FilterOptionsOf(config, ranks), config.threads,
                Pose2{config.start_x_m, config.start_y_m, config.start_heading_rad},
                TimeOrder::kNonDecreasing),
        geometry_(fastslam::VehicleGeometry::Of(config)) {
    reported_.push_back(driver_.mean_trajectory().front());
  }

  Status Control(double t_s, double v, double g) override {
    if (Status s = CheckInput(InputField::kTime, t_s); !s.ok()) {
      return InvalidArgumentError("control: " + s.message());
    }
    Status s = CheckInput(InputField::kSpeed, v);
    if (s.ok()) s = CheckSteering(config_, g);
    if (!s.ok()) {
      return InvalidArgumentError(fmt::format("control at t = {}: {}", t_s, s.message()));
    }
    GROVE_RETURN_IF_ERROR(CheckNotFailed("cannot take another control"));
    if (controls_ == 0) {
      GROVE_RETURN_IF_ERROR(driver_.SetStartTime(t_s));
      reported_.front().t_s = t_s;
    } else {
      if (!(t_s > last_control_s_)) {
        return InvalidArgumentError(
            fmt::format("control at t = {} is not after the previous control at t = {}: control "
                        "times must be strictly increasing",
                        t_s, last_control_s_));
      }
      if (t_s < LastTime()) {
        return InvalidArgumentError(
            fmt::format("control at t = {} is before the last scan at t = {}", t_s, LastTime()));
      }
      GROVE_RETURN_IF_ERROR(driver_.Guarded([&] {
        Defer(t_s, kControlPredict);
        return Status::Ok();
      }));
    }
    held_ = {v, g};
    last_control_s_ = t_s;
    ++controls_;
    return Status::Ok();
  }

  Status Scan(double t_s, std::span<const LandmarkObservation> z) override {
    if (Status s = CheckInput(InputField::kTime, t_s); !s.ok()) {
      return InvalidArgumentError("scan: " + s.message());
    }
    if (controls_ == 0) {
      return InvalidArgumentError(
          fmt::format("scan at t = {} comes before the first control: the filter has no start "
                      "time and no control to predict with",
                      t_s));
    }
    if (t_s < LastTime()) {
      return InvalidArgumentError(
          fmt::format("scan at t = {} is before the previous time {}: times must not decrease", t_s,
                      LastTime()));
    }
    if (pending_.empty() && !log_.empty() && log_.back().kind == kScanUpdate &&
        t_s == driver_.times().back()) {
      return InvalidArgumentError(fmt::format(
          "scan at t = {} follows the scan at the same time: the detections of one time are "
          "one scan",
          t_s));
    }
    for (size_t k = 0; k < z.size(); ++k) {
      Status s = CheckObservation(k, z[k], !model_.unknown_association());
      if (!s.ok()) return Status(s.code(), fmt::format("scan at t = {}: {}", t_s, s.message()));
    }
    GROVE_RETURN_IF_ERROR(CheckNotFailed("cannot take another scan"));
    return driver_.Guarded([&]() -> Status {
      if (t_s > LastTime()) Defer(t_s, kScanPredict);
      GROVE_RETURN_IF_ERROR(Settle());
      StepRecord record;
      record.kind = kScanUpdate;
      log_.push_back(record);
      model_.NoteScan(ScanStep{z});
      Status s = driver_.Update(t_s, ScanStep{z});
      if (!s.ok()) {
        log_.pop_back();
        return s;
      }
      reported_.push_back(driver_.mean_trajectory().back());
      ++scans_;
      observations_ += static_cast<int64_t>(z.size());
      return Status::Ok();
    });
  }

  // Runs the deferred predictions (Defer()): every read-out and Scan() first settles. Their
  // error stops the engine; it is returned here and, when a read-out without a status ran
  // them, by the next call that returns a status (SettleQuietly(), TakeDeferredError()).
  Status Settle() override {
    GROVE_RETURN_IF_ERROR(TakeDeferredError());
    if (pending_.empty()) return Status::Ok();
    return driver_.Guarded([&]() -> Status {
      std::vector<PendingStep> run;
      run.swap(pending_);
      std::vector<double> times(run.size());
      std::vector<PredictStep> steps(run.size());
      for (size_t j = 0; j < run.size(); ++j) {
        times[j] = run[j].t_s;
        steps[j] = {run[j].record.control, j == 0 && SegmentStarts()};
      }
      const size_t logged = log_.size();
      const int64_t before = driver_.steps();
      log_.reserve(logged + run.size());
      reported_.reserve(reported_.size() + run.size());
      for (const PendingStep& p : run) log_.push_back(p.record);
      Status s =
          driver_.PredictRun(std::span<const double>(times), std::span<const PredictStep>(steps));
      // The records of the steps done (a failed step has none, as before a failure).
      const int64_t added = driver_.steps() - before;
      const size_t done =
          s.ok() ? run.size() : static_cast<size_t>(std::max<int64_t>(0, added - 1));
      log_.resize(logged + done);
      const std::vector<StampedPose>& mean = driver_.mean_trajectory();
      for (size_t j = 0; j < done; ++j) {
        if (run[j].record.kind == kControlPredict) {
          reported_.push_back(mean[mean.size() - done + j]);
        }
      }
      return s;
    });
  }
  // Settle() for a read-out that returns no status: its error waits for the next call that
  // returns one.
  void SettleQuietly() override {
    Status s = Settle();
    if (!s.ok() && deferred_error_.ok()) deferred_error_ = s;
  }

  const FastSlamConfig& config() const override { return config_; }
  int64_t steps() const override { return driver_.steps(); }
  Pose2 MeanPose() const override { return driver_.mean_trajectory().back().pose; }
  Pose2 HeaviestPose() const override {
    std::vector<Pose2> mine;
    size_t i;
    if (Holds(driver_.filter().heaviest(), &i)) {
      const VehiclePose& p = model_.pose(i);
      mine.push_back(Pose2{p.x_m, p.y_m, p.heading_rad});
    }
    // Across ranks, from the rank that holds it (the mean pose if that fails).
    StatusOr<std::vector<Pose2>> all = GatherOverRanks(ranks_, std::move(mine));
    return all.ok() && all->size() == 1 ? all->front() : MeanPose();
  }
  const std::vector<StampedPose>& MeanTrajectory() const override { return reported_; }

  // The weighted covariance of the particles' poses about the weighted mean: sums over fixed
  // blocks of particles, added in block order (across ranks, every rank's blocks), so the same
  // at any thread or rank count. NaN when the ranks fail to exchange them.
  Pose2Covariance PoseCovariance() const override {
    const Pose2 mean = MeanPose();
    std::span<const double> lw = driver_.filter().log_weights();
    std::vector<Pose2Covariance> blocks;
    for (size_t b = 0; b < model_.size(); b += kSumBlock) {
      Pose2Covariance& c = blocks.emplace_back();
      for (size_t i = b; i < std::min(model_.size(), b + kSumBlock); ++i) {
        const VehiclePose& p = model_.pose(i);
        const double w = std::exp(lw[i]);
        const double dx = p.x_m - mean.x_m, dy = p.y_m - mean.y_m;
        const double dh = fastslam::WrapAngle(p.heading_rad - mean.heading_rad);
        c.xx += w * dx * dx;
        c.xy += w * dx * dy;
        c.xh += w * dx * dh;
        c.yy += w * dy * dy;
        c.yh += w * dy * dh;
        c.hh += w * dh * dh;
      }
    }
    StatusOr<std::vector<Pose2Covariance>> all = GatherOverRanks(ranks_, std::move(blocks));
    Pose2Covariance c;
    if (!all.ok()) {
      const double nan = std::nan("");
      return Pose2Covariance{nan, nan, nan, nan, nan, nan};
    }
    for (const Pose2Covariance& b : *all) {
      c.xx += b.xx;
      c.xy += b.xy;
      c.xh += b.xh;
      c.yy += b.yy;
      c.yh += b.yh;
      c.hh += b.hh;
    }
    return c;
  }

  // Replays the heaviest particle's predictions segment by segment (fastslam_model.h), on the
  // rank that holds it.
  StatusOr<std::vector<StampedPose>> HeaviestTrajectory() const override {
    size_t h;
    if (!Holds(driver_.filter().heaviest(), &h))
      return GatherOverRanks(ranks_, std::vector<StampedPose>{});
    return GatherOverRanks(ranks_, TrajectoryOf(h));
  }

  std::vector<StampedPose> TrajectoryOf(size_t h) const {
    const std::vector<double>& times = driver_.times();
    const size_t steps = log_.size();
    std::vector<StampedPose> out;
    out.reserve(reported_.size());
    out.push_back(reported_.front());
    if (steps == 0) return out;
    std::vector<const SegmentHistory::Node*> chain = SegmentHistory::Path(model_.path(h));
    const VehiclePose& now = model_.pose(h);
    for (size_t j = 0; j < chain.size(); ++j) {
      const fastslam::SegmentStart& s = chain[j]->value;
      VehiclePose p{s.x_m, s.y_m, s.heading_rad};
      // A segment starts after a draw, with the restarted covariance (filter_steps.h).
      fastslam::PoseCovariance cov = model_.steps().restart_covariance();
      const size_t stop = j + 1 < chain.size() ? chain[j + 1]->step : steps;
      for (size_t k = chain[j]->step; k < stop; ++k) {
        if (log_[k].kind == kScanUpdate) {
          // A scan closes its segment: the pose after it starts the next one (or is the
          // particle's pose now, after the last step).
          if (k + 1 == stop && j + 1 < chain.size()) {
            const fastslam::SegmentStart& next = chain[j + 1]->value;
            p = VehiclePose{next.x_m, next.y_m, next.heading_rad};
          } else if (k + 1 == steps) {
            p = now;
          }
        } else {
          bool usable = true;
          p = model_.steps().PredictPose(p, &cov, log_[k].control, k, s.index, &usable);
        }
        if (log_[k].kind != kScanPredict) {
          out.push_back({times[k + 1], Pose2{p.x_m, p.y_m, p.heading_rad}});
        }
      }
    }
    return out;
  }

  StatusOr<std::vector<LandmarkEstimate>> HeaviestLandmarks() const override {
    std::vector<LandmarkEstimate> out;
    size_t h;
    if (Holds(driver_.filter().heaviest(), &h)) {
      model_.trie().ForEach(model_.map(h), [&](uint64_t id, const fastslam::Landmark& leaf) {
        const fastslam::Landmark l =
            model_.traits().square_root_map() ? fastslam::WithCovariance(leaf) : leaf;
        out.push_back({static_cast<int64_t>(id), l.x_m, l.y_m, l.xx, l.xy, l.yy,
                       model_.unknown_association() ? l.tag : -1});
      });
    }
    return GatherOverRanks(ranks_, std::move(out));
  }

  FastSlamSummary Summary() const override {
    FastSlamSummary s;
    static_cast<FilterSummary&>(s) = driver_.Summary();
    s.controls = controls_;
    s.scans = scans_;
    s.observations = observations_;
    s.predict_steps = driver_.steps() - scans_;
    // The heaviest particle's figures from the rank that holds it, the evolution's summed over
    // the ranks (across ranks; left at 0 when the exchange fails).
    struct Figures {
      int64_t landmarks = 0;
      AssociationCounts association;
      EvolutionCounts evolution;
      uint8_t holds = 0;
    };
    Figures mine;
    mine.evolution = model_.evolution_counts();
    size_t h;
    if (Holds(driver_.filter().heaviest(), &h)) {
      mine.holds = 1;
      model_.trie().ForEach(model_.map(h),
                            [&](uint64_t, const fastslam::Landmark&) { ++mine.landmarks; });
      if (model_.unknown_association()) mine.association = model_.counts(h);
    }
    StatusOr<std::vector<Figures>> all = GatherOverRanks(ranks_, std::vector<Figures>{mine});
    if (all.ok()) {
      for (const Figures& f : *all) {
        if (f.holds) {
          s.landmarks = f.landmarks;
          s.association = f.association;
        }
        s.evolution.trials += f.evolution.trials;
        s.evolution.accepted += f.evolution.accepted;
      }
    }
    s.map_memory = model_.map_memory();
    s.trajectory_memory = model_.path_memory();
    return s;
  }

  Status CheckInvariants() const override { return model_.CheckCounts(); }

  StatusOr<std::string> Checkpoint(std::string_view user_data) const override {
    return SaveCheckpoint(kFastSlamCheckpoint, FastSlamConfigFields(), config_, ranks_, driver_,
                          user_data, [&](ByteWriter* w) {
                            model_.Save(w);
                            w->Put<int64_t>(controls_);
                            w->Put<int64_t>(scans_);
                            w->Put<int64_t>(observations_);
                            w->Put<double>(last_control_s_);
                            w->Put<double>(held_.v_mps);
                            w->Put<double>(held_.steer_rad);
                            w->Put<uint64_t>(log_.size());
                            w->PutBytes(log_.data(), log_.size() * sizeof(StepRecord));
                          });
  }

  Status Load(ByteReader* r) override {
    return LoadCheckpoint(r, ranks_, &driver_, [&](ByteReader* body) { return LoadBody(body); });
  }

  // The model's part of a checkpoint body, after the driver's.
  Status LoadBody(ByteReader* r) {
    const uint64_t steps = static_cast<uint64_t>(driver_.steps());
    GROVE_RETURN_IF_ERROR(model_.Load(r, steps));
    int64_t controls = 0, scans = 0, observations = 0;
    double last_control = 0, v = 0, g = 0;
    uint64_t count = 0;
    GROVE_RETURN_IF_ERROR(r->Get("controls", &controls));
    GROVE_RETURN_IF_ERROR(r->Get("scans", &scans));
    GROVE_RETURN_IF_ERROR(r->Get("observations", &observations));
    GROVE_RETURN_IF_ERROR(r->Get("last control time", &last_control));
    GROVE_RETURN_IF_ERROR(r->Get("held speed", &v));
    GROVE_RETURN_IF_ERROR(r->Get("held steering", &g));
    GROVE_RETURN_IF_ERROR(r->GetCount("step count", sizeof(StepRecord), &count));
    if (count != steps) return r->Error("step count", "not one record per filter step");
    std::vector<StepRecord> log(count);
    GROVE_RETURN_IF_ERROR(r->GetBytes("steps", log.data(), count * sizeof(StepRecord)));
    int64_t updates = 0, control_predicts = 0;
    for (const StepRecord& s : log) {
      if (s.kind > kScanUpdate) return r->Error("steps", "a step of an unknown kind");
      if (s.kind != kScanUpdate && (!std::isfinite(s.control.v_mps) ||
                                    !fastslam::SteeringUsable(geometry_, s.control.steer_rad) ||
                                    !(s.control.dt_s >= 0) || !std::isfinite(s.control.dt_s))) {
        return r->Error("steps", "a prediction's control is not usable");
      }
      updates += s.kind == kScanUpdate;
      control_predicts += s.kind == kControlPredict;
    }
    if (scans != updates || controls != control_predicts + (controls > 0 ? 1 : 0) ||
        (steps > 0 && controls == 0) || observations < 0) {
      return r->Error("controls", "the counts do not match the steps");
    }
    if (!std::isfinite(last_control) || !std::isfinite(v) ||
        !fastslam::SteeringUsable(geometry_, g)) {
      return r->Error("held control", "not finite or not usable");
    }
    controls_ = controls;
    scans_ = scans;
    observations_ = observations;
    last_control_s_ = last_control;
    held_ = {v, g};
    log_.swap(log);
    const std::vector<StampedPose>& mean = driver_.mean_trajectory();
    reported_.assign(1, mean.front());
    for (size_t k = 0; k < log_.size(); ++k) {
      if (log_[k].kind != kScanPredict) reported_.push_back(mean[k + 1]);
    }
    return Status::Ok();
  }

 private:
  // Whether this rank holds the filter's particle `global`, and its index here.
  bool Holds(size_t global, size_t* local) const {
    if (global < share_.first || global - share_.first >= model_.size()) return false;
    *local = global - share_.first;
    return true;
  }

  struct Held {
    double v_mps = 0;
    double steer_rad = 0;
  };

  // The time of the last step, deferred ones included.
  double LastTime() const {
    return pending_.empty() ? driver_.times().back() : pending_.back().t_s;
  }

  // A prediction with the held control from the last time to t_s, deferred to the next Settle():
  // the predictions between two scans then run in one pass over the particles.
  void Defer(double t_s, StepKind kind) {
    PendingStep p;
    p.t_s = t_s;
    p.record.control = ControlStep{held_.v_mps, held_.steer_rad, t_s - LastTime()};
    p.record.kind = kind;
    pending_.push_back(p);
  }

  // Whether the next filter step's prediction starts a path segment: at the start and after a
  // scan's update.
  bool SegmentStarts() const { return log_.empty() || log_.back().kind == kScanUpdate; }

  // The error a quiet Settle() kept, once: the next call that returns a status reports it.
  Status TakeDeferredError() {
    Status s = std::move(deferred_error_);
    deferred_error_ = Status::Ok();
    return s;
  }
  // The driver's CheckNotFailed(), after the error a quiet Settle() kept.
  Status CheckNotFailed(const char* what) {
    GROVE_RETURN_IF_ERROR(TakeDeferredError());
    return driver_.CheckNotFailed(what);
  }

  FastSlamConfig config_;
  Collective* ranks_;  // null: one process
  ParticleShare share_;
  WorkerPool workers_;
  Model model_;
  FilterDriver<Model> driver_;
  fastslam::VehicleGeometry geometry_;
  std::vector<StepRecord> log_;  // one per filter step
  struct PendingStep {
    double t_s = 0;
    StepRecord record;
  };
  std::vector<PendingStep> pending_;   // deferred predictions (Defer())
  Status deferred_error_;              // SettleQuietly()'s, for the next step
  std::vector<StampedPose> reported_;  // the mean pose at the start and each reported step
  Held held_;
  double last_control_s_ = 0;
  int64_t controls_ = 0;
  int64_t scans_ = 0;
  int64_t observations_ = 0;
};

// The run of each model, made in its own translation unit.
std::unique_ptr<FastSlam::Impl> MakeIdKeyedImpl(const FastSlamConfig& config, int threads,
                                                Collective* ranks);
std::unique_ptr<FastSlam::Impl> MakeCellKeyedImpl(const FastSlamConfig& config, int threads,
                                                  Collective* ranks);

}  // namespace fastslam_facade
}  // namespace grove

#endif  // GROVE_ENGINE_FASTSLAM_FASTSLAM_IMPL_H_
