// `grove footslam run|batch|simulate|evaluate|render`: their options and what runs them.
#include <limits>
#include <memory>
#include <string>

#include "grove/footslam.h"
#include "tools/cli/across_ranks.h"
#include "tools/cli/command.h"
#include "tools/cli/config_flags.h"
#include "tools/cli/mpi_world.h"
#include "tools/cli/run_flags.h"
#include "tools/cli/typed_flags.h"
#include "tools/run/footslam_batch.h"
#include "tools/run/footslam_run.h"
#include "tools/sim/walk_simulator.h"

namespace grove::tools {
namespace {

// Several commands write into these; each holds them alive for the run.
class FootSlamRunCli {
 public:
  explicit FootSlamRunCli(CLI::App* app)
      : steps_(AddPath(app, "--steps", &options_.steps_path, "Step file: CSV 't,dx,dy' or 't,x,y'",
                       "the bundled building walk")),
        flags_(app, FootSlamConfigFields()),
        typed_(app) {
    typed_.Real("--max-step", &options_.max_step_m, Interval::Above(0),
                "Reject input steps longer than this many metres");
    prior_ = AddPath(app, "--prior-map", &options_.prior_map_path,
                     "map.csv of an earlier walk through the same area, in this run's map frame: "
                     "prior counts (weighted by prior_map_confidence)");
  }

  int Run() {
    if (Status s = typed_.Apply(); !s.ok()) return Fail(kExitUsage, s.message());
    FootSlamConfig config;
    const int code =
        flags_.Prepare(&config, &options_.run, {{steps_, "--steps"}, {prior_, "--prior-map"}});
    if (code >= 0) return code;
    return RunOnRanks<FootSlam>(config, options_, RunFootSlamCommand);
  }

 private:
  FootSlamRunOptions options_;
  CLI::Option* steps_;
  RunFlags<FootSlamConfig> flags_;
  TypedFlags typed_;
  CLI::Option* prior_ = nullptr;
};

class FootSlamBatchCli {
 public:
  explicit FootSlamBatchCli(CLI::App* app) : typed_(app), flags_(nullptr) {
    AddPath(app, "--manifest", &options_.manifest_path,
            "JSON Lines: {\"name\", \"steps\", optional \"prior_map\" and \"config\"} per line")
        ->required();
    AddPath(app, "--out", &options_.out_dir, "Output directory: OUT/NAME per walk")->required();
    typed_.Integer("--jobs", &options_.jobs, 1, 1024,
                   "Walks run side by side; --threads is shared");
    typed_.Integer("--checkpoint-every", &options_.checkpoint_every, 0,
                   std::numeric_limits<int64_t>::max(),
                   "Each walk writes a checkpoint every N steps (a killed batch resumes from it)");
    AddPath(app, "--config", &config_path_, "JSON file setting any parameter of every walk");
    flags_ = std::make_unique<ConfigFlags<FootSlamConfig>>(app, FootSlamConfigFields());
  }

  int Run() {
    if (Status s = typed_.Apply(); !s.ok()) return Fail(kExitUsage, s.message());
    FootSlamConfig config;
    if (!config_path_.empty()) {
      Status s = LoadConfigFile(FootSlamConfigFields(), config_path_, &config);
      if (!s.ok()) {
        return Fail(s.code() == StatusCode::kNotFound || s.code() == StatusCode::kIoError
                        ? kExitInput
                        : kExitUsage,
                    s.message());
      }
    }
    if (Status s = flags_->Apply(&config); !s.ok()) return Fail(kExitUsage, s.message());
    MpiWorld world;  // one rank unless started by mpirun
    if (world.active()) {
      options_.rank = world.rank();
      options_.ranks = world.size();
      options_.all_gather = [&world](const std::string& mine) { return world.AllGather(mine); };
    }
    return RunFootSlamBatch(config, options_);
  }

 private:
  FootSlamBatchOptions options_;
  std::string config_path_;
  TypedFlags typed_;
  std::unique_ptr<ConfigFlags<FootSlamConfig>> flags_;  // after --config on the help page
};

class FootSlamSimulateCli {
 public:
  explicit FootSlamSimulateCli(CLI::App* app) : typed_(app) {
    AddPath(app, "--out", &options_.out_dir, "Output directory (steps.csv, truth.csv)")->required();
    typed_.Real("--minutes", &options_.minutes, WalkMinutesRange(), "Walk duration in minutes");
    typed_.Unsigned("--seed", &options_.seed, "Seed");
    typed_.Choice("--scenario", &options_.scenario, {"building", "open", "campus"},
                  "building, open or campus (three buildings in a row)");
    const SimulatorOptions defaults;
    options_.heading_drift = defaults.heading_drift_rad_per_sqrt_step;
    options_.scale_error = defaults.scale_error;
    drift_ = typed_.Real("--heading-drift", &options_.heading_drift, HeadingDriftRange(),
                         "Heading random walk of the odometry, rad per sqrt(step)");
    scale_ = typed_.Real("--scale-error", &options_.scale_error, ScaleErrorRange(),
                         "Step-length scale error of the odometry");
  }

  int Run() {
    if (Status s = typed_.Apply(); !s.ok()) return Fail(kExitUsage, s.message());
    options_.heading_drift_given = drift_->count() > 0;
    options_.scale_error_given = scale_->count() > 0;
    return SimulateCommand(options_);
  }

 private:
  SimulateOptions options_;
  TypedFlags typed_;
  CLI::Option* drift_ = nullptr;
  CLI::Option* scale_ = nullptr;
};

class FootSlamRenderCli {
 public:
  explicit FootSlamRenderCli(CLI::App* app) : typed_(app) {
    AddPath(app, "--dir", &dir_, "Directory holding map.csv and trajectory.csv")->required();
    typed_.Real("--hex-radius", &hex_radius_m_, Interval::Above(0), "Hexagon radius in metres")
        ->default_str("the run's, from summary.json, or 0.5");
    AddPath(app, "--steps", &steps_path_, "Step file to draw the raw odometry from");
  }

  int Run() {
    if (Status s = typed_.Apply(); !s.ok()) return Fail(kExitUsage, s.message());
    return RenderCommand(dir_, hex_radius_m_, steps_path_);
  }

 private:
  TypedFlags typed_;
  std::string dir_, steps_path_;
  double hex_radius_m_ = 0;  // 0: the run's
};

Command AddEvaluate(CLI::App* footslam) {
  CLI::App* app = footslam->add_subcommand("evaluate", "Position error against truth");
  auto paths = std::make_shared<std::pair<std::string, std::string>>();
  AddPath(app, "--truth", &paths->first, "Truth CSV (t,x,y)")->required();
  AddPath(app, "--trajectory", &paths->second, "Trajectory CSV (t,x,y,...)")->required();
  return {app, [paths] { return EvaluateCommand(paths->first, paths->second); }};
}

}  // namespace

std::vector<Command> AddFootSlamCommands(CLI::App* grove) {
  CLI::App* footslam = AddFamily(grove, "footslam", "Pedestrian SLAM from step odometry");
  return {
      AddCommand<FootSlamRunCli>(footslam, "run", "Run FootSLAM on a step file"),
      AddCommand<FootSlamBatchCli>(
          footslam, "batch",
          "Run many walks, one filter each, from a JSON Lines manifest, side by side"),
      AddCommand<FootSlamSimulateCli>(footslam, "simulate", "Simulate a pedestrian walk"),
      AddEvaluate(footslam),
      AddCommand<FootSlamRenderCli>(footslam, "render", "Redraw map.png and map.svg from CSVs"),
  };
}

}  // namespace grove::tools
