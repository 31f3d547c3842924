#include "engine/imu/zero_velocity_detector.h"

#include <algorithm>
#include <vector>

namespace grove::imu {

double DetectorStatistic(const DetectorOptions& o, const Eigen::Vector3d* accel,
                         const Eigen::Vector3d* gyro, int n) {
  const double inv_a = 1.0 / (o.sigma_a * o.sigma_a);
  const double inv_w = 1.0 / (o.sigma_w * o.sigma_w);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  if (o.kind == ZeroVelocityDetector::kShoe || o.kind == ZeroVelocityDetector::kMv) {
    for (int k = 0; k < n; ++k) mean += accel[k];
    mean /= n;
  }
  double sum = 0;
  switch (o.kind) {
    case ZeroVelocityDetector::kShoe: {
      const double norm = mean.norm();
      // A window whose mean specific force is zero (free fall) cannot be still.
      const Eigen::Vector3d up =
          norm > 0 ? Eigen::Vector3d(o.gravity * mean / norm) : Eigen::Vector3d::Zero();
      for (int k = 0; k < n; ++k) {
        sum += (accel[k] - up).squaredNorm() * inv_a + gyro[k].squaredNorm() * inv_w;
      }
      break;
    }
    case ZeroVelocityDetector::kAre:
      for (int k = 0; k < n; ++k) sum += gyro[k].squaredNorm() * inv_w;
      break;
    case ZeroVelocityDetector::kMv:
      for (int k = 0; k < n; ++k) sum += (accel[k] - mean).squaredNorm() * inv_a;
      break;
    case ZeroVelocityDetector::kMag:
      for (int k = 0; k < n; ++k) {
        const double d = accel[k].norm() - o.gravity;
        sum += d * d * inv_a;
      }
      break;
  }
  return sum / n;
}

ZeroVelocityDetectorStream::ZeroVelocityDetectorStream(const DetectorOptions& options)
    : options_(options), half_before_((options.window - 1) / 2), half_after_(options.window / 2) {}

void ZeroVelocityDetectorStream::Push(const Eigen::Vector3d& accel, const Eigen::Vector3d& gyro) {
  accel_.push_back(accel);
  gyro_.push_back(gyro);
  ++pushed_;
  DecideRaw();
  Close();
}

void ZeroVelocityDetectorStream::Finish() {
  finished_ = true;
  DecideRaw();
  Close();
}

std::optional<bool> ZeroVelocityDetectorStream::Pop() {
  if (ready_.empty()) return std::nullopt;
  const bool still = ready_.front();
  ready_.pop_front();
  return still;
}

void ZeroVelocityDetectorStream::DecideRaw() {
  std::vector<Eigen::Vector3d>& a = scratch_accel_;
  std::vector<Eigen::Vector3d>& w = scratch_gyro_;
  while (raw_decided_ < pushed_ && (finished_ || raw_decided_ + half_after_ < pushed_)) {
    const int64_t first = std::max<int64_t>(0, raw_decided_ - half_before_);
    const int64_t last = std::min<int64_t>(pushed_ - 1, raw_decided_ + half_after_);
    a.assign(accel_.begin() + (first - window_start_), accel_.begin() + (last + 1 - window_start_));
    w.assign(gyro_.begin() + (first - window_start_), gyro_.begin() + (last + 1 - window_start_));
    const double t = DetectorStatistic(options_, a.data(), w.data(), static_cast<int>(a.size()));
    raw_.push_back(t < options_.threshold);
    ++raw_decided_;
    while (window_start_ < raw_decided_ - half_before_) {
      accel_.pop_front();
      gyro_.pop_front();
      ++window_start_;
    }
  }
}

void ZeroVelocityDetectorStream::Close() {
  while (!raw_.empty()) {
    if (raw_.front()) {
      ready_.push_back(true);
      raw_.pop_front();
      ++closed_;
      last_raw_still_ = true;
      have_last_raw_ = true;
      continue;
    }
    // The start, or the rest, of a run of moving samples.
    const bool after_still = have_last_raw_ && last_raw_still_;
    size_t run = 0;
    while (run < raw_.size() && !raw_[run] && static_cast<int>(run) <= options_.gap) ++run;
    const bool short_run = static_cast<int>(run) <= options_.gap;
    if (after_still && short_run && run < raw_.size()) {
      // A short gap between still samples: still.
      for (size_t k = 0; k < run; ++k) ready_.push_back(true);
      raw_.erase(raw_.begin(), raw_.begin() + static_cast<std::ptrdiff_t>(run));
      closed_ += static_cast<int64_t>(run);
      last_raw_still_ = false;
      continue;
    }
    if (after_still && short_run && !finished_) return;  // wait for the run's end
    ready_.push_back(false);
    raw_.pop_front();
    ++closed_;
    last_raw_still_ = false;
    have_last_raw_ = true;
  }
}

}  // namespace grove::imu
