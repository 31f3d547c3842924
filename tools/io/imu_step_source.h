// Steps from an IMU recording: the file read by ImuReader, fed sample by sample through the
// foot IMU front end (grove/foot_imu.h), its steps handed out as they finish. What `grove
// footslam steps` writes and `grove footslam run --imu` filters, with no file in between.
#ifndef GROVE_TOOLS_IO_IMU_STEP_SOURCE_H_
#define GROVE_TOOLS_IO_IMU_STEP_SOURCE_H_

#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "grove/foot_imu.h"
#include "grove/status.h"
#include "tools/io/imu_reader.h"

namespace grove::tools {

// Not thread-safe. Movable.
class ImuStepSource {
 public:
  // Opens the recording (its errors as ImuReader::Open's) and builds the front end
  // (InvalidArgument for an invalid `config`).
  static StatusOr<ImuStepSource> Open(const std::string& path, const FootImuConfig& config,
                                      const ImuReaderOptions& options);

  // Sets *step to the next step and *line to the line (MAT: row) of the sample that finished
  // it, and returns true; false at the end of the recording. A recording that gives no step is
  // an error saying why. Errors in the file name its place; after an error every later call
  // returns it.
  StatusOr<bool> Next(FootStep* step, int64_t* line);

  // The time the odometry starts (the end of the first stance): known once a step was returned.
  double origin_time_s() const { return engine_->Summary().origin_t_s; }
  FootImuSummary Summary() const { return engine_->Summary(); }
  const ImuReader& reader() const { return reader_; }

 private:
  ImuStepSource(ImuReader reader, std::unique_ptr<FootImu> engine)
      : reader_(std::move(reader)), engine_(std::move(engine)) {}
  // Feeds samples until a step is ready or the recording ends.
  Status Fill();

  ImuReader reader_;
  std::unique_ptr<FootImu> engine_;
  std::deque<FootStep> ready_;
  std::deque<int64_t> ready_lines_;
  bool ended_ = false;
  int64_t steps_returned_ = 0;
  Status error_;
};

// `t,dx,dy,dz,dheading,var_dx,cov_dx_dy,var_dy,cov_dx_dheading,cov_dy_dheading,var_dheading`
// then one row per step: a step file (tools/io/step_reader.h) with the front end's extra
// columns, numbers in the shortest form that reads back exactly.
std::string FootStepsCsv(const std::vector<FootStep>& steps);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_IO_IMU_STEP_SOURCE_H_
