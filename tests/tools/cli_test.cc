// The grove command end to end: exit codes, one-line errors with file:line:column, nothing left
// in --out after a failure, and a full run's outputs.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>

#include "tests/tools/cli_testing.h"

namespace {

using grove::testing::CliTest;
using grove::testing::Outcome;
using grove::testing::Slurp;
using grove::testing::WithoutLastColumn;
namespace fs = std::filesystem;

TEST_F(CliTest, MalformedStepFilesStopWithFileLineColumn) {
  ExpectInputError("t,dx,dy\n1,0.7,0\n2,abc,0\n", "3:3:", "is not a number");
  ExpectInputError("t,dx,dy\n1,0.7,0\n2,nan,0\n", "3:3:", "must be finite");
  ExpectInputError("t,dx,dy\n1,0.7,0\n0.5,0.7,0\n", "3:1:", "strictly increasing");
  ExpectInputError("t,dx,dy\n1,0.7,0\n1,0.7,0\n", "3:1:", "strictly increasing");
  ExpectInputError("t,dx,dy\n1,0.7,0\n2,0.7\n", "3:1:", "expected 3 fields");
  ExpectInputError("t,dx,dz\n1,0.7,0\n", "1:1:", "unknown header");
  ExpectInputError("t,dx,dy\n1,0.7,0\n2,40,0\n", "3:1:", "longer than max_step_m");
  ExpectInputError("t,x,y\n0,0,0\n1,0.7,inf\n", "3:7:", "must be finite");
}

TEST_F(CliTest, EmptyOrHeaderOnlyFilesAreErrors) {
  fs::path out = dir_ / "out";
  std::string empty = Write("empty.csv", "");
  Outcome o = Grove("footslam run --no-progress --steps " + empty + " --out " + out.string());
  EXPECT_EQ(o.exit_code, 3);
  EXPECT_NE(o.err.find("empty file"), std::string::npos) << o.err;
  std::string header = Write("header.csv", "t,dx,dy\n");
  o = Grove("footslam run --no-progress --steps " + header + " --out " + out.string());
  EXPECT_EQ(o.exit_code, 3);
  EXPECT_NE(o.err.find("no steps"), std::string::npos) << o.err;
  o = Grove("footslam run --no-progress --steps " + (dir_ / "missing.csv").string() + " --out " +
            out.string());
  EXPECT_EQ(o.exit_code, 3);
  EXPECT_NE(o.err.find("missing.csv"), std::string::npos) << o.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(CliTest, ConfigErrorsNameTheKeyAndSuggest) {
  std::string cfg = Write("c.json", "{\n  \"particels\": 10\n}\n");
  Outcome o = Grove("footslam run --print-config --config " + cfg);
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find(cfg + ":2:3: unknown key \"particels\" (did you mean \"particles\"?)"),
            std::string::npos)
      << o.err;
  cfg = Write("c.json", "{\"degree\": \"sixteen\"}");
  o = Grove("footslam run --print-config --config " + cfg);
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find("degree = \"sixteen\": must be an integer"), std::string::npos) << o.err;
  cfg = Write("c.json", "{\"degree\": 16,,}");
  o = Grove("footslam run --print-config --config " + cfg);
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find(cfg + ":1:15: invalid JSON"), std::string::npos) << o.err;
  cfg = Write("c.json", "{\"resample_threshold\": 0}");
  o = Grove("footslam run --out " + (dir_ / "out").string() + " --config " + cfg);
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find("resample_threshold = 0: must be in (0, 1]"), std::string::npos) << o.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(CliTest, PrintConfigShowsFileAndFlagValues) {
  std::string cfg = Write("c.json", "{\"particles\": 1234, \"degree\": 4}");
  Outcome o = Grove("footslam run --print-config --config " + cfg + " --degree 64 --grid-size 64");
  EXPECT_EQ(o.exit_code, 0) << o.err;
  EXPECT_NE(o.out.find("\"particles\": 1234"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("\"degree\": 64"), std::string::npos) << o.out;
}

TEST_F(CliTest, SimulateRunEvaluateAndRenderEndToEnd) {
  fs::path sim = dir_ / "sim", out = dir_ / "out";
  Outcome o = Grove("footslam simulate --minutes 1 --seed 3 --out " + sim.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  o = Grove("footslam run --no-progress --particles 300 --threads 2 --steps " +
            (sim / "steps.csv").string() + " --out " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  for (const char* name : {"map.csv", "map_best.csv", "trajectory.csv", "mean_trajectory.csv",
                           "map.png", "map.svg", "summary.json"}) {
    EXPECT_TRUE(fs::exists(out / name)) << name;
  }
  EXPECT_EQ(Slurp(out / "map.csv").rfind("q,r,x,y,c0,c1,c2,c3,c4,c5\n", 0), 0u);
  EXPECT_NE(Slurp(out / "summary.json").find("\"particle_steps_per_s\""), std::string::npos);
  for (const auto& entry : fs::directory_iterator(out)) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos)
        << "temporary left behind: " << entry.path();
  }
  o = Grove("footslam evaluate --truth " + (sim / "truth.csv").string() + " --trajectory " +
            (out / "trajectory.csv").string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_NE(o.out.find("\"aligned_rmse_m\""), std::string::npos) << o.out;
  fs::remove(out / "map.png");
  o = Grove("footslam render --dir " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_TRUE(fs::exists(out / "map.png"));
}

TEST_F(CliTest, FailedRunKeepsEarlierOutputs) {
  fs::path out = dir_ / "out";
  std::string good = Write("good.csv", "t,dx,dy\n1,0.7,0\n2,0.7,0\n");
  ASSERT_EQ(
      Grove("footslam run --no-progress --particles 20 --steps " + good + " --out " + out.string())
          .exit_code,
      0);
  std::string before = Slurp(out / "map.csv");
  std::string bad = Write("bad.csv", "t,dx,dy\n1,0.7,0\n2,x,0\n");
  EXPECT_EQ(
      Grove("footslam run --no-progress --particles 20 --steps " + bad + " --out " + out.string())
          .exit_code,
      3);
  EXPECT_EQ(Slurp(out / "map.csv"), before);
}

TEST_F(CliTest, RunOverTheMemoryBudgetIsRefusedBeforeItStarts) {
  fs::path out = dir_ / "out";
  Outcome o = Grove("footslam run --no-progress --memory-budget 20M --out " + out.string());
  EXPECT_EQ(o.exit_code, 6) << o.err;
  EXPECT_NE(o.err.find("the run is predicted to need"), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("more than the --memory-budget of 20.0 MiB"), std::string::npos) << o.err;
  EXPECT_FALSE(fs::exists(out));
  o = Grove("footslam run --no-progress --memory-budget 12X --out " + out.string());
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_NE(o.err.find("--memory-budget = \"12X\""), std::string::npos) << o.err;
  o = Grove("footslam run --no-progress --particles 100 --memory-budget 1.5G --out " +
            out.string());
  EXPECT_EQ(o.exit_code, 0) << o.err;
  EXPECT_NE(Slurp(out / "summary.json").find("\"predicted_peak_bytes\""), std::string::npos);
}

TEST_F(CliTest, HelpOnEveryLevel) {
  for (const char* args :
       {"--help", "footslam --help", "footslam run --help", "footslam simulate --help",
        "footslam evaluate --help", "footslam render --help"}) {
    Outcome o = Grove(args);
    EXPECT_EQ(o.exit_code, 0) << args;
    EXPECT_NE(o.out.find("Usage"), std::string::npos) << args << ": " << o.out;
  }
  EXPECT_EQ(Grove("footslam bogus").exit_code, 2);
}

TEST_F(CliTest, VersionNamesTheBuild) {
  Outcome o = Grove("--version");
  EXPECT_EQ(o.exit_code, 0) << o.err;
  ASSERT_EQ(o.out.rfind("grove ", 0), 0u) << o.out;
  const std::string version = o.out.substr(6, o.out.find(' ', 6) - 6);  // "0.3.0"
  EXPECT_EQ(std::count(version.begin(), version.end(), '.'), 2) << o.out;
  EXPECT_NE(o.out.find(" (commit "), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("; SIMD: "), std::string::npos) << o.out;
  // The same in the run's manifest.
  const fs::path out = dir_ / "out";
  ASSERT_EQ(Grove("footslam run --no-progress --particles 20 --out " + out.string()).exit_code, 0);
  const nlohmann::json summary = nlohmann::json::parse(Slurp(out / "summary.json"));
  EXPECT_EQ(summary["grove"]["version"], version);
  EXPECT_FALSE(summary["grove"]["simd_targets"].get<std::string>().empty());
}

// The outputs that must not depend on interruptions (summary.json holds timings).
void ExpectSameOutputs(const fs::path& a, const fs::path& b) {
  for (const char* name :
       {"map.csv", "map_best.csv", "trajectory.csv", "mean_trajectory.csv", "map.png", "map.svg"}) {
    EXPECT_TRUE(Slurp(a / name) == Slurp(b / name)) << name << " differs";
  }
}

TEST_F(CliTest, ResumingFromAPeriodicCheckpointGivesIdenticalOutputs) {
  fs::path full = dir_ / "full", part = dir_ / "part", resumed = dir_ / "resumed";
  const std::string run = "footslam run --no-progress --particles 400 ";
  ASSERT_EQ(Grove(run + "--threads 2 --out " + full.string()).exit_code, 0);
  // The bundled walk has 872 steps: the last checkpoint is at step 800.
  Outcome o = Grove(run + "--threads 1 --checkpoint-every 200 --out " + part.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  fs::copy_file(part / "checkpoint.grove", dir_ / "at800.grove");
  o = Grove(run + "--threads 2 --resume " + (dir_ / "at800.grove").string() + " --out " +
            resumed.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_NE(Slurp(resumed / "summary.json").find("\"steps\": 872"), std::string::npos);
  ExpectSameOutputs(full, resumed);
}

// --prior-map: a run's map.csv feeds a second run (summary.json says how many hexagons it
// used); a bad row stops before the first step with FILE:LINE:COLUMN, and a resumed run refuses
// a prior map (its checkpoint carries the one it started with).
TEST_F(CliTest, APriorMapFromAnEarlierRunFeedsASecondRun) {
  fs::path first = dir_ / "first", second = dir_ / "second", bad_out = dir_ / "bad";
  const std::string run = "footslam run --no-progress --particles 200 ";
  ASSERT_EQ(Grove(run + "--out " + first.string()).exit_code, 0);
  const std::string prior = (first / "map.csv").string();
  Outcome o = Grove(run + "--prior-map " + prior + " --out " + second.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  const std::string summary = Slurp(second / "summary.json");
  EXPECT_NE(summary.find("\"prior_map\""), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"hexagons_outside_grid\": 0"), std::string::npos) << summary;
  EXPECT_NE(Slurp(second / "map.csv"), Slurp(first / "map.csv"));
  const std::string bad = Write("prior.csv",
                                "q,r,x,y,c0,c1,c2,c3,c4,c5\n0,0,0,0,1,1,1,1,1,1\n"
                                "1,0,0.8660,0,1,1,x,1,1,1\n");
  o = Grove(run + "--prior-map " + bad + " --out " + bad_out.string());
  EXPECT_EQ(o.exit_code, 3) << o.err;
  EXPECT_NE(o.err.find(bad + ":3:18: c2: \"x\" is not a number"), std::string::npos) << o.err;
  EXPECT_FALSE(fs::exists(bad_out));
  o = Grove(run + "--hex-radius-m 0.6 --prior-map " + prior + " --out " + bad_out.string());
  EXPECT_EQ(o.exit_code, 3) << o.err;
  EXPECT_NE(o.err.find("the map was made with another hexagon radius"), std::string::npos) << o.err;
  o = Grove(run + "--checkpoint-every 100 --prior-map " + prior + " --out " + bad_out.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  o = Grove(run + "--resume " + (bad_out / "checkpoint.grove").string() + " --prior-map " + prior +
            " --out " + (dir_ / "resumed").string());
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_NE(o.err.find("resume without --prior-map"), std::string::npos) << o.err;
}

TEST_F(CliTest, BadCheckpointsAreRefused) {
  fs::path out = dir_ / "out";
  std::string steps = Write("steps.csv", "t,dx,dy\n1,0.7,0\n2,0.7,0\n3,0,0.7\n4,-0.7,0\n");
  const std::string run = "footslam run --no-progress --particles 30 --steps " + steps + " ";
  fs::path ckpt = dir_ / "c.grove";
  ASSERT_EQ(
      Grove(run + "--checkpoint-every 2 --checkpoint " + ckpt.string() + " --out " + out.string())
          .exit_code,
      0);
  const std::string good = Slurp(ckpt);
  auto resume = [&](const std::string& extra, const std::string& bytes) {
    std::string path = Write("bad.grove", bytes);
    return Grove(run + extra + "--resume " + path + " --out " + (dir_ / "r").string());
  };
  ASSERT_EQ(resume("", good).exit_code, 0);

  Outcome o = resume("", good.substr(0, good.size() / 2));
  EXPECT_EQ(o.exit_code, 3);
  EXPECT_NE(o.err.find("bad.grove: truncated"), std::string::npos) << o.err;
  std::string flipped = good;
  flipped[flipped.size() - 40] ^= 0x20;
  o = resume("", flipped);
  EXPECT_EQ(o.exit_code, 3);
  EXPECT_NE(o.err.find("checksum mismatch"), std::string::npos) << o.err;
  o = resume("", "t,dx,dy\n");
  EXPECT_EQ(o.exit_code, 3);
  EXPECT_NE(o.err.find("not a grove checkpoint"), std::string::npos) << o.err;
  o = resume("--seed 2 ", good);
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find("made with seed = 1, this configuration has seed = 2"), std::string::npos)
      << o.err;
  o = Grove(run + "--resume " + (dir_ / "missing.grove").string() + " --out " + out.string());
  EXPECT_EQ(o.exit_code, 3);
  EXPECT_NE(o.err.find("missing.grove: cannot open"), std::string::npos) << o.err;
  o = Grove(run + "--resume " + dir_.string() + " --out " + out.string());
  EXPECT_EQ(o.exit_code, 3) << "a directory is a bad input, not an output error: " << o.err;
  o = Grove("footslam run --no-progress --steps " + dir_.string() + " --out " + out.string());
  EXPECT_EQ(o.exit_code, 3) << o.err;

  // Another step file: different steps, or too few of them.
  std::string other = Write("other.csv", "t,dx,dy\n1,0.7,0\n2,0.6,0\n3,0,0.7\n4,-0.7,0\n");
  o = Grove("footslam run --no-progress --particles 30 --steps " + other + " --resume " +
            ckpt.string() + " --out " + out.string());
  EXPECT_EQ(o.exit_code, 3);
  EXPECT_NE(o.err.find("the first 4 steps differ"), std::string::npos) << o.err;
  std::string shorter = Write("short.csv", "t,dx,dy\n1,0.7,0\n2,0.7,0\n");
  o = Grove("footslam run --no-progress --particles 30 --steps " + shorter + " --resume " +
            ckpt.string() + " --out " + out.string());
  EXPECT_EQ(o.exit_code, 3);
  EXPECT_NE(o.err.find("has 2 steps, but"), std::string::npos) << o.err;
}

TEST_F(CliTest, SigtermStopsAtAStepBoundaryWithACheckpoint) {
  fs::path full = dir_ / "full", out = dir_ / "out";
  const std::string run = "footslam run --no-progress --particles 4000 ";
  ASSERT_EQ(Grove(run + "--out " + full.string()).exit_code, 0);

  // Start the same run in the background; signal it once its first periodic checkpoint exists
  // (the run is then well before its end).
  fs::path ckpt = dir_ / "c.grove", err = dir_ / "bg.err", pid_file = dir_ / "pid";
  std::string cmd = std::string(GROVE_BINARY) + " " + run + "--checkpoint-every 25 --checkpoint " +
                    ckpt.string() + " --out " + out.string() + " 2>" + err.string() +
                    " & echo $! >" + pid_file.string() + "; wait $!; echo $? >" +
                    (dir_ / "rc").string();
  std::string bg = "sh -c '" + cmd + "' &";
  ASSERT_EQ(std::system(bg.c_str()), 0);
  while (!fs::exists(ckpt) || !fs::exists(pid_file) || Slurp(pid_file).empty()) {
    ASSERT_FALSE(fs::exists(dir_ / "rc"))
        << "the run ended before it was signalled: " << Slurp(err);
    std::system("sleep 0.01");
  }
  ASSERT_EQ(std::system(("kill -TERM " + Slurp(pid_file)).c_str()), 0);
  while (!fs::exists(dir_ / "rc") || Slurp(dir_ / "rc").empty()) std::system("sleep 0.01");
  EXPECT_EQ(std::stoi(Slurp(dir_ / "rc")), 143) << Slurp(err);
  EXPECT_NE(Slurp(err).find("stopped by"), std::string::npos) << Slurp(err);
  EXPECT_FALSE(fs::exists(out / "map.csv")) << "an interrupted run wrote final outputs";

  Outcome o = Grove(run + "--resume " + ckpt.string() + " --out " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  ExpectSameOutputs(full, out);
}

// grove footslam batch

size_t Occurrences(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// Three walks side by side: each walk's outputs are those of `footslam run` on it alone; a second
// batch skips every walk; a walk whose configuration changed is run again, alone.
TEST_F(CliTest, ABatchRunsEachWalkAsRunWouldAndSkipsWhatIsDone) {
  for (int s = 1; s <= 3; ++s) {
    ASSERT_EQ(Grove("footslam simulate --minutes 1 --seed " + std::to_string(s) + " --out " +
                    (dir_ / ("w" + std::to_string(s))).string())
                  .exit_code,
              0);
  }
  const std::string lines =
      "{\"name\": \"a\", \"steps\": \"w1/steps.csv\"}\n"
      "{\"name\": \"b\", \"steps\": \"w2/steps.csv\", \"config\": {\"particles\": 300}}\n\n"
      "{\"name\": \"c\", \"steps\": \"w3/steps.csv\", \"config\": {\"seed\": 5}}\n";
  const std::string manifest = Write("walks.jsonl", lines);
  const fs::path out = dir_ / "out";
  const std::string batch = "footslam batch --particles 600 --manifest " + manifest + " --out " +
                            out.string() + " --jobs ";
  Outcome o = Grove(batch + "2");
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_EQ(std::count(o.out.begin(), o.out.end(), '\n'), 3) << o.out;
  const std::string summary = Slurp(out / "batch_summary.jsonl");
  for (const char* name : {"a", "b", "c"}) {
    EXPECT_NE(summary.find(std::string("\"name\":\"") + name + "\""), std::string::npos);
  }
  EXPECT_EQ(Occurrences(summary, "\"status\":\"ok\""), 3u) << summary;
  // Walk c alone, as run does it.
  o = Grove("footslam run --no-progress --particles 600 --seed 5 --steps " +
            (dir_ / "w3" / "steps.csv").string() + " --out " + (dir_ / "solo").string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  ExpectSameOutputs(dir_ / "solo", out / "c");

  const std::string before = Slurp(out / "a" / "summary.json");
  o = Grove(batch + "1");
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_EQ(Occurrences(o.out, "\"status\":\"skipped\""), 3u) << o.out;
  EXPECT_EQ(Slurp(out / "a" / "summary.json"), before) << "a skipped walk was written again";

  std::string changed = lines;
  changed.replace(changed.find("\"seed\": 5"), 9, "\"seed\": 6");
  Write("walks.jsonl", changed);
  o = Grove(batch + "2");
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_NE(o.out.find("\"name\":\"c\",\"ns_per_particle_step\""), std::string::npos) << o.out;
  EXPECT_EQ(o.out.find("\"name\":\"c\",\"out\""), std::string::npos) << o.out;
  EXPECT_NE(Slurp(out / "c" / "trajectory.csv"), Slurp(dir_ / "solo" / "trajectory.csv"));
}

// A bad manifest line stops the batch before any walk with FILE:LINE:COLUMN; a walk that fails
// fails alone, and the exit code tells a scheduler a retry will not help.
TEST_F(CliTest, ABatchRefusesABadManifestAndReportsAFailedWalk) {
  ASSERT_EQ(Grove("footslam simulate --minutes 1 --out " + (dir_ / "w").string()).exit_code, 0);
  const fs::path out = dir_ / "out";
  struct Case {
    const char* text;
    const char* error;
  };
  for (const Case& c : {
           Case{"{\"name\": \"a\", \"steps\": \"w/steps.csv\"}\n{\"name\": \"a\", \"steps\": "
                "\"w/steps.csv\"}\n",
                "walks.jsonl:2:2: name = a: already used on line 1"},
           Case{"{\"name\": \"a\", \"steps\": \"w/steps.csv\", \"config\": {\"particles\": -4}}\n",
                "walks.jsonl:1:39: walk a: config:1:2: particles = -4: must be in"},
           Case{"{\"name\": \"a\", \"steps\": \"w/steps.csv\",}\n",
                "walks.jsonl:1:38: not a JSON object"},
           Case{"{\"name\": \"../a\", \"steps\": \"w/steps.csv\"}\n",
                "walks.jsonl:1:2: name = \"../a\""},
           Case{"{\"name\": \"a\", \"stpes\": \"w/steps.csv\"}\n",
                "walks.jsonl:1:15: unknown key \"stpes\""},
           Case{"\n\n", "walks.jsonl: no walks"},
           // Regression: the batch's own summary name was accepted and failed only at the end.
           Case{"{\"name\": \"batch_summary.jsonl\", \"steps\": \"w/steps.csv\"}\n",
                "walks.jsonl:1:2: name = \"batch_summary.jsonl\": reserved"},
           // Regression: duplicate keys were accepted, the last one winning.
           Case{"{\"name\": \"a\", \"name\": \"b\", \"steps\": \"w/steps.csv\"}\n",
                "walks.jsonl:1:15: duplicate key \"name\""},
           Case{"{\"name\": \"a\", \"steps\": \"w/steps.csv\", \"config\": {\"seed\": 1, "
                "\"seed\": 2}}\n",
                "walks.jsonl:1:61: duplicate key \"seed\""},
       }) {
    SCOPED_TRACE(c.text);
    const std::string manifest = Write("walks.jsonl", c.text);
    Outcome o = Grove("footslam batch --manifest " + manifest + " --out " + out.string());
    EXPECT_EQ(o.exit_code, 2) << o.err;
    EXPECT_NE(o.err.find(c.error), std::string::npos) << o.err;
    EXPECT_FALSE(fs::exists(out)) << "a refused batch made its output directory";
  }
  const std::string manifest = Write("walks.jsonl",
                                     "{\"name\": \"gone\", \"steps\": \"missing.csv\"}\n{\"name\": "
                                     "\"b\", \"steps\": \"w/steps.csv\"}\n");
  Outcome o =
      Grove("footslam batch --particles 200 --manifest " + manifest + " --out " + out.string());
  EXPECT_EQ(o.exit_code, 4) << o.err;
  EXPECT_NE(o.err.find("walk gone: steps"), std::string::npos) << o.err;
  EXPECT_NE(o.out.find("\"exit_code\":3,\"line\":1,\"name\":\"gone\""), std::string::npos) << o.out;
  EXPECT_TRUE(fs::exists(out / "b" / "map.csv"));
}

// SIGTERM stops a batch with the running walk checkpointed and the rest not started; the same
// command again resumes that walk and runs the rest, with the outputs of an uninterrupted run.
TEST_F(CliTest, ABatchStoppedBySigtermResumesWhereItStopped) {
  const std::string steps = (dir_ / "w" / "steps.csv").string();
  ASSERT_EQ(
      Grove("footslam simulate --minutes 8 --seed 4 --out " + (dir_ / "w").string()).exit_code, 0);
  const std::string manifest =
      Write("walks.jsonl",
            "{\"name\": \"x\", \"steps\": \"w/steps.csv\"}\n"
            "{\"name\": \"y\", \"steps\": \"w/steps.csv\", \"config\": {\"seed\": 2}}\n");
  const fs::path out = dir_ / "out";
  const std::string batch = "footslam batch --particles 4000 --checkpoint-every 25 --manifest " +
                            manifest + " --out " + out.string();
  fs::path err = dir_ / "bg.err", pid_file = dir_ / "pid", rc = dir_ / "rc";
  std::string cmd = std::string(GROVE_BINARY) + " " + batch + " >" + (dir_ / "bg.out").string() +
                    " 2>" + err.string() + " & echo $! >" + pid_file.string() +
                    "; wait $!; echo $? >" + rc.string();
  ASSERT_EQ(std::system(("sh -c '" + cmd + "' &").c_str()), 0);
  while (!fs::exists(out / "x" / "checkpoint.grove") || !fs::exists(pid_file) ||
         Slurp(pid_file).empty()) {
    ASSERT_FALSE(fs::exists(rc)) << "the batch ended before it was signalled: " << Slurp(err);
    std::system("sleep 0.01");
  }
  ASSERT_EQ(std::system(("kill -TERM " + Slurp(pid_file)).c_str()), 0);
  while (!fs::exists(rc) || Slurp(rc).empty()) std::system("sleep 0.01");
  EXPECT_EQ(std::stoi(Slurp(rc)), 143) << Slurp(err);
  // Regression: the advice was "--resume", which batch does not take.
  EXPECT_NE(Slurp(err).find("run the same batch command again: it resumes this walk"),
            std::string::npos)
      << Slurp(err);
  EXPECT_EQ(Slurp(err).find("--resume"), std::string::npos) << Slurp(err);
  const std::string stopped = Slurp(out / "batch_summary.jsonl");
  EXPECT_NE(stopped.find("\"name\":\"x\",\"out\""), std::string::npos) << stopped;
  EXPECT_NE(stopped.find("\"status\":\"stopped\""), std::string::npos) << stopped;
  EXPECT_NE(stopped.find("\"status\":\"not run\""), std::string::npos) << stopped;

  Outcome o = Grove(batch);
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_NE(o.out.find("\"resumed\":true"), std::string::npos) << o.out;
  o = Grove("footslam run --no-progress --particles 4000 --steps " + steps + " --out " +
            (dir_ / "solo").string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  ExpectSameOutputs(dir_ / "solo", out / "x");
}

// Reliability, round two (the issue's numbers in the test names' comments)

// 1: a step file from a pipe is read once, whole.
TEST_F(CliTest, StepsFromAFifoAreReadWhole) {
  fs::path sim = dir_ / "sim", out = dir_ / "out", fifo = dir_ / "steps.fifo";
  ASSERT_EQ(Grove("footslam simulate --minutes 2 --seed 5 --out " + sim.string()).exit_code, 0);
  ASSERT_EQ(std::system(("mkfifo " + fifo.string()).c_str()), 0);
  std::string feed = "cat " + (sim / "steps.csv").string() + " > " + fifo.string() + " &";
  ASSERT_EQ(std::system(feed.c_str()), 0);
  Outcome o = Grove("footslam run --no-progress --particles 200 --steps " + fifo.string() +
                    " --out " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  const std::string steps = Slurp(sim / "steps.csv");
  const auto lines = [](const std::string& t) { return std::count(t.begin(), t.end(), '\n'); };
  // The header and every step; the trajectory has the start too.
  EXPECT_EQ(lines(Slurp(out / "trajectory.csv")), lines(steps) + 1);
}

// 2: the output set is written as a whole, summary.json last naming every file, and a second
// run into a directory in use is refused.
TEST_F(CliTest, OutputsAreASetWithAManifestAndTheDirectoryIsLocked) {
  fs::path out = dir_ / "out";
  const std::string run = "footslam run --no-progress --particles 50 --out " + out.string();
  fs::create_directories(out / ".grove-staging-old");  // what a killed run left
  Outcome o = Grove(run);
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_FALSE(fs::exists(out / ".grove-staging-old"));
  const std::string summary = Slurp(out / "summary.json");
  EXPECT_NE(summary.find("\"run_id\""), std::string::npos);
  for (const char* name :
       {"map.csv", "map_best.csv", "trajectory.csv", "mean_trajectory.csv", "map.png", "map.svg"}) {
    const std::string entry = "\"" + std::string(name) + "\": {\n      \"bytes\": " +
                              std::to_string(fs::file_size(out / name));
    EXPECT_NE(summary.find(entry), std::string::npos) << name << " not listed with its size";
  }
  for (const auto& e : fs::directory_iterator(out)) {
    EXPECT_EQ(e.path().filename().string().rfind(".grove", 0), std::string::npos) << e.path();
  }
  // A summary.json that cannot be written stops the run before its first step: nothing new.
  fs::path other = dir_ / "other";
  fs::create_directories(other / "summary.json");
  o = Grove("footslam run --no-progress --particles 50 --out " + other.string());
  EXPECT_EQ(o.exit_code, 5) << o.err;
  EXPECT_NE(o.err.find("summary.json: it is a directory"), std::string::npos) << o.err;
  EXPECT_FALSE(fs::exists(other / "map.csv"));
  // Another process holds the directory's lock (flock(1) takes the same lock grove does).
  o = Grove("footslam run --no-progress --particles 50 --out " + out.string());
  ASSERT_EQ(o.exit_code, 0);
  std::string lock = "flock -n " + out.string() + " sh -c '" + std::string(GROVE_BINARY) + " " +
                     run + " 2>" + (dir_ / "locked.err").string() + "; echo $? >" +
                     (dir_ / "locked.rc").string() + "'";
  ASSERT_EQ(std::system(lock.c_str()), 0);
  EXPECT_EQ(Slurp(dir_ / "locked.rc"), "5\n") << Slurp(dir_ / "locked.err");
  EXPECT_NE(Slurp(dir_ / "locked.err").find("is in use by another grove run"), std::string::npos);
}

// 4, 5: every output path is checked before the first step.
TEST_F(CliTest, OutputPathsAreCheckedBeforeTheFirstStep) {
  std::string steps = Write("steps.csv", "t,dx,dy\n1,0.7,0\n2,0.7,0\n");
  const std::string before = Slurp(steps);
  fs::path out = dir_ / "out";
  Outcome o = Grove("footslam run --no-progress --particles 20 --steps " + steps +
                    " --checkpoint " + steps + " --out " + out.string());
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_NE(o.err.find("it is the input " + steps), std::string::npos) << o.err;
  EXPECT_EQ(Slurp(steps), before);
  // A hard link to the input is the input too.
  fs::create_hard_link(steps, dir_ / "link.csv");
  o = Grove("footslam run --no-progress --particles 20 --steps " + steps + " --checkpoint " +
            (dir_ / "link.csv").string() + " --out " + out.string());
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_EQ(Slurp(steps), before);
  // An output in the output directory that is the input.
  fs::create_directories(dir_ / "in");
  fs::copy_file(steps, dir_ / "in" / "map.csv");
  o = Grove("footslam run --no-progress --particles 20 --steps " +
            (dir_ / "in" / "map.csv").string() + " --out " + (dir_ / "in").string());
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_EQ(Slurp(dir_ / "in" / "map.csv"), before);
  // A checkpoint path under a file, and --out on a file: refused at once, not after the run.
  o = Grove("footslam run --no-progress --particles 20 --steps " + steps + " --checkpoint " +
            steps + "/ck.grove --checkpoint-every 1000 --out " + out.string());
  EXPECT_EQ(o.exit_code, 5) << o.err;
  EXPECT_FALSE(fs::exists(out)) << "a refused run left its new output directory";
  o = Grove("footslam run --no-progress --particles 20 --steps " + steps + " --out " + steps);
  EXPECT_EQ(o.exit_code, 5) << o.err;
  EXPECT_NE(o.err.find("exists and is not a directory"), std::string::npos) << o.err;
}

// 7: a closed stderr or terminal does not kill a run.
TEST_F(CliTest, ARunSurvivesAClosedPipeAndAHangup) {
  fs::path out = dir_ / "out";
  std::string cmd = "bash -c '" + std::string(GROVE_BINARY) +
                    " footslam run --particles 300 --out " + out.string() +
                    " 2>&1 | head -c 1 >/dev/null; echo ${PIPESTATUS[0]}' > " +
                    (dir_ / "rc").string();
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  EXPECT_EQ(Slurp(dir_ / "rc"), "0\n");
  EXPECT_TRUE(fs::exists(out / "summary.json"));
  // The hangup comes once the run has made its output directory, which it does after its
  // handlers are in place (a fixed delay raced with a slow start under the sanitizers).
  fs::path hup = dir_ / "hup";
  cmd = "sh -c '" + std::string(GROVE_BINARY) + " footslam run --particles 2000 --out " +
        hup.string() + " 2>/dev/null & pid=$!; n=0; while [ ! -d " + hup.string() +
        " ] && [ $n -lt 1200 ]; do sleep 0.05; n=$((n+1)); done; kill -HUP $pid; wait $pid; " +
        "echo $?' > " + (dir_ / "hup.rc").string();
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  EXPECT_EQ(Slurp(dir_ / "hup.rc"), "0\n");
  EXPECT_TRUE(fs::exists(hup / "summary.json"));
}

// 8, 15: empty paths, and configuration files that are not files.
TEST_F(CliTest, EmptyPathsAndNonFileConfigsAreErrors) {
  const std::string out = " --out " + (dir_ / "out").string();
  for (const char* option : {"--steps", "--resume", "--config", "--checkpoint"}) {
    Outcome o = Grove(std::string("footslam run --no-progress ") + option + " ''" + out);
    EXPECT_EQ(o.exit_code, 2) << option;
    EXPECT_NE(o.err.find(std::string(option) + ": the path is empty"), std::string::npos) << o.err;
  }
  Outcome o = Grove("footslam run --print-config --config /dev/zero");
  EXPECT_EQ(o.exit_code, 3);
  EXPECT_NE(o.err.find("is not a regular file"), std::string::npos) << o.err;
  o = Grove("footslam run --print-config --config " + dir_.string());
  EXPECT_EQ(o.exit_code, 3);
  EXPECT_NE(o.err.find("is a directory"), std::string::npos) << o.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

// 9: trajectories keep their resolution far from the origin.
TEST_F(CliTest, GeoreferencedTrajectoriesAreNotQuantised) {
  fs::path out = dir_ / "out";
  std::string steps = Write("steps.csv", "t,dx,dy\n1,0.1,0.03\n2,0.1,0.03\n3,0.1,0.03\n");
  Outcome o = Grove(
      "footslam run --no-progress --particles 1 --heading-drift-sigma-rad 0 "
      "--heading-sigma-rad 0 --step-length-sigma-m 0 --start-x-m 500000 "
      "--start-y-m 5000000 --steps " +
      steps + " --out " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  const std::string t = Slurp(out / "trajectory.csv");
  EXPECT_NE(t.find("500000.100000,5000000.030000"), std::string::npos) << t;
  EXPECT_NE(t.find("500000.300000,5000000.090000"), std::string::npos) << t;
}

// 10-13, 17: values that used to crash, produce NaN or be taken silently are refused.
TEST_F(CliTest, OutOfRangeValuesAreRefusedNamingTheOption) {
  const std::string out = " --out " + (dir_ / "out").string();
  struct Case {
    std::string args, message;
    int code;
  };
  const Case cases[] = {
      {"footslam run --heading-sigma-rad 1e308" + out,
       "--heading-sigma-rad = 1e+308: must be in [0, 10]", 2},
      {"footslam run --threads 70000" + out, "--threads = 70000: must be in 0..256", 2},
      {"footslam run --threads 2147483647" + out, "--threads = 2147483647", 2},
      {"footslam run --start-x-m 1e10" + out, "start_x_m = 10000000000: must be within", 2},
      {"footslam run --max-step 0" + out, "--max-step = 0: must be > 0", 2},
      {"footslam run --particles abc" + out, "--particles = \"abc\": must be an integer", 2},
      {"footslam simulate --heading-drift -5 --out " + (dir_ / "s").string(),
       "--heading-drift = -5: must be in [0, 0.5]", 2},
      {"footslam simulate --scale-error -1 --out " + (dir_ / "s").string(),
       "--scale-error = -1: must be in (-0.5, 0.5)", 2},
      {"footslam simulate --seed -1 --out " + (dir_ / "s").string(), "--seed = \"-1\"", 2},
      {"footslam simulate --minutes 1e-9 --out " + (dir_ / "s").string(), "shorter than one step",
       2},
      {"footslam render --hex-radius 0 --dir " + dir_.string(), "--hex-radius = 0: must be > 0", 2},
      {"bench paper --only bogus --out " + (dir_ / "b").string(),
       "--only = \"bogus\": must be one of", 2},
      {"bench scaling --steps 0 --out " + (dir_ / "b").string(), "--steps", 2},
      {"bench scaling --grid round --out " + (dir_ / "b").string(), "--grid", 2},
      {"bench paper --naive-limit -1 --out " + (dir_ / "b").string(), "--naive-limit", 2},
      {"bench paper --repeat 0 --out " + (dir_ / "b").string(), "--repeat", 2},
  };
  for (const Case& c : cases) {
    Outcome o = Grove(c.args);
    EXPECT_EQ(o.exit_code, c.code) << c.args << ": " << o.err;
    EXPECT_NE(o.err.find(c.message), std::string::npos) << c.args << ": " << o.err;
  }
  EXPECT_FALSE(fs::exists(dir_ / "out"));
  EXPECT_FALSE(fs::exists(dir_ / "s" / "steps.csv"));
}

// bench scaling takes --grid (growing by default) and names the grid in its report.
TEST_F(CliTest, BenchScalingNamesTheGridInItsReport) {
  for (const char* grid : {"", "fixed", "growing"}) {
    const fs::path out = dir_ / (std::string("scaling-") + grid);
    std::string args = "bench scaling --steps 2 --max-particles 1000 --out " + out.string();
    if (*grid != '\0') args += std::string(" --grid ") + grid;
    Outcome o = Grove(args);
    ASSERT_EQ(o.exit_code, 0) << args << ": " << o.err;
    const std::string md = Slurp(out / "scaling.md");
    const std::string named = std::string(*grid == '\0' ? "growing" : grid) + " grid";
    EXPECT_NE(md.find(named), std::string::npos) << args << ":\n" << md;
  }
}

// --max-particles bounds every run of bench scaling, the thread sweep's included.
TEST_F(CliTest, BenchScalingKeepsEveryRunWithinMaxParticles) {
  const fs::path out = dir_ / "scaling";
  Outcome o = Grove("bench scaling --steps 2 --max-particles 300 --out " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  std::istringstream csv(Slurp(out / "scaling.csv"));
  std::string line;
  std::getline(csv, line);
  ASSERT_EQ(line.rfind("sweep,particles,threads,", 0), 0u) << line;
  int rows = 0;
  while (std::getline(csv, line)) {
    const size_t a = line.find(',');
    const size_t b = line.find(',', a + 1);
    ASSERT_NE(b, std::string::npos) << line;
    EXPECT_LE(std::stoll(line.substr(a + 1, b - a - 1)), 300) << line;
    ++rows;
  }
  EXPECT_GE(rows, 1);
}

// 12, 17: hostile configuration files get short one-line errors.
TEST_F(CliTest, HostileConfigurationsGetShortErrors) {
  std::string deep = "{\"particles\": " + std::string(100000, '[') + std::string(100000, ']') + "}";
  Outcome o = Grove("footslam run --print-config --config " + Write("deep.json", deep));
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find("nested deeper than 32 levels"), std::string::npos) << o.err.substr(0, 300);
  std::string big = "{\"particles\": \"" + std::string(500000, 'x') + "\"}";
  o = Grove("footslam run --print-config --config " + Write("big.json", big));
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_LT(o.err.size(), 400u) << "a huge value is echoed whole";
  o = Grove("footslam run --print-config --config " +
            Write("dup.json", "{\"particles\": 10,\n \"particles\": 20}"));
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find(":2:2: duplicate key \"particles\""), std::string::npos) << o.err;
  o = Grove("footslam run --print-config --config " +
            Write("ctl.json", "{\"seed\": \"\x1b[31mred\"}"));
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_EQ(o.err.find('\x1b'), std::string::npos) << "an escape sequence reached the terminal";
}

// 17: a checkpoint of another configuration names the choice, not its number.
TEST_F(CliTest, CheckpointMismatchNamesChoices) {
  std::string steps = Write("steps.csv", "t,dx,dy\n1,0.7,0\n2,0.7,0\n3,0,0.7\n");
  fs::path ckpt = dir_ / "c.grove";
  const std::string run = "footslam run --no-progress --particles 30 --steps " + steps;
  ASSERT_EQ(Grove(run + " --checkpoint-every 1 --checkpoint " + ckpt.string() + " --out " +
                  (dir_ / "a").string())
                .exit_code,
            0);
  Outcome o = Grove(run + " --resampling residual --resume " + ckpt.string() + " --out " +
                    (dir_ / "b").string());
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find("made with resampling = systematic, this configuration has resampling = "
                       "residual"),
            std::string::npos)
      << o.err;
}

// 14: the memory budget counts the walk's length and the process's limits.
TEST_F(CliTest, TheMemoryBudgetCountsTheWalkAndTheAddressSpaceLimit) {
#ifdef __SANITIZE_ADDRESS__
  GTEST_SKIP() << "AddressSanitizer reserves terabytes of address space: no ulimit -v";
#endif
  fs::path out = dir_ / "out";
  Outcome o = Grove("footslam run --no-progress --particles 100 --out " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  // Under ulimit -v the default budget is what the limit leaves.
  std::string cmd = "sh -c 'ulimit -v 1500000; " + std::string(GROVE_BINARY) +
                    " footslam run --no-progress --particles 2000000 --out " +
                    (dir_ / "big").string() + " 2>" + (dir_ / "err").string() + "; echo $?' >" +
                    (dir_ / "rc").string();
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  EXPECT_EQ(Slurp(dir_ / "rc"), "6\n") << Slurp(dir_ / "err");
  EXPECT_NE(Slurp(dir_ / "err").find("address-space limit"), std::string::npos)
      << Slurp(dir_ / "err");
  EXPECT_FALSE(fs::exists(dir_ / "big"));
}

// An allocation that fails under a small ulimit -v, past the budget check: a clean error, no
// outputs and no crash.
TEST_F(CliTest, RunningOutOfMemoryIsACleanError) {
#ifdef __SANITIZE_ADDRESS__
  GTEST_SKIP() << "AddressSanitizer reserves terabytes of address space: no ulimit -v";
#endif
  std::string cmd = "sh -c 'ulimit -v 1200000; " + std::string(GROVE_BINARY) +
                    " footslam run --no-progress --particles 3000000 --memory-budget 1T --out " +
                    (dir_ / "oom").string() + " 2>" + (dir_ / "err").string() + "; echo $?' >" +
                    (dir_ / "rc").string();
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  const std::string rc = Slurp(dir_ / "rc");
  EXPECT_TRUE(rc == "6\n") << rc << Slurp(dir_ / "err");
  EXPECT_NE(Slurp(dir_ / "err").find("out of memory"), std::string::npos) << Slurp(dir_ / "err");
  EXPECT_FALSE(fs::exists(dir_ / "oom" / "map.csv"));
}

// Bailey's simulator through the command: the four files, and its errors.
TEST_F(CliTest, FastSlamSimulateWritesControlsObservationsAndTruth) {
  fs::path out = dir_ / "fs";
  Outcome o = Grove("fastslam simulate --seed 3 --out " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_EQ(Slurp(out / "controls.csv").rfind("t,v,steer\n", 0), 0u);
  EXPECT_EQ(Slurp(out / "observations.csv").rfind("t,range,bearing,id\n", 0), 0u);
  EXPECT_EQ(Slurp(out / "truth.csv").rfind("t,x,y,heading\n", 0), 0u);
  EXPECT_EQ(Slurp(out / "landmarks_truth.csv").rfind("id,x,y\n", 0), 0u);
  o = Grove("fastslam simulate --preset bogus --out " + (dir_ / "b").string());
  EXPECT_EQ(o.exit_code, 2) << o.err;
  o = Grove("fastslam simulate --map " + (dir_ / "missing.txt").string() + " --out " +
            (dir_ / "b").string());
  EXPECT_EQ(o.exit_code, 3) << o.err;
  o = Grove("fastslam simulate --seed -2 --out " + (dir_ / "b").string());
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_FALSE(fs::exists(dir_ / "b" / "controls.csv"));
  // A map whose only waypoint is the start: refused, not an empty simulation.
  const fs::path still = dir_ / "still.txt";
  std::ofstream(still) << "lm 2 1\n1 2\nwp 2 1\n0 0\n";
  o = Grove("fastslam simulate --map " + still.string() + " --out " + (dir_ / "b").string());
  EXPECT_EQ(o.exit_code, 3) << o.err;
  EXPECT_NE(o.err.find(still.string() + ": wp: every waypoint lies within at_waypoint_m = 1 m"),
            std::string::npos)
      << o.err;
  EXPECT_FALSE(fs::exists(dir_ / "b"));
}

// `grove fastslam run` end to end on the simulator's files: every output, the truth scored, the
// run identical at 1 and 2 threads, and `evaluate` agreeing with the run's own score.
TEST_F(CliTest, FastSlamSimulateRunAndEvaluate) {
  fs::path sim = dir_ / "sim";
  ASSERT_EQ(Grove("fastslam simulate --seed 2 --out " + sim.string()).exit_code, 0);
  const std::string inputs = " --controls " + (sim / "controls.csv").string() + " --observations " +
                             (sim / "observations.csv").string() + " --truth " +
                             (sim / "truth.csv").string() + " --landmarks-truth " +
                             (sim / "landmarks_truth.csv").string();
  fs::path a = dir_ / "a", b = dir_ / "b";
  Outcome o = Grove("fastslam run --no-progress --particles 20 --threads 1" + inputs + " --out " +
                    a.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  for (const char* f : {"trajectory.csv", "heaviest_trajectory.csv", "landmarks.csv", "map.png",
                        "map.svg", "summary.json"}) {
    EXPECT_TRUE(fs::exists(a / f)) << f;
  }
  EXPECT_EQ(Slurp(a / "landmarks.csv").rfind("id,x,y,sxx,sxy,syy,source_id\n", 0), 0u);
  const std::string summary = Slurp(a / "summary.json");
  EXPECT_NE(summary.find("\"position_rmse_m\""), std::string::npos);
  EXPECT_NE(summary.find("\"landmark_accuracy\""), std::string::npos);
  o = Grove("fastslam run --no-progress --particles 20 --threads 2 --filter fastslam2" + inputs +
            " --out " + b.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  for (const char* f : {"trajectory.csv", "heaviest_trajectory.csv", "landmarks.csv"}) {
    EXPECT_EQ(Slurp(a / f), Slurp(b / f)) << f;
  }
  o = Grove("fastslam evaluate --truth " + (sim / "truth.csv").string() + " --trajectory " +
            (a / "trajectory.csv").string() + " --landmarks " + (a / "landmarks.csv").string() +
            " --landmarks-truth " + (sim / "landmarks_truth.csv").string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_NE(o.out.find("\"position_mse_variance_m4\""), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("\"rmse_m\""), std::string::npos) << o.out;
  o = Grove("fastslam run --print-config --filter fastslam1 --controls x --observations y");
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_NE(o.out.find("\"filter\": \"fastslam1\""), std::string::npos) << o.out;
}

// Bad FastSLAM inputs: file:line:column, exit 3, no output directory left behind.
TEST_F(CliTest, FastSlamBadInputsStopWithFileLineColumn) {
  const std::string good_controls = "t,v,steer\n0,3,0\n0.025,3,0.1\n0.05,3,0.1\n";
  const std::string good_observations = "t,range,bearing,id\n0.025,10,0.5,1\n0.05,11,0.4,1\n";
  struct Case {
    std::string controls, observations, file, where, what;
  };
  const Case cases[] = {
      {"t,v,steer\n0,3,0\n0.05,3,0\n0.025,3,0\n", good_observations, "controls",
       "4:1:", "strictly increasing"},
      {"t,v,steer\n0,3,0\n0.025,nan,0\n", good_observations, "controls", "3:", "must be finite"},
      {good_controls, "t,range,bearing,id\n0.025,-1,0.5,1\n", "observations",
       "2:7:", "range = -1: must be in [0, 1e6] m"},
      {good_controls, "t,range,bearing,id\n0.025,10,3.5,1\n", "observations",
       "2:10:", "bearing = 3.5: must be in (-pi, pi] rad"},
      {good_controls, "t,range,bearing,id\n0.025,10,0.5,1.5\n", "observations",
       "2:", "not an integer"},
      {good_controls, "t,range,bearing,id\n0.05,10,0.5,1\n0.025,10,0.5,1\n", "observations",
       "3:1:", "must not decrease"},
      {"t,v,steer\n1,3,0\n2,3,0\n", "t,range,bearing,id\n0.5,10,0.5,1\n", "observations",
       "2:1:", "before the first control"},
      {good_controls, "t,range,bearing,id\n0.025,inf,0.5,1\n", "observations",
       "2:", "must be finite"},
      {"t,v\n0,3\n", good_observations, "controls", "1:1:", "unknown header"},
      // Regression: a controls file with only its header blamed the first observation.
      {"t,v,steer\n", good_observations, "controls", " no controls", "needs at least one"},
      {"t,v,steer\n", "t,range,bearing,id\n", "controls", " no controls", "needs at least one"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.controls + " | " + c.observations);
    const std::string controls = Write("controls.csv", c.controls);
    const std::string observations = Write("observations.csv", c.observations);
    fs::path out = dir_ / "out";
    Outcome o = Grove("fastslam run --no-progress --particles 5 --controls " + controls +
                      " --observations " + observations + " --out " + out.string());
    EXPECT_EQ(o.exit_code, 3) << o.err;
    const std::string& path = c.file == "controls" ? controls : observations;
    EXPECT_NE(o.err.find(path + ":" + c.where), std::string::npos) << o.err;
    EXPECT_NE(o.err.find(c.what), std::string::npos) << o.err;
    EXPECT_FALSE(fs::exists(out)) << "a failed run left " << out;
  }
}

// The generic run loop's checkpoints serve FastSLAM too: resuming from a periodic checkpoint,
// at another thread count, gives the same outputs as the uninterrupted run.
TEST_F(CliTest, FastSlamResumesFromAPeriodicCheckpoint) {
  fs::path sim = dir_ / "sim";
  ASSERT_EQ(Grove("fastslam simulate --seed 4 --out " + sim.string()).exit_code, 0);
  const std::string run = "fastslam run --no-progress --particles 30 --controls " +
                          (sim / "controls.csv").string() + " --observations " +
                          (sim / "observations.csv").string() + " ";
  fs::path full = dir_ / "full", part = dir_ / "part", resumed = dir_ / "resumed";
  ASSERT_EQ(Grove(run + "--threads 2 --out " + full.string()).exit_code, 0);
  Outcome o = Grove(run + "--threads 1 --checkpoint-every 7000 --out " + part.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  ASSERT_TRUE(fs::exists(part / "checkpoint.grove"));
  fs::copy_file(part / "checkpoint.grove", dir_ / "cp.grove");
  o = Grove(run + "--threads 2 --resume " + (dir_ / "cp.grove").string() + " --out " +
            resumed.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  for (const char* f : {"trajectory.csv", "heaviest_trajectory.csv", "landmarks.csv", "map.png"}) {
    EXPECT_TRUE(Slurp(full / f) == Slurp(resumed / f)) << f << " differs";
  }
  // A FootSLAM checkpoint is not a FastSLAM one.
  ASSERT_EQ(Grove("footslam run --no-progress --particles 50 --checkpoint-every 100 --out " +
                  (dir_ / "foot").string())
                .exit_code,
            0);
  o = Grove(run + "--resume " + (dir_ / "foot" / "checkpoint.grove").string() + " --out " +
            (dir_ / "wrong").string());
  EXPECT_NE(o.exit_code, 0);
  EXPECT_NE(o.err.find("footslam"), std::string::npos) << o.err;
}

// Observations without an id column run under unknown association; with ids and --association
// ml the ids only tag, and the summary and evaluate report the association against them.
TEST_F(CliTest, FastSlamUnknownAssociationFromTheFileOrTheFlag) {
  fs::path sim = dir_ / "sim";
  ASSERT_EQ(Grove("fastslam simulate --out " + sim.string()).exit_code, 0);
  const std::string without_ids = WithoutLastColumn(Slurp(sim / "observations.csv"));
  ASSERT_EQ(without_ids.rfind("t,range,bearing\n", 0), 0u);
  const std::string observations = Write("no_ids.csv", without_ids);
  const std::string controls = " --controls " + (sim / "controls.csv").string();
  fs::path a = dir_ / "a", b = dir_ / "b";
  Outcome o = Grove("fastslam run --no-progress --particles 20" + controls + " --observations " +
                    observations + " --out " + a.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_NE(o.err.find("no id column"), std::string::npos) << o.err;
  std::string summary = Slurp(a / "summary.json");
  EXPECT_NE(summary.find("\"association\": \"ml\""), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"created\""), std::string::npos) << summary;
  o = Grove("fastslam run --no-progress --particles 20 --association ml" + controls +
            " --observations " + (sim / "observations.csv").string() + " --out " + b.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  summary = Slurp(b / "summary.json");
  EXPECT_NE(summary.find("\"error_rate\": 0"), std::string::npos) << summary;
  // Same decisions with and without the tags: the trajectories agree.
  EXPECT_EQ(Slurp(a / "trajectory.csv"), Slurp(b / "trajectory.csv"));
  o = Grove("fastslam evaluate --truth " + (sim / "truth.csv").string() + " --trajectory " +
            (b / "trajectory.csv").string() + " --landmarks " + (b / "landmarks.csv").string() +
            " --landmarks-truth " + (sim / "landmarks_truth.csv").string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_NE(o.out.find("\"matched_by\": \"source_id\""), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("\"duplicates\""), std::string::npos) << o.out;
}

// The bundled Victoria Park dataset end to end on its first two minutes.
TEST_F(CliTest, VictoriaParkRunsAShortSegment) {
  fs::path out = dir_ / "park";
  Outcome o = Grove("fastslam victoria-park --no-progress --particles 30 --until 120 --out " +
                    out.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  for (const char* f : {"trajectory.csv", "heaviest_trajectory.csv", "landmarks.csv",
                        "gps_error.csv", "map.png", "map.svg", "summary.json"}) {
    EXPECT_TRUE(fs::exists(out / f)) << f;
  }
  const nlohmann::json summary = nlohmann::json::parse(Slurp(out / "summary.json"));
  EXPECT_EQ(summary["config"]["vehicle"], "guivant_nebot");
  EXPECT_EQ(summary["config"]["association"], "ml");
  const double mean = summary["gps"]["mean_m"].get<double>();
  // This test's own bound for the first part of the park (the whole run's mean is in
  // engine/fastslam/README.md, "Victoria Park"): 2 m.
  EXPECT_LT(mean, 2.0) << summary["gps"].dump();
  EXPECT_GT(summary["gps"]["fixes"].get<int>(), 250);
  EXPECT_GT(summary["landmarks"].get<int>(), 20);
  EXPECT_EQ(summary["inputs"]["scans_before_the_first_control"], 1);
}

// A bad or truncated dataset file: file:line:column (or the file and what is wrong), exit 3,
// no output directory.
TEST_F(CliTest, VictoriaParkBadDataStopsWithTheFileAndLine) {
  const fs::path data = dir_ / "data";
  fs::create_directories(data);
  for (const char* f : {"inputs.dat.gz", "measurements.dat.gz", "gps.dat.gz"}) {
    fs::copy_file(fs::path(GROVE_SOURCE_DIR) / "tools/data/victoria_park" / f, data / f);
  }
  fs::path out = dir_ / "out";
  auto run = [&] {
    return Grove("fastslam victoria-park --no-progress --particles 5 --until 10 --data " +
                 data.string() + " --out " + out.string());
  };
  ASSERT_EQ(run().exit_code, 0);
  fs::remove_all(out);
  // A plain file beside the compressed one: which one is meant is not guessed.
  std::ofstream(data / "measurements.dat") << "     0.852   20.46202    0.88575    0.35404\n"
                                           << "     0.900   abc    0.88575    0.35404\n";
  Outcome o = run();
  EXPECT_EQ(o.exit_code, 3);
  EXPECT_NE(o.err.find("both measurements.dat and measurements.dat.gz exist"), std::string::npos)
      << o.err;
  EXPECT_FALSE(fs::exists(out));
  fs::rename(data / "measurements.dat.gz", dir_ / "measurements.dat.gz");
  o = run();
  EXPECT_EQ(o.exit_code, 3);
  EXPECT_NE(o.err.find((data / "measurements.dat").string() + ":2:14:"), std::string::npos)
      << o.err;
  EXPECT_NE(o.err.find("range"), std::string::npos) << o.err;
  EXPECT_FALSE(fs::exists(out));
  std::ofstream(data / "measurements.dat") << "     0.852   20.46202    4.5    0.35404\n";
  o = run();
  EXPECT_EQ(o.exit_code, 3);
  EXPECT_NE(o.err.find(":1:26: bearing = 4.5: must be in [0, pi]"), std::string::npos) << o.err;
  std::ofstream(data / "measurements.dat") << "     0.852   20.46202\n";
  o = run();
  EXPECT_EQ(o.exit_code, 3);
  EXPECT_NE(o.err.find("2 numbers where 4 are expected"), std::string::npos) << o.err;
  fs::remove(data / "measurements.dat");
  fs::rename(dir_ / "measurements.dat.gz", data / "measurements.dat.gz");
  // A truncated gzip file.
  const std::string gz = Slurp(data / "inputs.dat.gz");
  std::ofstream(data / "inputs.dat.gz", std::ios::binary) << gz.substr(0, gz.size() / 2);
  o = run();
  EXPECT_EQ(o.exit_code, 3);
  EXPECT_NE(o.err.find("inputs.dat.gz"), std::string::npos) << o.err;
  EXPECT_FALSE(fs::exists(out));
  fs::remove(data / "gps.dat.gz");
  o = run();
  EXPECT_EQ(o.exit_code, 3);
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(CliTest, FastSlamMonteCarloHelpAndBadOptions) {
  Outcome o = Grove("fastslam montecarlo --help");
  EXPECT_EQ(o.exit_code, 0);
  for (const char* option : {"--scenario", "--filters", "--runs", "--out", "--particles", "--seed",
                             "--threads", "--loops", "--no-progress"}) {
    EXPECT_NE(o.out.find(option), std::string::npos) << option << "\n" << o.out;
  }
  const std::string out = (dir_ / "mc").string();
  o = Grove("fastslam montecarlo --scenario sim3 --filters srcd --runs abc --out " + out);
  EXPECT_EQ(o.exit_code, 2) << o.err;
  o = Grove("fastslam montecarlo --scenario sim3 --filters srcd,nope --runs 2 --out " + out);
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_EQ(o.err.rfind("grove: error: --filters = \"srcd,nope\": unknown filter \"nope\"", 0), 0u)
      << o.err;
  o = Grove("fastslam montecarlo --scenario sim3 --filters srcd --runs 0 --out " + out);
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_NE(o.err.find("--runs = 0"), std::string::npos) << o.err;
  o = Grove("fastslam montecarlo --scenario sim3 --filters srcd --particles 0 --runs 1 --out " +
            out);
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_NE(o.err.find("--particles = \"0\""), std::string::npos) << o.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(CliTest, AMistypedOptionOrCommandGetsTheNearestSuggested) {
  Outcome o = Grove("footslam run --particels 10");
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_EQ(o.err,
            "grove: error: footslam run: unknown option \"--particels\" (did you mean "
            "--particles?)\n");
  o = Grove("footslam rn");
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_EQ(o.err, "grove: error: footslam: unknown command \"rn\" (did you mean run?)\n");
  o = Grove("fastslam montecarlo --scenario sim3 --filters srcd --runs 1 --loop 2 --out " +
            (dir_ / "mc").string());
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_NE(o.err.find("(did you mean --loops?)"), std::string::npos) << o.err;
  o = Grove("bench scalng --out " + (dir_ / "b").string());
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_NE(o.err.find("(did you mean scaling?)"), std::string::npos) << o.err;
  o = Grove("footslam");
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_EQ(o.err,
            "grove: error: footslam: a command is required: run, steps, batch, simulate, evaluate "
            "or render\n");
  EXPECT_FALSE(fs::exists(dir_ / "mc"));
  EXPECT_FALSE(fs::exists(dir_ / "b"));
}

// CLI11's errors in grove's form: one short line naming the flag, the value and the rule.
TEST_F(CliTest, ParseErrorsAreOneGroveLineWithExitCode2) {
  const std::string park = "fastslam victoria-park --out " + (dir_ / "v").string() + " --until ";
  struct Case {
    std::string args, err;
  };
  const Case cases[] = {
      {park + "abc", "grove: error: --until = \"abc\": must be a number\n"},
      {park + "-1", "grove: error: --until = -1: must be >= 0\n"},
      {park + "inf", "grove: error: --until = inf: must be finite\n"},
      {park + "nan", "grove: error: --until = nan: must be finite\n"},
      {park + "''", "grove: error: --until = \"\": must be a number\n"},
      {"footslam run --particles", "grove: error: footslam run: --particles needs a value\n"},
      {"footslam evaluate --truth t.csv",
       "grove: error: footslam evaluate: --trajectory is "
       "required\n"},
      {"footslam run extra", "grove: error: footslam run: unexpected argument \"extra\"\n"},
      {"footslam run --particles 1 --particles 2",
       "grove: error: footslam run: --particles is given more than once\n"},
      {"footslam run --print-config=abc",
       "grove: error: footslam run: --print-config = \"abc\": a flag takes no value\n"},
      {"bench scaling --steps 1.5 --out " + (dir_ / "b").string(),
       "grove: error: --steps = \"1.5\": must be an integer\n"},
      {"bench paper --grid round --out " + (dir_ / "b").string(),
       "grove: error: --grid = \"round\": must be one of \"fixed\", \"growing\"\n"},
  };
  for (const Case& c : cases) {
    Outcome o = Grove(c.args);
    EXPECT_EQ(o.exit_code, 2) << c.args;
    EXPECT_EQ(o.err, c.err) << c.args;
  }
  EXPECT_FALSE(fs::exists(dir_ / "v"));
  EXPECT_FALSE(fs::exists(dir_ / "b"));
}

TEST_F(CliTest, HelpShowsTypesRangesChoicesAndDefaults) {
  Outcome o = Grove("fastslam run --help");
  ASSERT_EQ(o.exit_code, 0) << o.err;
  for (const char* text :
       {"Usage: grove fastslam run [OPTIONS]", "--controls PATH REQUIRED",
        "--particles INT             Number of particles. Range: 1..2147483648. Default: 100",
        "--resampling CHOICE         Resampling scheme. One of: systematic, stratified, "
        "residual,\n                              multinomial. Default: systematic",
        "--resample-threshold FLOAT", "Range: (0, 1]. Default: 0.75", "--seed INT",
        "Range: 0..18446744073709551615", "--memory-budget SIZE", "Default: the memory available",
        "--checkpoint-every INT"}) {
    EXPECT_NE(o.out.find(text), std::string::npos) << text << "\n" << o.out;
  }
  EXPECT_EQ(o.out.find(" TEXT"), std::string::npos) << o.out;
  std::istringstream lines(o.out);
  for (std::string line; std::getline(lines, line);) EXPECT_LE(line.size(), 100u) << line;
  // Victoria Park's defaults are its own.
  o = Grove("fastslam victoria-park --help");
  EXPECT_NE(o.out.find("--vehicle CHOICE            The vehicle model: bailey or guivant_nebot. "
                       "One of: bailey,\n                              guivant_nebot. Default: "
                       "guivant_nebot"),
            std::string::npos)
      << o.out;
  EXPECT_NE(o.out.find("--until FLOAT"), std::string::npos) << o.out;
  o = Grove("fastslam montecarlo --help");
  for (const char* text : {"--filters LIST REQUIRED", "Each one of: fastslam1, fastslam2",
                           "--runs INT REQUIRED", "Range: 1..100000",
                           "--loops INT                 Loops through the waypoints. Range: "
                           "1..1000. Default: the scenario's"}) {
    EXPECT_NE(o.out.find(text), std::string::npos) << text << "\n" << o.out;
  }
  o = Grove("footslam simulate --help");
  EXPECT_NE(o.out.find("--minutes FLOAT             Walk duration in minutes. Range: (0, 1440]. "
                       "Default: 8"),
            std::string::npos)
      << o.out;
  EXPECT_NE(o.out.find("--scenario CHOICE"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("One of: building,\n                              open, campus. Default: "
                       "building"),
            std::string::npos)
      << o.out;
}

// Values that used to mean "the scenario's" or "the seed's" are refused, as is a seed that
// would wrap past 2^64 - 1 for a later run.
TEST_F(CliTest, MonteCarloRefusesLoopsZeroAnEmptyListAndAWrappingSeed) {
  const std::string mc =
      "fastslam montecarlo --scenario sim3 --filters srcd --out " + (dir_ / "mc").string() + " ";
  struct Case {
    std::string args, err;
  };
  const Case cases[] = {
      {"--runs 2 --loops 0", "grove: error: --loops = 0: must be in 1..1000\n"},
      {"--runs 2 --particles ''",
       "grove: error: --particles = \"\": must be a comma list of particle counts, each in "
       "1..2147483648\n"},
      {"--runs 2 --seed 18446744073709551615",
       "grove: error: --seed = 18446744073709551615 with --runs = 2: run r uses seed + r, so "
       "seed + runs - 1 must be at most 18446744073709551615\n"},
      {"--runs 100001", "grove: error: --runs = 100001: must be in 1..100000\n"},
      {"--runs 2 --threads -1", "grove: error: --threads = -1: must be in 0..256\n"},
  };
  for (const Case& c : cases) {
    Outcome o = Grove(mc + c.args);
    EXPECT_EQ(o.exit_code, 2) << c.args;
    EXPECT_EQ(o.err, c.err) << c.args;
  }
  EXPECT_FALSE(fs::exists(dir_ / "mc"));
  // The largest seed that does not wrap runs.
  Outcome o = Grove(mc + "--runs 1 --particles 5 --loops 1 --seed 18446744073709551615");
  EXPECT_EQ(o.exit_code, 0) << o.err;
}

// The last progress line reaches its total: the data read up to --until, the scans of a CSV
// run (not its observation rows).
TEST_F(CliTest, ProgressReachesOneHundredPercent) {
  const std::regex done(R"(done: step (\d+)/(\d+) \((\d+)%\))");
  auto expect_done = [&](const std::string& args) {
    Outcome o = Grove(args);
    ASSERT_EQ(o.exit_code, 0) << args << ": " << o.err;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(o.err, m, done)) << args << ": " << o.err;
    EXPECT_EQ(m[1], m[2]) << args << ": " << o.err;
    EXPECT_EQ(m[3], "100") << args << ": " << o.err;
  };
  expect_done("fastslam victoria-park --particles 5 --until 60 --out " + (dir_ / "v").string());
  ASSERT_EQ(Grove("fastslam simulate --out " + (dir_ / "sim").string()).exit_code, 0);
  expect_done("fastslam run --particles 5 --controls " + (dir_ / "sim/controls.csv").string() +
              " --observations " + (dir_ / "sim/observations.csv").string() + " --out " +
              (dir_ / "f").string());
  const std::string steps = Write("steps.csv", "t,dx,dy\n# a comment\n1,0.7,0\n\n2,0.7,0\n");
  expect_done("footslam run --particles 5 --steps " + steps + " --out " + (dir_ / "s").string());
}

// A simulated target tracked from its ranges: the same trajectory.csv at 1 and 2 threads and
// after a resume from a periodic checkpoint, close to the truth by `footslam evaluate`.
TEST_F(CliTest, TrackingSimulateRunResumeAndEvaluate) {
  fs::path sim = dir_ / "sim";
  Outcome o = Grove("tracking simulate --seconds 60 --seed 3 --out " + sim.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_EQ(Slurp(sim / "beacons.csv").rfind("id,x,y\n", 0), 0u);
  EXPECT_EQ(Slurp(sim / "measurements.csv").rfind("t,beacon,range\n", 0), 0u);
  const std::string run = "tracking run --no-progress --particles 1000 --beacons " +
                          (sim / "beacons.csv").string() + " --measurements " +
                          (sim / "measurements.csv").string() + " ";
  fs::path one = dir_ / "one", two = dir_ / "two", part = dir_ / "part", resumed = dir_ / "res";
  ASSERT_EQ(Grove(run + "--threads 1 --out " + one.string()).exit_code, 0);
  ASSERT_EQ(Grove(run + "--threads 2 --out " + two.string()).exit_code, 0);
  EXPECT_TRUE(Slurp(one / "trajectory.csv") == Slurp(two / "trajectory.csv"));
  const nlohmann::json summary = nlohmann::json::parse(Slurp(one / "summary.json"));
  EXPECT_EQ(summary["measurements"], 240);
  EXPECT_EQ(summary["steps"], 60);
  EXPECT_EQ(summary["config"]["particles"], 1000);

  ASSERT_EQ(Grove(run + "--checkpoint-every 25 --out " + part.string()).exit_code, 0);
  fs::copy_file(part / "checkpoint.grove", dir_ / "cp.grove");
  o = Grove(run + "--threads 2 --resume " + (dir_ / "cp.grove").string() + " --out " +
            resumed.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_TRUE(Slurp(one / "trajectory.csv") == Slurp(resumed / "trajectory.csv"));
  o = Grove(run + "--range-sigma-m 0.4 --resume " + (dir_ / "cp.grove").string() + " --out " +
            (dir_ / "other").string());
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find("range_sigma_m = 0.5"), std::string::npos) << o.err;

  o = Grove("footslam evaluate --truth " + (sim / "truth.csv").string() + " --trajectory " +
            (one / "trajectory.csv").string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  const nlohmann::json error = nlohmann::json::parse(o.out);
  EXPECT_EQ(error["matched"], 60);
  EXPECT_LT(error["rmse_m"].get<double>(), 1.0) << o.out;
}

// Bad tracking inputs: file:line:column, exit 3, no output directory left behind.
TEST_F(CliTest, TrackingBadInputsStopWithFileLineColumn) {
  const std::string beacons = Write("beacons.csv", "id,x,y\n0,0,0\n1,10,0\n");
  auto expect = [&](const std::string& rows, const std::string& where, const std::string& what) {
    SCOPED_TRACE(rows);
    const std::string m = Write("m.csv", "t,beacon,range\n" + rows);
    fs::path out = dir_ / "out";
    Outcome o = Grove("tracking run --no-progress --particles 50 --beacons " + beacons +
                      " --measurements " + m + " --out " + out.string());
    EXPECT_EQ(o.exit_code, 3) << o.err;
    EXPECT_NE(o.err.find(m + ":" + where), std::string::npos) << o.err;
    EXPECT_NE(o.err.find(what), std::string::npos) << o.err;
    EXPECT_FALSE(fs::exists(out));
  };
  expect("1,0,5\n1,7,5\n", "3:3:", "beacon 7 is not one of the beacons file's");
  expect("1,0,5\n2,1,-1\n", "3:5:", "range = -1: must be >= 0");
  expect("2,0,5\n1,1,5\n", "3:1:", "is before the previous row's");
  expect("1,0,nan\n", "2:5:", "must be finite");
}

// A bad IMU recording stops `footslam steps` and `footslam run --imu` with FILE:LINE:COLUMN, the
// field, its value and the rule; nothing is written.
TEST_F(CliTest, BadImuRecordingsStopWithFileLineColumnAndWriteNothing) {
  const std::string header = "t,ax,ay,az,gx,gy,gz\n";
  const std::string still = "0,0,0,9.8,0,0,0\n0.005,0,0,9.8,0,0,0\n";
  struct Case {
    std::string text;
    std::string extra;  // flags
    std::string where;
    std::string what;
  };
  std::string at_200hz = header;
  for (int k = 0; k < 100; ++k) at_200hz += std::to_string(0.005 * k) + ",0,0,9.8,0,0,0\n";
  const Case cases[] = {
      {header + still + "0.004,0,0,9.8,0,0,0\n", "", ":4:1:", "is not after the previous sample"},
      {header + still + "0.01,0,nan,9.8,0,0,0\n", "", ":4:8:", "ay = nan: must be finite"},
      {header + still + "0.01,0,0,9.8,0,0,40\n", "", ":4:18:", "saturated"},
      {header + still + "0.5,0,0,9.8,0,0,0\n", "", ":4:1:", "a gap of 0.495 s"},
      {header + still + "0.01,0,0,9.8,0,0,x\n", "", ":4:18:", "gz"},
      {"t,ax,ay,az,gx\n0,0,0,9.8,0\n", "", ":1:1:", "no column for gy, gz"},
      {at_200hz, " --rate 100", ":66:1:", "does not match the time column"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text.substr(0, 80) + c.extra);
    const std::string imu = Write("imu.csv", c.text);
    for (const std::string& command :
         {"footslam steps --out " + (dir_ / "steps.csv").string(),
          "footslam run --particles 20 --out " + (dir_ / "run").string()}) {
      Outcome o = Grove(command + " --no-progress --imu " + imu + c.extra);
      EXPECT_EQ(o.exit_code, 3) << command << ": " << o.err;
      EXPECT_NE(o.err.find(imu + c.where), std::string::npos) << command << ": " << o.err;
      EXPECT_NE(o.err.find(c.what), std::string::npos) << command << ": " << o.err;
    }
    EXPECT_FALSE(fs::exists(dir_ / "steps.csv"));
    EXPECT_FALSE(fs::exists(dir_ / "run" / "steps.csv"));
  }
  Outcome o = Grove("footslam steps --units furlong --imu " + Write("imu.csv", at_200hz) +
                    " --out " + (dir_ / "steps.csv").string());
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_NE(o.err.find("--units = \"furlong\""), std::string::npos) << o.err;
}

// The simulator's IMU recording through `footslam steps` gives a step file that `footslam run
// --steps` reads, and `footslam run --imu` streams the same steps into the filter.
TEST_F(CliTest, ImuStepsAndStreamedRunAgree) {
  const fs::path sim = dir_ / "sim";
  ASSERT_EQ(Grove("footslam simulate --minutes 1 --seed 4 --imu --out " + sim.string()).exit_code,
            0);
  ASSERT_TRUE(fs::exists(sim / "imu.csv"));
  Outcome o = Grove("footslam steps --no-progress --imu " + (sim / "imu.csv").string() + " --out " +
                    (dir_ / "imu_steps.csv").string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  const std::string common = " --no-progress --particles 100 --seed 2 --threads 1";
  o = Grove("footslam run --steps " + (dir_ / "imu_steps.csv").string() + common + " --out " +
            (dir_ / "from_file").string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  o = Grove("footslam run --imu " + (sim / "imu.csv").string() + common + " --out " +
            (dir_ / "streamed").string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  const std::string from_file = Slurp(dir_ / "from_file" / "mean_trajectory.csv");
  EXPECT_GT(std::count(from_file.begin(), from_file.end(), '\n'), 30);
  // The same poses after every step; the streamed run knows when the odometry started (the end
  // of the first stance), the step file does not.
  const std::string streamed = Slurp(dir_ / "streamed" / "mean_trajectory.csv");
  const auto after_start = [](const std::string& text) {
    return text.substr(text.find('\n', text.find('\n') + 1));
  };
  EXPECT_EQ(after_start(streamed), after_start(from_file));
}

}  // namespace
