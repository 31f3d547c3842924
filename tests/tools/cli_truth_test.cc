// `--truth` on `footslam run` and `fastslam run`: the score in summary.json, error.csv,
// error.png and the terminal's last line; the same score from a CSV and a TUM truth; a bad truth
// stops the run before it starts.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "tests/tools/cli_testing.h"

namespace grove::testing {
namespace {

const std::string kWalkTruth =
    (fs::path(GROVE_SOURCE_DIR) / "tools/data/building_walk_truth.csv").string();

// The last line of `text` (without its line end).
std::string LastLine(const std::string& text) {
  const size_t end = text.ends_with('\n') ? text.size() - 1 : text.size();
  const size_t begin = text.rfind('\n', end == 0 ? 0 : end - 1);
  return text.substr(begin == std::string::npos ? 0 : begin + 1, end - (begin + 1));
}

// A CSV truth (t,x,y[,heading]) rewritten as TUM with the same number texts; the heading (0
// without a column) as a quaternion about z.
std::string CsvToTum(const std::string& csv) {
  std::istringstream in(csv);
  std::string line, out = "# t x y z qx qy qz qw\n";
  std::getline(in, line);  // the header
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::istringstream fields(line);
    for (std::string s; std::getline(fields, s, ',');) f.push_back(s);
    const double heading = f.size() > 3 ? std::stod(f[3]) : 0.0;
    char q[80];
    std::snprintf(q, sizeof(q), "0 0 %.17g %.17g", std::sin(heading / 2), std::cos(heading / 2));
    out += f[0] + " " + f[1] + " " + f[2] + " 0 " + q + "\n";
  }
  return out;
}

nlohmann::json Accuracy(const fs::path& out) {
  return nlohmann::json::parse(Slurp(out / "summary.json")).at("accuracy");
}

TEST_F(CliTest, FootSlamRunScoresTheSmoothedPathAgainstTheTruth) {
  fs::path out = dir_ / "m";
  Outcome o = Grove("footslam run --no-progress --particles 200 --truth " + kWalkTruth + " --out " +
                    out.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  const nlohmann::json a = Accuracy(out);
  EXPECT_EQ(a.at("estimate"), "smoothed_trajectory");
  const int matched = a.at("matched").get<int>();
  EXPECT_EQ(matched, 873);  // every truth pose: the smoothed path spans the whole walk
  const double rmse = a.at("rmse_m").get<double>(), aligned = a.at("aligned_rmse_m").get<double>();
  EXPECT_GT(rmse, 0);
  EXPECT_LE(aligned, rmse);
  EXPECT_LE(aligned, a.at("aligned_max_m").get<double>());

  // error.csv: one aligned error per matched truth pose; their RMS is the aligned RMSE.
  std::istringstream csv(Slurp(out / "error.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "t,error");
  int rows = 0;
  double sum_squared = 0, last_t = -1;
  while (std::getline(csv, line)) {
    double t = 0, e = 0;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf", &t, &e), 2) << line;
    EXPECT_GT(t, last_t) << line;
    EXPECT_GE(e, 0) << line;
    last_t = t;
    sum_squared += e * e;
    ++rows;
  }
  EXPECT_EQ(rows, matched);
  EXPECT_NEAR(std::sqrt(sum_squared / rows), aligned, 1e-5);
  EXPECT_EQ(Slurp(out / "error.png").substr(1, 3), "PNG");

  // The headline is the last line on the terminal (stderr; stdout stays empty), with the
  // summary's figures.
  EXPECT_EQ(o.out, "");
  char expected[160];
  std::snprintf(expected, sizeof(expected),
                "error against truth: RMSE %.2f m (aligned %.2f m), max %.2f m over %d points",
                rmse, aligned, a.at("max_m").get<double>(), matched);
  EXPECT_EQ(LastLine(o.err), expected) << o.err;
  const nlohmann::json outputs = nlohmann::json::parse(Slurp(out / "summary.json")).at("outputs");
  for (const char* name : {"error.csv", "error.png", "map.png", "smoothed_trajectory.kitti"}) {
    EXPECT_TRUE(outputs.contains(name)) << name;
  }
}

TEST_F(CliTest, FootSlamTruthAsTumGivesTheSameScoreAsCsv) {
  const std::string tum = Write("truth.tum", CsvToTum(Slurp(kWalkTruth)));
  Outcome a = Grove("footslam run --no-progress --particles 100 --truth " + kWalkTruth + " --out " +
                    (dir_ / "a").string());
  ASSERT_EQ(a.exit_code, 0) << a.err;
  Outcome b = Grove("footslam run --no-progress --particles 100 --truth " + tum + " --out " +
                    (dir_ / "b").string());
  ASSERT_EQ(b.exit_code, 0) << b.err;
  EXPECT_EQ(Accuracy(dir_ / "a"), Accuracy(dir_ / "b"));
  EXPECT_EQ(LastLine(a.err), LastLine(b.err));
  EXPECT_EQ(Slurp(dir_ / "a" / "error.csv"), Slurp(dir_ / "b" / "error.csv"));
}

// Bad truth files, CSV and TUM: FILE:LINE:COLUMN and what is wrong, exit 3, before the run
// starts: no output directory is made, and an earlier run's outputs stay as they were.
TEST_F(CliTest, BadTruthStopsTheRunBeforeItStarts) {
  struct Case {
    const char* name;
    const char* text;
    const char* where_and_what;
  };
  const Case cases[] = {
      {"t.csv", "t,x,y\n0,0,0\n1,abc,0\n", ":3:3: x: \"abc\" is not a number"},
      {"t.csv", "t,x,y,heading\n0,0,0,0\n2,1,0,0\n  2,2,0,0\n",
       ":4:3: t = 2 is not after the previous time 2: times must be strictly increasing"},
      {"t.tum", "# t x y z qx qy qz qw\n0 0 0 0 0 0 0 1\n1 1 0 0 0 0 zz 1\n",
       ":3:13: qz: \"zz\" is not a number"},
      {"t.tum", "0 0 0 0 0 0 0 1\n# comment\n1 1 0 0 0 0 0 1\n0.5 2 0 0 0 0 0 1\n",
       ":4:1: t = 0.5 is not after the previous time 1: times must be strictly increasing"},
      {"t.txt", "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 1\n",
       ":2:1: expected 8 numbers \"t x y z qx qy qz qw\" separated by spaces, found 7 field(s)"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    const std::string truth = Write(c.name, c.text);
    fs::path out = dir_ / "new" / "out";
    for (const char* command : {"footslam run --particles 50", "fastslam run --particles 5"}) {
      SCOPED_TRACE(command);
      std::string args =
          std::string(command) + " --no-progress --truth " + truth + " --out " + out.string();
      if (std::string(command).starts_with("fastslam")) {
        args += " --controls " + Write("controls.csv", "t,v,steer\n0,1,0\n1,1,0\n") +
                " --observations " + Write("observations.csv", "t,range,bearing,id\n");
      }
      Outcome o = Grove(args);
      EXPECT_EQ(o.exit_code, 3) << o.err;
      EXPECT_EQ(o.err, "grove: error: " + truth + c.where_and_what + "\n");
      EXPECT_FALSE(fs::exists(dir_ / "new")) << "a failed run left " << out;
    }
  }
  // Into the directory of an earlier run: nothing in it changes.
  fs::path out = dir_ / "earlier";
  ASSERT_EQ(Grove("footslam run --no-progress --particles 50 --out " + out.string()).exit_code, 0);
  const std::string summary = Slurp(out / "summary.json");
  const std::string truth = Write("t.csv", cases[0].text);
  EXPECT_EQ(
      Grove("footslam run --no-progress --particles 60 --truth " + truth + " --out " + out.string())
          .exit_code,
      3);
  EXPECT_EQ(Slurp(out / "summary.json"), summary);
  EXPECT_FALSE(fs::exists(out / "error.csv"));
}

// FastSLAM keeps its pose errors and adds the aligned ones; a TUM truth gives the same.
TEST_F(CliTest, FastSlamRunAddsTheAlignedErrorToItsAccuracy) {
  fs::path sim = dir_ / "sim";
  ASSERT_EQ(Grove("fastslam simulate --seed 2 --out " + sim.string()).exit_code, 0);
  const std::string inputs = " --no-progress --particles 10 --controls " +
                             (sim / "controls.csv").string() + " --observations " +
                             (sim / "observations.csv").string();
  Outcome o = Grove("fastslam run" + inputs + " --truth " + (sim / "truth.csv").string() +
                    " --out " + (dir_ / "a").string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  const nlohmann::json a = Accuracy(dir_ / "a");
  for (const char* field :
       {"matched", "truth_without_estimate", "position_rmse_m", "heading_rmse_rad",
        "max_position_error_m", "position_mse_mean_m2", "position_mse_variance_m4",
        "aligned_matched", "aligned_position_rmse_m", "aligned_max_position_error_m",
        "alignment_rotation_rad", "alignment_translation_m"}) {
    EXPECT_TRUE(a.contains(field)) << field << " in " << a.dump();
  }
  EXPECT_LE(a.at("aligned_position_rmse_m").get<double>(), a.at("position_rmse_m").get<double>());
  EXPECT_TRUE(LastLine(o.err).starts_with("error against truth: RMSE ")) << o.err;
  EXPECT_TRUE(fs::exists(dir_ / "a" / "error.csv"));
  EXPECT_TRUE(fs::exists(dir_ / "a" / "error.png"));

  const std::string tum = Write("truth.tum", CsvToTum(Slurp(sim / "truth.csv")));
  o = Grove("fastslam run" + inputs + " --truth " + tum + " --out " + (dir_ / "b").string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  nlohmann::json b = Accuracy(dir_ / "b");
  EXPECT_NEAR(b.at("heading_rmse_rad").get<double>(), a.at("heading_rmse_rad").get<double>(),
              1e-12);
  b["heading_rmse_rad"] = a.at("heading_rmse_rad");
  EXPECT_EQ(a, b);
}

// A truth without a heading column scores positions only.
TEST_F(CliTest, FastSlamTruthWithoutHeadingHasNoHeadingError) {
  fs::path sim = dir_ / "sim";
  ASSERT_EQ(Grove("fastslam simulate --seed 3 --out " + sim.string()).exit_code, 0);
  const std::string positions = WithoutLastColumn(Slurp(sim / "truth.csv"));
  ASSERT_TRUE(positions.starts_with("t,x,y\n"));
  Outcome o = Grove("fastslam run --no-progress --particles 10 --controls " +
                    (sim / "controls.csv").string() + " --observations " +
                    (sim / "observations.csv").string() + " --truth " +
                    Write("truth.csv", positions) + " --out " + (dir_ / "a").string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  const nlohmann::json a = Accuracy(dir_ / "a");
  EXPECT_TRUE(a.at("heading_rmse_rad").is_null()) << a.dump();
  EXPECT_GT(a.at("position_rmse_m").get<double>(), 0);
}

}  // namespace
}  // namespace grove::testing
