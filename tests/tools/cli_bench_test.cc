// `grove bench footslam` and `grove bench fastslam`: benchmarks on the user's own input.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/tools/cli_testing.h"

namespace grove::testing {
namespace {

// The rows of a CSV without quoted fields (the bench's), the header first.
std::vector<std::vector<std::string>> CsvRows(const fs::path& path) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(Slurp(path));
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> fields;
    std::istringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) fields.push_back(cell);
    rows.push_back(fields);
  }
  return rows;
}

// The first `lines` lines of `text`.
std::string Head(const std::string& text, int lines) {
  size_t end = 0;
  for (int k = 0; k < lines && end != std::string::npos; ++k) end = text.find('\n', end + 1);
  return end == std::string::npos ? text : text.substr(0, end + 1);
}

class CliBenchTest : public CliTest {
 protected:
  // The bundled walk's first 100 steps.
  std::string SmallWalk() {
    return Write(
        "steps.csv",
        Head(Slurp(fs::path(GROVE_SOURCE_DIR) / "tools/data/building_walk_steps.csv"), 101));
  }

  // Checks the outputs of a sweep of `particles` x `threads` counts run `repeat` times each.
  void ExpectSweep(const Outcome& o, const fs::path& out, const std::vector<std::string>& particles,
                   const std::vector<std::string>& threads, int repeat) {
    ASSERT_EQ(o.exit_code, 0) << o.err;
    const std::string md = Slurp(out / "bench.md");
    EXPECT_NE(o.out.find(md), std::string::npos) << "stdout lacks bench.md:\n" << o.out;
    EXPECT_NE(md.find("Machine: "), std::string::npos) << md;
    EXPECT_NE(md.find("Command: `grove bench "), std::string::npos) << md;
    for (const std::string& n : particles) {
      for (const std::string& t : threads) {
        EXPECT_NE(md.find("\n| " + n + " | " + t + " | "), std::string::npos)
            << "no row for " << n << " particles x " << t << " threads:\n"
            << md;
      }
    }
    const auto summary = CsvRows(out / "bench_summary.csv");
    ASSERT_EQ(summary.size(), 1 + particles.size() * threads.size());
    ASSERT_EQ(summary[0][4], "median_filter_s");
    ASSERT_EQ(summary[0][5], "min_filter_s");
    ASSERT_EQ(summary[0][6], "max_filter_s");
    for (size_t k = 1; k < summary.size(); ++k) {
      const double median = std::stod(summary[k][4]);
      EXPECT_GT(median, 0);
      EXPECT_LE(std::stod(summary[k][5]), median) << "row " << k;
      EXPECT_GE(std::stod(summary[k][6]), median) << "row " << k;
      EXPECT_EQ(summary[k][2], std::to_string(repeat)) << "runs of row " << k;
    }
    const auto runs = CsvRows(out / "bench.csv");
    EXPECT_EQ(runs.size(), 1 + particles.size() * threads.size() * repeat);
    EXPECT_TRUE(fs::exists(out / "threads.png"));
    EXPECT_EQ(fs::exists(out / "particles.png"), particles.size() > 1);
    EXPECT_TRUE(fs::exists(out / "summary.json"));
  }
};

TEST_F(CliBenchTest, FootSlamBenchReportsEveryPairOfItsStepFile) {
  const std::string steps = SmallWalk();
  const fs::path out = dir_ / "bench";
  const Outcome o = Grove("bench footslam --steps " + steps +
                          " --particles 30,50 --threads 1,2 --repeat 2 --out " + out.string());
  ExpectSweep(o, out, {"30", "50"}, {"1", "2"}, 2);
}

TEST_F(CliBenchTest, FastSlamBenchReportsEveryPairOfItsInputs) {
  const fs::path sim = dir_ / "sim";
  ASSERT_EQ(Grove("fastslam simulate --out " + sim.string()).exit_code, 0);
  // The first 300 controls (7.5 s) and the detections up to their end.
  const std::string controls = Write("controls.csv", Head(Slurp(sim / "controls.csv"), 301));
  std::istringstream in(Slurp(sim / "observations.csv"));
  std::string observations_text, line;
  std::getline(in, line);
  observations_text = line + "\n";
  while (std::getline(in, line) && std::stod(line.substr(0, line.find(','))) <= 7.4) {
    observations_text += line + "\n";
  }
  const std::string observations = Write("observations.csv", observations_text);
  const fs::path out = dir_ / "bench";
  // A list's values separated by spaces, as by commas in the FootSLAM test.
  const Outcome o =
      Grove("bench fastslam --controls " + controls + " --observations " + observations +
            " --filter fastslam1 --particles 20 --threads 1 2 --repeat 2 --out " + out.string());
  ExpectSweep(o, out, {"20"}, {"1", "2"}, 2);
  EXPECT_NE(Slurp(out / "bench.md").find("filter = \"fastslam1\""), std::string::npos);
}

TEST_F(CliBenchTest, BadSweepValuesAreRefusedNamingTheFlagValueAndRule) {
  const std::string steps = SmallWalk();
  const fs::path out = dir_ / "bench";
  const std::string common = "bench footslam --steps " + steps + " --out " + out.string();
  struct Case {
    std::string args, message;
  };
  const Case cases[] = {
      {" --threads 0", "--threads = 0: must be in 1..256"},
      {" --threads -2", "--threads = -2: must be in 1..256"},
      {" --threads 1,,2",
       "--threads = \"1,,2\": an empty item; must be a list of values, each in 1..256"},
      {" --threads 1,", "--threads = \"1,\": an empty item"},
      {" --threads 2,2", "--threads: 2 is given twice"},
      {" --particles 0", "--particles = 0: must be in 1..2147483648"},
      {" --particles 4294967296", "--particles = 4294967296: must be in 1..2147483648"},
      {" --repeat 0", "--repeat = 0: must be in 1..1000"},
  };
  for (const Case& c : cases) {
    const Outcome o = Grove(common + c.args);
    EXPECT_EQ(o.exit_code, 2) << c.args << ": " << o.err;
    EXPECT_NE(o.err.find(c.message), std::string::npos) << c.args << ": " << o.err;
  }
  const std::string fastslam = "bench fastslam --controls c.csv --observations o.csv";
  const Outcome o = Grove(fastslam + " --threads 1,,2 --out " + out.string());
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_NE(o.err.find("--threads = \"1,,2\": an empty item"), std::string::npos) << o.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(CliBenchTest, BadStepFileIsAnInputErrorNamingItsLine) {
  const std::string steps = Write("steps.csv", "t,dx,dy\n1,0.5,0\n2,abc,0\n");
  const fs::path out = dir_ / "bench";
  const Outcome o = Grove("bench footslam --particles 10 --threads 1 --repeat 1 --steps " + steps +
                          " --out " + out.string());
  EXPECT_EQ(o.exit_code, 3) << o.err;
  EXPECT_NE(o.err.find(steps + ":3:3: dx: \"abc\" is not a number"), std::string::npos) << o.err;
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace grove::testing
