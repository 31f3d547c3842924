// Streaming zero-velocity detection: the test statistics of Skog et al., "Zero-velocity
// detection - an algorithm evaluation" (IEEE TBME 2010), on a window centred on each sample,
// thresholded, then short moving gaps between still samples closed.
#ifndef GROVE_ENGINE_IMU_ZERO_VELOCITY_DETECTOR_H_
#define GROVE_ENGINE_IMU_ZERO_VELOCITY_DETECTOR_H_

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "grove/foot_imu.h"

namespace grove::imu {

struct DetectorOptions {
  ZeroVelocityDetector kind = ZeroVelocityDetector::kShoe;
  int window = 5;        // >= 1
  double threshold = 0;  // > 0
  double sigma_a = 0.01;
  double sigma_w = 0.001;
  double gravity = 9.81;
  int gap = 0;  // moving runs of at most this many samples between still ones become still
};

// The statistic T of `kind` over n samples (Skog et al., eqs. for SHOE, ARE, MV, MAG).
// REQUIRES: n >= 1.
double DetectorStatistic(const DetectorOptions& options, const Eigen::Vector3d* accel,
                         const Eigen::Vector3d* gyro, int n);

// Decides samples in order, each once the samples its window and the gap rule need have come:
// delay() samples after it, or at Finish().
// Not thread-safe.
class ZeroVelocityDetectorStream {
 public:
  explicit ZeroVelocityDetectorStream(const DetectorOptions& options);

  void Push(const Eigen::Vector3d& accel, const Eigen::Vector3d& gyro);
  // No more samples: the last ones are decided on windows cut at the end.
  void Finish();
  // The decision for the oldest sample not yet popped (true: still), if it is known.
  std::optional<bool> Pop();
  // Samples pushed and not yet decidable, at most.
  int delay() const { return half_after_ + options_.gap; }

 private:
  // Decides raw flags for every sample whose window is complete (or all, after Finish()).
  void DecideRaw();
  // Moves raw flags to closed flags once the gap rule can be applied.
  void Close();

  DetectorOptions options_;
  int half_before_ = 0;  // samples of the window before and after the centre
  int half_after_ = 0;
  bool finished_ = false;
  // The recent samples: window_start_ is the index of accel_.front().
  std::deque<Eigen::Vector3d> accel_;
  std::deque<Eigen::Vector3d> gyro_;
  int64_t window_start_ = 0;
  int64_t pushed_ = 0;
  int64_t raw_decided_ = 0;  // samples with a raw flag
  // Raw flags not yet closed, from index closed_; the raw flag of closed_ - 1 is last_raw_.
  std::deque<bool> raw_;
  int64_t closed_ = 0;
  bool last_raw_still_ = false;
  bool have_last_raw_ = false;
  std::deque<bool> ready_;                      // closed flags not yet popped
  std::vector<Eigen::Vector3d> scratch_accel_;  // contiguous copies of a window
  std::vector<Eigen::Vector3d> scratch_gyro_;
};

}  // namespace grove::imu

#endif  // GROVE_ENGINE_IMU_ZERO_VELOCITY_DETECTOR_H_
