// `grove footslam run|steps|batch|simulate|evaluate|render`: their options and what runs them.
#include <limits>
#include <memory>
#include <string>

#include "grove/config_json.h"
#include "grove/foot_imu.h"
#include "grove/footslam.h"
#include "tools/cli/across_ranks.h"
#include "tools/cli/command.h"
#include "tools/cli/config_flags.h"
#include "tools/cli/mpi_world.h"
#include "tools/cli/run_flags.h"
#include "tools/cli/typed_flags.h"
#include "tools/run/foot_imu_commands.h"
#include "tools/run/footslam_batch.h"
#include "tools/run/footslam_run.h"
#include "tools/sim/walk_simulator.h"

namespace grove::tools {
namespace {

// The flags of an IMU recording's reading and front end: --imu, --rate, --units, --imu-config
// and one flag per FootImuConfig field (`grove footslam steps` and `run --imu`).
class ImuFlags {
 public:
  ImuFlags(CLI::App* app, const char* imu_help) : typed_(app) {
    imu_ = AddPath(app, "--imu", &imu_path_, imu_help);
    typed_
        .Real("--rate", &rate_hz_, Interval::Above(0),
              "Sample rate, Hz: checked against the time column, or the times without one")
        ->default_str("the time column");
    Document(app->add_option("--units", units_,
                             "Units of the columns whose header names none: ACCEL,GYRO with "
                             "ACCEL m/s^2 or g, GYRO rad/s or deg/s"),
             {"TEXT", "", {}, "m/s^2,rad/s"});
    config_ = AddPath(app, "--imu-config", &config_path_,
                      "JSON file setting any foot IMU parameter (the flags below override it)");
    flags_ = std::make_unique<ConfigFlags<FootImuConfig>>(app, FootImuConfigFields());
  }

  CLI::Option* imu_option() const { return imu_; }
  const std::string& imu_path() const { return imu_path_; }

  // After parsing: the configuration (file, then flags) and the reader options; -1 to go on,
  // else the exit code.
  int Prepare(FootImuConfig* config, ImuReaderOptions* reader) {
    if (Status s = typed_.Apply(); !s.ok()) return Fail(kExitUsage, s.message());
    if (*config_ && config_path_.empty())
      return Fail(kExitUsage, "--imu-config: the path is empty");
    if (*imu_ && imu_path_.empty()) return Fail(kExitUsage, "--imu: the path is empty");
    if (!config_path_.empty()) {
      if (const int code = LoadConfigFlag(FootImuConfigFields(), config_path_, config); code >= 0) {
        return code;
      }
    }
    if (Status s = flags_->Apply(config); !s.ok()) return Fail(kExitUsage, s.message());
    if (Status s = config->Validate(); !s.ok()) return Fail(kExitUsage, s.message());
    StatusOr<ImuReaderOptions> options = MakeImuReaderOptions(*config, units_, rate_hz_);
    if (!options.ok()) return Fail(kExitUsage, options.status().message());
    *reader = *options;
    return -1;
  }

 private:
  TypedFlags typed_;
  CLI::Option* imu_ = nullptr;
  CLI::Option* config_ = nullptr;
  std::string imu_path_;
  std::string config_path_;
  std::string units_;
  double rate_hz_ = 0;
  std::unique_ptr<ConfigFlags<FootImuConfig>> flags_;  // after the others on the help page
};

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
    truth_ = AddPath(app, "--truth", &options_.truth_path,
                     "True path, CSV (t,x,y,...) or TUM: the smoothed path's error against it "
                     "goes into summary.json, error.csv, error.png and the last line");
    imu_ = std::make_unique<ImuFlags>(
        app,
        "Foot-mounted IMU recording (CSV, CSV.gz or PyShoe MAT) instead of --steps: its steps "
        "from the foot IMU front end, streamed into the filter");
    imu_->imu_option()->excludes(steps_);
  }

  int Run() {
    if (Status s = typed_.Apply(); !s.ok()) return Fail(kExitUsage, s.message());
    if (int code = imu_->Prepare(&options_.imu_config, &options_.imu_reader); code >= 0) {
      return code;
    }
    options_.imu_path = imu_->imu_path();
    FootSlamConfig config;
    const int code =
        flags_.Prepare(&config, &options_.run,
                       {{steps_, "--steps"}, {prior_, "--prior-map"}, {truth_, "--truth"}});
    if (code >= 0) return code;
    return RunOnRanks<FootSlam>(config, options_, RunFootSlamCommand);
  }

 private:
  FootSlamRunOptions options_;
  CLI::Option* steps_;
  RunFlags<FootSlamConfig> flags_;
  TypedFlags typed_;
  CLI::Option* prior_ = nullptr;
  CLI::Option* truth_ = nullptr;
  std::unique_ptr<ImuFlags> imu_;  // after the run's flags on the help page
};

class FootSlamStepsCli {
 public:
  explicit FootSlamStepsCli(CLI::App* app) : typed_(app) {
    imu_ = std::make_unique<ImuFlags>(
        app,
        "Foot-mounted IMU recording: CSV (t,ax,ay,az,gx,gy,gz or x-io's export), CSV.gz or "
        "PyShoe MAT");
    imu_->imu_option()->required();
    AddPath(app, "--out", &options_.out_path, "Step file to write")->required();
    AddPath(app, "--stances", &options_.stances_path,
            "Also write the stance that ends each step: t,begin,end (seconds)");
    app->add_flag("--print-config", print_config_,
                  "Print the effective foot IMU configuration and exit");
    app->add_flag("--no-progress", no_progress_, "No summary on stderr");
  }

  int Run() {
    if (Status s = typed_.Apply(); !s.ok()) return Fail(kExitUsage, s.message());
    FootImuConfig config;
    if (int code = imu_->Prepare(&config, &options_.reader); code >= 0) return code;
    if (print_config_) {
      std::printf("%s\n", ConfigToJson(FootImuConfigFields(), config, 2).c_str());
      return kExitOk;
    }
    if (options_.out_path.empty()) return Fail(kExitUsage, "--out: the path is empty");
    options_.imu_path = imu_->imu_path();
    options_.progress = !no_progress_;
    return FootImuStepsCommand(config, options_);
  }

 private:
  TypedFlags typed_;
  FootImuStepsOptions options_;
  bool print_config_ = false;
  bool no_progress_ = false;
  std::unique_ptr<ImuFlags> imu_;
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
      if (const int code = LoadConfigFlag(FootSlamConfigFields(), config_path_, &config);
          code >= 0) {
        return code;
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
    app->add_flag("--imu", options_.imu,
                  "Also a foot-mounted IMU recording of the walk: imu.csv (t,ax,ay,az,gx,gy,gz in "
                  "m/s^2 and rad/s) and stances.csv (the foot's true stances)");
    typed_.Real("--imu-rate", &options_.imu_options.rate_hz, Interval::Closed(50, 2000),
                "IMU samples per second");
    typed_.Choice("--imu-sensor", &options_.imu_options.sensor, {"bmi160", "ideal"},
                  "IMU errors: bmi160 (a consumer MEMS IMU, engine/imu/README.md) or ideal (none)");
    imu_seed_ =
        typed_.Unsigned("--imu-seed", &options_.imu_options.seed, "Seed of the IMU's errors")
            ->default_str("--seed");
    typed_.Integer("--imu-digits", &options_.imu_options.digits, 0, 17,
                   "Significant digits in imu.csv; 0: every digit (reads back exactly)");
  }

  int Run() {
    if (Status s = typed_.Apply(); !s.ok()) return Fail(kExitUsage, s.message());
    options_.heading_drift_given = drift_->count() > 0;
    options_.scale_error_given = scale_->count() > 0;
    if (imu_seed_->count() == 0) options_.imu_options.seed = options_.seed;
    return SimulateCommand(options_);
  }

 private:
  SimulateOptions options_;
  TypedFlags typed_;
  CLI::Option* imu_seed_ = nullptr;
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
      AddCommand<FootSlamRunCli>(footslam, "run",
                                 "Run FootSLAM on a step file or a foot-mounted IMU recording"),
      AddCommand<FootSlamStepsCli>(
          footslam, "steps",
          "Steps from a foot-mounted IMU recording (zero-velocity-aided INS) into a step file"),
      AddCommand<FootSlamBatchCli>(
          footslam, "batch",
          "Run many walks, one filter each, from a JSON Lines manifest, side by side"),
      AddCommand<FootSlamSimulateCli>(
          footslam, "simulate",
          "Simulate a pedestrian walk (and a foot-mounted IMU recording of it)"),
      AddEvaluate(footslam),
      AddCommand<FootSlamRenderCli>(footslam, "render", "Redraw map.png and map.svg from CSVs"),
  };
}

}  // namespace grove::tools
