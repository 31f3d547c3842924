// TrackingModel: the particles of range-only beacon tracking (grove/tracking.h) for a
// ParticleFilter: each particle's position and velocity, moved by the discrete white-noise
// acceleration model and weighted by the ranges of an update. No map: a particle's whole state is
// four doubles, so resampling copies values and the particles move between ranks as bytes.
//
// Random numbers: particle i's initial state draws from RandomStream(seed, 0, i, kInit) and its
// acceleration at step k from RandomStream(seed, k + 1, i, kMotion), so results do not depend
// on threads or ranks.
//
// Thread safety: Advance() runs on disjoint particle ranges from the filter's workers; the rest
// from the driving thread.
#ifndef GROVE_ENGINE_TRACKING_TRACKING_MODEL_H_
#define GROVE_ENGINE_TRACKING_TRACKING_MODEL_H_

#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "concurrency/random_stream.h"
#include "concurrency/worker_pool.h"
#include "engine/filter/generation.h"
#include "engine/io/checkpoint_io.h"
#include "engine/ranks/collective.h"
#include "grove/status.h"
#include "grove/tracking.h"
#include "grove/types.h"

namespace grove::tracking {

// One update's input: the time since the previous state and the ranges.
struct RangeUpdate {
  double dt_s = 0;
  std::span<const RangeMeasurement> ranges;
};

class TrackingModel {
 public:
  // The particles of `share` (default: all of config.particles), drawn from the prior.
  // REQUIRES: config.Validate() is ok.
  TrackingModel(const TrackerConfig& config, ParticleShare share = {})
      : config_(config),
        first_(share.first),
        state_(share.count != 0 || share.first != 0 ? static_cast<size_t>(share.count)
                                                    : static_cast<size_t>(config.particles)) {
    for (size_t i = 0; i < state_.size(); ++i) {
      RandomStream rs(config.seed, 0, static_cast<uint32_t>(first_ + i), StreamPurpose::kInit);
      TargetState& s = state_[i];
      s.x_m = config.start_x_m + config.initial_position_sigma_m * rs.NextNormal();
      s.y_m = config.start_y_m + config.initial_position_sigma_m * rs.NextNormal();
      s.vx_mps = config.start_vx_mps + config.initial_velocity_sigma_mps * rs.NextNormal();
      s.vy_mps = config.start_vy_mps + config.initial_velocity_sigma_mps * rs.NextNormal();
    }
  }

  size_t size() const { return state_.size(); }
  const TargetState& state(size_t i) const { return state_[i]; }

  // PosedModel: the position, and the direction of motion as the heading (east at rest).
  double x(size_t i) const { return state_[i].x_m; }
  double y(size_t i) const { return state_[i].y_m; }
  double cos_heading(size_t i) const {
    const double v = Speed(i);
    return v > 0 ? state_[i].vx_mps / v : 1.0;
  }
  double sin_heading(size_t i) const {
    const double v = Speed(i);
    return v > 0 ? state_[i].vy_mps / v : 0.0;
  }
  Pose2 pose(size_t i) const {
    return Pose2{x(i), y(i), std::atan2(sin_heading(i), cos_heading(i))};
  }

  // Moves particles [begin, end) by in.dt_s and adds each one's log-likelihood of the ranges.
  Status Advance(const RangeUpdate& in, uint64_t step, size_t begin, size_t end, int /*slot*/,
                 double* log_w) {
    const double dt = in.dt_s, half_dt2 = 0.5 * in.dt_s * in.dt_s;
    const double sigma_a = config_.acceleration_sigma_mps2;
    const double inv_var = 1.0 / (config_.range_sigma_m * config_.range_sigma_m);
    for (size_t i = begin; i < end; ++i) {
      TargetState& s = state_[i];
      RandomStream rs(config_.seed, step + 1, static_cast<uint32_t>(first_ + i),
                      StreamPurpose::kMotion);
      const double ax = sigma_a * rs.NextNormal(), ay = sigma_a * rs.NextNormal();
      s.x_m += s.vx_mps * dt + ax * half_dt2;
      s.y_m += s.vy_mps * dt + ay * half_dt2;
      s.vx_mps += ax * dt;
      s.vy_mps += ay * dt;
      double lw = 0;
      for (const RangeMeasurement& z : in.ranges) {
        const double e = z.range_m - std::hypot(s.x_m - z.beacon_x_m, s.y_m - z.beacon_y_m);
        lw -= 0.5 * e * e * inv_var;
      }
      log_w[i] += lw;
    }
    return Status::Ok();
  }

  void Gather(std::span<const uint32_t> parents, WorkerPool& workers) {
    GatherValues(parents, workers, &state_);
  }
  void ReleaseDead(WorkerPool& /*workers*/) {}

  // MigratingModel: particles `which` as their states; Import() appends them.
  void Export(std::span<const uint32_t> which, ByteWriter* w) const {
    for (uint32_t i : which) w->Put(state_[i]);
  }
  Status Import(ByteReader* r, size_t count, uint64_t /*step*/) {
    return ReadStates(r, count, &state_);
  }

  // The checkpoint's part: the particle count and every state.
  void Save(ByteWriter* w) const {
    w->Put<uint64_t>(state_.size());
    w->PutBytes(state_.data(), state_.size() * sizeof(TargetState));
  }
  Status Load(ByteReader* r) {
    GROVE_RETURN_IF_ERROR(ReadParticleCount(r, state_.size()));
    std::vector<TargetState> states;
    GROVE_RETURN_IF_ERROR(ReadStates(r, state_.size(), &states));
    state_.swap(states);
    return Status::Ok();
  }

 private:
  double Speed(size_t i) const { return std::hypot(state_[i].vx_mps, state_[i].vy_mps); }

  // Appends `count` states read from `r` to *out; DataLoss for one that is not finite.
  static Status ReadStates(ByteReader* r, size_t count, std::vector<TargetState>* out) {
    for (size_t k = 0; k < count; ++k) {
      TargetState s;
      GROVE_RETURN_IF_ERROR(r->Get("particle state", &s));
      if (!std::isfinite(s.x_m + s.y_m + s.vx_mps + s.vy_mps)) {
        return r->Error("particle state", "particle " + std::to_string(k) + " is not finite");
      }
      out->push_back(s);
    }
    return Status::Ok();
  }

  const TrackerConfig& config_;
  uint64_t first_;  // the global index of particle 0 here
  std::vector<TargetState> state_;
};

}  // namespace grove::tracking

#endif  // GROVE_ENGINE_TRACKING_TRACKING_MODEL_H_
