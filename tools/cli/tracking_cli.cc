// `grove tracking run|simulate`: their options and what runs them.
#include <string>

#include "grove/tracking.h"
#include "tools/cli/command.h"
#include "tools/cli/model_run_cli.h"
#include "tools/cli/typed_flags.h"
#include "tools/run/tracking_run.h"
#include "tools/sim/tracking_simulator.h"

namespace grove::tools {
namespace {

class TrackingRunCli : public ModelRunCli<Tracker, TrackingRunOptions> {
 public:
  explicit TrackingRunCli(CLI::App* app)
      : ModelRunCli(app, TrackerConfigFields(),
                    {{"--beacons", &TrackingRunOptions::beacons_path, "beacons.csv (id,x,y)"},
                     {"--measurements", &TrackingRunOptions::measurements_path,
                      "measurements.csv (t,beacon,range)"}},
                    RunTrackingCommand) {}
};

class TrackingSimulateCli {
 public:
  explicit TrackingSimulateCli(CLI::App* app) : typed_(app) {
    AddPath(app, "--out", &out_, "Output directory (beacons.csv, measurements.csv, truth.csv)")
        ->required();
    typed_.Real("--seconds", &options_.seconds, TrackingSecondsRange(), "Duration, seconds");
    typed_.Real("--rate", &options_.rate_hz, TrackingRateRange(), "Updates per second");
    typed_.Real("--range-sigma", &options_.range_sigma_m, TrackingRangeSigmaRange(),
                "Range noise (standard deviation), metres");
    typed_.Unsigned("--seed", &options_.seed, "Seed");
  }

  int Run() {
    if (Status s = typed_.Apply(); !s.ok()) return Fail(kExitUsage, s.message());
    return TrackingSimulateCommand(options_, out_);
  }

 private:
  TypedFlags typed_;
  TrackingSimOptions options_;
  std::string out_;
};

}  // namespace

std::vector<Command> AddTrackingCommands(CLI::App* grove) {
  CLI::App* tracking =
      AddFamily(grove, "tracking", "Range-only tracking of a moving target among beacons");
  return {AddCommand<TrackingRunCli>(
              tracking, "run", "Track a target from its ranges to beacons at known positions"),
          AddCommand<TrackingSimulateCli>(
              tracking, "simulate", "Simulate a target among four beacons: ranges and truth")};
}

}  // namespace grove::tools
