// `grove fastslam montecarlo` through its command function: files, reuse of finished runs,
// independence of the thread count, scenarios and the exit codes of bad options.
#include "tools/montecarlo/fastslam_montecarlo.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

namespace grove::tools {
namespace {

namespace fs = std::filesystem;

std::string Slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

class FastSlamMonteCarloTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("grove_mc_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // sim3 with one loop (about 60 s of driving), FastSLAM 2.0 and SRCD with 10 particles, 2 runs.
  MonteCarloOptions Tiny(const std::string& out) const {
    MonteCarloOptions o;
    o.scenario = "sim3";
    o.loops = 1;
    o.filters = "fastslam2,srcd";
    o.particles = "10";
    o.runs = 2;
    o.out_dir = (dir_ / out).string();
    o.threads = 2;
    o.progress = false;
    return o;
  }
  std::string Write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name) << text;
    return (dir_ / name).string();
  }
  nlohmann::json Summary(const std::string& out) const {
    return nlohmann::json::parse(Slurp(dir_ / out / "summary.json"));
  }

  fs::path dir_;
};

TEST_F(FastSlamMonteCarloTest, WritesEveryFileAndReusesFinishedRuns) {
  ASSERT_EQ(FastSlamMonteCarloCommand(Tiny("out")), 0);
  const fs::path out = dir_ / "out";
  for (const char* group : {"fastslam2_p10", "srcd_p10"}) {
    for (int r = 0; r < 2; ++r) {
      const fs::path csv = out / "runs" / group / ("run_" + std::to_string(r) + ".csv");
      const fs::path js = out / "runs" / group / ("run_" + std::to_string(r) + ".json");
      ASSERT_TRUE(fs::exists(csv)) << csv;
      ASSERT_TRUE(fs::exists(js)) << js;
      const std::string record_text = Slurp(js);
      EXPECT_EQ(std::count(record_text.begin(), record_text.end(), '\n'), 1) << "one line";
      const nlohmann::json record = nlohmann::json::parse(record_text);
      EXPECT_EQ(record["status"], "ok");
      EXPECT_EQ(record["run"], r);
      EXPECT_EQ(record["seed"], 1 + r);
      EXPECT_EQ(record["particles"], 10);
      EXPECT_GT(record["position_mse_mean"].get<double>(), 0);
      EXPECT_GE(record["position_mse_variance"].get<double>(), 0);
      EXPECT_GT(record["heading_mse_mean"].get<double>(), 0);
      EXPECT_GE(record["final_position_error_m"].get<double>(), 0);
      EXPECT_GT(record["cpu_s"].get<double>(), 0);
      EXPECT_GT(record["nees_scans"].get<int64_t>(), 100);
      // Every truth row is scored (the start and each control time).
      EXPECT_EQ(record["rows_evaluated"], record["rows"]);
      const std::string text = Slurp(csv);
      EXPECT_EQ(
          text.rfind("t,x,y,heading,truth_x,truth_y,truth_heading,position_error2,heading_error2,"
                     "nees\n",
                     0),
          0u);
      EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), record["rows"].get<int64_t>() + 1);
    }
  }
  for (const char* name :
       {"table.md", "table.csv", "summary.json", "mse_position.png", "mse_position.svg",
        "mse_heading.png", "mse_heading.svg", "boxplot_position.png", "boxplot_position.svg",
        "nees.png", "nees.svg"}) {
    EXPECT_TRUE(fs::exists(out / name)) << name;
  }
  // One particle count: no accuracy-against-CPU chart.
  EXPECT_FALSE(fs::exists(out / "accuracy_vs_cpu.png"));
  const std::string table = Slurp(out / "table.csv");
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), 3) << table;
  EXPECT_NE(table.find("\nfastslam2,10,2,0,"), std::string::npos) << table;
  EXPECT_NE(table.find("\nsrcd,10,2,0,"), std::string::npos) << table;
  nlohmann::json summary = Summary("out");
  EXPECT_EQ(summary["jobs"], 4);
  EXPECT_EQ(summary["jobs_reused"], 0);
  EXPECT_NEAR(summary["nees_interval"]["low"].get<double>(), 0.6187, 1e-3);  // 2 runs

  // A second invocation reuses all 2 x 2 runs and writes the same table.
  ASSERT_EQ(FastSlamMonteCarloCommand(Tiny("out")), 0);
  summary = Summary("out");
  EXPECT_EQ(summary["jobs_reused"], 4);
  EXPECT_EQ(summary["jobs_run"], 0);
  EXPECT_EQ(Slurp(out / "table.csv"), table);
}

TEST_F(FastSlamMonteCarloTest, RunsDoNotDependOnTheThreadCount) {
  MonteCarloOptions one = Tiny("one");
  one.threads = 1;
  one.charts = false;
  MonteCarloOptions two = Tiny("two");
  two.threads = 2;
  two.charts = false;
  ASSERT_EQ(FastSlamMonteCarloCommand(one), 0);
  ASSERT_EQ(FastSlamMonteCarloCommand(two), 0);
  int compared = 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir_ / "one" / "runs")) {
    if (entry.path().extension() != ".csv") continue;
    const fs::path other = dir_ / "two" / fs::relative(entry.path(), dir_ / "one");
    EXPECT_EQ(Slurp(entry.path()), Slurp(other)) << entry.path();
    ++compared;
  }
  EXPECT_EQ(compared, 4);
}

TEST_F(FastSlamMonteCarloTest, RedoesRunsOfAnotherConfigurationOrWithADamagedCsv) {
  MonteCarloOptions o = Tiny("out");
  o.filters = "fastslam2";
  o.charts = false;
  ASSERT_EQ(FastSlamMonteCarloCommand(o), 0);
  // A damaged CSV: that run only is redone.
  const fs::path csv = dir_ / "out" / "runs" / "fastslam2_p10" / "run_1.csv";
  const std::string before = Slurp(csv);
  std::ofstream(csv, std::ios::app) << "1,2,3\n";
  ASSERT_EQ(FastSlamMonteCarloCommand(o), 0);
  EXPECT_EQ(Summary("out")["jobs_reused"], 1);
  EXPECT_EQ(Slurp(csv), before);
  // Another seed: run 0 is now seed 2, run 1 seed 3; nothing matches.
  o.seed = "2";
  ASSERT_EQ(FastSlamMonteCarloCommand(o), 0);
  EXPECT_EQ(Summary("out")["jobs_reused"], 0);
  // Another loop count changes the scenario digest.
  o.loops = 2;
  o.runs = 1;
  ASSERT_EQ(FastSlamMonteCarloCommand(o), 0);
  EXPECT_EQ(Summary("out")["jobs_reused"], 0);
}

TEST_F(FastSlamMonteCarloTest, BadOptionsGiveTheirExitCodes) {
  auto code = [&](auto change) {
    MonteCarloOptions o = Tiny("bad");
    o.charts = false;
    change(o);
    return FastSlamMonteCarloCommand(o);
  };
  EXPECT_EQ(code([](MonteCarloOptions& o) { o.runs = 0; }), 2);
  EXPECT_EQ(code([](MonteCarloOptions& o) { o.runs = 100001; }), 2);
  EXPECT_EQ(code([](MonteCarloOptions& o) { o.filters = "fastslam2,fastslam3"; }), 2);
  EXPECT_EQ(code([](MonteCarloOptions& o) { o.filters = "srcd,srcd"; }), 2);
  EXPECT_EQ(code([](MonteCarloOptions& o) { o.filters = ""; }), 2);
  EXPECT_EQ(code([](MonteCarloOptions& o) { o.particles = "0"; }), 2);
  EXPECT_EQ(code([](MonteCarloOptions& o) { o.particles = "10,abc"; }), 2);
  EXPECT_EQ(code([](MonteCarloOptions& o) { o.particles = "2147483649"; }), 2);
  EXPECT_EQ(code([](MonteCarloOptions& o) { o.scenario = "sim4"; }), 2);
  EXPECT_EQ(code([](MonteCarloOptions& o) { o.seed = "-1"; }), 2);
  EXPECT_EQ(code([](MonteCarloOptions& o) { o.threads = 257; }), 2);
  EXPECT_EQ(code([](MonteCarloOptions& o) { o.loops = 1001; }), 2);
  EXPECT_EQ(code([](MonteCarloOptions& o) {
              o.seed = "18446744073709551615";
              o.runs = 2;
            }),
            2);
  EXPECT_EQ(code([](MonteCarloOptions& o) { o.out_dir = ""; }), 2);
  // A scenario file that does not exist is a bad input file.
  EXPECT_EQ(code([&](MonteCarloOptions& o) { o.scenario = (dir_ / "missing.json").string(); }), 3);
  // Nothing was written for any of them.
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
  // An output directory that cannot be made: its parent is a file.
  const std::string file = Write("file", "x");
  EXPECT_EQ(code([&](MonteCarloOptions& o) { o.out_dir = file + "/out"; }), 5);
}

TEST_F(FastSlamMonteCarloTest, ScenarioFilesNameTheLineAndColumnOfABadKey) {
  const std::string map_text = EmbeddedSim3Map();
  Write("small_map.txt", map_text);
  const std::string good = Write("good.json",
                                 "{\n  \"map\": \"small_map.txt\",\n  \"preset\": \"sim3\",\n"
                                 "  \"association\": \"ml\",\n  \"loops\": 3,\n"
                                 "  \"sigma_range_m\": 0.5,\n  \"max_range_m\": 6\n}\n");
  StatusOr<MonteCarloScenarioSpec> spec = ParseMonteCarloScenario(good, 0);
  ASSERT_TRUE(spec.ok()) << spec.status().message();
  EXPECT_EQ(spec->preset, "sim3");
  EXPECT_EQ(spec->association, FastSlamAssociation::kMaximumLikelihood);
  EXPECT_EQ(spec->sim.loops, 3);
  EXPECT_EQ(spec->sim.sigma_range_m, 0.5);
  EXPECT_EQ(spec->sim.max_range_m, 6);
  EXPECT_EQ(spec->sim.wheelbase_m, 0.26);                        // the preset's
  EXPECT_EQ(spec->map_path, (dir_ / "small_map.txt").string());  // beside the JSON file
  StatusOr<MonteCarloScenario> scenario = LoadMonteCarloScenario(*spec);
  ASSERT_TRUE(scenario.ok()) << scenario.status().message();
  EXPECT_EQ(scenario->map.landmarks.size(), 30u);
  // --loops overrides the file, and changes the digest.
  StatusOr<MonteCarloScenarioSpec> two = ParseMonteCarloScenario(good, 2);
  ASSERT_TRUE(two.ok());
  EXPECT_EQ(two->sim.loops, 2);
  EXPECT_NE(LoadMonteCarloScenario(*two)->digest, scenario->digest);
  // The filter gets the simulator's noise and sensor.
  const FastSlamConfig config = MonteCarloJobConfig(*scenario, FastSlamFilter::kSrcd, 10, 7);
  EXPECT_EQ(config.sigma_range_m, 0.5);
  EXPECT_EQ(config.sigma_speed_mps, spec->sim.sigma_speed_mps);
  EXPECT_EQ(config.wheelbase_m, 0.26);
  EXPECT_EQ(config.sensor_range_m, 6);
  EXPECT_EQ(config.association, FastSlamAssociation::kMaximumLikelihood);
  EXPECT_EQ(config.threads, 1);
  EXPECT_EQ(config.seed, 7u);

  auto error = [&](const std::string& text) {
    const std::string path = Write("bad.json", text);
    StatusOr<MonteCarloScenarioSpec> s = ParseMonteCarloScenario(path, 0);
    EXPECT_FALSE(s.ok()) << text;
    return s.ok() ? std::string() : s.status().message();
  };
  const std::string bad = (dir_ / "bad.json").string();
  EXPECT_EQ(error("{\"preset\": \"sim3\",\n \"association\": \"known\",\n \"sigma_rnage_m\": 1}"),
            bad + ":3:2: unknown key \"sigma_rnage_m\" (did you mean \"sigma_range_m\"?)");
  EXPECT_EQ(error("{\"preset\": \"sim3\", \"association\": \"known\",\n\"loops\": 0}")
                .rfind(bad + ":2:1: loops = 0: must be in 1..1000", 0),
            0u);
  EXPECT_EQ(
      error("{\"preset\": \"sim5\", \"association\": \"known\"}").rfind(bad + ":1:2: preset", 0),
      0u);
  EXPECT_EQ(error("{\"preset\": \"sim3\", \"association\": \"maybe\"}")
                .rfind(bad + ":1:20: association", 0),
            0u);
  EXPECT_EQ(error("{\"preset\": \"sim3\", \"association\": \"known\", \"map\": 5}")
                .rfind(bad + ":1:44: map", 0),
            0u);
  EXPECT_NE(error("{\"preset\": \"sim3\"}").find("missing key \"association\""), std::string::npos);
  EXPECT_NE(error("{\"preset\": \"sim3\",").find("invalid JSON"), std::string::npos);
  EXPECT_EQ(error("{\"preset\": \"sim3\", \"association\": \"known\", \"sigma_speed_mps\": -1}")
                .rfind(bad + ":1:44: sigma_speed_mps = -1: must be", 0),
            0u);
}

TEST_F(FastSlamMonteCarloTest, BuiltInScenariosAndThePapersParticles) {
  StatusOr<MonteCarloScenarioSpec> sim2 = ParseMonteCarloScenario("sim2", 0);
  ASSERT_TRUE(sim2.ok());
  EXPECT_EQ(sim2->association, FastSlamAssociation::kMaximumLikelihood);
  StatusOr<MonteCarloScenario> s2 = LoadMonteCarloScenario(*sim2);
  ASSERT_TRUE(s2.ok()) << s2.status().message();
  EXPECT_EQ(s2->map_name, "bundled:sim2_map.txt");
  EXPECT_EQ(s2->map.landmarks.size(), 60u);
  StatusOr<MonteCarloScenarioSpec> sim1 = ParseMonteCarloScenario("sim1", 0);
  ASSERT_TRUE(sim1.ok());
  EXPECT_EQ(sim1->association, FastSlamAssociation::kKnown);
  EXPECT_EQ(sim1->sim.sigma_range_m, 1.2);
  StatusOr<MonteCarloScenario> s1 = LoadMonteCarloScenario(*sim1);
  ASSERT_TRUE(s1.ok());
  EXPECT_EQ(s1->map_name, std::string(EmbeddedBaileyWebmapName()));
  StatusOr<MonteCarloScenario> s3 = LoadMonteCarloScenario(*ParseMonteCarloScenario("sim3", 0));
  ASSERT_TRUE(s3.ok());
  EXPECT_EQ(s3->map.landmarks.size(), 30u);
  EXPECT_NE(s3->digest, s2->digest);

  EXPECT_EQ(PaperParticles("sim2", FastSlamFilter::kUnscented), 30);
  EXPECT_EQ(PaperParticles("sim2", FastSlamFilter::kSrcd), 30);
  EXPECT_EQ(PaperParticles("sim2", FastSlamFilter::kDeSrcd), 3);
  EXPECT_EQ(PaperParticles("sim3", FastSlamFilter::kFastSlam2), 100);
  EXPECT_EQ(PaperParticles("sim3", FastSlamFilter::kDeSrcd), 10);
  EXPECT_EQ(PaperParticles("sim1", FastSlamFilter::kSrcdAided), 100);
}

}  // namespace
}  // namespace grove::tools
