// The run loop of every model's `grove ... run` command, written once: output and checkpoint
// paths checked before the first step, the output directory locked, the memory budget, create
// or resume (with the input digest), the step loop with progress, periodic and signal
// checkpoints, and the outputs written as a set (OutputSet) with summary.json last. A run that
// does not succeed leaves no directory it made but those holding a checkpoint.
//
// Signals (tools/run/signal_policy.h): SIGINT and SIGTERM stop the run at the next step
// boundary, or during the writing of the outputs before anything is renamed into place; it
// writes a checkpoint and exits with 128 + the signal. Memory: tools/run/memory_budget.h.
#ifndef GROVE_TOOLS_RUN_RUN_LOOP_H_
#define GROVE_TOOLS_RUN_RUN_LOOP_H_

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "grove/collective.h"
#include "grove/status.h"
#include "tools/io/output_set.h"
#include "tools/report/map_render.h"
#include "tools/run/memory_budget.h"
#include "tools/run/signal_policy.h"

namespace grove::tools {

// Exit codes of the grove command (documented in tools/README.md, "Exit codes").
enum ExitCode : int {
  kExitOk = 0,
  kExitInternal = 1,  // a bug: please report
  kExitUsage = 2,     // bad command line or configuration
  kExitInput = 3,     // bad input file (steps, truth, CSV, checkpoint)
  kExitRun = 4,       // the run itself failed: left the grid, filter degenerated
  kExitOutput = 5,    // outputs could not be written (earlier outputs are left intact)
  kExitMemory = 6,    // the predicted memory exceeds the budget; nothing was run
  // 128 + the signal (130 for SIGINT, 143 for SIGTERM): stopped by the signal after writing a
  // checkpoint.
  kExitSignalBase = 128,
};

// Prints "grove: error: MESSAGE" on stderr and returns `code`.
int Fail(int code, std::string_view message);
// The exit code of a run's or an output's error status.
int ExitCodeOf(const Status& s);
// The CPUs this process may run on (its affinity mask: a scheduler's, mpirun's binding or
// taskset's CPU set), at least 1.
int UsableCpus();

// Options of a run that are not the model's configuration.
struct RunOptions {
  std::string out_dir;
  bool progress = true;             // progress on stderr
  int64_t memory_budget_bytes = 0;  // refuse runs predicted to need more; 0: the memory available
  int64_t checkpoint_every = 0;     // steps between checkpoints; 0: only when stopped by a signal
  std::string checkpoint_path;      // empty: out_dir + "/checkpoint.grove"
  std::string resume_path;          // continue from this checkpoint
  // What the message after a stop by a signal tells the user to do; empty: "continue with the
  // same command and --resume CHECKPOINT".
  std::string resume_advice;
  // Install SignalHandlers for the run; false when the caller has (runs side by side).
  bool handle_signals = true;
  // One filter across these ranks (null: one process). Rank 0 checks the output paths, writes
  // the outputs and reports; the ranks agree on every record read, every error and every stop
  // signal, and all exit with the same code. Each rank checkpoints its own share
  // (RankCheckpointPath).
  Collective* ranks = nullptr;
};

// What a model's run gives the loop.
class RunJob {
 public:
  virtual ~RunJob() = default;

  // The files the run reads (never written over) and the names of the files it writes into
  // the output directory (summary.json aside).
  virtual std::vector<std::string> InputPaths() const = 0;
  virtual std::vector<std::string> OutputNames() const = 0;
  // What the checkpoint's input position names ("steps.csv"), and what its records are called
  // in messages ("steps").
  virtual std::string InputName() const = 0;
  virtual const char* RecordsName() const = 0;
  // Input records in the whole input, or 0 when not known (a stream): memory.
  virtual int64_t ExpectedRecords() const = 0;
  // The records Read() will return, as far as it is known before the run (0: not known): the
  // progress line's total, which must reach it when the run ends.
  virtual int64_t ExpectedSteps() const { return ExpectedRecords(); }
  virtual int64_t particles() const = 0;
  // Predicted peak memory of the whole run, bytes, for `records` input records.
  virtual int64_t PredictPeakBytes(int64_t records) const = 0;
  // "the run is predicted to need 120.0 MiB (30000 particles, htree map, 872 steps)": what the
  // prediction is made of, for the refusal message.
  virtual std::string DescribePrediction(int64_t records) const = 0;

  virtual Status Create() = 0;
  // Continues from a checkpoint; sets *user_data to what the loop stored in it.
  virtual Status Resume(std::string_view bytes, const std::string& name,
                        std::string* user_data) = 0;
  virtual StatusOr<std::string> Checkpoint(std::string_view user_data) const = 0;

  // Reads the next input record: false at the end of the input. Appends the bytes that
  // identify the record (its values) to *digest_bytes.
  virtual StatusOr<bool> Read(std::string* digest_bytes) = 0;
  // The record read last was covered by the checkpoint: note it without stepping (a resumed
  // run re-reads what it has done).
  virtual void Replay() = 0;
  // Feeds the record read last to the engine. The message names the input's file and line.
  virtual Status Step() = 0;
  // Filter steps taken so far.
  virtual int64_t steps() const = 0;

  // Adds the model's outputs to `out` and its fields to `summary`; StopRequested() is true
  // when a signal asked the run to stop (check it between long pieces of work). Across ranks
  // every rank calls it (the read-outs are collective) and `out` is null except on rank 0.
  virtual Status WriteOutputs(OutputSet* out, nlohmann::json* summary) = 0;
  // One paragraph for the terminal after a run.
  virtual std::string BriefReport() const = 0;
  // The terminal's last line after a run, below the files written: the score against a truth
  // or a GPS (empty: none). Called after WriteOutputs, on the lead rank only.
  virtual std::string Headline() const { return {}; }
};

// The part of a RunJob every model writes alike: its engine made, resumed and checkpointed
// through its facade (FootSlam, FastSlam: Create, Resume, Checkpoint, steps), across `ranks`
// (null: one process; RunOptions::ranks).
template <typename Facade, typename Config>
class FacadeRunJob : public RunJob {
 public:
  FacadeRunJob(const Config& config, Collective* ranks) : config_(config), ranks_(ranks) {}

  int64_t particles() const override { return config_.particles; }
  Status Create() override {
    StatusOr<std::unique_ptr<Facade>> engine = Facade::Create(config_, ranks_);
    if (!engine.ok()) return engine.status();
    engine_ = std::move(engine).value();
    return Status::Ok();
  }
  // Across ranks, collective: this rank's share from the file this rank wrote.
  Status Resume(std::string_view bytes, const std::string& name, std::string* user) override {
    StatusOr<std::unique_ptr<Facade>> engine = Facade::Resume(config_, bytes, name, user, ranks_);
    if (!engine.ok()) return engine.status();
    engine_ = std::move(engine).value();
    return Status::Ok();
  }
  StatusOr<std::string> Checkpoint(std::string_view user_data) const override {
    return engine_->Checkpoint(user_data);
  }
  int64_t steps() const override { return engine_->steps(); }
  std::string BriefReport() const override { return engine_->Summary().BriefReport(); }

 protected:
  Config config_;
  Collective* ranks_;
  std::unique_ptr<Facade> engine_;
};

// The records `reader` (with StatusOr<bool> Next(Record*)) yields before its end, or 0 when it
// fails before then: what ExpectedSteps() counts with a second reader of a file.
template <typename Record, typename Reader>
int64_t CountRecords(Reader& reader) {
  Record record;
  int64_t records = 0;
  for (;;) {
    StatusOr<bool> more = reader.Next(&record);
    if (!more.ok()) return 0;
    if (!*more) return records;
    ++records;
  }
}

// Newlines in `text`, and in a regular file (0 for anything else: a pipe must be read once, by
// the run): the record counts behind progress and memory predictions.
int64_t CountLines(std::string_view text);
int64_t CountRegularFileLines(const std::string& path);

// The checkpoint file of rank `rank` of a run whose checkpoint path is `path`: `path` itself for
// rank 0 (and for one process), `path.rank<q>` beside it for rank q.
std::string RankCheckpointPath(const std::string& path, int rank);

// Runs `job` as `options` say; `config_json` is the effective configuration (ConfigToJson) for
// summary.json. Returns the exit code after printing any error on stderr as one line.
int RunCommand(RunJob* job, const RunOptions& options, const std::string& config_json);

// Renders `image` as map.png and map.svg into `out`, stopping early (Ok, with what is done)
// when StopRequested().
Status AddMapImages(OutputSet* out, const MapImage& image);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_RUN_RUN_LOOP_H_
