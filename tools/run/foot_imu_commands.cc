#include "tools/run/foot_imu_commands.h"

#include <fmt/format.h>

#include <cstdio>
#include <vector>

#include "tools/io/atomic_file.h"
#include "tools/io/imu_step_source.h"
#include "tools/run/run_loop.h"

namespace grove::tools {

StatusOr<ImuReaderOptions> MakeImuReaderOptions(const FootImuConfig& config,
                                                const std::string& units, double rate_hz) {
  ImuReaderOptions options;
  if (!units.empty()) GROVE_RETURN_IF_ERROR(ParseImuUnits(units, &options));
  options.rate_hz = rate_hz;
  options.accel_range_mps2 = config.accel_range_mps2;
  options.gyro_range_radps = config.gyro_range_radps;
  options.max_interval_s = config.max_sample_interval_s;
  return options;
}

int FootImuStepsCommand(const FootImuConfig& config, const FootImuStepsOptions& options) {
  if (Status s = config.Validate(); !s.ok()) return Fail(kExitUsage, s.message());
  StatusOr<ImuStepSource> source = ImuStepSource::Open(options.imu_path, config, options.reader);
  if (!source.ok()) return Fail(kExitInput, source.status().message());
  std::vector<FootStep> steps;
  FootStep step;
  int64_t line = 0;
  for (;;) {
    StatusOr<bool> more = source->Next(&step, &line);
    if (!more.ok()) return Fail(kExitInput, more.status().message());
    if (!*more) break;
    steps.push_back(step);
  }
  if (Status s = WriteFileAtomically(options.out_path, FootStepsCsv(steps)); !s.ok()) {
    return Fail(kExitOutput, s.message());
  }
  if (!options.stances_path.empty()) {
    std::string text = "t,begin,end\n";
    for (const FootStep& s : steps) {
      text += fmt::format("{},{},{}\n", s.t_s, s.stance_begin_s, s.stance_end_s);
    }
    if (Status s = WriteFileAtomically(options.stances_path, text); !s.ok()) {
      return Fail(kExitOutput, s.message());
    }
  }
  if (options.progress) {
    const FootImuSummary summary = source->Summary();
    std::fprintf(stderr, "%s\n", summary.BriefReport().c_str());
    const int64_t duplicates = source->reader().duplicates();
    std::fprintf(
        stderr, "wrote %s: %zu steps from %s (%s%s); the odometry starts at t = %.6g s\n",
        options.out_path.c_str(), steps.size(), options.imu_path.c_str(), source->reader().format(),
        duplicates > 0 ? fmt::format(", {} duplicate rows skipped", duplicates).c_str() : "",
        summary.origin_t_s);
  }
  return kExitOk;
}

StatusOr<int64_t> WriteSimulatedImu(const SimulatedWalk& walk, const SimulateImuOptions& options,
                                    const std::string& out_dir) {
  FootImuSimOptions sim;
  sim.rate_hz = options.rate_hz;
  sim.seed = options.seed;
  if (options.sensor == "ideal") {
    sim.mems = MemsModel::None();
  } else if (options.sensor != "bmi160") {
    return InvalidArgumentError(
        fmt::format("--imu-sensor = {}: must be bmi160 or ideal", QuoteForMessage(options.sensor)));
  }
  StatusOr<SimulatedFootImu> imu = SimulateFootImu(walk, sim);
  if (!imu.ok()) return imu.status();
  GROVE_RETURN_IF_ERROR(WriteFileAtomically(out_dir + "/imu.csv", ImuCsv(*imu, options.digits)));
  GROVE_RETURN_IF_ERROR(WriteFileAtomically(out_dir + "/stances.csv", StancesCsv(*imu)));
  return static_cast<int64_t>(imu->samples.size());
}

}  // namespace grove::tools
