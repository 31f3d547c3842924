// Regressions of the `grove` command found by hostile use: values outside the input rules
// (grove/input_rules.h) named at their file, line and column; checkpoints at least every N steps
// and never twice at one; failed runs leaving no directory they made; bytes after a JSON
// document; Monte Carlo's failed jobs, memory budget and signals.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tests/tools/cli_testing.h"

namespace {

using grove::testing::CliTest;
using grove::testing::Outcome;
using grove::testing::Slurp;
namespace fs = std::filesystem;

// The lines of `text`.
std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::string Joined(const std::vector<std::string>& lines) {
  std::string text;
  for (const std::string& l : lines) text += l + "\n";
  return text;
}

class CliInputRulesTest : public CliTest {
 protected:
  // The webmap's first 50 s: controls rows 2..2001 and the observations up to t = 50.
  void SetUp() override {
    CliTest::SetUp();
    ASSERT_EQ(Grove("fastslam simulate --out " + (dir_ / "sim").string()).exit_code, 0);
    std::vector<std::string> c = Lines(Slurp(dir_ / "sim" / "controls.csv"));
    c.resize(2001);
    controls_ = c;
    for (const std::string& line : Lines(Slurp(dir_ / "sim" / "observations.csv"))) {
      if (observations_.empty() || std::stod(line.substr(0, line.find(','))) <= 50) {
        observations_.push_back(line);
      }
    }
  }

  // Runs FastSLAM on the controls and observations given; expects exit 3 with `where` (after
  // the file's path) and `what` in the error, and no output directory.
  void ExpectRefused(const std::vector<std::string>& controls,
                     const std::vector<std::string>& observations, const std::string& file,
                     const std::string& where, const std::string& what) {
    const std::string c = Write("c.csv", Joined(controls));
    const std::string o = Write("o.csv", Joined(observations));
    const fs::path out = dir_ / "out";
    Outcome r = Grove("fastslam run --no-progress --particles 20 --controls " + c +
                      " --observations " + o + " --out " + out.string());
    SCOPED_TRACE(what);
    EXPECT_EQ(r.exit_code, 3) << r.err;
    EXPECT_NE(r.err.find((dir_ / file).string() + ":" + where + ": " + what), std::string::npos)
        << r.err;
    EXPECT_FALSE(fs::exists(out));
  }

  std::vector<std::string> controls_, observations_;
};

// A FastSLAM control's prediction waits for the next scan or read-out. Here no scan follows the
// controls, so their predictions run when the outputs read the engine: a failure there (FastSLAM
// 1.0's noisy steering beyond what the vehicle model can use) fails the run, which writes
// nothing, as it did when every control predicted at once.
TEST_F(CliTest, PredictionsThatFailAfterTheLastScanFailTheRun) {
  const std::string c = Write("c.csv", "t,v,steer\n0,3,1.2\n0.025,3,1.2\n0.05,3,1.2\n");
  const std::string o = Write("o.csv", "t,range,bearing,id\n");
  const fs::path out = dir_ / "out";
  Outcome r = Grove(
      "fastslam run --no-progress --filter fastslam1 --particles 50 --vehicle guivant_nebot "
      "--sigma-steer-rad 1.0 --controls " +
      c + " --observations " + o + " --out " + out.string());
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_NE(r.err.find("step 1 (t = 0.025 s): particle "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("steering angle is outside"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

// A huge finite range made a landmark of infinite covariance: the run went on and failed later
// at a valid line (or after the whole run, naming no line). It is refused at its own field.
TEST_F(CliInputRulesTest, AHugeRangeIsRefusedAtItsField) {
  const int line = static_cast<int>(observations_.size()) + 1;
  for (const auto& [range, shown] :
       {std::pair{"1e300", "1e+300"}, std::pair{"1e12", "1000000000000"},
        std::pair{"1000000.5", "1000000.5"}}) {
    std::vector<std::string> o = observations_;
    o.push_back(std::string("50,") + range + ",0.1,99");
    o.push_back("50.2,10,0.1,99");
    ExpectRefused(controls_, o, "o.csv", std::to_string(line) + ":4",
                  std::string("range = ") + shown + ": must be in [0, 1e6] m");
  }
}

// A control's speed of 1e300 (or 1e30) was named nowhere: the run failed at a later scan's
// observation. Steering was unbounded (4 rad and 1e10 rad accepted); a time of 1e300 too.
TEST_F(CliInputRulesTest, AControlOutsideTheRulesIsRefusedAtItsRow) {
  auto with_row_101 = [&](const std::string& row) {
    std::vector<std::string> c = controls_;
    c[100] = row;
    return c;
  };
  const std::string t = controls_[100].substr(0, controls_[100].find(','));
  const int steer_column = static_cast<int>(t.size() + std::string(",3,").size()) + 1;
  ExpectRefused(with_row_101(t + ",1e300,0"), observations_, "c.csv",
                "101:" + std::to_string(t.size() + 2), "speed = 1e+300: must be within +-1000 m/s");
  ExpectRefused(with_row_101(t + ",1e30,0"), observations_, "c.csv",
                "101:" + std::to_string(t.size() + 2), "speed = 1e+30: must be within +-1000 m/s");
  ExpectRefused(with_row_101(t + ",3,4"), observations_, "c.csv",
                "101:" + std::to_string(steer_column),
                "steering = 4: must be in (-pi/2, pi/2) rad");
  ExpectRefused(with_row_101(t + ",3,1e10"), observations_, "c.csv",
                "101:" + std::to_string(steer_column),
                "steering = 10000000000: must be in (-pi/2, pi/2) rad");
  std::vector<std::string> c = controls_;
  c.push_back("1e300,3,0");
  ExpectRefused(c, observations_, "c.csv", "2002:1", "t = 1e+300: must be within +-1e12 s");
}

// `--checkpoint-every N` checkpointed when steps % N == 0: a scan takes two steps, so multiples
// were skipped (12 checkpoints for 14,701 steps at N = 1000; 59 for 198 at N = 3), and a record
// that takes no step (the first control) checkpointed the same step twice (3 on the webmap at
// N = 7000). A record takes at most 2 steps, so for N > 2 each multiple gives one checkpoint.
TEST_F(CliTest, PeriodicCheckpointsComeAtLeastEveryNStepsAndNeverTwiceAtOne) {
  struct Case {
    std::string command;
    int64_t every;
  };
  ASSERT_EQ(Grove("fastslam simulate --out " + (dir_ / "sim").string()).exit_code, 0);
  const std::string sim = (dir_ / "sim").string();
  for (const Case& c : {Case{"fastslam victoria-park --until 300", 1000},
                        Case{"fastslam run --controls " + sim + "/controls.csv --observations " +
                                 sim + "/observations.csv",
                             7000},
                        Case{"fastslam victoria-park --until 5", 3}}) {
    SCOPED_TRACE(c.command);
    const fs::path out = dir_ / "out";
    fs::remove_all(out);
    Outcome o = Grove(c.command + " --no-progress --particles 5 --checkpoint-every " +
                      std::to_string(c.every) + " --out " + out.string());
    ASSERT_EQ(o.exit_code, 0) << o.err;
    const nlohmann::json s = nlohmann::json::parse(Slurp(out / "summary.json"));
    const int64_t steps = s["steps"].get<int64_t>();
    EXPECT_EQ(s["checkpoints"]["written"].get<int64_t>(), steps / c.every) << steps << " steps";
  }
}

// A run whose checkpoint could not be written (a full disk: here a file size limit) left the
// directories it had made: the output directory's parents and the checkpoint's directory.
TEST_F(CliTest, AFailedRunLeavesNoDirectoryItMade) {
  ASSERT_EQ(
      Grove("footslam simulate --minutes 1 --seed 1 --out " + (dir_ / "w").string()).exit_code, 0);
  const fs::path out = dir_ / "n1" / "n2" / "n3", checkpoint = dir_ / "ck" / "sub" / "ck.grove";
  const std::string cmd = "sh -c \"trap '' XFSZ; ulimit -f 1; exec " + std::string(GROVE_BINARY) +
                          " footslam run --no-progress --particles 2000 --checkpoint-every 10" +
                          " --steps " + (dir_ / "w" / "steps.csv").string() + " --out " +
                          out.string() + " --checkpoint " + checkpoint.string() + "\" 2>" +
                          (dir_ / "err").string();
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 5) << Slurp(dir_ / "err");
  EXPECT_NE(Slurp(dir_ / "err").find("File too large"), std::string::npos) << Slurp(dir_ / "err");
  EXPECT_FALSE(fs::exists(dir_ / "n1")) << "the output directory's parents were left";
  EXPECT_FALSE(fs::exists(dir_ / "ck")) << "the checkpoint's directory was left";
  // A path too long to make (ENAMETOOLONG after 20 levels) left the levels it had made.
  std::string deep = (dir_ / "r").string();
  for (int k = 0; k < 25; ++k) deep += "/" + std::string(200, 'd');
  Outcome o = Grove("footslam run --no-progress --particles 50 --steps " +
                    (dir_ / "w" / "steps.csv").string() + " --out " + deep);
  EXPECT_EQ(o.exit_code, 5) << o.err;
  EXPECT_NE(o.err.find("File name too long"), std::string::npos) << o.err;
  EXPECT_FALSE(fs::exists(dir_ / "r")) << "the levels made were left";
}

// The JSON parser takes a NUL byte for the end of its input: a configuration, a Monte Carlo
// scenario or a batch manifest line followed by a NUL and anything was accepted.
TEST_F(CliTest, BytesAfterANulInJsonAreRefused) {
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name, std::ios::binary) << text;
    return (dir_ / name).string();
  };
  const std::string nul(1, '\0');
  std::string config = write("c.json", "{\"particles\": 30}" + nul + "garbage");
  Outcome o = Grove("footslam run --print-config --config " + config);
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_NE(o.err.find(config + ":1:18: invalid JSON: a NUL byte"), std::string::npos) << o.err;
  o = Grove("fastslam run --print-config --config " + config);
  EXPECT_EQ(o.exit_code, 2) << o.out;

  std::string scenario =
      write("s.json", "{\"preset\": \"sim3\", \"association\": \"known\"}" + nul + "x");
  o = Grove("fastslam montecarlo --scenario " + scenario + " --filters fastslam2 --runs 1 --out " +
            (dir_ / "mc").string());
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_NE(o.err.find(scenario + ":1:43: invalid JSON: a NUL byte"), std::string::npos) << o.err;
  EXPECT_FALSE(fs::exists(dir_ / "mc"));

  ASSERT_EQ(
      Grove("footslam simulate --minutes 1 --seed 1 --out " + (dir_ / "w").string()).exit_code, 0);
  std::string manifest =
      write("walks.jsonl", "{\"name\": \"a\", \"steps\": \"w/steps.csv\"}" + nul + "junk\n");
  o = Grove("footslam batch --manifest " + manifest + " --out " + (dir_ / "b").string());
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_NE(o.err.find(manifest + ":1:38: not a JSON object: a NUL byte"), std::string::npos)
      << o.err;
  EXPECT_FALSE(fs::exists(dir_ / "b"));
}

// Monte Carlo had no memory prediction: 10 million particles ran 16 s to 4.5 GB and then
// reported out of memory with exit 0. It is refused before any job, as `run` refuses, and
// without making its output directory.
TEST_F(CliTest, MonteCarloOverTheMemoryBudgetIsRefusedBeforeAnyJob) {
  const fs::path out = dir_ / "m";
  const std::string mc =
      "fastslam montecarlo --no-progress --scenario sim3 --filters fastslam2 "
      "--loops 1 --out " +
      out.string();
  Outcome o = Grove(mc + " --runs 1 --particles 10000000 --memory-budget 1G");
  EXPECT_EQ(o.exit_code, 6) << o.err;
  EXPECT_NE(o.err.find("the run is predicted to need"), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("more than the --memory-budget of 1024.0 MiB"), std::string::npos) << o.err;
  EXPECT_FALSE(fs::exists(out));
  // The jobs that run side by side are budgeted together: a budget that one job fits refuses
  // two side by side.
  auto predicted_mib = [](const std::string& err) {
    const std::string key = "predicted to need ";
    const size_t at = err.find(key);
    return at == std::string::npos ? -1.0 : std::stod(err.substr(at + key.size()));
  };
  o = Grove(mc + " --runs 1 --particles 100000 --memory-budget 1M");
  EXPECT_NE(o.err.find("(1 job side by side, the largest with 100000 particles)"),
            std::string::npos)
      << o.err;
  const double one = predicted_mib(o.err);
  ASSERT_GT(one, 1) << o.err;
  const std::string budget = std::to_string(static_cast<int>(one) + 1) + "M";
  o = Grove(mc + " --runs 2 --threads 2 --particles 100000 --memory-budget " + budget);
  EXPECT_EQ(o.exit_code, 6) << o.err;
  EXPECT_NE(o.err.find("(2 jobs side by side"), std::string::npos) << o.err;
  EXPECT_GT(predicted_mib(o.err), one + 1) << o.err;
  EXPECT_FALSE(fs::exists(out));
  // Without --memory-budget: the address-space limit.
#ifdef __SANITIZE_ADDRESS__
  GTEST_SKIP() << "AddressSanitizer reserves terabytes of address space: no ulimit -v";
#endif
  const std::string cmd = "sh -c \"ulimit -v 6000000; exec " + std::string(GROVE_BINARY) + " " +
                          mc + " --runs 1 --particles 10000000\" 2>" + (dir_ / "err").string();
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 6) << Slurp(dir_ / "err");
  EXPECT_NE(Slurp(dir_ / "err").find("address-space limit"), std::string::npos)
      << Slurp(dir_ / "err");
  EXPECT_FALSE(fs::exists(out));
}

// A job that failed (out of memory here) counted as finished for ever and the command exited 0.
// Now it exits non-zero with the count, and the same command runs the job again.
TEST_F(CliTest, MonteCarloFailedJobsExitNonZeroAndRunAgain) {
#ifdef __SANITIZE_ADDRESS__
  GTEST_SKIP() << "AddressSanitizer reserves terabytes of address space: no ulimit -v";
#endif
  const fs::path out = dir_ / "m";
  const std::string cmd = "sh -c \"ulimit -v 3000000; exec " + std::string(GROVE_BINARY) +
                          " fastslam montecarlo --no-progress --scenario sim3 --filters "
                          "fastslam2 --runs 1 --loops 1 --threads 1 --particles 3000000 "
                          "--memory-budget 1T --out " +
                          out.string() + "\" >/dev/null 2>" + (dir_ / "err").string();
  for (int attempt = 0; attempt < 2; ++attempt) {
    SCOPED_TRACE(attempt);
    const int status = std::system(cmd.c_str());
    const std::string err = Slurp(dir_ / "err");
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 6) << err;
    EXPECT_NE(err.find("grove: error: 1 of 1 jobs failed (first: fastslam2_p3000000 run 0: "),
              std::string::npos)
        << err;
    EXPECT_NE(err.find("out of memory"), std::string::npos) << err;
    EXPECT_NE(err.find("run the same command again to run them again"), std::string::npos) << err;
    EXPECT_NE(err.find("0 reused from an earlier invocation, 1 to run"), std::string::npos) << err;
  }
  const nlohmann::json record =
      nlohmann::json::parse(Slurp(out / "runs" / "fastslam2_p3000000" / "run_0.json"));
  EXPECT_EQ(record["status_code"], "resource exhausted");
}

// montecarlo installed no signal handling: a closed pipe on stderr killed it (exit 141) at the
// next progress line, and SIGTERM killed it outright. Now SIGPIPE is ignored, and SIGTERM stops
// it between jobs with the finished ones kept (exit 143); the same command finishes the rest.
TEST_F(CliTest, MonteCarloSurvivesAClosedPipeAndStopsBetweenJobsOnSigterm) {
  const fs::path out = dir_ / "m";
  const std::string mc = std::string(GROVE_BINARY) +
                         " fastslam montecarlo --scenario sim3 --filters fastslam2 --loops 1 "
                         "--particles 30 --threads 1 --out " +
                         out.string();
  const fs::path rc = dir_ / "rc";
  std::string cmd =
      "sh -c '(" + mc + " --runs 12 2>&1; echo $? >" + rc.string() + ") | head -c 10 >/dev/null'";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  EXPECT_EQ(std::stoi(Slurp(rc)), 0);
  EXPECT_TRUE(fs::exists(out / "table.md"));

  fs::remove_all(out);
  fs::remove(rc);
  const fs::path pid_file = dir_ / "pid", err = dir_ / "err";
  cmd = "sh -c '" + mc + " --runs 200 >/dev/null 2>" + err.string() + " & echo $! >" +
        pid_file.string() + "; wait $!; echo $? >" + rc.string() + "' &";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  const fs::path first = out / "runs" / "fastslam2_p30" / "run_0.json";
  while (!fs::exists(first) || !fs::exists(pid_file) || Slurp(pid_file).empty()) {
    ASSERT_FALSE(fs::exists(rc)) << "it ended before it was signalled: " << Slurp(err);
    std::system("sleep 0.01");
  }
  ASSERT_EQ(std::system(("kill -TERM " + Slurp(pid_file)).c_str()), 0);
  while (!fs::exists(rc) || Slurp(rc).empty()) std::system("sleep 0.01");
  EXPECT_EQ(std::stoi(Slurp(rc)), 143) << Slurp(err);
  EXPECT_NE(Slurp(err).find("stopped by Terminated; the jobs finished so far are kept"),
            std::string::npos)
      << Slurp(err);
  EXPECT_FALSE(fs::exists(out / "table.md"));
  int64_t kept = 0;
  for (const auto& e : fs::directory_iterator(out / "runs" / "fastslam2_p30")) {
    kept += e.path().extension() == ".json";
  }
  EXPECT_GE(kept, 1);
  EXPECT_LT(kept, 200);
  Outcome o = Grove(
      "fastslam montecarlo --no-progress --scenario sim3 --filters fastslam2 "
      "--loops 1 --particles 30 --threads 1 --runs 200 --out " +
      out.string());
  EXPECT_EQ(o.exit_code, 0) << o.err;
  EXPECT_NE(o.err.find(std::to_string(kept) + " reused from an earlier invocation"),
            std::string::npos)
      << o.err;
}

}  // namespace
