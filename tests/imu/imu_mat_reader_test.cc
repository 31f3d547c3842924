// The PyShoe MAT layout (ts, imu N x 6) read through libmatio gives the samples the CSV form
// gives, and its bad values are named by row and column. Skipped without libmatio.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "tools/io/imu_reader.h"
#include "tools/io/mat_file.h"

namespace grove::tools {
namespace {

namespace fs = std::filesystem;

// n samples of a still, level sensor at 200 Hz; ts as a row, imu as N x 6.
std::vector<std::pair<std::string, MatMatrix>> Recording(int n) {
  MatMatrix ts{1, static_cast<size_t>(n), {}};
  MatMatrix imu{static_cast<size_t>(n), 6, std::vector<double>(6 * static_cast<size_t>(n), 0.0)};
  for (int k = 0; k < n; ++k) {
    ts.values.push_back(0.005 * k);
    imu.values[k + 2 * n] = 9.8;        // az
    imu.values[k + 3 * n] = 0.001 * k;  // gx
  }
  return {{"ts", ts}, {"imu", imu}, {"gt", MatMatrix{1, 1, {0.0}}}};
}

class ImuMatReaderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    path_ = (fs::path(::testing::TempDir()) / ("grove_imu_" + std::to_string(::getpid()) + ".mat"))
                .string();
  }
  void TearDown() override { fs::remove(path_); }
  std::string path_;
};

TEST_F(ImuMatReaderTest, PyShoeLayoutGivesEverySampleInSiUnits) {
  Status written = WriteMatFile(path_, Recording(50));
  if (!written.ok()) GTEST_SKIP() << written.ToString();
  auto reader = ImuReader::Open(path_);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  ImuRecord record;
  int n = 0;
  for (;;) {
    StatusOr<bool> more = reader->Next(&record);
    ASSERT_TRUE(more.ok()) << more.status().ToString();
    if (!*more) break;
    EXPECT_EQ(record.sample.t_s, 0.005 * n);
    EXPECT_EQ(record.sample.accel_mps2[2], 9.8);
    EXPECT_EQ(record.sample.gyro_radps[0], 0.001 * n);
    EXPECT_EQ(record.line, n + 1);
    ++n;
  }
  EXPECT_EQ(n, 50);
  EXPECT_STREQ(reader->format(), "MAT (PyShoe)");
}

TEST_F(ImuMatReaderTest, NotANumberIsNamedByRowAndColumn) {
  auto recording = Recording(50);
  recording[1].second.values[20 + 50] = std::nan("");  // row 21, ay
  Status written = WriteMatFile(path_, recording);
  if (!written.ok()) GTEST_SKIP() << written.ToString();
  auto reader = ImuReader::Open(path_);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  ImuRecord record;
  StatusOr<bool> more = true;
  while (more.ok() && *more) more = reader->Next(&record);
  ASSERT_FALSE(more.ok());
  EXPECT_NE(more.status().message().find(path_ + ": imu row 21, column 2: ay = nan"),
            std::string::npos)
      << more.status().message();
}

// Without ts the rate gives the times; without either the reader says what is missing.
TEST_F(ImuMatReaderTest, WithoutTsTheRateGivesTheTimes) {
  auto recording = Recording(10);
  recording.erase(recording.begin());
  Status written = WriteMatFile(path_, recording);
  if (!written.ok()) GTEST_SKIP() << written.ToString();
  ImuReaderOptions options;
  options.rate_hz = 100;
  auto reader = ImuReader::Open(path_, options);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  ImuRecord record;
  ASSERT_TRUE(reader->Next(&record).ok());
  ASSERT_TRUE(reader->Next(&record).ok());
  EXPECT_EQ(record.sample.t_s, 0.01);
  auto without_rate = ImuReader::Open(path_);
  ASSERT_TRUE(without_rate.ok()) << without_rate.status().ToString();
  StatusOr<bool> more = without_rate->Next(&record);
  ASSERT_FALSE(more.ok());
  EXPECT_NE(more.status().message().find("rate"), std::string::npos) << more.status().message();
}

}  // namespace
}  // namespace grove::tools
