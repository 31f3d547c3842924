// The foot IMU commands: `grove footslam steps` (an IMU recording to a step file) and the
// recording `grove footslam simulate --imu` writes beside the walk.
#ifndef GROVE_TOOLS_RUN_FOOT_IMU_COMMANDS_H_
#define GROVE_TOOLS_RUN_FOOT_IMU_COMMANDS_H_

#include <cstdint>
#include <string>

#include "grove/foot_imu.h"
#include "grove/status.h"
#include "tools/io/imu_reader.h"
#include "tools/sim/foot_imu_simulator.h"
#include "tools/sim/walk_simulator.h"

namespace grove::tools {

struct FootImuStepsOptions {
  std::string imu_path;
  std::string out_path;      // the step file
  std::string stances_path;  // the stance of each step: t,begin,end (empty: none)
  ImuReaderOptions reader;
  bool progress = true;  // the summary on stderr
};

// `grove footslam steps`: writes the step file atomically (nothing when the input is bad) and
// returns an exit code after printing any error to stderr as one line.
int FootImuStepsCommand(const FootImuConfig& config, const FootImuStepsOptions& options);

// The reader options of a run: `units` (ParseImuUnits; empty: SI) and `rate_hz`, with the
// ranges and longest interval of `config`.
StatusOr<ImuReaderOptions> MakeImuReaderOptions(const FootImuConfig& config,
                                                const std::string& units, double rate_hz);

struct SimulateImuOptions {
  double rate_hz = 200;
  std::string sensor = "bmi160";  // or "ideal": MemsModel::None()
  uint64_t seed = 1;
  int digits = 0;  // significant digits in imu.csv; 0: exact
};

// imu.csv and stances.csv of `walk` into `out_dir`; the number of samples, or an error.
StatusOr<int64_t> WriteSimulatedImu(const SimulatedWalk& walk, const SimulateImuOptions& options,
                                    const std::string& out_dir);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_RUN_FOOT_IMU_COMMANDS_H_
