// The TUM and KITTI trajectories `footslam run` and `fastslam run` write beside their CSVs, read
// back with parsers of the test's own, as an evaluation tool (evo) reads them: TUM, `#` comments
// then `t x y z qx qy qz qw` separated by spaces; KITTI, the 12 numbers of a 3x4 matrix [R | t].
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <sstream>
#include <string>
#include <utility>
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

// The numbers of every line that is not empty or a `#` comment, and the line.
std::vector<std::pair<std::vector<double>, std::string>> NumberLines(const std::string& text) {
  std::vector<std::pair<std::vector<double>, std::string>> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::vector<double> v;
    for (double d; fields >> d;) v.push_back(d);
    EXPECT_TRUE(fields.eof()) << "not a number in: " << line;
    lines.emplace_back(std::move(v), line);
  }
  return lines;
}

// A TUM file: every non-comment line has exactly eight numbers, z = qx = qy = 0 and a unit
// quaternion; the heading comes back as 2 atan2(qz, qw).
std::vector<Row> ReadTum(const std::string& text) {
  std::vector<Row> rows;
  for (const auto& [v, line] : NumberLines(text)) {
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

// A KITTI file: every line has exactly twelve numbers, the rows of [R | t]; R is a rotation
// about z (orthonormal, determinant 1, third row and column those of the identity) and tz = 0.
// The heading comes back as atan2(R10, R00); the time is not in the file (NaN).
std::vector<Row> ReadKitti(const std::string& text) {
  std::vector<Row> rows;
  for (const auto& [v, line] : NumberLines(text)) {
    EXPECT_EQ(v.size(), 12u) << line;
    if (v.size() != 12) continue;
    const double r[3][3] = {{v[0], v[1], v[2]}, {v[4], v[5], v[6]}, {v[8], v[9], v[10]}};
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        double dot = 0;  // row i . row j
        for (int k = 0; k < 3; ++k) dot += r[i][k] * r[j][k];
        EXPECT_NEAR(dot, i == j ? 1.0 : 0.0, 1e-12) << line;
      }
    }
    const double det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1]) -
                       r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0]) +
                       r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
    EXPECT_NEAR(det, 1.0, 1e-12) << line;
    EXPECT_EQ(r[2][2], 1.0) << line;
    EXPECT_EQ(r[0][2], 0.0) << line;
    EXPECT_EQ(r[2][0], 0.0) << line;
    EXPECT_EQ(v[11], 0.0) << line;  // tz
    rows.push_back({NAN, v[3], v[7], std::atan2(r[1][0], r[0][0])});
  }
  return rows;
}

double AngleBetween(double a, double b) { return std::remainder(a - b, 2 * std::numbers::pi); }

// The CSV, TUM and KITTI files of one trajectory hold the same poses in the same order.
void ExpectSamePoses(const fs::path& csv) {
  SCOPED_TRACE(csv.string());
  fs::path tum = csv, kitti = csv;
  tum.replace_extension(".tum");
  kitti.replace_extension(".kitti");
  const std::vector<Row> a = ReadCsv(Slurp(csv));
  const std::vector<Row> b = ReadTum(Slurp(tum));
  const std::vector<Row> c = ReadKitti(Slurp(kitti));
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.size(), c.size());
  ASSERT_GT(a.size(), 10u);
  for (size_t i = 0; i < a.size(); ++i) {
    // The CSV has 6 decimals, the TUM file 9, the KITTI file every digit.
    EXPECT_NEAR(a[i].t, b[i].t, 1e-6) << i;
    for (const Row* r : {&b[i], &c[i]}) {
      EXPECT_NEAR(a[i].x, r->x, 1e-6) << i;
      EXPECT_NEAR(a[i].y, r->y, 1e-6) << i;
      EXPECT_NEAR(AngleBetween(a[i].heading, r->heading), 0.0, 1e-6) << i;
    }
  }
}

TEST_F(CliTest, FootSlamRunWritesEveryTrajectoryAsTumAndKittiToo) {
  fs::path out = dir_ / "m";
  Outcome o = Grove("footslam run --no-progress --particles 200 --out " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  for (const char* name : {"trajectory", "mean_trajectory", "smoothed_trajectory"}) {
    ExpectSamePoses(out / (std::string(name) + ".csv"));
  }
}

TEST_F(CliTest, FastSlamRunWritesBothTrajectoriesAsTumAndKittiToo) {
  fs::path sim = dir_ / "sim";
  ASSERT_EQ(Grove("fastslam simulate --seed 2 --out " + sim.string()).exit_code, 0);
  fs::path out = dir_ / "f";
  Outcome o = Grove("fastslam run --no-progress --particles 20 --controls " +
                    (sim / "controls.csv").string() + " --observations " +
                    (sim / "observations.csv").string() + " --out " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  ExpectSamePoses(out / "trajectory.csv");
  ExpectSamePoses(out / "heaviest_trajectory.csv");
}

}  // namespace
}  // namespace grove::testing
