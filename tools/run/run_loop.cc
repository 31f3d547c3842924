#include "tools/run/run_loop.h"

#include <fmt/format.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <optional>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include "grove/checksum.h"
#include "tools/io/atomic_file.h"
#include "tools/io/csv_reader.h"
#include "tools/run/progress_reporter.h"

namespace grove::tools {
namespace {

// Where the run stands in its input: kept in each checkpoint so that a resumed run can check
// that it reads the same records.
struct InputPosition {
  std::string input_name;
  int64_t records = 0;
  uint32_t digest = 0;  // CRC-32 of the digest bytes of every record so far

  void Add(std::string_view bytes) {
    digest = Crc32(bytes, digest);
    ++records;
  }
  std::string ToJson() const {
    // The FootSLAM checkpoints of earlier versions named these steps_file and steps.
    return nlohmann::json{{"steps_file", input_name}, {"steps", records}, {"digest", digest}}.dump(
        -1, ' ', false, nlohmann::json::error_handler_t::replace);
  }
  static StatusOr<InputPosition> FromJson(const std::string& text, const std::string& name) {
    InputPosition p;
    try {
      nlohmann::json j = nlohmann::json::parse(text);
      p.input_name = j.at("steps_file").get<std::string>();
      p.records = j.at("steps").get<int64_t>();
      p.digest = j.at("digest").get<uint32_t>();
    } catch (const nlohmann::json::exception& e) {
      return DataLossError(fmt::format("{}: the input position is unreadable: {}", name,
                                       QuoteForMessage(e.what(), 200)));
    }
    if (p.records < 0) return DataLossError(name + ": the input position is negative");
    return p;
  }
};

// The file `path` names, if it exists.
bool StatOf(const std::string& path, struct stat* st) {
  return !path.empty() && ::stat(path.c_str(), st) == 0;
}

bool SameFile(const struct stat& a, const struct stat& b) {
  return a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

std::string DirectoryOf(const std::string& path) {
  size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

// Every path the run will write is checked before the first step: none is an input, none is
// a directory, the checkpoint's directory exists (or is made: *created gets what was made) and
// takes a file.
Status CheckOutputPaths(const RunJob& job, const std::string& out_dir,
                        const std::string& checkpoint_path, std::vector<std::string>* created) {
  struct Input {
    std::string path;
    struct stat st;
  };
  std::vector<Input> inputs;
  for (const std::string& p : job.InputPaths()) {
    Input in{p, {}};
    if (StatOf(p, &in.st)) inputs.push_back(in);
  }
  std::vector<std::string> outputs;
  for (const std::string& name : job.OutputNames()) outputs.push_back(out_dir + "/" + name);
  outputs.push_back(out_dir + "/summary.json");
  for (const std::string& target : outputs) {
    if (target == checkpoint_path) {
      return InvalidArgumentError(
          fmt::format("--checkpoint {} is one of the run's outputs: choose another path", target));
    }
  }
  outputs.push_back(checkpoint_path);
  for (const std::string& target : outputs) {
    struct stat st;
    if (!StatOf(target, &st)) continue;
    for (const Input& in : inputs) {
      if (SameFile(st, in.st)) {
        return InvalidArgumentError(fmt::format(
            "{} would be written over, but it is the input {}: write the outputs elsewhere", target,
            in.path));
      }
    }
    if (S_ISDIR(st.st_mode)) {
      return IoError(fmt::format("cannot write {}: it is a directory", target));
    }
  }
  // The checkpoint's directory must take a file now, not after hours of running.
  GROVE_RETURN_IF_ERROR(EnsureDirectory(DirectoryOf(checkpoint_path), created));
  StatusOr<AtomicFileWriter> probe = AtomicFileWriter::Create(checkpoint_path);
  if (!probe.ok()) return probe.status();
  return Status::Ok();  // the probe's temporary is removed here
}

// Reads a checkpoint: a regular file, whole.
StatusOr<std::string> ReadCheckpointFile(const std::string& path) {
  if (path.empty()) return InvalidArgumentError("--resume: the path is empty");
  struct stat st;
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    return IoError(fmt::format("{}: {}, not a checkpoint file", path,
                               S_ISDIR(st.st_mode) ? "is a directory" : "is not a regular file"));
  }
  return ReadWholeFile(path);
}

}  // namespace

int Fail(int code, std::string_view message) {
  std::fprintf(stderr, "grove: error: %.*s\n", static_cast<int>(message.size()), message.data());
  return code;
}

int ExitCodeOf(const Status& s) {
  switch (s.code()) {
    case StatusCode::kInvalidArgument:
    case StatusCode::kNotFound:
    case StatusCode::kDataLoss:
      return kExitInput;
    case StatusCode::kIoError:
    case StatusCode::kResourceExhausted:
      return kExitOutput;
    case StatusCode::kOutOfRange:
    case StatusCode::kFailedPrecondition:
      return kExitRun;
    default:
      return kExitInternal;
  }
}

int UsableCpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

// Every rank's `mine`, in rank order (collective).
template <typename T>
StatusOr<std::vector<T>> EveryRanks(Collective& ranks, const T& mine) {
  static_assert(std::is_trivially_copyable_v<T>);
  std::vector<std::string> parts;
  GROVE_RETURN_IF_ERROR(
      ranks.AllGather(std::string(reinterpret_cast<const char*>(&mine), sizeof(T)), &parts));
  std::vector<T> values(parts.size());
  for (size_t q = 0; q < parts.size(); ++q) {
    if (parts[q].size() != sizeof(T)) {
      return InternalError(
          fmt::format("collective: rank {} sent {} bytes, not {}", q, parts[q].size(), sizeof(T)));
    }
    std::memcpy(&values[q], parts[q].data(), sizeof(T));
  }
  return values;
}

// Across ranks, before a record is stepped: the lowest rank's stop signal (0: none), or an error
// when a rank failed to read, or the ranks read different records or not the same number.
StatusOr<int> AgreeOnRecord(Collective& ranks, const StatusOr<bool>& more,
                            const std::string& record, int64_t number,
                            const std::string& input_name, const char* records_name) {
  struct Mark {
    int32_t signal;
    int32_t state;  // 0: the input ended, 1: a record, 2: a read error
    uint32_t crc;
    uint32_t zero;
  };
  const Mark mine{StopSignal(), more.ok() ? (*more ? 1 : 0) : 2, Crc32(record), 0};
  StatusOr<std::vector<Mark>> gathered = EveryRanks(ranks, mine);
  if (!gathered.ok()) return gathered.status();
  const std::vector<Mark>& all = *gathered;
  for (const Mark& m : all) {
    if (m.signal != 0) return m.signal;
  }
  bool failed = false;
  for (const Mark& m : all) failed = failed || m.state == 2;
  if (failed) {
    GROVE_RETURN_IF_ERROR(AgreeStatus(ranks, more.ok() ? Status::Ok() : more.status()));
  }
  for (size_t q = 1; q < all.size(); ++q) {
    if (all[q].state != all[0].state) {
      return InvalidArgumentError(fmt::format(
          "{}: rank {} and rank 0 disagree on whether {} {} exists: every rank must read the "
          "same input",
          input_name, q, records_name, number));
    }
    if (all[q].crc != all[0].crc) {
      return InvalidArgumentError(
          fmt::format("{}: rank {} read other values than rank 0 in {} {}: every rank must read "
                      "the same input",
                      input_name, q, records_name, number));
    }
  }
  return 0;
}

// Across ranks: the lowest rank's stop signal (0: none).
StatusOr<int> AgreeOnSignal(Collective& ranks) {
  StatusOr<std::vector<int32_t>> all = EveryRanks<int32_t>(ranks, StopSignal());
  if (!all.ok()) return all.status();
  for (int32_t s : *all) {
    if (s != 0) return s;
  }
  return 0;
}

std::string RankCheckpointPath(const std::string& path, int rank) {
  return rank == 0 ? path : fmt::format("{}.rank{}", path, rank);
}

namespace {

// One run of a RunJob, stage by stage. Across ranks rank 0 (the lead) checks and writes the
// outputs and reports; every rank takes the same steps, agrees on every error, and exits with
// the same code. Each stage returns -1 to go on, or the exit code after printing any error.
class RunLoop {
 public:
  RunLoop(RunJob* job, const RunOptions& options)
      : job_(job),
        options_(options),
        ranks_(options.ranks),
        lead_(ranks_ == nullptr || ranks_->rank() == 0),
        checkpoint_path_(options.checkpoint_path.empty() ? options.out_dir + "/checkpoint.grove"
                                                         : options.checkpoint_path),
        // Across ranks each rank writes and reads its own share's file.
        my_checkpoint_path_(RankCheckpointPath(checkpoint_path_, rank())),
        my_resume_path_(
            options.resume_path.empty() ? "" : RankCheckpointPath(options.resume_path, rank())) {
    position_.input_name = job->InputName();
  }
  // A run that did not succeed leaves no directory it made: those of the checkpoint here, the
  // output directory's in OutputDirectory (only empty ones go: one holding a checkpoint stays).
  ~RunLoop() {
    if (!succeeded_) RemoveCreatedDirectories(checkpoint_dirs_made_);
  }

  // Every output path is checked, and the output directory locked, before any work.
  int OpenOutputs() {
    Status paths_ok;
    if (lead_) {
      StatusOr<OutputDirectory> opened = OutputDirectory::Open(options_.out_dir);
      if (opened.ok()) {
        out_dir_.emplace(std::move(opened).value());
        paths_ok =
            CheckOutputPaths(*job_, options_.out_dir, checkpoint_path_, &checkpoint_dirs_made_);
      } else {
        paths_ok = opened.status();
      }
    }
    if (Status s = Agree(paths_ok); !s.ok()) {
      return Fail(s.code() == StatusCode::kInvalidArgument ? kExitUsage : kExitOutput, s.message());
    }
    return -1;
  }

  // Refuses a run that would not fit, before building anything.
  int CheckMemory() {
    const int64_t records = job_->ExpectedRecords();
    budget_ = MemoryBudget::Of(options_.memory_budget_bytes);
    predicted_ = job_->PredictPeakBytes(records);
    Status fits = budget_.Check(predicted_, job_->DescribePrediction(records),
                                "use fewer particles or raise --memory-budget");
    if (Status s = Agree(fits); !s.ok()) return Fail(kExitMemory, s.message());
    return -1;
  }

  // A new engine, or one continuing from a checkpoint.
  int CreateOrResume() {
    if (options_.resume_path.empty()) {
      if (Status s = Agree(job_->Create()); !s.ok()) {
        return Fail(s.code() == StatusCode::kResourceExhausted ? kExitMemory : ExitCodeOf(s),
                    s.message());
      }
      return -1;
    }
    StatusOr<std::string> bytes = ReadCheckpointFile(my_resume_path_);
    if (!bytes.ok() && rank() > 0) {
      bytes = Status(bytes.status().code(),
                     bytes.status().message() +
                         " (across ranks, rank q resumes from the file --resume names plus "
                         "\".rank<q>\": resume on as many ranks as wrote the checkpoint)");
    }
    if (Status s = Agree(bytes.status()); !s.ok()) return Fail(kExitInput, s.message());
    std::string user;
    // Collective across ranks: every rank's error reaches every rank.
    Status s = job_->Resume(*bytes, my_resume_path_, &user);
    if (!s.ok()) {
      // Another configuration or format is a usage error; a corrupt file a bad input.
      return Fail(s.code() == StatusCode::kFailedPrecondition  ? kExitUsage
                  : s.code() == StatusCode::kResourceExhausted ? kExitMemory
                                                               : kExitInput,
                  s.message());
    }
    StatusOr<InputPosition> at = InputPosition::FromJson(user, my_resume_path_);
    if (Status s = Agree(at.status()); !s.ok()) return Fail(kExitInput, s.message());
    resumed_at_ = *at;
    last_checkpoint_steps_ = job_->steps();
    return -1;
  }

  // Reads and steps every input record, with progress and checkpoints.
  int StepThroughInput() {
    const bool terminal = isatty(fileno(stderr)) != 0;
    ProgressReporter progress(job_->ExpectedSteps(), job_->particles(), stderr, terminal);
    const bool show_progress = options_.progress && lead_;
    std::string digest_bytes;
    while (true) {
      if (ranks_ == nullptr) {
        if (int signal = StopSignal(); signal != 0) return StopWithCheckpoint(signal);
      }
      digest_bytes.clear();
      StatusOr<bool> more = job_->Read(&digest_bytes);
      if (ranks_ != nullptr) {
        // Every rank reads the input itself: the ranks agree on a stop signal, on the read's
        // outcome and on the record's bytes before any of them steps.
        StatusOr<int> signal = AgreeOnRecord(*ranks_, more, digest_bytes, position_.records + 1,
                                             job_->InputName(), job_->RecordsName());
        if (!signal.ok()) return Fail(kExitInput, signal.status().message());
        if (*signal != 0) return StopWithCheckpoint(*signal);
      }
      if (!more.ok()) return Fail(kExitInput, more.status().message());
      if (!*more) break;
      // The records a resumed run has taken already: re-read to check them, not stepped again.
      const bool replay = position_.records < resumed_at_.records;
      position_.Add(digest_bytes);
      if (replay) {
        if (const int code = ReplayRecord(); code >= 0) return code;
        continue;
      }
      if (Status s = job_->Step(); !s.ok()) {
        // Out of memory in a step is the memory's fault, not the disk's.
        return Fail(s.code() == StatusCode::kResourceExhausted ? kExitMemory : ExitCodeOf(s),
                    s.message());
      }
      if (show_progress && !HangupSeen()) progress.Update(position_.records);
      if (CheckpointDue()) {
        if (Status s = WriteCheckpoint(); !s.ok()) return Fail(ExitCodeOf(s), s.message());
      }
    }
    Status long_enough;
    if (position_.records < resumed_at_.records) {
      long_enough = InvalidArgumentError(fmt::format(
          "{}: has {} {}, but {} was made after {}: resume with the same input", job_->InputName(),
          position_.records, job_->RecordsName(), my_resume_path_, resumed_at_.records));
    }
    if (Status s = Agree(long_enough); !s.ok()) return Fail(kExitInput, s.message());
    if (job_->steps() == 0) return Fail(kExitInput, fmt::format("{}: no steps", job_->InputName()));
    if (show_progress && !HangupSeen()) progress.Finish();
    return -1;
  }

  // The outputs as a set: staged, then renamed into place, summary.json last. Across ranks
  // every rank computes them (the read-outs are collective); the lead writes them.
  int WriteOutputs(const std::string& config_json, std::chrono::steady_clock::time_point start) {
    std::optional<OutputSet> out;
    Status staged;
    if (lead_) {
      StatusOr<OutputSet> begun = OutputSet::Begin(options_.out_dir);
      if (begun.ok()) {
        out.emplace(std::move(begun).value());
      } else {
        staged = begun.status();
      }
    }
    if (Status s = Agree(staged); !s.ok()) return Fail(kExitOutput, s.message());
    nlohmann::json summary = {{"config", nlohmann::json::parse(config_json)}};
    if (Status s = Agree(job_->WriteOutputs(out ? &*out : nullptr, &summary)); !s.ok()) {
      return Fail(ExitCodeOf(s), s.message());
    }
    if (ranks_ != nullptr) {
      StatusOr<int> signal = AgreeOnSignal(*ranks_);
      if (!signal.ok()) return Fail(kExitInternal, signal.status().message());
      if (*signal != 0) return StopWithCheckpoint(*signal);
    } else if (int signal = StopSignal(); signal != 0) {
      return StopWithCheckpoint(signal);
    }
    AddRunFigures(start, &summary);
    if (Status s = Agree(lead_ ? out->Commit(summary) : Status::Ok()); !s.ok()) {
      return Fail(kExitOutput, s.message());
    }
    const std::string brief = job_->BriefReport();  // collective across ranks: every rank
    succeeded_ = true;
    if (!lead_) return kExitOk;
    out_dir_->Keep();
    std::string names;
    for (const std::string& n : out->names()) names += n + ", ";
    std::fprintf(stderr, "%s\nwrote %s/{%ssummary.json}\n", brief.c_str(), options_.out_dir.c_str(),
                 names.c_str());
    if (const std::string headline = job_->Headline(); !headline.empty()) {
      std::fprintf(stderr, "%s\n", headline.c_str());
    }
    return kExitOk;
  }

 private:
  int rank() const { return ranks_ == nullptr ? 0 : ranks_->rank(); }
  Status Agree(const Status& s) const { return ranks_ == nullptr ? s : AgreeStatus(*ranks_, s); }
  // Prints on the lead only.
  int Fail(int code, std::string_view message) const {
    return lead_ ? tools::Fail(code, message) : code;
  }

  // A record a resumed run re-read: at the checkpoint's position the records so far must be
  // those the checkpoint was made after.
  int ReplayRecord() {
    Status same;
    if (position_.records == resumed_at_.records && position_.digest != resumed_at_.digest) {
      same = InvalidArgumentError(
          fmt::format("{}: the first {} {} differ from those of {} (made from {}): resume with "
                      "the same input",
                      job_->InputName(), resumed_at_.records, job_->RecordsName(), my_resume_path_,
                      QuoteForMessage(resumed_at_.input_name, 200)));
    }
    if (ranks_ != nullptr && position_.records == resumed_at_.records) same = Agree(same);
    if (!same.ok()) return Fail(kExitInput, same.message());
    job_->Replay();
    return -1;
  }

  // --checkpoint-every N: a checkpoint at the first record after which the step count has
  // reached the next multiple of N, however many steps a record takes (a scan takes two, a
  // control before the first none), so one at least every N steps and never two at one step.
  bool CheckpointDue() const {
    const int64_t n = options_.checkpoint_every;
    return n > 0 && job_->steps() / n > last_checkpoint_steps_ / n;
  }

  // Across ranks every rank writes its own file and the ranks agree on the outcome; a crash
  // between two ranks' renames leaves files of two steps, which a resume refuses.
  Status WriteCheckpoint() {
    auto t0 = std::chrono::steady_clock::now();
    StatusOr<std::string> bytes = job_->Checkpoint(position_.ToJson());
    Status s = bytes.status();
    if (s.ok()) s = WriteFileAtomically(my_checkpoint_path_, *bytes);
    GROVE_RETURN_IF_ERROR(Agree(s));
    if (out_dir_) out_dir_->Keep();  // it holds a checkpoint now (the default path)
    last_checkpoint_steps_ = job_->steps();
    ++checkpoints_written_;
    checkpoint_bytes_ = static_cast<int64_t>(bytes->size());
    checkpoint_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return Status::Ok();
  }

  // Across ranks every rank comes here together (the signal is agreed).
  int StopWithCheckpoint(int signal) {
    if (position_.records < resumed_at_.records) {  // still re-reading: nothing new to save
      if (lead_) {
        std::fprintf(stderr, "\ngrove: stopped by %s before any new step; %s is unchanged\n",
                     strsignal(signal), options_.resume_path.c_str());
      }
      return kExitSignalBase + signal;
    }
    Status s = WriteCheckpoint();
    if (!s.ok()) return Fail(kExitOutput, s.message());
    if (lead_) {
      const std::string advice =
          options_.resume_advice.empty()
              ? "continue with the same command and --resume " + checkpoint_path_
              : options_.resume_advice;
      std::fprintf(
          stderr, "\ngrove: stopped by %s after step %lld: wrote %s%s; %s\n", strsignal(signal),
          static_cast<long long>(job_->steps()), checkpoint_path_.c_str(),
          ranks_ == nullptr ? "" : " (and one file per further rank beside it)", advice.c_str());
    }
    return kExitSignalBase + signal;
  }

  // What the run cost, for summary.json.
  void AddRunFigures(std::chrono::steady_clock::time_point start, nlohmann::json* summary) const {
    nlohmann::json& s = *summary;
    s["wall_time_s"] =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    s["peak_rss_bytes"] = PeakRssBytes();
    s["predicted_peak_bytes"] = predicted_;
    s["memory_budget"] = {{"bytes", budget_.bytes}, {"source", budget_.source}};
    s["checkpoints"] = {{"written", checkpoints_written_},
                        {"seconds", checkpoint_s_},
                        {"last_bytes", checkpoint_bytes_},
                        {"resumed_from", options_.resume_path},
                        {"resumed_at_record", resumed_at_.records}};
    if (ranks_ != nullptr) s["ranks"] = ranks_->size();
  }

  RunJob* const job_;
  const RunOptions& options_;
  Collective* const ranks_;
  const bool lead_;
  const std::string checkpoint_path_;
  const std::string my_checkpoint_path_;
  const std::string my_resume_path_;
  std::optional<OutputDirectory> out_dir_;
  MemoryBudget budget_;
  int64_t predicted_ = 0;
  InputPosition resumed_at_;
  InputPosition position_;
  bool succeeded_ = false;
  int64_t last_checkpoint_steps_ = 0;              // the step count of the last checkpoint
  std::vector<std::string> checkpoint_dirs_made_;  // the checkpoint's directories this run made
  int64_t checkpoints_written_ = 0, checkpoint_bytes_ = 0;
  double checkpoint_s_ = 0;
};

}  // namespace

int RunCommand(RunJob* job, const RunOptions& options, const std::string& config_json) {
  auto wall_start = std::chrono::steady_clock::now();
  std::optional<SignalHandlers> signals;
  if (options.handle_signals) signals.emplace();
  RunLoop loop(job, options);
  if (const int code = loop.OpenOutputs(); code >= 0) return code;
  if (const int code = loop.CheckMemory(); code >= 0) return code;
  if (const int code = loop.CreateOrResume(); code >= 0) return code;
  if (const int code = loop.StepThroughInput(); code >= 0) return code;
  return loop.WriteOutputs(config_json, wall_start);
}

int64_t CountLines(std::string_view text) {
  return static_cast<int64_t>(std::count(text.begin(), text.end(), '\n'));
}

int64_t CountRegularFileLines(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return 0;
  std::ifstream in(path, std::ios::binary);
  std::vector<char> buffer(1 << 20);
  int64_t lines = 0;
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    lines += CountLines(std::string_view(buffer.data(), static_cast<size_t>(in.gcount())));
  }
  return lines;
}

Status AddMapImages(OutputSet* out, const MapImage& image) {
  if (StopRequested()) return Status::Ok();
  StatusOr<std::string> png = RenderPng(image);
  if (!png.ok()) return png.status();
  GROVE_RETURN_IF_ERROR(out->Add("map.png", *png));
  if (StopRequested()) return Status::Ok();
  StatusOr<std::string> svg = RenderSvg(image);
  if (!svg.ok()) return svg.status();
  return out->Add("map.svg", *svg);
}

}  // namespace grove::tools
