// `grove bench paper|scaling|fastslam-accuracy|fastslam-speed|victoria-park|footslam|fastslam`:
// their options and what runs them.
#include <cstdint>
#include <limits>

#include "grove/fastslam.h"
#include "grove/footslam.h"
#include "tools/bench/bench_commands.h"
#include "tools/cli/command.h"
#include "tools/cli/fastslam_input_flags.h"
#include "tools/cli/sweep_flags.h"
#include "tools/cli/typed_flags.h"
#include "tools/run/run_loop.h"

namespace grove::tools {
namespace {

constexpr int64_t kMaxParticles = int64_t{1} << 31;

const FieldInfo& FastSlamField(const char* name) {
  return FindField(FastSlamConfigFields(), name)->info;
}

// The options of a benchmark, parsed into T's options (`Options`) and run by `run`.
template <typename Options, int (*kRun)(const Options&)>
class BenchCli {
 public:
  explicit BenchCli(CLI::App* app) : typed_(app) {
    AddPath(app, "--out", &options_.out_dir, "Output directory")->required();
  }
  int Run() {
    if (Status s = typed_.Apply(); !s.ok()) return Fail(kExitUsage, s.message());
    return kRun(options_);
  }

 protected:
  Options options_;
  TypedFlags typed_;
};

class PaperCli : public BenchCli<PaperBenchOptions, PaperBenchCommand> {
 public:
  explicit PaperCli(CLI::App* app) : BenchCli(app) {
    typed_.Integer("--particles", &options_.particles, 1, kMaxParticles, "Particles");
    typed_.Real("--minutes", &options_.minutes, Interval::Closed(0.1, 1440), "Walk length");
    typed_.Integer("--threads", &options_.threads, 0, 256, "Worker threads; 0: all cores");
    typed_.Real("--naive-limit", &options_.naive_limit_s, Interval::Above(0),
                "Stop the naive run after this many seconds");
    typed_
        .Choice("--only", &options_.only, PaperBenchConfigurations(),
                "Run one configuration, e.g. 'htree s=16 T=5'")
        ->default_str("every configuration");
    typed_.Integer("--repeat", &options_.repeat, 1, 1000,
                   "Runs per configuration (median reported)");
    typed_.Choice("--grid", &options_.grid, {"fixed", "growing"},
                  "fixed (the paper's grid) or growing (the same walk on a grid that grows)");
  }
};

class ScalingCli : public BenchCli<ScalingBenchOptions, ScalingBenchCommand> {
 public:
  explicit ScalingCli(CLI::App* app) : BenchCli(app) {
    typed_.Integer("--steps", &options_.steps, 1, 1000000, "Steps of the paper walk per point");
    typed_.Integer("--max-particles", &options_.max_particles, 1, kMaxParticles,
                   "The largest particle count");
    typed_.Choice("--grid", &options_.grid, {"fixed", "growing"},
                  "growing (the default configuration's grid) or fixed (the paper's, as bench "
                  "paper runs it)");
  }
};

class FastSlamAccuracyCli : public BenchCli<FastSlamAccuracyOptions, FastSlamAccuracyBenchCommand> {
 public:
  explicit FastSlamAccuracyCli(CLI::App* app) : BenchCli(app) {
    typed_.Integer("--seeds", &options_.seeds, 1, 1000, "Simulator seeds per particle count");
    const FieldInfo& particles = FastSlamField("particles");
    typed_.IntegerList("--particles", &options_.particles, particles.min_integer,
                       particles.max_integer, "Particle counts");
    typed_.Integer("--threads", &options_.threads, 0, 256, "Worker threads; 0: all cores");
    typed_.Choice("--association", &options_.association, FastSlamField("association").choices,
                  "Data association: known, ml, ml_exclusive, sampled or jcbb");
  }
};

class FastSlamSpeedCli : public BenchCli<FastSlamSpeedOptions, FastSlamSpeedBenchCommand> {
 public:
  explicit FastSlamSpeedCli(CLI::App* app) : BenchCli(app) {
    typed_.Integer("--max-particles", &options_.max_particles, 100, kMaxParticles,
                   "The largest particle count of the throughput points");
    typed_.Integer("--controls", &options_.controls, 1, 100000000,
                   "Control rows per throughput point");
  }
};

class VictoriaParkBenchCli : public BenchCli<VictoriaParkBenchOptions, VictoriaParkBenchCommand> {
 public:
  explicit VictoriaParkBenchCli(CLI::App* app) : BenchCli(app) {
    const FieldInfo& particles = FastSlamField("particles");
    typed_.IntegerList("--particles", &options_.particles, particles.min_integer,
                       particles.max_integer, "Particle counts");
    typed_.ChoiceList("--filters", &options_.filters, FastSlamField("filter").choices, "Filters");
    typed_.Integer("--max-one-thread-particles", &options_.max_one_thread_particles, 0,
                   std::numeric_limits<int64_t>::max(),
                   "Larger counts run on every hardware thread only");
    typed_
        .Real("--until", &options_.until_s, Interval::AtLeast(0), "Data up to this time, seconds")
        ->default_str("the whole run");
  }
};

class FootSlamBenchCli {
 public:
  explicit FootSlamBenchCli(CLI::App* app)
      : steps_(AddPath(app, "--steps", &options_.steps_path, "Step file: CSV 't,dx,dy' or 't,x,y'")
                   ->required()),
        typed_(app),
        max_step_(typed_.Real("--max-step", &options_.max_step_m, Interval::Above(0),
                              "Reject input steps longer than this many metres")),
        flags_(app, FootSlamConfigFields()) {}
  int Run() {
    if (Status s = typed_.Apply(); !s.ok()) return Fail(kExitUsage, s.message());
    FootSlamConfig config;
    const int code = flags_.Prepare(&config, &options_.sweep, {{steps_, "--steps"}});
    if (code >= 0) return code;
    return FootSlamBenchCommand(config, options_);
  }

 private:
  FootSlamBenchOptions options_;
  CLI::Option* steps_;
  TypedFlags typed_;
  CLI::Option* max_step_;
  SweepFlags<FootSlamConfig> flags_;  // after the input's flags on the help page
};

class FastSlamBenchCli {
 public:
  explicit FastSlamBenchCli(CLI::App* app)
      : inputs_(app, &options_.controls_path, &options_.observations_path),
        flags_(app, FastSlamConfigFields()) {}
  int Run() {
    FastSlamConfig config;
    const int code = flags_.Prepare(
        &config, &options_.sweep,
        {{inputs_.controls, "--controls"}, {inputs_.observations, "--observations"}});
    if (code >= 0) return code;
    return FastSlamBenchCommand(config, options_);
  }

 private:
  FastSlamBenchOptions options_;
  FastSlamInputFlags inputs_;
  SweepFlags<FastSlamConfig> flags_;
};

}  // namespace

std::vector<Command> AddBenchCommands(CLI::App* grove) {
  CLI::App* bench = AddFamily(grove, "bench", "Reproduce the paper's figures; measure scaling");
  return {
      AddCommand<PaperCli>(
          bench, "paper", "Run time and memory against walk time (paper Figs. 9, 10) for each map"),
      AddCommand<ScalingCli>(bench, "scaling", "Throughput against threads and particle counts"),
      AddCommand<FastSlamAccuracyCli>(
          bench, "fastslam-accuracy",
          "FastSLAM 1.0 and 2.0 RMSE on the webmap against particles and seeds"),
      AddCommand<FastSlamSpeedCli>(
          bench, "fastslam-speed",
          "FastSLAM run time on the webmap and throughput against particles and threads"),
      AddCommand<VictoriaParkBenchCli>(
          bench, "victoria-park",
          "Victoria Park: GPS error, landmarks, time and memory per particle count"),
      AddCommand<FootSlamBenchCli>(
          bench, "footslam", "FootSLAM's time on your step file against threads and particles"),
      AddCommand<FastSlamBenchCli>(
          bench, "fastslam",
          "FastSLAM's time on your controls and observations against threads and particles"),
  };
}

}  // namespace grove::tools
