// grove: the command-line front end. Subcommands:
//   grove footslam run|simulate|evaluate|render ...
//   grove fastslam run|victoria-park|simulate|evaluate|montecarlo ...
//   grove bench paper|scaling ...
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>
#include <utility>
#include <variant>

#include "grove/fastslam.h"
#include "grove/footslam.h"
#include "grove/version.h"
#include "tools/bench/bench_commands.h"
#include "tools/cli/mpi_world.h"
#include "tools/cli/run_flags.h"
#include "tools/io/victoria_park.h"
#include "tools/montecarlo/fastslam_montecarlo.h"
#include "tools/run/fastslam_run.h"
#include "tools/run/footslam_batch.h"
#include "tools/run/footslam_run.h"
#include "tools/sim/fastslam_simulator.h"

namespace {

using grove::FootSlamConfig;
namespace gt = grove::tools;

// Under mpirun with more than one rank, one filter across the ranks: checks the configuration
// for them (exit 2, one error line from rank 0, when it cannot run across that many), takes the
// threads per rank from the rank's CPU set unless given and points the run at the ranks. -1 to
// go on.
template <typename Facade, typename Config>
int AcrossRanks(gt::MpiWorld& world, Config* config, gt::RunOptions* run) {
  if (!world.active() || world.size() == 1) return -1;
  if (grove::Status s = Facade::CheckAcrossRanks(*config, world.size()); !s.ok()) {
    return world.rank() == 0 ? gt::Fail(gt::kExitUsage, s.message()) : gt::kExitUsage;
  }
  if (config->threads == 0) config->threads = gt::UsableCpus();
  run->ranks = &world;
  return -1;
}
int AcrossRanks(gt::MpiWorld& world, FootSlamConfig* config, gt::RunOptions* run) {
  return AcrossRanks<grove::FootSlam>(world, config, run);
}
int AcrossRanks(gt::MpiWorld& world, grove::FastSlamConfig* config, gt::RunOptions* run) {
  return AcrossRanks<grove::FastSlam>(world, config, run);
}

int Main(int argc, char** argv) {
  CLI::App app{"grove: particle-filter SLAM with shared persistent maps"};
  app.set_version_flag(
      "--version", [] { return grove::VersionString(); },
      "The version, commit, compiler and SIMD targets of this build");
  app.require_subcommand(1);
  CLI::App* footslam = app.add_subcommand("footslam", "Pedestrian SLAM from step odometry");
  footslam->require_subcommand(1);

  // ---- run ----
  CLI::App* run = footslam->add_subcommand("run", "Run FootSLAM on a step file");
  gt::FootSlamRunOptions run_options;
  CLI::Option* steps_option =
      run->add_option("--steps", run_options.steps_path,
                      "Step file: CSV 't,dx,dy' or 't,x,y' (default: the bundled building walk)");
  gt::RunFlags<FootSlamConfig> run_flags(run, grove::FootSlamConfigFields());
  run->add_option("--max-step", run_options.max_step_m,
                  "Reject input steps longer than this many metres (default 5)");
  CLI::Option* prior_option = run->add_option(
      "--prior-map", run_options.prior_map_path,
      "map.csv of an earlier walk through the same area, in this run's map frame: prior counts "
      "(weighted by prior_map_confidence)");

  // ---- batch ----
  CLI::App* batch = footslam->add_subcommand(
      "batch", "Run many walks, one filter each, from a JSON Lines manifest, side by side");
  gt::FootSlamBatchOptions batch_options;
  std::string batch_config_path;
  batch
      ->add_option("--manifest", batch_options.manifest_path,
                   "JSON Lines: {\"name\", \"steps\", optional \"prior_map\" and \"config\"} per "
                   "line")
      ->required();
  batch->add_option("--out", batch_options.out_dir, "Output directory: OUT/NAME per walk")
      ->required();
  batch->add_option("--jobs", batch_options.jobs, "Walks run side by side; --threads is shared")
      ->capture_default_str();
  batch
      ->add_option("--checkpoint-every", batch_options.checkpoint_every,
                   "Each walk writes a checkpoint every N steps (a killed batch resumes from it)")
      ->check(CLI::NonNegativeNumber);
  batch->add_option("--config", batch_config_path, "JSON file setting any parameter of every walk");
  gt::ConfigFlags<FootSlamConfig> batch_flags(batch, grove::FootSlamConfigFields());

  // ---- simulate ----
  CLI::App* simulate = footslam->add_subcommand("simulate", "Simulate a pedestrian walk");
  gt::SimulateOptions sim;
  std::string sim_seed = "1";
  simulate->add_option("--out", sim.out_dir, "Output directory (steps.csv, truth.csv)")->required();
  simulate->add_option("--minutes", sim.minutes, "Walk duration in minutes")->capture_default_str();
  simulate->add_option("--seed", sim_seed, "Seed, a non-negative integer")->capture_default_str();
  simulate
      ->add_option("--scenario", sim.scenario,
                   "building, open or campus (three buildings in a row)")
      ->capture_default_str();
  CLI::Option* drift_option = simulate->add_option(
      "--heading-drift", sim.heading_drift,
      "Heading random walk of the odometry, rad per sqrt(step) (default 0.006)");
  CLI::Option* scale_option = simulate->add_option(
      "--scale-error", sim.scale_error, "Step-length scale error of the odometry (default 0.02)");

  // ---- evaluate ----
  CLI::App* evaluate = footslam->add_subcommand("evaluate", "Position error against truth");
  std::string truth_path, trajectory_path;
  evaluate->add_option("--truth", truth_path, "Truth CSV (t,x,y)")->required();
  evaluate->add_option("--trajectory", trajectory_path, "Trajectory CSV (t,x,y,...)")->required();

  // ---- render ----
  CLI::App* render = footslam->add_subcommand("render", "Redraw map.png and map.svg from CSVs");
  std::string render_dir, odometry_path;
  double render_radius = 0;
  render->add_option("--dir", render_dir, "Directory holding map.csv and trajectory.csv")
      ->required();
  CLI::Option* radius_option = render->add_option(
      "--hex-radius", render_radius,
      "Hexagon radius in metres (default: the run's, from summary.json, or 0.5)");
  render->add_option("--steps", odometry_path, "Step file to draw the raw odometry from");

  // ---- fastslam ----
  CLI::App* fastslam = app.add_subcommand("fastslam", "Landmark FastSLAM");
  fastslam->require_subcommand(1);
  CLI::App* fs_run = fastslam->add_subcommand(
      "run", "Run FastSLAM 1.0 or 2.0 on controls.csv and observations.csv");
  gt::FastSlamRunOptions fs_run_options;
  CLI::Option* fs_controls =
      fs_run->add_option("--controls", fs_run_options.controls_path, "controls.csv (t,v,steer)")
          ->required();
  CLI::Option* fs_observations =
      fs_run
          ->add_option("--observations", fs_run_options.observations_path,
                       "observations.csv (t,range,bearing,id)")
          ->required();
  CLI::Option* fs_truth = fs_run->add_option("--truth", fs_run_options.truth_path,
                                             "truth.csv (t,x,y,heading): scored and drawn");
  CLI::Option* fs_landmarks_truth =
      fs_run->add_option("--landmarks-truth", fs_run_options.landmarks_truth_path,
                         "landmarks_truth.csv (id,x,y): scored and drawn");
  gt::RunFlags<grove::FastSlamConfig> fs_run_flags(fs_run, grove::FastSlamConfigFields());
  CLI::App* fs_park = fastslam->add_subcommand(
      "victoria-park",
      "Run FastSLAM on the bundled Victoria Park dataset (unknown association) and score it "
      "against GPS");
  gt::FastSlamRunOptions fs_park_options;
  fs_park_options.victoria_park_dir = gt::BundledVictoriaParkDir();
  CLI::Option* fs_park_data =
      fs_park
          ->add_option("--data", fs_park_options.victoria_park_dir,
                       "Directory holding inputs.dat, measurements.dat and gps.dat (or .gz)")
          ->capture_default_str();
  fs_park
      ->add_option("--until", fs_park_options.until_s,
                   "Use the records up to this time, seconds (default: the whole run)")
      ->check(CLI::NonNegativeNumber);
  gt::RunFlags<grove::FastSlamConfig> fs_park_flags(fs_park, grove::FastSlamConfigFields());
  CLI::App* fs_evaluate =
      fastslam->add_subcommand("evaluate", "Pose and landmark errors against the truth");
  std::string fs_eval_truth, fs_eval_trajectory, fs_eval_landmarks, fs_eval_landmarks_truth;
  fs_evaluate->add_option("--truth", fs_eval_truth, "truth.csv (t,x,y,heading)")->required();
  fs_evaluate->add_option("--trajectory", fs_eval_trajectory, "trajectory.csv (t,x,y,heading)")
      ->required();
  fs_evaluate->add_option("--landmarks", fs_eval_landmarks, "landmarks.csv of the run");
  fs_evaluate->add_option("--landmarks-truth", fs_eval_landmarks_truth, "landmarks_truth.csv");
  CLI::App* fs_simulate = fastslam->add_subcommand(
      "simulate", "Bailey's FastSLAM simulator: controls, observations, truth");
  std::string fs_map, fs_preset = "webmap", fs_out, fs_seed = "1";
  fs_simulate->add_option("--map", fs_map,
                          "Bailey's map file (blocks lm and wp; default: the bundled webmap)");
  fs_simulate->add_option("--preset", fs_preset, "webmap, sim1, sim2 or sim3")
      ->capture_default_str();
  fs_simulate->add_option("--seed", fs_seed, "Seed, a non-negative integer")->capture_default_str();
  fs_simulate->add_option("--out", fs_out, "Output directory")->required();
  CLI::App* fs_mc = fastslam->add_subcommand(
      "montecarlo",
      "Monte Carlo runs of the filters on the seed paper's Simulations I-III: MSE tables with "
      "95 % intervals, MSE, NEES and box-plot charts; rerunning into --out reuses finished runs");
  gt::MonteCarloOptions mc_options;
  bool mc_no_progress = false;
  fs_mc
      ->add_option("--scenario", mc_options.scenario,
                   "sim1 (webmap, known association), sim2 (its own map, unknown association), "
                   "sim3 (small robot, known association), or a scenario FILE.json (keys map, "
                   "preset, association, loops, sigma_speed_mps, sigma_steer_rad, sigma_range_m, "
                   "sigma_bearing_rad, max_range_m)")
      ->required();
  fs_mc
      ->add_option("--filters", mc_options.filters,
                   "Comma list of filters: fastslam1, fastslam2, ufastslam, srcd, srcd_aided, "
                   "srcd_pf, de_srcd")
      ->required();
  fs_mc
      ->add_option("--runs", mc_options.runs,
                   "Monte Carlo runs per filter and particle count, 1..100000")
      ->required();
  fs_mc
      ->add_option("--out", mc_options.out_dir,
                   "Output directory: runs/<filter>_p<particles>/run_<r>.csv|json, table.md, "
                   "table.csv, summary.json and the charts")
      ->required();
  fs_mc->add_option("--particles", mc_options.particles,
                    "Comma list of particle counts; every filter runs at each (default: the "
                    "seed's per scenario and filter: sim2 30, de_srcd 3; sim3 100, de_srcd 10; "
                    "sim1 100)");
  fs_mc
      ->add_option("--seed", mc_options.seed,
                   "S: run r uses seed S + r for the simulator and the filter")
      ->capture_default_str();
  fs_mc
      ->add_option("--threads", mc_options.threads,
                   "Jobs run in parallel on this many threads, each filter on one (0: every "
                   "hardware thread); results do not depend on it")
      ->capture_default_str();
  fs_mc->add_option("--loops", mc_options.loops,
                    "Loops through the waypoints, 1..1000 (default: the scenario's)");
  fs_mc->add_flag("--no-progress", mc_no_progress, "No progress output");

  // ---- bench ----
  CLI::App* bench = app.add_subcommand("bench", "Reproduce the paper's figures; measure scaling");
  bench->require_subcommand(1);
  CLI::App* paper = bench->add_subcommand(
      "paper", "Run time and memory against walk time (paper Figs. 9, 10) for each map");
  gt::PaperBenchOptions paper_options;
  paper->add_option("--out", paper_options.out_dir, "Output directory")->required();
  paper->add_option("--particles", paper_options.particles)
      ->capture_default_str()
      ->check(CLI::Range(int64_t{1}, int64_t{1} << 31));
  paper->add_option("--minutes", paper_options.minutes, "Walk length")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 1440.0));
  paper->add_option("--threads", paper_options.threads, "0 = all cores")
      ->capture_default_str()
      ->check(CLI::Range(0, 256));
  paper
      ->add_option("--naive-limit", paper_options.naive_limit_s,
                   "Stop the naive run after this many seconds")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  paper->add_option("--only", paper_options.only, "Run one configuration, e.g. 'htree s=16 T=5'");
  paper->add_option("--repeat", paper_options.repeat, "Runs per configuration (median reported)")
      ->check(CLI::Range(1, 1000));
  paper
      ->add_option("--grid", paper_options.grid,
                   "fixed (the paper's grid) or growing (the same walk on a grid that grows)")
      ->capture_default_str()
      ->check(CLI::IsMember({"fixed", "growing"}));
  CLI::App* scaling =
      bench->add_subcommand("scaling", "Throughput against threads and particle counts");
  gt::ScalingBenchOptions scaling_options;
  scaling->add_option("--out", scaling_options.out_dir, "Output directory")->required();
  scaling->add_option("--steps", scaling_options.steps, "Steps of the paper walk per point")
      ->capture_default_str()
      ->check(CLI::Range(int64_t{1}, int64_t{1000000}));
  scaling->add_option("--max-particles", scaling_options.max_particles)
      ->capture_default_str()
      ->check(CLI::Range(int64_t{1}, int64_t{1} << 31));
  scaling
      ->add_option("--grid", scaling_options.grid,
                   "growing (the default configuration's grid) or fixed (the paper's, as "
                   "bench paper runs it)")
      ->capture_default_str()
      ->check(CLI::IsMember({"fixed", "growing"}));

  CLI::App* fs_accuracy = bench->add_subcommand(
      "fastslam-accuracy", "FastSLAM 1.0 and 2.0 RMSE on the webmap against particles and seeds");
  gt::FastSlamAccuracyOptions fs_accuracy_options;
  fs_accuracy->add_option("--out", fs_accuracy_options.out_dir, "Output directory")->required();
  fs_accuracy->add_option("--seeds", fs_accuracy_options.seeds)
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  fs_accuracy->add_option("--particles", fs_accuracy_options.particles, "Particle counts")
      ->check(CLI::Range(int64_t{1}, int64_t{1} << 31));
  fs_accuracy->add_option("--threads", fs_accuracy_options.threads, "0 = all cores")
      ->check(CLI::Range(0, 256));
  fs_accuracy
      ->add_option("--association", fs_accuracy_options.association, "known, ml or ml_exclusive")
      ->capture_default_str();
  CLI::App* fs_speed = bench->add_subcommand(
      "fastslam-speed",
      "FastSLAM run time on the webmap and throughput against particles and threads");
  gt::FastSlamSpeedOptions fs_speed_options;
  fs_speed->add_option("--out", fs_speed_options.out_dir, "Output directory")->required();
  fs_speed->add_option("--max-particles", fs_speed_options.max_particles)
      ->capture_default_str()
      ->check(CLI::Range(int64_t{100}, int64_t{1} << 31));
  fs_speed->add_option("--controls", fs_speed_options.controls, "Control rows per throughput point")
      ->capture_default_str()
      ->check(CLI::Range(int64_t{1}, int64_t{100000000}));

  CLI::App* park_bench = bench->add_subcommand(
      "victoria-park", "Victoria Park: GPS error, landmarks, time and memory per particle count");
  gt::VictoriaParkBenchOptions park_bench_options;
  park_bench->add_option("--out", park_bench_options.out_dir, "Output directory")->required();
  park_bench->add_option("--particles", park_bench_options.particles)->capture_default_str();
  park_bench->add_option("--filters", park_bench_options.filters)->capture_default_str();
  park_bench
      ->add_option("--max-one-thread-particles", park_bench_options.max_one_thread_particles,
                   "Larger counts run on every hardware thread only")
      ->capture_default_str();
  park_bench->add_option("--until", park_bench_options.until_s, "Data up to this time, seconds")
      ->check(CLI::NonNegativeNumber);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? gt::kExitOk : gt::kExitUsage;
  }

  if (*run) {
    FootSlamConfig config;
    const int code = run_flags.Prepare(&config, &run_options.run,
                                       {{steps_option, "--steps"}, {prior_option, "--prior-map"}});
    if (code >= 0) return code;
    gt::MpiWorld world;  // one rank unless started by mpirun
    if (const int refused = AcrossRanks(world, &config, &run_options.run); refused >= 0) {
      return refused;
    }
    return gt::RunFootSlamCommand(config, run_options);
  }
  if (*batch) {
    FootSlamConfig config;
    if (!batch_config_path.empty()) {
      grove::Status s =
          grove::LoadConfigFile(grove::FootSlamConfigFields(), batch_config_path, &config);
      if (!s.ok()) {
        return gt::Fail(
            s.code() == grove::StatusCode::kNotFound || s.code() == grove::StatusCode::kIoError
                ? gt::kExitInput
                : gt::kExitUsage,
            s.message());
      }
    }
    if (grove::Status s = batch_flags.Apply(&config); !s.ok()) {
      return gt::Fail(gt::kExitUsage, s.message());
    }
    gt::MpiWorld world;  // one rank unless started by mpirun
    if (world.active()) {
      batch_options.rank = world.rank();
      batch_options.ranks = world.size();
      batch_options.all_gather = [&world](const std::string& mine) {
        return world.AllGather(mine);
      };
    }
    return gt::RunFootSlamBatch(config, batch_options);
  }
  if (*fs_run) {
    grove::FastSlamConfig config;
    const int code = fs_run_flags.Prepare(&config, &fs_run_options.run,
                                          {{fs_controls, "--controls"},
                                           {fs_observations, "--observations"},
                                           {fs_truth, "--truth"},
                                           {fs_landmarks_truth, "--landmarks-truth"}});
    if (code >= 0) return code;
    gt::MpiWorld world;  // one rank unless started by mpirun
    if (const int refused = AcrossRanks(world, &config, &fs_run_options.run); refused >= 0) {
      return refused;
    }
    return gt::RunFastSlamCommand(config, fs_run_options);
  }
  if (*fs_park) {
    grove::FastSlamConfig config = gt::VictoriaParkConfig();
    const int code =
        fs_park_flags.Prepare(&config, &fs_park_options.run, {{fs_park_data, "--data"}});
    if (code >= 0) return code;
    gt::MpiWorld world;  // one rank unless started by mpirun
    if (const int refused = AcrossRanks(world, &config, &fs_park_options.run); refused >= 0) {
      return refused;
    }
    return gt::RunFastSlamCommand(config, fs_park_options);
  }
  if (*fs_mc) {
    mc_options.progress = !mc_no_progress;
    gt::MpiWorld world;  // one rank unless started by mpirun
    if (world.active()) {
      mc_options.rank = world.rank();
      mc_options.ranks = world.size();
      mc_options.all_gather = [&world](const std::string& mine) { return world.AllGather(mine); };
      mc_options.progress = mc_options.progress && world.rank() == 0;
    }
    return gt::FastSlamMonteCarloCommand(mc_options);
  }
  if (*fs_evaluate) {
    return gt::FastSlamEvaluateCommand(fs_eval_truth, fs_eval_trajectory, fs_eval_landmarks,
                                       fs_eval_landmarks_truth);
  }
  if (*paper) return gt::PaperBenchCommand(paper_options);
  if (*park_bench) return gt::VictoriaParkBenchCommand(park_bench_options);
  if (*fs_accuracy) return gt::FastSlamAccuracyBenchCommand(fs_accuracy_options);
  if (*fs_speed) return gt::FastSlamSpeedBenchCommand(fs_speed_options);
  if (*scaling) return gt::ScalingBenchCommand(scaling_options);
  if (*simulate) {
    grove::FieldInfo seed_info{
        "--seed", "", grove::FieldType::kUnsigned, grove::kChangesResults, 0, 0, {}, {}};
    grove::StatusOr<grove::FieldValue> seed = grove::ParseFieldValue(seed_info, sim_seed);
    if (!seed.ok()) return gt::Fail(gt::kExitUsage, seed.status().message());
    sim.seed = std::get<uint64_t>(*seed);
    sim.heading_drift_given = drift_option->count() > 0;
    sim.scale_error_given = scale_option->count() > 0;
    return gt::SimulateCommand(sim);
  }
  if (*fs_simulate) {
    grove::FieldInfo seed_info{
        "--seed", "", grove::FieldType::kUnsigned, grove::kChangesResults, 0, 0, {}, {}};
    grove::StatusOr<grove::FieldValue> seed = grove::ParseFieldValue(seed_info, fs_seed);
    if (!seed.ok()) return gt::Fail(gt::kExitUsage, seed.status().message());
    return gt::FastSlamSimulateCommand(fs_map, fs_preset, fs_out, std::get<uint64_t>(*seed));
  }
  if (*evaluate) return gt::EvaluateCommand(truth_path, trajectory_path);
  if (*render) {
    if (*radius_option && !(render_radius > 0)) {
      return gt::Fail(gt::kExitUsage, fmt::format("--hex-radius = {}: must be > 0", render_radius));
    }
    return gt::RenderCommand(render_dir, render_radius, odometry_path);
  }
  return gt::kExitUsage;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Main(argc, argv);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "grove: error: out of memory\n");
    return grove::tools::kExitMemory;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "grove: internal error: %s\n", e.what());
    return grove::tools::kExitInternal;
  }
}
