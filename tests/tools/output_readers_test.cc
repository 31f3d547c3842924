#include "tools/io/output_readers.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace grove::tools {
namespace {

constexpr char kMapHeader[] = "q,r,x,y,c0,c1,c2,c3,c4,c5\n";

class OutputReadersTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = (std::filesystem::path(::testing::TempDir()) /
            ("output_readers_" + std::to_string(::getpid())))
               .string();
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  std::string Write(const std::string& name, const std::string& contents) {
    std::string path = dir_ + "/" + name;
    std::ofstream(path, std::ios::binary) << contents;
    return path;
  }
  // The message of ReadMapCsv on a map.csv holding `contents`, which must fail with
  // InvalidArgument.
  std::string MapError(const std::string& contents) {
    std::string path = Write("map.csv", contents);
    StatusOr<std::vector<RenderHex>> hexes = ReadMapCsv(path);
    EXPECT_EQ(hexes.status().code(), StatusCode::kInvalidArgument) << hexes.status().ToString();
    std::string message = hexes.status().message();
    EXPECT_EQ(message.rfind(path + ":", 0), 0u) << message;
    return message.substr(path.size());
  }
  std::string PathError(const std::string& contents) {
    std::string path = Write("trajectory.csv", contents);
    StatusOr<std::vector<RenderPoint>> points = ReadPathCsv(path);
    EXPECT_EQ(points.status().code(), StatusCode::kInvalidArgument) << points.status().ToString();
    std::string message = points.status().message();
    EXPECT_EQ(message.rfind(path + ":", 0), 0u) << message;
    return message.substr(path.size());
  }
  std::string dir_;
};

TEST_F(OutputReadersTest, MapUseIsTheSumOfTheSixCounts) {
  std::string path = Write("map.csv", std::string(kMapHeader) +
                                          "0,0,0.0,0.0,1,2,3,4,5,6\n"
                                          "-3,7,1.5,-2.25,0.5,0,0,0,0,0.25\n");
  StatusOr<std::vector<RenderHex>> hexes = ReadMapCsv(path);
  ASSERT_TRUE(hexes.ok()) << hexes.status().ToString();
  ASSERT_EQ(hexes->size(), 2u);
  EXPECT_EQ((*hexes)[0].q, 0);
  EXPECT_EQ((*hexes)[0].r, 0);
  EXPECT_DOUBLE_EQ((*hexes)[0].use, 21.0);
  EXPECT_EQ((*hexes)[1].q, -3);
  EXPECT_EQ((*hexes)[1].r, 7);
  EXPECT_DOUBLE_EQ((*hexes)[1].use, 0.75);
}

TEST_F(OutputReadersTest, MapAcceptsCrlfBlankLinesSpacesPlusSignsAndExtraColumns) {
  std::string path = Write("map.csv",
                           "q, r ,x,y,c0,c1,c2,c3,c4,c5,note\r\n"
                           "\r\n"
                           " 2 ,+3, 1e1 ,4,1,1,1,1,1,+1 ,hello\r\n"
                           "   \n"
                           "4,5,0,0,0,0,0,0,0,2,\n");  // last line without a final newline
  StatusOr<std::vector<RenderHex>> hexes = ReadMapCsv(path);
  ASSERT_TRUE(hexes.ok()) << hexes.status().ToString();
  ASSERT_EQ(hexes->size(), 2u);
  EXPECT_EQ((*hexes)[0].q, 2);
  EXPECT_EQ((*hexes)[0].r, 3);
  EXPECT_DOUBLE_EQ((*hexes)[0].use, 6.0);
  EXPECT_DOUBLE_EQ((*hexes)[1].use, 2.0);
}

// A prior map keeps the counts and the centres, and a centre that is not (q, r)'s at the run's
// hexagon radius (a map made with another radius) is an error at its column.
TEST_F(OutputReadersTest, PriorMapKeepsCountsAndChecksTheCentresAgainstTheRadius) {
  const std::string path = Write("map.csv", std::string(kMapHeader) +
                                                "0,0,0.0000,0.0000,1,2,3,4,5,6\n"
                                                "1,2,1.7321,1.5000,0.5,0,0,0,0,0.25\n");
  StatusOr<std::vector<HexCounts>> hexes = ReadPriorMapCsv(path, 0.5);
  ASSERT_TRUE(hexes.ok()) << hexes.status().ToString();
  ASSERT_EQ(hexes->size(), 2u);
  EXPECT_EQ((*hexes)[1].q, 1);
  EXPECT_EQ((*hexes)[1].r, 2);
  EXPECT_EQ((*hexes)[1].counts[0], 0.5);
  EXPECT_EQ((*hexes)[1].counts[5], 0.25);
  EXPECT_EQ((*hexes)[0].counts[3], 4.0);
  StatusOr<std::vector<HexCounts>> other = ReadPriorMapCsv(path, 0.6);
  EXPECT_EQ(other.status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(other.status().message(),
            path +
                ":3:5: x: \"1.7321\" is not the centre of hexagon (q=1, r=2) at hex_radius_m = "
                "0.6 (expected 2.0785): the map was made with another hexagon radius");
  const std::string bad = Write("bad.csv", std::string(kMapHeader) + "0,0,0,0,1,2,-3,4,5,6\n");
  EXPECT_EQ(ReadPriorMapCsv(bad, 0.5).status().message(),
            bad + ":2:13: c2: \"-3\" is negative (counts are >= 0)");
}

TEST_F(OutputReadersTest, MapWithOnlyAHeaderIsEmpty) {
  StatusOr<std::vector<RenderHex>> hexes = ReadMapCsv(Write("map.csv", kMapHeader));
  ASSERT_TRUE(hexes.ok());
  EXPECT_TRUE(hexes->empty());
}

TEST_F(OutputReadersTest, MissingFileIsNotFoundNamingThePath) {
  std::string path = dir_ + "/absent.csv";
  StatusOr<std::vector<RenderHex>> hexes = ReadMapCsv(path);
  EXPECT_EQ(hexes.status().code(), StatusCode::kNotFound);
  EXPECT_NE(hexes.status().message().find(path), std::string::npos);
  EXPECT_EQ(ReadPathCsv(path).status().code(), StatusCode::kNotFound);
}

TEST_F(OutputReadersTest, UnreadableFileIsAnIoError) {
  // A directory opens but cannot be read.
  EXPECT_EQ(ReadPathCsv(dir_).status().code(), StatusCode::kIoError);
}

TEST_F(OutputReadersTest, EmptyMapFileReportsTheMissingHeader) {
  EXPECT_EQ(MapError(""), ":1:1: missing header (expected \"q,r,x,y,c0,c1,c2,c3,c4,c5\")");
}

TEST_F(OutputReadersTest, WrongHeaderNameReportsItsColumn) {
  EXPECT_EQ(MapError("q,r,x,y,c0,c1,c9,c3,c4,c5\n"),
            ":1:15: header: expected \"c2\", found \"c9\" (the header "
            "\"q,r,x,y,c0,c1,c2,c3,c4,c5\" is required)");
}

TEST_F(OutputReadersTest, ShortHeaderReportsTheMissingColumnAtTheEndOfTheLine) {
  EXPECT_EQ(MapError("q,r,x,y,c0\n"),
            ":1:11: header: missing column \"c1\" (expected \"q,r,x,y,c0,c1,c2,c3,c4,c5\")");
}

TEST_F(OutputReadersTest, DataWithoutHeaderIsRejected) {
  EXPECT_EQ(MapError("0,0,0,0,1,1,1,1,1,1\n").substr(0, 33), ":1:1: header: expected \"q\", found");
}

TEST_F(OutputReadersTest, BadNumberReportsLineColumnAndField) {
  EXPECT_EQ(MapError(std::string(kMapHeader) + "0,0,0,0,1,1,1,1,1,1\n1,2,3,4,5,6,x,8,9,10\n"),
            ":3:13: c2: \"x\" is not a number");
  EXPECT_EQ(MapError(std::string(kMapHeader) + "0,0,0,0,1,1,1.5e,1,1,1\n"),
            ":2:13: c2: \"1.5e\" is not a number");
}

TEST_F(OutputReadersTest, NanAndInfinityAreRejected) {
  EXPECT_EQ(MapError(std::string(kMapHeader) + "0,0,nan,0,1,1,1,1,1,1\n"),
            ":2:5: x: \"nan\" is not finite");
  EXPECT_EQ(MapError(std::string(kMapHeader) + "0,0,0,-inf,1,1,1,1,1,1\n"),
            ":2:7: y: \"-inf\" is not finite");
  EXPECT_EQ(MapError(std::string(kMapHeader) + "0,0,0,0,1,1,1,1,1,1e999\n"),
            ":2:19: c5: \"1e999\" is out of range");
}

TEST_F(OutputReadersTest, NegativeCountIsRejected) {
  EXPECT_EQ(MapError(std::string(kMapHeader) + "0,0,0,0,1,-2,1,1,1,1\n"),
            ":2:11: c1: \"-2\" is negative (counts are >= 0)");
}

TEST_F(OutputReadersTest, HexCoordinatesMustBeInt32) {
  EXPECT_EQ(MapError(std::string(kMapHeader) + "1.5,0,0,0,1,1,1,1,1,1\n"),
            ":2:1: q: \"1.5\" is not an integer");
  EXPECT_EQ(MapError(std::string(kMapHeader) + "0,3000000000,0,0,1,1,1,1,1,1\n"),
            ":2:3: r: \"3000000000\" is outside the int32 range");
}

TEST_F(OutputReadersTest, EmptyFieldIsAMissingValue) {
  EXPECT_EQ(MapError(std::string(kMapHeader) + "0,0,0,0,1,1,,1,1,1\n"), ":2:13: c2: missing value");
}

TEST_F(OutputReadersTest, WrongFieldCountIsReported) {
  EXPECT_EQ(MapError(std::string(kMapHeader) + "0,0,0,0,1,1\n"),
            ":2:12: expected 10 fields, found 6");
  EXPECT_EQ(MapError(std::string(kMapHeader) + "0,0,0,0,1,1,1,1,1,1,7\n"),
            ":2:21: expected 10 fields, found 11");
}

TEST_F(OutputReadersTest, DuplicateHexagonNamesTheFirstLine) {
  EXPECT_EQ(MapError(std::string(kMapHeader) + "1,-1,0,0,1,1,1,1,1,1\n\n1,-1,0,0,1,1,1,1,1,1\n"),
            ":4:1: duplicate hexagon (q=1, r=-1) (first on line 2)");
}

TEST_F(OutputReadersTest, LongBadFieldIsShortenedInTheMessage) {
  std::string junk(500, 'z');
  std::string message = MapError(std::string(kMapHeader) + "0,0,0,0,1,1,1,1,1," + junk + "\n");
  EXPECT_LT(message.size(), 100u) << message;
  EXPECT_NE(message.find("...\" is not a number"), std::string::npos) << message;
}

// Regression: header and field text was echoed raw, control bytes, escape
// sequences and NULs included.
TEST_F(OutputReadersTest, ControlBytesInHeaderAndFieldsAreEscaped) {
  EXPECT_EQ(PathError(std::string("t,x,\x1b[2J\0\n", 9)),
            ":1:5: header: expected \"y\", found \"\\x1b[2J\\x00\" (the header \"t,x,y\" is "
            "required)");
  EXPECT_EQ(MapError(std::string(kMapHeader) + "0,\x9b"
                                               "31m,0,0,1,1,1,1,1,1\n"),
            ":2:3: r: \"\\x9b31m\" is not an integer");
}

TEST_F(OutputReadersTest, TrajectoryGivesPointsInOrder) {
  std::string path =
      Write("trajectory.csv", "t,x,y,heading\n0,0,0,0\n0.5,1.25,-2,0.1\n1.0,3,4.5,3.14\n");
  StatusOr<std::vector<RenderPoint>> points = ReadPathCsv(path);
  ASSERT_TRUE(points.ok()) << points.status().ToString();
  ASSERT_EQ(points->size(), 3u);
  EXPECT_DOUBLE_EQ((*points)[1].x_m, 1.25);
  EXPECT_DOUBLE_EQ((*points)[1].y_m, -2.0);
  EXPECT_DOUBLE_EQ((*points)[2].x_m, 3.0);
  EXPECT_DOUBLE_EQ((*points)[2].y_m, 4.5);
}

TEST_F(OutputReadersTest, AnyCsvStartingWithTXYIsAPath) {
  StatusOr<std::vector<RenderPoint>> points = ReadPathCsv(Write("odometry.csv", "t,x,y\n0,1,2\n"));
  ASSERT_TRUE(points.ok()) << points.status().ToString();
  ASSERT_EQ(points->size(), 1u);
  EXPECT_DOUBLE_EQ((*points)[0].x_m, 1.0);
  EXPECT_DOUBLE_EQ((*points)[0].y_m, 2.0);
}

TEST_F(OutputReadersTest, PathErrorsNameTheField) {
  EXPECT_EQ(PathError("t,x,z\n"),
            ":1:5: header: expected \"y\", found \"z\" (the header \"t,x,y\" is required)");
  EXPECT_EQ(PathError("t,x,y,heading\n0,1,abc,0\n"), ":2:5: y: \"abc\" is not a number");
  EXPECT_EQ(PathError("t,x,y,heading\ninf,1,2,0\n"), ":2:1: t: \"inf\" is not finite");
  EXPECT_EQ(PathError("t,x,y,heading\n0,1,2\n"), ":2:6: expected 4 fields, found 3");
}

}  // namespace
}  // namespace grove::tools
