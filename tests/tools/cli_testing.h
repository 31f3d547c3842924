// The fixture of the `grove` command's end-to-end tests: each test gets a directory of its own
// and runs the binary with its output captured.
#ifndef GROVE_TESTS_TOOLS_CLI_TESTING_H_
#define GROVE_TESTS_TOOLS_CLI_TESTING_H_

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace grove::testing {

namespace fs = std::filesystem;

struct Outcome {
  int exit_code;
  std::string out;
  std::string err;
};

inline std::string Slurp(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A CSV text without its last column.
inline std::string WithoutLastColumn(const std::string& csv) {
  std::istringstream in(csv);
  std::string line, out;
  while (std::getline(in, line)) out += line.substr(0, line.rfind(',')) + "\n";
  return out;
}

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // The process id too: two test runs on one machine (a build and a sanitizer build) must not
    // share a directory.
    dir_ = fs::path(::testing::TempDir()) /
           ("grove_cli_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  Outcome Grove(const std::string& args) {
    std::string cmd = std::string(GROVE_BINARY) + " " + args + " >" + (dir_ / "stdout").string() +
                      " 2>" + (dir_ / "stderr").string();
    int status = std::system(cmd.c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, Slurp(dir_ / "stdout"),
            Slurp(dir_ / "stderr")};
  }
  std::string Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return (dir_ / name).string();
  }
  // Runs on a bad step file and checks the error and that --out stays absent.
  void ExpectInputError(const std::string& text, const std::string& where,
                        const std::string& what) {
    SCOPED_TRACE(text);
    std::string steps = Write("steps.csv", text);
    fs::path out = dir_ / "out";
    Outcome o = Grove("footslam run --no-progress --particles 50 --steps " + steps + " --out " +
                      out.string());
    EXPECT_EQ(o.exit_code, 3) << o.err;
    EXPECT_NE(o.err.find(steps + ":" + where), std::string::npos) << o.err;
    EXPECT_NE(o.err.find(what), std::string::npos) << o.err;
    EXPECT_FALSE(fs::exists(out)) << "a failed run left " << out;
  }

  fs::path dir_;
};

}  // namespace grove::testing

#endif  // GROVE_TESTS_TOOLS_CLI_TESTING_H_
