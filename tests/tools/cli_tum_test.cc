// The TUM trajectories `footslam run` and `fastslam run` write beside their CSVs, read back with
// a parser of the test's own, as an evaluation tool (evo) reads them: `#` comments, then
// `t x y z qx qy qz qw` separated by spaces.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "tests/tools/cli_testing.h"

namespace grove::testing {
namespace {

struct Row {
  double t, x, y, heading;
};

// trajectory.csv: a header `t,x,y,heading`, then one pose a line.
std::vector<Row> ReadCsv(const std::string& text) {
  std::vector<Row> rows;
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "t,x,y,heading");
  while (std::getline(in, line)) {
    Row r{};
    char c1, c2, c3;
    std::istringstream fields(line);
    fields >> r.t >> c1 >> r.x >> c2 >> r.y >> c3 >> r.heading;
    EXPECT_TRUE(fields && c1 == ',' && c2 == ',' && c3 == ',') << line;
    rows.push_back(r);
  }
  return rows;
}

// A TUM file: every non-comment line has exactly eight numbers, z = qx = qy = 0 and a unit
// quaternion; the heading comes back as 2 atan2(qz, qw).
std::vector<Row> ReadTum(const std::string& text) {
  std::vector<Row> rows;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::vector<double> v;
    for (double d; fields >> d;) v.push_back(d);
    EXPECT_TRUE(fields.eof()) << "not a number in: " << line;
    EXPECT_EQ(v.size(), 8u) << line;
    if (v.size() != 8) continue;
    EXPECT_EQ(v[3], 0.0) << line;
    EXPECT_EQ(v[4], 0.0) << line;
    EXPECT_EQ(v[5], 0.0) << line;
    EXPECT_NEAR(v[6] * v[6] + v[7] * v[7], 1.0, 1e-8) << line;
    rows.push_back({v[0], v[1], v[2], 2 * std::atan2(v[6], v[7])});
  }
  return rows;
}

double AngleBetween(double a, double b) { return std::remainder(a - b, 2 * std::numbers::pi); }

void ExpectSamePoses(const fs::path& csv, const fs::path& tum) {
  SCOPED_TRACE(tum.string());
  const std::vector<Row> a = ReadCsv(Slurp(csv));
  const std::vector<Row> b = ReadTum(Slurp(tum));
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 10u);
  for (size_t i = 0; i < a.size(); ++i) {
    // The CSV has 6 decimals, the TUM file 9.
    EXPECT_NEAR(a[i].t, b[i].t, 1e-6) << i;
    EXPECT_NEAR(a[i].x, b[i].x, 1e-6) << i;
    EXPECT_NEAR(a[i].y, b[i].y, 1e-6) << i;
    EXPECT_NEAR(AngleBetween(a[i].heading, b[i].heading), 0.0, 1e-6) << i;
  }
}

TEST_F(CliTest, FootSlamRunWritesEveryTrajectoryAsTumToo) {
  fs::path out = dir_ / "m";
  Outcome o = Grove("footslam run --no-progress --particles 200 --out " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  for (const char* name : {"trajectory", "mean_trajectory", "smoothed_trajectory"}) {
    ExpectSamePoses(out / (std::string(name) + ".csv"), out / (std::string(name) + ".tum"));
  }
}

TEST_F(CliTest, FastSlamRunWritesBothTrajectoriesAsTumToo) {
  fs::path sim = dir_ / "sim";
  ASSERT_EQ(Grove("fastslam simulate --seed 2 --out " + sim.string()).exit_code, 0);
  fs::path out = dir_ / "f";
  Outcome o = Grove("fastslam run --no-progress --particles 20 --controls " +
                    (sim / "controls.csv").string() + " --observations " +
                    (sim / "observations.csv").string() + " --out " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  ExpectSamePoses(out / "trajectory.csv", out / "trajectory.tum");
  ExpectSamePoses(out / "heaviest_trajectory.csv", out / "heaviest_trajectory.tum");
}

}  // namespace
}  // namespace grove::testing
