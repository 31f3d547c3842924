// TrackerEngine, the Tracker of grove/tracking.h: a TrackingModel on the generic FilterDriver,
// its input (Update), read-outs and checkpoints on the facade helpers
// (engine/filter/filter_facade.h).
#include <fmt/format.h>

#include <cmath>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "concurrency/worker_pool.h"
#include "engine/filter/filter_driver.h"
#include "engine/filter/filter_facade.h"
#include "engine/tracking/tracking_model.h"
#include "grove/tracking.h"

namespace grove {

using tracking::RangeUpdate;
using tracking::TrackingModel;

namespace {

// The tracker's checkpoints: after the driver's state, the particles and the count of ranges.
constexpr CheckpointFormat kTrackerCheckpoint = {"grove tracker", "Tracker", 1};

// The weighted sums of the particles' states (MeanState).
struct StateSum {
  double w = 0, x = 0, y = 0, vx = 0, vy = 0;
};

// Thread safety: one thread drives a tracker (see FilterDriver).
class TrackerEngine final : public Tracker {
 public:
  TrackerEngine(const TrackerConfig& config, int threads, Collective* ranks)
      : config_(config),
        ranks_(ranks),
        share_(ShareOf(static_cast<uint64_t>(config.particles), ranks, kSumBlock)),
        workers_(threads),
        model_(config_, share_),
        driver_(&model_, &workers_, FilterOptionsOf(config, ranks), config.threads,
                Pose2{config.start_x_m, config.start_y_m,
                      std::atan2(config.start_vy_mps, config.start_vx_mps)},
                TimeOrder::kIncreasing) {}

  Status SetStartTime(double t_s) override { return driver_.SetStartTime(t_s); }

  Status Update(double t_s, std::span<const RangeMeasurement> z) override {
    for (size_t k = 0; k < z.size(); ++k) {
      const RangeMeasurement& m = z[k];
      if (!std::isfinite(m.beacon_x_m + m.beacon_y_m + m.range_m) || m.range_m < 0) {
        return InvalidArgumentError(fmt::format(
            "update at t = {}: measurement {}: beacon ({}, {}), range {}: must be finite, the "
            "range >= 0",
            t_s, k, m.beacon_x_m, m.beacon_y_m, m.range_m));
      }
    }
    // The prior's time is the first update's unless it was set.
    const double dt = driver_.start_time_set() ? t_s - driver_.times().back() : 0.0;
    return NoThrow([&]() -> Status {
      GROVE_RETURN_IF_ERROR(driver_.Update(t_s, RangeUpdate{dt, z}));
      measurements_ += static_cast<int64_t>(z.size());
      return Status::Ok();
    });
  }

  const TrackerConfig& config() const override { return config_; }
  int64_t steps() const override { return driver_.steps(); }
  Pose2 MeanPose() const override { return driver_.mean_trajectory().back().pose; }
  Pose2 HeaviestPose() const override {
    return FromHolder<Pose2>(
        ranks_, share_, model_.size(), driver_.filter().heaviest(),
        [&](size_t i) { return model_.pose(i); }, MeanPose());
  }
  const std::vector<StampedPose>& MeanTrajectory() const override {
    return driver_.mean_trajectory();
  }

  // NaN when the ranks fail to exchange their sums.
  TargetState MeanState() const override {
    std::span<const double> lw = driver_.filter().log_weights();
    StatusOr<StateSum> sum = SumOverBlocks<StateSum>(
        ranks_, model_.size(),
        [&](size_t begin, size_t end) {
          StateSum s;
          for (size_t i = begin; i < end; ++i) {
            const double w = std::exp(lw[i]);
            const TargetState& p = model_.state(i);
            s.w += w;
            s.x += w * p.x_m;
            s.y += w * p.y_m;
            s.vx += w * p.vx_mps;
            s.vy += w * p.vy_mps;
          }
          return s;
        },
        [](StateSum* total, const StateSum& s) {
          *total = {total->w + s.w, total->x + s.x, total->y + s.y, total->vx + s.vx,
                    total->vy + s.vy};
        });
    if (!sum.ok()) return TargetState{NAN, NAN, NAN, NAN};
    return TargetState{sum->x / sum->w, sum->y / sum->w, sum->vx / sum->w, sum->vy / sum->w};
  }

  TrackerSummary Summary() const override {
    TrackerSummary s;
    static_cast<FilterSummary&>(s) = driver_.Summary();
    s.measurements = measurements_;
    s.mean_state = MeanState();
    return s;
  }

  StatusOr<std::string> Checkpoint(std::string_view user_data) const override {
    return NoThrow([&] {
      return SaveCheckpoint(kTrackerCheckpoint, TrackerConfigFields(), config_, ranks_, driver_,
                            user_data, [&](ByteWriter* w) {
                              model_.Save(w);
                              w->Put<int64_t>(measurements_);
                            });
    });
  }

  // Reads the rest of a checkpoint after its head into this new tracker.
  Status Load(ByteReader* r) {
    return LoadCheckpoint(r, ranks_, &driver_, [&](ByteReader* body) -> Status {
      GROVE_RETURN_IF_ERROR(model_.Load(body));
      GROVE_RETURN_IF_ERROR(body->Get("measurements", &measurements_));
      if (measurements_ < 0) return body->Error("measurements", "negative");
      return Status::Ok();
    });
  }

 private:
  TrackerConfig config_;
  Collective* ranks_;  // null: one process
  ParticleShare share_;
  WorkerPool workers_;
  TrackingModel model_;
  FilterDriver<TrackingModel> driver_;
  int64_t measurements_ = 0;
};

static_assert(PosedModel<TrackingModel> && MigratingModel<TrackingModel>);

}  // namespace

Tracker::~Tracker() = default;

Status Tracker::CheckAcrossRanks(const TrackerConfig& config, int ranks) {
  return CheckRankShares(static_cast<uint64_t>(config.particles), ranks, kSumBlock);
}

StatusOr<std::unique_ptr<Tracker>> Tracker::Create(const TrackerConfig& config, Collective* ranks) {
  return CreateFacade<Tracker>(config, ranks, [&](int threads, Collective* r) {
    return std::unique_ptr<Tracker>(std::make_unique<TrackerEngine>(config, threads, r));
  });
}

StatusOr<std::unique_ptr<Tracker>> Tracker::Resume(const TrackerConfig& config,
                                                   std::string_view checkpoint,
                                                   const std::string& name, std::string* user_data,
                                                   Collective* ranks) {
  return ResumeFacade<Tracker>(
      kTrackerCheckpoint, TrackerConfigFields(), config, checkpoint, name, user_data, ranks,
      [](Tracker& t, ByteReader* r) { return static_cast<TrackerEngine&>(t).Load(r); });
}

}  // namespace grove
