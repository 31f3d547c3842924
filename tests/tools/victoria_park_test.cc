// The Victoria Park readers, their events in the filter's order, and the error against GPS.
#include "tools/io/victoria_park.h"

#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "grove/checksum.h"

namespace grove::tools {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;

class VictoriaParkTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("grove_park_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  void Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
  }
  fs::path dir_;
};

TEST_F(VictoriaParkTest, ReadsTheFilesAndMergesControlsBeforeScans) {
  Write("inputs.dat", "  1.0 2.0 0.1\n  2.0 2.5 -0.1\n\n  3.0 0.0 0.0\n");
  Write("measurements.dat",
        "0.5 10 1.0 0.2\n1.0 12 0.0 0.3\n1.5 20 3.14159 0.3\n1.5 21 1.5707963267948966 0.4\n"
        "3.5 5 1 0.1\n");
  Write("gps.dat", "0.0 1 2\n1.0 3 4\n");
  StatusOr<VictoriaParkData> d = ReadVictoriaPark(dir_.string(), 3.0);
  ASSERT_TRUE(d.ok()) << d.status().message();
  EXPECT_EQ(d->controls.size(), 3u);
  ASSERT_EQ(d->observations.size(), 4u);  // 3.5 s is after --until
  EXPECT_EQ(d->gps.size(), 2u);
  EXPECT_NEAR(d->observations[0].z.bearing_rad, 1.0 - kPi / 2, 1e-15);
  EXPECT_EQ(d->observations[0].z.id, -1);
  EXPECT_NEAR(d->observations[3].z.bearing_rad, 0, 1e-15);
  VictoriaParkEvents events(&*d);
  FastSlamEvent e;
  std::vector<std::string> order;
  for (;;) {
    StatusOr<bool> more = events.Next(&e);
    ASSERT_TRUE(more.ok());
    if (!*more) break;
    order.push_back(e.is_scan ? "scan " + std::to_string(e.scan.size()) + " @" +
                                    std::to_string(e.scan_t_s)
                              : "control @" + std::to_string(e.control.t_s));
  }
  const std::vector<std::string> expected = {"control @1.000000", "scan 1 @1.000000",
                                             "scan 2 @1.500000", "control @2.000000",
                                             "control @3.000000"};
  EXPECT_EQ(order, expected);
  EXPECT_EQ(events.skipped_scans(), 1);  // 0.5 s, before the first control
}

TEST_F(VictoriaParkTest, ErrorsNameFileLineAndColumn) {
  Write("gps.dat", "0.0 1 2\n");
  Write("measurements.dat", "1.0 12 0.0 0.3\n");
  Write("inputs.dat", "1.0 2.0 0.1\n1.0 2.0 0.1\n");
  StatusOr<VictoriaParkData> d = ReadVictoriaPark(dir_.string(), 1e9);
  ASSERT_FALSE(d.ok());
  EXPECT_NE(d.status().message().find("inputs.dat:2:1: time = 1: must be after the previous time"),
            std::string::npos)
      << d.status().message();
  Write("inputs.dat", "1.0 2.0 1.6\n");
  d = ReadVictoriaPark(dir_.string(), 1e9);
  EXPECT_NE(d.status().message().find("inputs.dat:1:9: steering = 1.6"), std::string::npos)
      << d.status().message();
  Write("inputs.dat", "1.0 2.0 0.1 7\n");
  d = ReadVictoriaPark(dir_.string(), 1e9);
  EXPECT_NE(d.status().message().find("inputs.dat:1:13: 4 numbers where 3 are expected"),
            std::string::npos)
      << d.status().message();
  Write("inputs.dat", "1.0 nan 0.1\n");
  d = ReadVictoriaPark(dir_.string(), 1e9);
  EXPECT_NE(d.status().message().find("inputs.dat:1:5: speed"), std::string::npos)
      << d.status().message();
  fs::remove(dir_ / "inputs.dat");
  d = ReadVictoriaPark(dir_.string(), 1e9);
  EXPECT_EQ(d.status().code(), StatusCode::kNotFound);
  EXPECT_NE(d.status().message().find("inputs.dat.gz: no such file"), std::string::npos);
}

TEST_F(VictoriaParkTest, RecordsEveryFileReadWithItsSizeAndCrc) {
  Write("inputs.dat", "1.0 2.0 0.1\n");
  Write("measurements.dat", "1.0 12 0.0 0.3\n");
  Write("gps.dat", "0.0 1 2\n");
  StatusOr<VictoriaParkData> d = ReadVictoriaPark(dir_.string(), 1e9);
  ASSERT_TRUE(d.ok()) << d.status().message();
  ASSERT_EQ(d->files.size(), 3u);
  EXPECT_EQ(d->files[0].path, (dir_ / "inputs.dat").string());
  EXPECT_EQ(d->files[0].bytes, 12u);
  EXPECT_EQ(d->files[0].crc32, Crc32("1.0 2.0 0.1\n"));
  EXPECT_EQ(d->files[2].path, (dir_ / "gps.dat").string());
  EXPECT_EQ(InputFilesJson(d->files)[1]["bytes"], 15);
}

// Regression: a stale plain inputs.dat beside inputs.dat.gz was read silently.
TEST_F(VictoriaParkTest, APlainAndACompressedCopyOfOneFileIsAnError) {
  Write("inputs.dat", "1.0 2.0 0.1\n");
  Write("inputs.dat.gz", "not read\n");
  Write("measurements.dat", "1.0 12 0.0 0.3\n");
  Write("gps.dat", "0.0 1 2\n");
  StatusOr<VictoriaParkData> d = ReadVictoriaPark(dir_.string(), 1e9);
  ASSERT_FALSE(d.ok());
  EXPECT_EQ(d.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(d.status().message().find("both inputs.dat and inputs.dat.gz exist"), std::string::npos)
      << d.status().message();
}

// Regression: a line of a billion zeros was held whole (1 GB of memory) before it was refused.
TEST_F(VictoriaParkTest, ALineLongerThanTheLimitIsRefusedWithoutBeingHeld) {
  Write("inputs.dat", "1.0 2.0 0.1\n");
  Write("measurements.dat", "1.0 12 0.0 0.3\n" + std::string(200000, '0') + "\n");
  Write("gps.dat", "0.0 1 2\n");
  StatusOr<VictoriaParkData> d = ReadVictoriaPark(dir_.string(), 1e9);
  ASSERT_FALSE(d.ok());
  EXPECT_NE(d.status().message().find("measurements.dat:2:1: line longer than 65536 bytes"),
            std::string::npos)
      << d.status().message();
}

TEST_F(VictoriaParkTest, CompressedFilesAreReadAndTruncatedOnesRefused) {
  const std::string text = "1.0 2.0 0.1\n2.0 2.5 -0.1\n";
  gzFile f = gzopen((dir_ / "inputs.dat.gz").c_str(), "wb");
  ASSERT_NE(f, nullptr);
  ASSERT_EQ(gzwrite(f, text.data(), static_cast<unsigned>(text.size())),
            static_cast<int>(text.size()));
  ASSERT_EQ(gzclose(f), Z_OK);
  Write("measurements.dat", "1.0 12 0.0 0.3\n");
  Write("gps.dat", "0.0 1 2\n");
  StatusOr<VictoriaParkData> d = ReadVictoriaPark(dir_.string(), 1e9);
  ASSERT_TRUE(d.ok()) << d.status().message();
  EXPECT_EQ(d->controls.size(), 2u);
  EXPECT_EQ(d->files[0].path, (dir_ / "inputs.dat.gz").string());
  // Cut the compressed file short: its end is missing.
  fs::resize_file(dir_ / "inputs.dat.gz", fs::file_size(dir_ / "inputs.dat.gz") - 6);
  d = ReadVictoriaPark(dir_.string(), 1e9);
  ASSERT_FALSE(d.ok());
  EXPECT_EQ(d.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(d.status().message().find("inputs.dat.gz: the compressed data is truncated"),
            std::string::npos)
      << d.status().message();
}

TEST(CompareWithGpsTest, AlignsRigidlyAndCountsTheGpsJumps) {
  // A path on a circle; the GPS is the same path rotated by 0.3 rad and moved by (5, -2), one
  // fix a second, with one fix thrown 40 m off.
  std::vector<StampedPose> path;
  std::vector<TimedPoint> gps;
  const double c = std::cos(0.3), s = std::sin(0.3);
  for (int k = 0; k <= 200; ++k) {
    const double t = 0.5 * k, a = 0.05 * t;
    const double x = 20 * std::cos(a), y = 20 * std::sin(a);
    path.push_back({t, Pose2{x, y, a}});
    if (k % 2 == 0) gps.push_back({t, c * x - s * y + 5, s * x + c * y - 2});
  }
  gps[50].x_m += 40;
  StatusOr<GpsErrors> e = CompareWithGps(path, gps);
  ASSERT_TRUE(e.ok()) << e.status().message();
  EXPECT_EQ(e->fixes.size(), gps.size());
  EXPECT_EQ(e->jumps, 2);  // away and back
  EXPECT_EQ(e->gaps, 0);
  EXPECT_NEAR(e->alignment.rotation_rad, 0.3, 0.05);
  EXPECT_LT(e->median_m, 1.5);
  EXPECT_GT(e->max_m, 35);
  EXPECT_GT(e->mean_m, e->median_m);
  EXPECT_LT(e->max_without_jumps_m, 2.0);
  EXPECT_LT(e->mean_without_jumps_m, e->mean_m);
  // Without the jump the alignment is exact.
  gps[50].x_m -= 40;
  e = CompareWithGps(path, gps);
  ASSERT_TRUE(e.ok());
  EXPECT_NEAR(e->alignment.rotation_rad, 0.3, 1e-9);
  EXPECT_LT(e->max_m, 1e-6);
  EXPECT_EQ(e->jumps, 0);
}

// PHD-SLAM's score: scans at 0.2 s, a GPS fix every 0.5 s shifted by 10 ms (kept) or 40 ms
// (dropped); the path's estimate at a scan is its last pose at that time, and the estimate sits
// (0, 1) m from the GPS frame's point but for the scan at t = 3, off by 3 m more.
TEST(CompareWithGpsAtScansTest, KeepsFixesWithin25MsOfAScanEstimate) {
  std::vector<StampedPose> path;
  std::vector<double> scans;
  std::vector<TimedPoint> gps;
  auto truth_x = [](double t) { return 2 * t; };
  for (int k = 0; k <= 50; ++k) {
    const double t = 0.2 * k;
    scans.push_back(t);
    scans.push_back(t);                                  // two detections of one scan
    path.push_back({t, Pose2{truth_x(t) + 100, 7, 0}});  // the prediction to the scan
    const double off = std::abs(t - 3.0) < 1e-9 ? 3 : 0;
    path.push_back({t, Pose2{truth_x(t), 1 + off, 0}});  // after its update
  }
  for (int k = 0; k <= 20; ++k) {
    const double t = 0.5 * k + (k % 2 == 0 ? 0.010 : 0.040);  // 0.01, 0.54, 1.01, 1.54, ...
    gps.push_back({t, truth_x(t - (k % 2 == 0 ? 0.010 : 0.040)), 0});
  }
  StatusOr<GpsScanErrors> e = CompareWithGpsAtScans(path, scans, gps);
  ASSERT_TRUE(e.ok()) << e.status().message();
  EXPECT_EQ(e->scans, 51);
  // Kept: the fixes near t = 0, 1, 2, ..., 10 (11 of them); the ones 40 ms off a scan are not.
  EXPECT_EQ(e->pairs, 11);
  // After the best rigid alignment of the 11 pairs what is left is the one 3 m outlier: the
  // shift alone (of y by the mean offset) leaves `shifted`; the rotation takes a little more.
  const double mean_y = (11 * 1.0 + 3) / 11;
  const double shifted = std::sqrt((10 * std::pow(1 - mean_y, 2) + std::pow(4 - mean_y, 2)) / 11);
  EXPECT_LE(e->rmse_m, shifted + 1e-9);
  EXPECT_GT(e->rmse_m, 0.8 * shifted);
  // Without the outlier the pairs align exactly.
  for (StampedPose& p : path) {
    if (std::abs(p.t_s - 3.0) < 1e-9 && p.pose.x_m < 50) p.pose.y_m = 1;
  }
  e = CompareWithGpsAtScans(path, scans, gps);
  ASSERT_TRUE(e.ok());
  EXPECT_LT(e->rmse_m, 1e-9);
  EXPECT_NEAR(e->alignment.translation_y_m, -1, 1e-9);
  // Fewer than two pairs: an error.
  EXPECT_FALSE(CompareWithGpsAtScans(path, scans, {gps[0]}).ok());
}

}  // namespace
}  // namespace grove::tools
