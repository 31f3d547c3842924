// Replays the committed fuzz corpora (tests/fuzz/corpus/) through the fuzzers' property checks
// (tests/fuzz/fuzz_checks.h), so the corpus runs in the normal test suite, and holds the minimal
// reproducers of the bugs the fuzzers found, each test named after its bug.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "grove/config_json.h"
#include "grove/footslam.h"
#include "grove/status.h"
#include "tests/fuzz/fuzz_checks.h"
#include "tools/io/step_reader.h"

#ifndef GROVE_FUZZ_CORPUS
#error "GROVE_FUZZ_CORPUS must name the tests/fuzz/corpus directory"
#endif

namespace grove::testing {
namespace {

using CheckFunction = std::string (*)(const uint8_t*, size_t);

std::string RunCheck(CheckFunction check, const std::string& input) {
  return check(reinterpret_cast<const uint8_t*>(input.data()), input.size());
}

// Runs `check` on every file of the corpus of `target`; returns how many files it read.
size_t ReplayCorpus(const std::string& target, CheckFunction check) {
  const std::filesystem::path dir = std::filesystem::path(GROVE_FUZZ_CORPUS) / target;
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.is_regular_file()) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  for (const std::filesystem::path& file : files) {
    std::ifstream in(file, std::ios::binary);
    const std::string input((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_TRUE(in.good() || in.eof()) << "cannot read " << file;
    EXPECT_EQ(RunCheck(check, input), "") << file;
  }
  return files.size();
}

TEST(FuzzCorpusTest, StepReaderCorpusKeepsItsProperties) {
  EXPECT_GE(ReplayCorpus("step_reader", &CheckStepReader), 5u);
}

TEST(FuzzCorpusTest, ConfigJsonCorpusKeepsItsProperties) {
  EXPECT_GE(ReplayCorpus("config_json", &CheckConfigJson), 5u);
}

TEST(FuzzCorpusTest, CheckpointCorpusKeepsItsProperties) {
  EXPECT_GE(ReplayCorpus("checkpoint", &CheckCheckpoint), 3u);
}

TEST(FuzzCorpusTest, CsvReadersCorpusKeepsItsProperties) {
  EXPECT_GE(ReplayCorpus("csv_readers", &CheckCsvReaders), 5u);
}

// The checks themselves must be able to fail.
TEST(FuzzChecksTest, ReportBrokenProperties) {
  // A valid file passes, and a property the reader keeps is not reported.
  EXPECT_EQ(RunCheck(&CheckStepReader, "t,dx,dy\n1,0.5,0\n2,0.5,0\n"), "");
  EXPECT_EQ(RunCheck(&CheckCsvReaders, "t,x,y\n0,0,0\n"), "");
  EXPECT_EQ(RunCheck(&CheckConfigJson, "{\"particles\": 5}"), "");
  // Error positions are checked against the input.
  const std::string text = "t,dx,dy\n1,2\n";
  EXPECT_EQ(fuzz_internal::CheckError(InvalidArgumentError("f:2:1: bad"), "f", text), "");
  EXPECT_NE(fuzz_internal::CheckError(InvalidArgumentError("f:3:1: bad"), "f", text), "");
  EXPECT_NE(fuzz_internal::CheckError(InvalidArgumentError("f:2:5: bad"), "f", text), "");
  EXPECT_NE(fuzz_internal::CheckError(InvalidArgumentError("f:2:1: two\nlines"), "f", text), "");
  EXPECT_NE(fuzz_internal::CheckError(InvalidArgumentError("g:2:1: bad"), "f", text), "");
  EXPECT_NE(fuzz_internal::CheckError(NotFoundError("f: missing"), "f", text), "");
}

// Bug: ApplyConfigJson catches only json::parse_error, but nlohmann::json::parse throws
// json::out_of_range (406) for a number literal that overflows a double, so the exception left
// the function (config_json_fuzzer, first seconds).
TEST(ConfigJsonRegressionTest, NumberOverflowIsAnErrorNotAnException) {
  for (const std::string text : {"{\"hex_radius_m\": 1e400}", "-1e999"}) {
    FootSlamConfig config;
    Status status;
    EXPECT_NO_THROW(status = ApplyConfigJson(FootSlamConfigFields(), "c.json", text, &config))
        << text;
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << text;
    EXPECT_TRUE(status.message().starts_with("c.json:")) << status.message();
    EXPECT_EQ(config.hex_radius_m, FootSlamConfig().hex_radius_m);
  }
}

// Bug: the "unknown key" message prints the decoded key, so a key written with the escape \n puts
// a line break (any control character, in fact) into the one-line error message.
TEST(ConfigJsonRegressionTest, UnknownKeyWithEscapedNewlineGivesOneLineMessage) {
  FootSlamConfig config;
  const Status status =
      ApplyConfigJson(FootSlamConfigFields(), "c.json", "{\"a\\nb\": 1}", &config);
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(status.message().find('\n'), std::string::npos) << status.message();
}

// Bug: for a signed field, an integer above INT64_MAX (json stores it unsigned) is cast to int64_t
// and wraps before the range check, so 18446744073709551615 is applied as -1.
TEST(ConfigJsonRegressionTest, IntegerAboveInt64MaxIsRejectedNotWrapped) {
  for (const std::string text :
       {"{\"particles\": 18446744073709551615}", "{\"batch\": 9223372036854775808}",
        "{\"degree\": 18446744073709551600}"}) {
    FootSlamConfig config;
    const Status status = ApplyConfigJson(FootSlamConfigFields(), "c.json", text, &config);
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << text;
    EXPECT_EQ(config.particles, FootSlamConfig().particles) << text;
    EXPECT_EQ(config.batch, FootSlamConfig().batch) << text;
    EXPECT_EQ(config.degree, FootSlamConfig().degree) << text;
  }
}

// Bug: with one t,dx,dy row the start time is t - 1, which rounds to t once |t| >= 2^53, so the
// start is not before the first step and the engine rejects that step.
TEST(StepReaderRegressionTest, OneRowStartTimeIsBeforeTheStepForLargeTimes) {
  // Times are now bounded to +-1e12 s: such a file is refused with the position of the field.
  StatusOr<tools::StepReader> reader = tools::StepReader::OpenText("s.csv", "t,dx,dy\n1e17,0,0\n");
  ASSERT_FALSE(reader.ok());
  EXPECT_TRUE(reader.status().message().starts_with("s.csv:2:1: t = 1e+17: must be within"))
      << reader.status().message();
  // Inside the bound, one row's start time is strictly before the step.
  reader = tools::StepReader::OpenText("s.csv", "t,dx,dy\n999999999999.5,0,0\n");
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  tools::StepRecord step;
  StatusOr<bool> more = reader->Next(&step);
  ASSERT_TRUE(more.ok() && *more) << more.status().ToString();
  EXPECT_LT(reader->start_time_s(), step.t_s);
}

// Bug: with two t,dx,dy rows the start time t1 - (t2 - t1) overflows to -inf for finite times
// far apart; the reader promises finite times.
TEST(StepReaderRegressionTest, StartTimeIsFiniteWhenTheFirstPeriodOverflows) {
  StatusOr<tools::StepReader> reader =
      tools::StepReader::OpenText("s.csv", "t,dx,dy\n-1e308,0,0\n1e308,0,0\n");
  if (!reader.ok()) {
    EXPECT_TRUE(reader.status().message().starts_with("s.csv:")) << reader.status().message();
    return;
  }
  tools::StepRecord step;
  StatusOr<bool> more = reader->Next(&step);
  ASSERT_TRUE(more.ok() && *more) << more.status().ToString();
  EXPECT_TRUE(std::isfinite(reader->start_time_s())) << reader->start_time_s();
  EXPECT_LT(reader->start_time_s(), step.t_s);
}

}  // namespace
}  // namespace grove::testing
