// `grove fastslam run|victoria-park|evaluate|simulate|montecarlo`: their options and what runs
// them.
#include <fmt/format.h>

#include <memory>
#include <string>

#include "grove/fastslam.h"
#include "tools/cli/across_ranks.h"
#include "tools/cli/command.h"
#include "tools/cli/fastslam_input_flags.h"
#include "tools/cli/mpi_world.h"
#include "tools/cli/run_flags.h"
#include "tools/cli/typed_flags.h"
#include "tools/io/victoria_park.h"
#include "tools/montecarlo/fastslam_montecarlo.h"
#include "tools/run/fastslam_run.h"
#include "tools/sim/fastslam_simulator.h"

namespace grove::tools {
namespace {

const std::vector<std::string>& Choices(const char* field) {
  return FindField(FastSlamConfigFields(), field)->info.choices;
}

class FastSlamRunCli {
 public:
  explicit FastSlamRunCli(CLI::App* app)
      : inputs_(app, &options_.controls_path, &options_.observations_path),
        truth_(AddPath(app, "--truth", &options_.truth_path,
                       "True path, CSV (t,x,y[,heading]) or TUM: scored and drawn")),
        landmarks_truth_(AddPath(app, "--landmarks-truth", &options_.landmarks_truth_path,
                                 "landmarks_truth.csv (id,x,y): scored and drawn")),
        flags_(app, FastSlamConfigFields()) {}

  int Run() {
    FastSlamConfig config;
    const int code = flags_.Prepare(&config, &options_.run,
                                    {{inputs_.controls, "--controls"},
                                     {inputs_.observations, "--observations"},
                                     {truth_, "--truth"},
                                     {landmarks_truth_, "--landmarks-truth"}});
    if (code >= 0) return code;
    return RunOnRanks<FastSlam>(config, options_, RunFastSlamCommand);
  }

 private:
  FastSlamRunOptions options_;
  FastSlamInputFlags inputs_;
  CLI::Option* truth_;
  CLI::Option* landmarks_truth_;
  RunFlags<FastSlamConfig> flags_;
};

class VictoriaParkCli {
 public:
  explicit VictoriaParkCli(CLI::App* app)
      : data_(AddPath(app, "--data", &options_.victoria_park_dir,
                      "Directory holding inputs.dat, measurements.dat and gps.dat (or .gz)",
                      BundledVictoriaParkDir())),
        typed_(app),
        until_(typed_
                   .Real("--until", &options_.until_s, Interval::AtLeast(0),
                         "Use the records up to this time, seconds")
                   ->default_str("the whole run")),
        flags_(app, FastSlamConfigFields(), VictoriaParkConfig()) {
    options_.victoria_park_dir = BundledVictoriaParkDir();
  }

  int Run() {
    if (Status s = typed_.Apply(); !s.ok()) return Fail(kExitUsage, s.message());
    FastSlamConfig config = VictoriaParkConfig();
    const int code = flags_.Prepare(&config, &options_.run, {{data_, "--data"}});
    if (code >= 0) return code;
    return RunOnRanks<FastSlam>(config, options_, RunFastSlamCommand);
  }

 private:
  FastSlamRunOptions options_;
  CLI::Option* data_;
  TypedFlags typed_;
  CLI::Option* until_;
  RunFlags<FastSlamConfig> flags_;
};

class FastSlamEvaluateCli {
 public:
  explicit FastSlamEvaluateCli(CLI::App* app) {
    AddPath(app, "--truth", &truth_, "truth.csv (t,x,y,heading)")->required();
    AddPath(app, "--trajectory", &trajectory_, "trajectory.csv (t,x,y,heading)")->required();
    AddPath(app, "--landmarks", &landmarks_, "landmarks.csv of the run");
    AddPath(app, "--landmarks-truth", &landmarks_truth_, "landmarks_truth.csv");
  }

  int Run() const {
    return FastSlamEvaluateCommand(truth_, trajectory_, landmarks_, landmarks_truth_);
  }

 private:
  std::string truth_, trajectory_, landmarks_, landmarks_truth_;
};

class FastSlamSimulateCli {
 public:
  explicit FastSlamSimulateCli(CLI::App* app) : typed_(app) {
    AddPath(app, "--map", &map_, "Bailey's map file (blocks lm and wp)", "the bundled webmap");
    typed_.Choice(
        "--preset", &preset_,
        std::vector<std::string>(std::begin(kBaileyPresetNames), std::end(kBaileyPresetNames)),
        "Bailey's simulator settings: his webmap's or one of the seed paper's "
        "Simulations I-III");
    typed_.Unsigned("--seed", &seed_, "Seed");
    AddPath(app, "--out", &out_, "Output directory")->required();
  }

  int Run() {
    if (Status s = typed_.Apply(); !s.ok()) return Fail(kExitUsage, s.message());
    return FastSlamSimulateCommand(map_, preset_, out_, seed_);
  }

 private:
  TypedFlags typed_;
  std::string map_, preset_ = "webmap", out_;
  uint64_t seed_ = 1;
};

class MonteCarloCli {
 public:
  explicit MonteCarloCli(CLI::App* app) : typed_(app) {
    Document(app->add_option(
                 "--scenario", options_.scenario,
                 "sim1 (webmap, known association), sim2 (its own map, unknown association), "
                 "sim3 (small robot, known association), or a scenario FILE.json (keys map, "
                 "preset, association, loops, sigma_speed_mps, sigma_steer_rad, sigma_range_m, "
                 "sigma_bearing_rad, max_range_m)"),
             {"NAME|PATH", "", {}, ""})
        ->required();
    Document(app->add_option("--filters", options_.filters, "Comma list of filters"),
             {"LIST", "", Choices("filter"), ""})
        ->required();
    typed_
        .Integer("--runs", &options_.runs, 1, kMonteCarloMaxRuns,
                 "Monte Carlo runs per filter and particle count")
        ->required()
        ->default_str("");
    AddPath(app, "--out", &options_.out_dir,
            "Output directory: runs/<filter>_p<particles>/run_<r>.csv|json, table.md, "
            "table.csv, summary.json and the charts")
        ->required();
    particles_ =
        Document(app->add_option("--particles", options_.particles,
                                 "Comma list of particle counts; every filter runs at each"),
                 {"LIST",
                  fmt::format("each 1..{}", kMonteCarloMaxParticles),
                  {},
                  "the seed's per scenario and filter: sim2 30, de_srcd 3; sim3 100, de_srcd 10; "
                  "sim1 100"});
    Document(
        app->add_option("--seed", options_.seed,
                        "S: run r uses seed S + r for the simulator and the filter"),
        {"INT", fmt::format("0..{}", std::numeric_limits<uint64_t>::max()), {}, options_.seed});
    typed_.Integer("--threads", &options_.threads, 0, kMonteCarloMaxThreads,
                   "Jobs run in parallel on this many threads, each filter on one (0: every "
                   "hardware thread); results do not depend on it");
    typed_
        .Integer("--loops", &options_.loops, 1, kMonteCarloMaxLoops, "Loops through the waypoints")
        ->default_str("the scenario's");
    AddMemoryBudgetFlag(app, &memory_budget_);
    app->add_flag("--no-progress", no_progress_, "No progress output");
  }

  int Run() {
    if (Status s = typed_.Apply(); !s.ok()) return Fail(kExitUsage, s.message());
    if (const int code = ParseMemoryBudgetFlag(memory_budget_, &options_.memory_budget_bytes);
        code >= 0) {
      return code;
    }
    // An empty list is refused, never read as "the seed's counts".
    if (*particles_ && options_.particles.empty()) {
      return Fail(kExitUsage,
                  fmt::format("--particles = \"\": must be a comma list of particle counts, each "
                              "in 1..{}",
                              kMonteCarloMaxParticles));
    }
    options_.progress = !no_progress_;
    MpiWorld world;  // one rank unless started by mpirun
    if (world.active()) {
      options_.rank = world.rank();
      options_.ranks = world.size();
      options_.all_gather = [&world](const std::string& mine) { return world.AllGather(mine); };
      options_.progress = options_.progress && world.rank() == 0;
    }
    return FastSlamMonteCarloCommand(options_);
  }

 private:
  MonteCarloOptions options_;
  TypedFlags typed_;
  std::string memory_budget_;
  CLI::Option* particles_ = nullptr;
  bool no_progress_ = false;
};

}  // namespace

std::vector<Command> AddFastSlamCommands(CLI::App* grove) {
  CLI::App* fastslam = AddFamily(grove, "fastslam", "Landmark FastSLAM");
  return {
      AddCommand<FastSlamRunCli>(fastslam, "run",
                                 "Run FastSLAM 1.0 or 2.0 on controls.csv and observations.csv"),
      AddCommand<VictoriaParkCli>(fastslam, "victoria-park",
                                  "Run FastSLAM on the bundled Victoria Park dataset (unknown "
                                  "association) and score it against GPS"),
      AddCommand<FastSlamEvaluateCli>(fastslam, "evaluate",
                                      "Pose and landmark errors against the truth"),
      AddCommand<FastSlamSimulateCli>(fastslam, "simulate",
                                      "Bailey's FastSLAM simulator: controls, observations, truth"),
      AddCommand<MonteCarloCli>(
          fastslam, "montecarlo",
          "Monte Carlo runs of the filters on the seed paper's Simulations I-III: MSE tables "
          "with 95 % intervals, MSE, NEES and box-plot charts; rerunning into --out reuses "
          "finished runs"),
  };
}

}  // namespace grove::tools
