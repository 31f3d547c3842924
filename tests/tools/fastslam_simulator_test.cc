#include "tools/sim/fastslam_simulator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "tools/io/csv_reader.h"

namespace grove::tools {
namespace {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;

// The repository's root, from this file's path (tests/tools/fastslam_simulator_test.cc).
fs::path RepositoryRoot() { return fs::path(__FILE__).parent_path().parent_path().parent_path(); }

fs::path WebmapPath() { return RepositoryRoot() / "tools/data/bailey_webmap/example_webmap.txt"; }

std::string TempPath(const std::string& name) {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  return (fs::path(::testing::TempDir()) /
          (std::string("grove_") + info->test_suite_name() + "_" + info->name() + "_" + name))
      .string();
}

// The test's own wrap to (-pi, pi], written apart from the simulator's.
double Wrap(double a) {
  while (a > kPi) a -= 2 * kPi;
  while (a <= -kPi) a += 2 * kPi;
  return a;
}

// A CSV written by the simulator: header and rows of numbers.
struct Csv {
  std::string header;
  std::vector<std::vector<double>> rows;
};

Csv ParseCsv(const std::string& text) {
  Csv csv;
  std::istringstream in(text);
  std::string line;
  std::getline(in, csv.header);
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::istringstream fields(line);
    std::string field;
    while (std::getline(fields, field, ',')) {
      char* end = nullptr;
      row.push_back(std::strtod(field.c_str(), &end));
      EXPECT_EQ(*end, '\0') << "not a number: " << field << " in " << line;
    }
    csv.rows.push_back(std::move(row));
  }
  return csv;
}

BaileyMap Webmap() {
  StatusOr<BaileyMap> map = ParseBaileyMap(EmbeddedBaileyWebmapName(), EmbeddedBaileyWebmap());
  EXPECT_TRUE(map.ok()) << map.status().ToString();
  return map.ok() ? std::move(map).value() : BaileyMap{};
}

BaileySimulation Simulate(const BaileyMap& map, const BaileySimOptions& options) {
  StatusOr<BaileySimulation> sim = SimulateBailey(map, options);
  EXPECT_TRUE(sim.ok()) << "seed " << options.seed << ": " << sim.status().ToString();
  return sim.ok() ? std::move(sim).value() : BaileySimulation{};
}

BaileySimOptions NoNoise(BaileySimOptions o) {
  o.sigma_speed_mps = 0;
  o.sigma_steer_rad = 0;
  o.sigma_range_m = 0;
  o.sigma_bearing_rad = 0;
  return o;
}

// The map reader.

TEST(BaileyMapReaderTest, ReadsTheRealWebmap) {
  StatusOr<BaileyMap> map = ReadBaileyMap(WebmapPath().string());
  ASSERT_TRUE(map.ok()) << map.status().ToString();
  ASSERT_EQ(map->landmarks.size(), 35u);
  ASSERT_EQ(map->waypoints.size(), 17u);
  EXPECT_EQ(map->landmarks.front().x_m, 2.9922);
  EXPECT_EQ(map->landmarks.front().y_m, -25.7009);
  EXPECT_EQ(map->landmarks.back().x_m, 48.1757);
  EXPECT_EQ(map->landmarks.back().y_m, 57.9979);
  EXPECT_EQ(map->landmarks[29].x_m, -127.0053);  // the westmost
  EXPECT_EQ(map->waypoints.front().x_m, 12.6495);
  EXPECT_EQ(map->waypoints.front().y_m, -41.5888);
  EXPECT_EQ(map->waypoints.back().x_m, -17.5685);
  EXPECT_EQ(map->waypoints.back().y_m, -51.5576);
}

TEST(BaileyMapReaderTest, BundledCopyIsTheRepositoryFile) {
  StatusOr<std::string> file = ReadWholeFile(WebmapPath().string());
  ASSERT_TRUE(file.ok()) << file.status().ToString();
  EXPECT_EQ(EmbeddedBaileyWebmap(), *file);
  // The shared original beside the checkout, when it is there.
  const fs::path shared = RepositoryRoot().parent_path() / "shared/data/bailey-webmap";
  if (fs::exists(shared / "example_webmap.txt")) {
    StatusOr<std::string> original = ReadWholeFile((shared / "example_webmap.txt").string());
    ASSERT_TRUE(original.ok());
    EXPECT_EQ(*original, *file);
  }
}

TEST(BaileyMapReaderTest, SkipsCommentsAndBlankLinesAndTakesBlocksInAnyOrder) {
  StatusOr<BaileyMap> map = ParseBaileyMap(
      "m.txt", "# a map\r\nwp 2 1\r\n\t3\t4\r\n\n  # landmarks\nlm 2 2\n1 2\n\n+5 -6e1\n");
  ASSERT_TRUE(map.ok()) << map.status().ToString();
  ASSERT_EQ(map->waypoints.size(), 1u);
  EXPECT_EQ(map->waypoints[0].x_m, 3);
  EXPECT_EQ(map->waypoints[0].y_m, 4);
  ASSERT_EQ(map->landmarks.size(), 2u);
  EXPECT_EQ(map->landmarks[1].x_m, 5);
  EXPECT_EQ(map->landmarks[1].y_m, -60);
  // No landmarks at all is a map.
  StatusOr<BaileyMap> empty = ParseBaileyMap("m.txt", "lm 2 0\nwp 2 1\n0 1\n");
  ASSERT_TRUE(empty.ok()) << empty.status().ToString();
  EXPECT_TRUE(empty->landmarks.empty());
}

TEST(BaileyMapReaderTest, ReportsErrorsWithLineAndColumn) {
  const std::string tail = "wp 2 1\n0 0\n";
  const struct {
    std::string text;
    std::string where;  // "LINE:COLUMN"
    std::string what;
  } cases[] = {
      {"lm 2 1\n1 abc\n" + tail, "2:3", "lm row 1 y: \"abc\" is not a number"},
      {"lm 2 1\nnan 1\n" + tail, "2:1", "lm row 1 x = nan: must be finite"},
      {"lm 2 1\n1 -inf\n" + tail, "2:3", "lm row 1 y = -inf: must be finite"},
      {"lm 2 1\n1e10 0\n" + tail, "2:1", "lm row 1 x = 10000000000: must be within +-1e+09 m"},
      {"lm 2 1\n1 2 3\n" + tail, "2:5", "lm row 1: expected 2 numbers (x y), found 3"},
      {"lm 2 1\n  7\n" + tail, "2:4", "lm row 1: expected 2 numbers (x y), found 1"},
      {"lm 2 2\n1 2\n" + tail, "3:1", "block lm (line 1) declares 2 rows but has 1"},
      {"lm 2 1\n1 2\n3 4\n" + tail, "3:1", "block lm (line 1) declares 1 rows but has more"},
      {"lm 2 1\n1 2\nwp 2 3\n0 0\n", "3:6", "block wp declares 3 rows but the file ends after 1"},
      {"lm 2 1\n1 2\n", "2:1", "no wp block"},
      {"# only\n" + tail, "3:1", "no lm block"},
      {"", "1:1", "no lm block"},
      {"xy 2 1\n", "1:1", "unknown block \"xy\": expected lm or wp"},
      {"1 2\n", "1:1", "a row of numbers before any block header"},
      {"lm 3 1\n", "1:4", "lm columns = 3: must be 2"},
      {"lm 2.5 1\n", "1:4", "lm columns: \"2.5\" is not an integer"},
      {"lm 2 -1\n", "1:6", "lm rows = -1: must be in [0, 10000000]"},
      {"lm 2 x\n", "1:6", "lm rows: \"x\" is not an integer"},
      {"lm 2 0\nwp 2 0\n", "2:6", "wp rows = 0: must be in [1, 10000000]"},
      {"lm 2 0\nlm 2 0\n", "2:1", "a second lm block (the first is on line 1)"},
      {"lm 2\n", "1:5", "block header lm: expected 3 fields \"name columns rows\", found 2"},
      {"lm 2 1 9\n", "1:8", "block header lm: expected 3 fields \"name columns rows\", found 4"},
  };
  for (const auto& c : cases) {
    StatusOr<BaileyMap> map = ParseBaileyMap("map.txt", c.text);
    ASSERT_FALSE(map.ok()) << c.text;
    EXPECT_EQ(map.status().code(), StatusCode::kInvalidArgument) << c.text;
    const std::string prefix = "map.txt:" + c.where + ": ";
    EXPECT_EQ(map.status().message().substr(0, prefix.size()), prefix)
        << map.status().message() << "\nfor:\n"
        << c.text;
    EXPECT_NE(map.status().message().find(c.what), std::string::npos)
        << map.status().message() << "\nexpected: " << c.what;
  }
}

TEST(BaileyMapReaderTest, FileErrorsNameThePath) {
  const std::string path = TempPath("bad.txt");
  std::ofstream(path) << "lm 2 1\n1 2\nwp 2 1\n0 zero\n";
  StatusOr<BaileyMap> map = ReadBaileyMap(path);
  ASSERT_FALSE(map.ok());
  EXPECT_EQ(map.status().message(), path + ":4:3: wp row 1 y: \"zero\" is not a number");
  fs::remove(path);
  StatusOr<BaileyMap> missing = ReadBaileyMap(TempPath("missing.txt"));
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
}

// Options and presets.

// The webmap preset is example_webmap.ini, read here from the bundled copy.
TEST(BaileySimOptionsTest, WebmapPresetIsTheIni) {
  std::ifstream in(RepositoryRoot() / "tools/data/bailey_webmap/example_webmap.ini");
  ASSERT_TRUE(in.is_open());
  std::map<std::string, double> ini;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string key, equals;
    double value = 0;
    if (line.empty() || line[0] == '#') continue;
    if (fields >> key >> equals >> value && equals == "=") ini[key] = value;
  }
  const BaileySimOptions o = WebmapPreset();
  EXPECT_EQ(o.speed_mps, ini.at("V"));
  EXPECT_EQ(o.max_steer_rad, ini.at("MAXG"));
  EXPECT_EQ(o.max_steer_rate_radps, ini.at("RATEG"));
  EXPECT_EQ(o.wheelbase_m, ini.at("WHEELBASE"));
  EXPECT_EQ(o.dt_control_s, ini.at("DT_CONTROLS"));
  EXPECT_EQ(o.sigma_speed_mps, ini.at("sigmaV"));
  EXPECT_EQ(o.sigma_steer_rad, ini.at("sigmaG"));
  EXPECT_EQ(o.max_range_m, ini.at("MAX_RANGE"));
  EXPECT_EQ(o.dt_observe_s, ini.at("DT_OBSERVE"));
  EXPECT_EQ(o.sigma_range_m, ini.at("sigmaR"));
  EXPECT_EQ(o.sigma_bearing_rad, ini.at("sigmaB"));
  EXPECT_EQ(o.at_waypoint_m, ini.at("AT_WAYPOINT"));
  EXPECT_EQ(o.loops, ini.at("NUMBER_LOOPS"));
  EXPECT_EQ(o.field_of_view_rad, kPi);
  EXPECT_TRUE(o.Validate().ok());
}

TEST(BaileySimOptionsTest, PaperPresets) {
  const BaileySimOptions one = Simulation1Preset();
  EXPECT_EQ(one.speed_mps, 3);
  EXPECT_EQ(one.wheelbase_m, 4);
  EXPECT_EQ(one.dt_control_s, 0.025);
  EXPECT_EQ(one.dt_observe_s, 0.2);
  EXPECT_EQ(one.max_range_m, 30);
  EXPECT_EQ(one.sigma_speed_mps, 1.0);
  EXPECT_NEAR(one.sigma_steer_rad, 10 * kPi / 180, 1e-15);
  EXPECT_EQ(one.sigma_range_m, 1.2);
  EXPECT_NEAR(one.sigma_bearing_rad, 12 * kPi / 180, 1e-15);
  EXPECT_EQ(one.field_of_view_rad, kPi);
  const BaileySimOptions two = Simulation2Preset();
  EXPECT_EQ(two.sigma_range_m, one.sigma_range_m);
  EXPECT_EQ(two.sigma_steer_rad, one.sigma_steer_rad);
  const BaileySimOptions three = Simulation3Preset();
  EXPECT_EQ(three.wheelbase_m, 0.26);
  EXPECT_EQ(three.speed_mps, 0.8);
  EXPECT_EQ(three.dt_control_s, 0.025);
  EXPECT_EQ(three.dt_observe_s, 0.2);
  EXPECT_EQ(three.sigma_speed_mps, 0.4);
  EXPECT_NEAR(three.sigma_steer_rad, 4 * kPi / 180, 1e-15);
  EXPECT_EQ(three.sigma_range_m, 0.2);
  EXPECT_NEAR(three.sigma_bearing_rad, 2 * kPi / 180, 1e-15);
  EXPECT_EQ(three.max_range_m, 5);
  EXPECT_EQ(three.field_of_view_rad, kPi);
  for (std::string_view name : kBaileyPresetNames) {
    StatusOr<BaileySimOptions> preset = BaileyPreset(name);
    ASSERT_TRUE(preset.ok()) << name;
    EXPECT_TRUE(preset->Validate().ok()) << name << ": " << preset->Validate().ToString();
  }
  StatusOr<BaileySimOptions> unknown = BaileyPreset("sim4");
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.status().message(), "preset \"sim4\": must be one of webmap, sim1, sim2, sim3");
}

TEST(BaileySimOptionsTest, ValidateNamesFieldValueAndRule) {
  const double nan = std::nan("");
  const struct {
    void (*change)(BaileySimOptions*, double);
    double value;
    std::string message;
  } cases[] = {
      {[](BaileySimOptions* o, double v) { o->speed_mps = v; }, 0,
       "speed_mps = 0: must be > 0 and <= 100"},
      {[](BaileySimOptions* o, double v) { o->wheelbase_m = v; }, nan,
       "wheelbase_m = nan: must be > 0 and <= 100"},
      {[](BaileySimOptions* o, double v) { o->max_steer_rad = v; }, 2,
       "max_steer_rad = 2: must be > 0 and <= pi/2"},
      {[](BaileySimOptions* o, double v) { o->max_steer_rate_radps = v; }, -1,
       "max_steer_rate_radps = -1: must be > 0 and <= 100"},
      {[](BaileySimOptions* o, double v) { o->at_waypoint_m = v; }, 0,
       "at_waypoint_m = 0: must be > 0 and <= 1e+06"},
      {[](BaileySimOptions* o, double v) { o->loops = static_cast<int32_t>(v); }, 0,
       "loops = 0: must be in [1, 1000]"},
      {[](BaileySimOptions* o, double v) { o->dt_control_s = v; }, INFINITY,
       "dt_control_s = inf: must be > 0 and <= 10"},
      {[](BaileySimOptions* o, double v) { o->dt_observe_s = v; }, 0.21,
       "dt_observe_s = 0.21: must be a whole multiple n of dt_control_s = 0.025 with 1 <= n <= "
       "1e6 (it is 8.4 times dt_control_s)"},
      {[](BaileySimOptions* o, double v) { o->dt_observe_s = v; }, 0.0125,
       "dt_observe_s = 0.0125: must be a whole multiple n of dt_control_s = 0.025 with 1 <= n <= "
       "1e6 (it is 0.5 times dt_control_s)"},
      {[](BaileySimOptions* o, double v) { o->max_range_m = v; }, -30,
       "max_range_m = -30: must be > 0 and <= 1e+06"},
      {[](BaileySimOptions* o, double v) { o->field_of_view_rad = v; }, 7,
       "field_of_view_rad = 7: must be > 0 and <= 2 pi"},
      {[](BaileySimOptions* o, double v) { o->sigma_speed_mps = v; }, -0.1,
       "sigma_speed_mps = -0.1: must be >= 0 and <= 100"},
      {[](BaileySimOptions* o, double v) { o->sigma_steer_rad = v; }, nan,
       "sigma_steer_rad = nan: must be >= 0 and <= pi"},
      {[](BaileySimOptions* o, double v) { o->sigma_range_m = v; }, 1e5,
       "sigma_range_m = 100000: must be >= 0 and <= 1e4"},
      {[](BaileySimOptions* o, double v) { o->sigma_bearing_rad = v; }, 4,
       "sigma_bearing_rad = 4: must be >= 0 and <= pi"},
      {[](BaileySimOptions* o, double v) { o->start_x_m = v; }, nan,
       "start_x_m = nan: must be within +-1e9"},
      {[](BaileySimOptions* o, double v) { o->start_heading_rad = v; }, -kPi,
       "start_heading_rad = -3.141592653589793: must be in (-pi, pi]"},
      {[](BaileySimOptions* o, double v) { o->max_steps = static_cast<int64_t>(v); }, 0,
       "max_steps = 0: must be in [1, 1e8]"},
  };
  EXPECT_TRUE(BaileySimOptions().Validate().ok());
  for (const auto& c : cases) {
    BaileySimOptions o;
    c.change(&o, c.value);
    const Status s = o.Validate();
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << c.message;
    EXPECT_EQ(s.message(), c.message);
    // The simulator refuses the same options with the same message.
    StatusOr<BaileySimulation> sim = SimulateBailey(Webmap(), o);
    ASSERT_FALSE(sim.ok());
    EXPECT_EQ(sim.status().message(), c.message);
  }
}

// The simulation.

// With zero noise, integrating controls.csv from the start of truth.csv by the vehicle model,
// with dt the difference of the written times, lands on every row of truth.csv.
TEST(BaileySimulatorTest, ZeroNoiseControlsReproduceTruth) {
  for (const char* preset : {"webmap", "sim3"}) {
    SCOPED_TRACE(preset);
    BaileySimOptions o = NoNoise(*BaileyPreset(preset));
    const BaileySimulation sim = Simulate(Webmap(), o);
    const Csv controls = ParseCsv(BaileyControlsCsv(sim));
    const Csv truth = ParseCsv(BaileyTruthCsv(sim));
    ASSERT_EQ(controls.header, "t,v,steer");
    ASSERT_EQ(truth.header, "t,x,y,heading");
    ASSERT_EQ(controls.rows.size(), truth.rows.size());
    ASSERT_GT(truth.rows.size(), 1000u);
    EXPECT_EQ(truth.rows[0], (std::vector<double>{0, 0, 0, 0}));
    double x = truth.rows[0][1];
    double y = truth.rows[0][2];
    double phi = truth.rows[0][3];
    double worst_m = 0;
    double worst_rad = 0;
    for (size_t k = 0; k + 1 < controls.rows.size(); ++k) {
      ASSERT_EQ(controls.rows[k][0], truth.rows[k][0]) << "row " << k;
      ASSERT_LT(controls.rows[k][0], controls.rows[k + 1][0]) << "row " << k;
      const double dt = controls.rows[k + 1][0] - controls.rows[k][0];
      const double v = controls.rows[k][1];
      const double g = controls.rows[k][2];
      x += v * dt * std::cos(g + phi);
      y += v * dt * std::sin(g + phi);
      phi = Wrap(phi + v * dt * std::sin(g) / o.wheelbase_m);
      const std::vector<double>& t = truth.rows[k + 1];
      worst_m = std::max({worst_m, std::fabs(x - t[1]), std::fabs(y - t[2])});
      worst_rad = std::max(worst_rad, std::fabs(Wrap(phi - t[3])));
      EXPECT_GT(t[3], -kPi);
      EXPECT_LE(t[3], kPi);
    }
    EXPECT_LE(worst_m, 1e-9);
    EXPECT_LE(worst_rad, 1e-12);
    // The last row is the stop.
    EXPECT_EQ(controls.rows.back()[0], truth.rows.back()[0]);
    EXPECT_EQ(controls.rows.back()[1], 0);
  }
}

// With zero noise every observation is the range and bearing of its landmark from the true pose
// of its time, every scan holds every landmark in range and view, and scans come every
// dt_observe_s / dt_control_s control steps.
TEST(BaileySimulatorTest, ZeroNoiseObservationsAreTheTrueRangeAndBearing) {
  for (const char* preset : {"webmap", "sim3"}) {
    SCOPED_TRACE(preset);
    BaileySimOptions o = NoNoise(*BaileyPreset(preset));
    const BaileySimulation sim = Simulate(Webmap(), o);
    const Csv truth = ParseCsv(BaileyTruthCsv(sim));
    const Csv landmarks = ParseCsv(BaileyLandmarksCsv(sim));
    const Csv observations = ParseCsv(BaileyObservationsCsv(sim));
    ASSERT_EQ(landmarks.header, "id,x,y");
    ASSERT_EQ(observations.header, "t,range,bearing,id");
    ASSERT_EQ(landmarks.rows.size(), 35u);
    std::map<double, size_t> row_at;
    for (size_t k = 0; k < truth.rows.size(); ++k) row_at[truth.rows[k][0]] = k;

    std::map<size_t, std::set<int>> seen;  // truth row -> ids
    double previous_t = 0;
    for (const std::vector<double>& z : observations.rows) {
      ASSERT_GE(z[0], previous_t);
      previous_t = z[0];
      ASSERT_TRUE(row_at.count(z[0])) << "observation at t = " << z[0] << " is not a truth time";
      const size_t k = row_at[z[0]];
      EXPECT_EQ(k % 8, 0u) << "t = " << z[0];
      const int id = static_cast<int>(z[3]);
      ASSERT_EQ(z[3], id);
      ASSERT_GE(id, 0);
      ASSERT_LT(id, 35);
      EXPECT_EQ(landmarks.rows[id][0], id);
      EXPECT_TRUE(seen[k].insert(id).second) << "landmark " << id << " twice at t = " << z[0];
      const double dx = landmarks.rows[id][1] - truth.rows[k][1];
      const double dy = landmarks.rows[id][2] - truth.rows[k][2];
      EXPECT_NEAR(z[1], std::hypot(dx, dy), 1e-9);
      EXPECT_NEAR(Wrap(z[2] - Wrap(std::atan2(dy, dx) - truth.rows[k][3])), 0, 1e-12);
    }
    // Completeness: a scan at every 8th row holds every landmark clearly in range and view.
    size_t scans = 0;
    for (size_t k = 8; k < truth.rows.size(); k += 8) {
      ++scans;
      for (int id = 0; id < 35; ++id) {
        const double dx = landmarks.rows[id][1] - truth.rows[k][1];
        const double dy = landmarks.rows[id][2] - truth.rows[k][2];
        const double range = std::hypot(dx, dy);
        const double bearing = Wrap(std::atan2(dy, dx) - truth.rows[k][3]);
        const bool clearly_in = range < o.max_range_m - 1e-6 && std::fabs(bearing) < kPi / 2 - 1e-9;
        const bool clearly_out =
            range > o.max_range_m + 1e-6 || std::fabs(bearing) > kPi / 2 + 1e-9;
        if (clearly_in) {
          EXPECT_TRUE(seen[k].count(id)) << "missed " << id << " at row " << k;
        }
        if (clearly_out) {
          EXPECT_FALSE(seen[k].count(id)) << "saw " << id << " at row " << k;
        }
      }
    }
    EXPECT_EQ(scans, sim.scan_times_s.size());
  }
}

TEST(BaileySimulatorTest, VisitsEveryWaypointInOrderLoopsThenStops) {
  const BaileyMap map = Webmap();
  for (int32_t loops : {1, 2, 3}) {
    SCOPED_TRACE(loops);
    BaileySimOptions o = WebmapPreset();
    o.loops = loops;
    o.seed = 11;
    const BaileySimulation sim = Simulate(map, o);
    const size_t n = map.waypoints.size();
    ASSERT_EQ(sim.visits.size(), n * static_cast<size_t>(loops));
    int64_t previous = 0;
    for (size_t i = 0; i < sim.visits.size(); ++i) {
      const BaileyWaypointVisit& v = sim.visits[i];
      EXPECT_EQ(v.waypoint, static_cast<int32_t>(i % n));
      EXPECT_EQ(v.loop, static_cast<int32_t>(i / n));
      ASSERT_GT(v.step, previous);
      const BaileyPoint& w = map.waypoints[static_cast<size_t>(v.waypoint)];
      const BaileyPose& p = sim.truth[static_cast<size_t>(v.step)];
      EXPECT_LT(std::hypot(p.x_m - w.x_m, p.y_m - w.y_m), o.at_waypoint_m);
      // It switches the first time it comes that close.
      for (int64_t k = previous; k < v.step; ++k) {
        const BaileyPose& q = sim.truth[static_cast<size_t>(k)];
        ASSERT_GE(std::hypot(q.x_m - w.x_m, q.y_m - w.y_m), o.at_waypoint_m)
            << "waypoint " << v.waypoint << " reached at row " << k << " before " << v.step;
      }
      previous = v.step;
    }
    // It stops at the last waypoint of the last loop.
    EXPECT_EQ(sim.visits.back().step, sim.control_steps());
    EXPECT_EQ(sim.controls.back().speed_mps, 0);
  }
}

TEST(BaileySimulatorTest, SteeringStaysWithinAngleAndRateLimits) {
  for (const char* preset : {"webmap", "sim3"}) {
    SCOPED_TRACE(preset);
    const BaileySimOptions o = *BaileyPreset(preset);
    const BaileySimulation sim = Simulate(Webmap(), o);
    const double max_delta = o.max_steer_rate_radps * o.dt_control_s;
    double previous = 0;
    int at_angle_limit = 0;
    int at_rate_limit = 0;
    for (size_t k = 0; k + 1 < sim.true_controls.size(); ++k) {
      const double g = sim.true_controls[k].steer_rad;
      ASSERT_LE(std::fabs(g), o.max_steer_rad) << "row " << k;
      ASSERT_LE(std::fabs(g - previous), max_delta * (1 + 1e-12)) << "row " << k;
      at_angle_limit += std::fabs(g) == o.max_steer_rad;
      at_rate_limit += std::fabs(std::fabs(g - previous) - max_delta) < 1e-15;
      EXPECT_EQ(sim.true_controls[k].speed_mps, o.speed_mps);
      previous = g;
    }
    // The limits bind, so the checks above test something.
    EXPECT_GT(at_rate_limit, 100);
    std::cout << preset << ": " << at_angle_limit << " steps at the angle limit, " << at_rate_limit
              << " at the rate limit\n";
  }
}

TEST(BaileySimulatorTest, ObservesOnlyWithinRangeAndFieldOfView) {
  const BaileyMap map = Webmap();
  for (double fov : {kPi, kPi / 3, 2 * kPi}) {
    for (const char* preset : {"webmap", "sim3"}) {
      BaileySimOptions o = *BaileyPreset(preset);
      o.field_of_view_rad = fov;
      o.seed = 5;
      SCOPED_TRACE(std::string(preset) + " fov " + std::to_string(fov) + " seed 5");
      const BaileySimulation sim = Simulate(map, o);
      ASSERT_FALSE(sim.observations.empty());
      std::map<double, size_t> row_at;
      for (size_t k = 0; k < sim.truth.size(); ++k) row_at[sim.truth[k].t_s] = k;
      double widest = 0;
      for (const BaileyObservation& z : sim.observations) {
        const BaileyPose& p = sim.truth[row_at.at(z.t_s)];
        const BaileyPoint& l = map.landmarks[static_cast<size_t>(z.id)];
        const double range = std::hypot(l.x_m - p.x_m, l.y_m - p.y_m);
        const double bearing = Wrap(std::atan2(l.y_m - p.y_m, l.x_m - p.x_m) - p.heading_rad);
        EXPECT_LT(range, o.max_range_m + 1e-9);
        EXPECT_LT(std::fabs(bearing), fov / 2 + 1e-9);
        EXPECT_GT(z.bearing_rad, -kPi);
        EXPECT_LE(z.bearing_rad, kPi);
        EXPECT_GT(z.range_m, 0);
        widest = std::max(widest, std::fabs(bearing));
      }
      // The view is used to its edge.
      EXPECT_GT(widest, 0.8 * std::min(fov / 2, kPi));
    }
  }
}

TEST(BaileySimulatorTest, NoisyBearingsAreWrappedAcrossPi) {
  BaileySimOptions o = WebmapPreset();
  o.field_of_view_rad = 2 * kPi;
  o.sigma_bearing_rad = 0.5;
  o.seed = 3;
  const BaileySimulation sim = Simulate(Webmap(), o);
  int near_pi = 0;
  for (const BaileyObservation& z : sim.observations) {
    ASSERT_GT(z.bearing_rad, -kPi) << "seed 3";
    ASSERT_LE(z.bearing_rad, kPi) << "seed 3";
    near_pi += std::fabs(z.bearing_rad) > 3.0;
  }
  EXPECT_GT(near_pi, 100);  // many crossed +-pi and were wrapped back
}

TEST(BaileySimulatorTest, SameSeedSameFilesOtherSeedOtherNoise) {
  const BaileyMap map = Webmap();
  BaileySimOptions o = WebmapPreset();
  o.loops = 1;
  o.seed = 7;
  const BaileySimulation a = Simulate(map, o);
  const BaileySimulation b = Simulate(map, o);
  EXPECT_EQ(BaileyControlsCsv(a), BaileyControlsCsv(b));
  EXPECT_EQ(BaileyObservationsCsv(a), BaileyObservationsCsv(b));
  EXPECT_EQ(BaileyTruthCsv(a), BaileyTruthCsv(b));
  EXPECT_EQ(BaileyLandmarksCsv(a), BaileyLandmarksCsv(b));
  o.seed = 8;
  const BaileySimulation c = Simulate(map, o);
  EXPECT_NE(BaileyControlsCsv(a), BaileyControlsCsv(c)) << "seeds 7 and 8";
  EXPECT_NE(BaileyObservationsCsv(a), BaileyObservationsCsv(c)) << "seeds 7 and 8";
  // The truth does not depend on the noise.
  EXPECT_EQ(BaileyTruthCsv(a), BaileyTruthCsv(c));
  // The control noise does not depend on the sensor.
  o.max_range_m = 10;
  o.sigma_range_m = 1;
  const BaileySimulation d = Simulate(map, o);
  EXPECT_EQ(BaileyControlsCsv(c), BaileyControlsCsv(d)) << "seed 8";
}

// The noise has the configured spread: residuals against the truth over a whole run.
TEST(BaileySimulatorTest, NoiseHasTheConfiguredStandardDeviations) {
  const BaileyMap map = Webmap();
  BaileySimOptions o = WebmapPreset();
  o.seed = 21;
  const BaileySimulation sim = Simulate(map, o);
  std::map<double, size_t> row_at;
  for (size_t k = 0; k < sim.truth.size(); ++k) row_at[sim.truth[k].t_s] = k;
  const auto check = [](const std::vector<double>& r, double sigma, const char* what) {
    ASSERT_GT(r.size(), 1000u);
    double sum = 0;
    double sum2 = 0;
    for (double e : r) {
      sum += e;
      sum2 += e * e;
    }
    const double n = static_cast<double>(r.size());
    const double mean = sum / n;
    const double sd = std::sqrt(sum2 / n - mean * mean);
    std::cout << what << ": " << r.size() << " samples, mean " << mean << ", sd " << sd
              << " (sigma " << sigma << ")\n";
    EXPECT_NEAR(sd, sigma, 0.05 * sigma) << what << ", seed 21";
    EXPECT_NEAR(mean, 0, 5 * sigma / std::sqrt(n)) << what << ", seed 21";
  };
  std::vector<double> dv, dg, dr, db;
  for (size_t k = 0; k + 1 < sim.controls.size(); ++k) {
    dv.push_back(sim.controls[k].speed_mps - sim.true_controls[k].speed_mps);
    dg.push_back(sim.controls[k].steer_rad - sim.true_controls[k].steer_rad);
  }
  for (const BaileyObservation& z : sim.observations) {
    const BaileyPose& p = sim.truth[row_at.at(z.t_s)];
    const BaileyPoint& l = map.landmarks[static_cast<size_t>(z.id)];
    dr.push_back(z.range_m - std::hypot(l.x_m - p.x_m, l.y_m - p.y_m));
    db.push_back(Wrap(z.bearing_rad - std::atan2(l.y_m - p.y_m, l.x_m - p.x_m) + p.heading_rad));
  }
  check(dv, o.sigma_speed_mps, "speed");
  check(dg, o.sigma_steer_rad, "steer");
  check(dr, o.sigma_range_m, "range");
  check(db, o.sigma_bearing_rad, "bearing");
}

// The figures of Bailey's webmap run: about 17,400 control steps over 2 loops, and one scan
// every 8 steps (Bailey's own loop would scan every 9th: printed for comparison).
TEST(BaileySimulatorTest, WebmapRunHasBaileysStepAndScanCounts) {
  BaileySimOptions o = WebmapPreset();
  const BaileySimulation sim = Simulate(Webmap(), o);
  const int64_t steps = sim.control_steps();
  const auto scans = static_cast<int64_t>(sim.scan_times_s.size());
  int64_t bailey_scans = 0;
  double dtsum = 0;
  for (int64_t k = 0; k < steps; ++k) {
    dtsum += o.dt_control_s;
    if (dtsum >= o.dt_observe_s) {
      dtsum = 0;
      ++bailey_scans;
    }
  }
  std::cout << "webmap, seed " << o.seed << ": " << steps << " control steps ("
            << sim.truth.back().t_s << " s), " << scans << " scans, " << sim.observations.size()
            << " observations; Bailey's dtsum loop would scan " << bailey_scans << " times\n";
  EXPECT_GE(steps, 17000);
  EXPECT_LE(steps, 18000);
  EXPECT_GE(scans, 1900);
  EXPECT_LE(scans, 2200);
  EXPECT_EQ(scans, steps / 8);
  EXPECT_EQ(bailey_scans, steps / 9);
  // Most landmarks are seen; five inner ones never come within 30 m in front of the vehicle
  // (the completeness test above checks that none is missed).
  std::set<int32_t> ids;
  for (const BaileyObservation& z : sim.observations) ids.insert(z.id);
  std::cout << ids.size() << " of 35 landmarks observed\n";
  EXPECT_GE(ids.size(), 30u);
}

TEST(BaileySimulatorTest, UnreachableWaypointFailsInsteadOfCirclingForEver) {
  // The turning radius is 4 m / sin(30 deg) = 8 m: a waypoint 3 m to the left of the start lies
  // inside the circle the vehicle can drive, which stays 3 m away from it.
  BaileyMap map;
  map.waypoints = {{0, 3}};
  BaileySimOptions o = WebmapPreset();
  o.max_steps = 20'000;
  StatusOr<BaileySimulation> sim = SimulateBailey(map, o);
  ASSERT_FALSE(sim.ok());
  EXPECT_EQ(sim.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(sim.status().message().find("did not reach waypoint 0 (0, 3) of loop 1 within "
                                        "max_steps = 20000"),
            std::string::npos)
      << sim.status().message();
  EXPECT_FALSE(SimulateBailey(BaileyMap{}, o).ok());  // no waypoint
}

TEST(BaileySimulatorTest, WaypointsAllAtTheStartAreRefusedInsteadOfAnEmptyRun) {
  BaileyMap map;
  map.landmarks = {{1, 2}};
  map.waypoints = {{0, 0}, {0.5, 0.2}};
  StatusOr<BaileySimulation> sim = SimulateBailey(map, WebmapPreset());
  ASSERT_FALSE(sim.ok());
  EXPECT_EQ(sim.status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(sim.status().message(),
            "wp: every waypoint lies within at_waypoint_m = 1 m of the start (0, 0), so the "
            "vehicle would not move: the path needs a waypoint farther from the start");
  map.waypoints.push_back({30, 0});  // one waypoint away from the start is enough
  EXPECT_TRUE(SimulateBailey(map, WebmapPreset()).ok());
}

// The command.

class FastSlamSimulateCommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = TempPath("out");
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  static std::string Read(const fs::path& path) {
    StatusOr<std::string> text = ReadWholeFile(path.string());
    EXPECT_TRUE(text.ok()) << text.status().ToString();
    return text.ok() ? *text : "";
  }

  std::string dir_;
};

TEST_F(FastSlamSimulateCommandTest, WritesTheFourFilesOfTheBundledWebmap) {
  ASSERT_EQ(FastSlamSimulateCommand("", "webmap", dir_ + "/a/b", 5), 0);
  BaileySimOptions o = WebmapPreset();
  o.seed = 5;
  const BaileySimulation sim = Simulate(Webmap(), o);
  EXPECT_EQ(Read(dir_ + "/a/b/controls.csv"), BaileyControlsCsv(sim));
  EXPECT_EQ(Read(dir_ + "/a/b/observations.csv"), BaileyObservationsCsv(sim));
  EXPECT_EQ(Read(dir_ + "/a/b/truth.csv"), BaileyTruthCsv(sim));
  EXPECT_EQ(Read(dir_ + "/a/b/landmarks_truth.csv"), BaileyLandmarksCsv(sim));
  // A map file and another preset.
  ASSERT_EQ(FastSlamSimulateCommand(WebmapPath().string(), "sim1", dir_, 9), 0);
  BaileySimOptions one = Simulation1Preset();
  one.seed = 9;
  EXPECT_EQ(Read(dir_ + "/observations.csv"), BaileyObservationsCsv(Simulate(Webmap(), one)));
}

TEST_F(FastSlamSimulateCommandTest, ExitCodes) {
  EXPECT_EQ(FastSlamSimulateCommand("", "nope", dir_, 1), 2);
  EXPECT_EQ(FastSlamSimulateCommand("", "webmap", "", 1), 2);
  EXPECT_EQ(FastSlamSimulateCommand(TempPath("missing.txt"), "webmap", dir_, 1), 3);
  const std::string bad = TempPath("bad.txt");
  std::ofstream(bad) << "lm 2 1\n1 2\n";
  EXPECT_EQ(FastSlamSimulateCommand(bad, "webmap", dir_, 1), 3);
  EXPECT_FALSE(fs::exists(dir_)) << "nothing is written after an error";
  const std::string file = TempPath("a_file");
  std::ofstream(file) << "x";
  EXPECT_EQ(FastSlamSimulateCommand("", "webmap", file + "/out", 1), 5);
  fs::remove(bad);
  fs::remove(file);
}

}  // namespace
}  // namespace grove::tools
