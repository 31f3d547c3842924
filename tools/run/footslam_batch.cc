// `grove footslam batch` (tools/run/footslam_batch.h).
#include "tools/run/footslam_batch.h"

#include <fmt/format.h>
#include <sys/stat.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string_view>
#include <thread>
#include <vector>

#include "grove/checksum.h"
#include "grove/config_json.h"
#include "tools/io/atomic_file.h"
#include "tools/io/csv_reader.h"
#include "tools/run/footslam_run.h"
#include "tools/run/run_loop.h"

namespace grove::tools {
namespace {

struct Walk {
  int line = 0;
  std::string name;
  std::string steps_path;
  std::string prior_map_path;  // empty: none
  FootSlamConfig config;
  std::string digest;  // hex CRC-32 of the steps, the prior map and the result-changing config
};

struct WalkResult {
  // "ok", "skipped", "failed", "stopped" (by a signal, with a checkpoint), "not run" (the batch
  // was stopped before it)
  std::string status;
  int exit_code = 0;
  bool resumed = false;
  double wall_time_s = 0;
  std::string line;  // ResultJson's, once the walk is done
};

bool FileExists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

// The summary the batch writes into --out, and the prefix of its temporaries: no walk may take
// it as its name.
constexpr std::string_view kSummaryName = "batch_summary.jsonl";

bool ValidName(const std::string& name) {
  if (name.empty() || name.size() > 200 || name[0] == '.') return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
           c == '_' || c == '-';
  });
}

// A parser callback that sets *duplicate to the first key given twice in one object (nlohmann
// keeps the last silently) and lets parsing go on.
nlohmann::json::parser_callback_t DuplicateKeyFinder(std::string* duplicate) {
  auto seen = std::make_shared<std::vector<std::set<std::string>>>();
  return [seen, duplicate](int /*depth*/, nlohmann::json::parse_event_t event,
                           nlohmann::json& parsed) {
    using Event = nlohmann::json::parse_event_t;
    if (event == Event::object_start) seen->emplace_back();
    if (event == Event::object_end && !seen->empty()) seen->pop_back();
    if (event == Event::key && !seen->empty() && duplicate->empty() &&
        !seen->back().insert(parsed.get<std::string>()).second) {
      *duplicate = parsed.get<std::string>();
    }
    return true;
  };
}

// The configuration fields that change results, as JSON: what a walk's digest covers (threads
// and batch size do not change its outputs, so a batch with other --jobs skips it still).
std::string ResultConfigJson(const FootSlamConfig& config) {
  return ResultConfigToJson(FootSlamConfigFields(), config);
}

// Reads and checks every manifest line; InvalidArgument "manifest:line:column: ..." for the
// first bad one, NotFound or IoError when the manifest cannot be read.
StatusOr<std::vector<Walk>> ReadManifest(const std::string& path, const FootSlamConfig& base,
                                         int walk_threads) {
  StatusOr<std::string> text = ReadWholeFile(path);
  if (!text.ok()) return Status(text.status().code(), "--manifest " + text.status().message());
  const size_t slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "" : path.substr(0, slash + 1);
  auto resolve = [&](const std::string& p) { return p[0] == '/' ? p : dir + p; };
  std::vector<Walk> walks;
  std::map<std::string, int> names;
  std::istringstream lines(*text);
  std::string line;
  for (int number = 1; std::getline(lines, line); ++number) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    auto error = [&](size_t column, const std::string& message) {
      return InvalidArgumentError(fmt::format("{}:{}:{}: {}", path, number, column, message));
    };
    // The parser takes a NUL byte for the end of the input: what follows one would be ignored.
    if (const size_t nul = line.find('\0'); nul != std::string::npos) {
      return error(nul + 1, "not a JSON object: a NUL byte (JSON text has none)");
    }
    nlohmann::json j;
    std::string duplicate;
    try {
      j = nlohmann::json::parse(line, DuplicateKeyFinder(&duplicate));
    } catch (const nlohmann::json::parse_error& e) {
      return error(std::max<size_t>(e.byte, 1), "not a JSON object: " + std::string(e.what()));
    }
    if (!duplicate.empty()) {
      const std::string quoted = "\"" + duplicate + "\"";
      return error(line.find(quoted, line.find(quoted) + 1) + 1,
                   fmt::format("duplicate key {}", QuoteForMessage(duplicate)));
    }
    if (!j.is_object()) return error(1, "not a JSON object");
    for (const auto& [key, value] : j.items()) {
      if (key != "name" && key != "steps" && key != "prior_map" && key != "config") {
        return error(line.find("\"" + key + "\"") + 1,
                     fmt::format("unknown key {}: the keys are name, steps, prior_map and config",
                                 QuoteForMessage(key)));
      }
    }
    auto column_of = [&](const char* key) { return line.find(std::string("\"") + key) + 1; };
    Walk w;
    w.line = number;
    if (!j.contains("name") || !j["name"].is_string())
      return error(1, "name: a string is required");
    w.name = j["name"].get<std::string>();
    if (!ValidName(w.name)) {
      return error(column_of("name"),
                   fmt::format("name = {}: use letters, digits, '.', '_' and '-' (at most 200, "
                               "not starting with '.')",
                               QuoteForMessage(w.name)));
    }
    if (std::string_view(w.name).starts_with(kSummaryName)) {
      return error(column_of("name"), fmt::format("name = {}: reserved for the batch's own {}",
                                                  QuoteForMessage(w.name), kSummaryName));
    }
    if (auto [it, added] = names.emplace(w.name, number); !added) {
      return error(column_of("name"),
                   fmt::format("name = {}: already used on line {}", w.name, it->second));
    }
    if (!j.contains("steps") || !j["steps"].is_string() || j["steps"].get<std::string>().empty()) {
      return error(j.contains("steps") ? column_of("steps") : 1,
                   "steps: a non-empty path is required");
    }
    w.steps_path = resolve(j["steps"].get<std::string>());
    if (j.contains("prior_map")) {
      if (!j["prior_map"].is_string() || j["prior_map"].get<std::string>().empty()) {
        return error(column_of("prior_map"), "prior_map: must be a non-empty path");
      }
      w.prior_map_path = resolve(j["prior_map"].get<std::string>());
    }
    w.config = base;
    w.config.threads = walk_threads;
    if (j.contains("config")) {
      if (!j["config"].is_object()) return error(column_of("config"), "config: must be an object");
      Status s = ApplyConfigJson(FootSlamConfigFields(), "config", j["config"].dump(), &w.config);
      if (!s.ok()) {
        return error(column_of("config"), fmt::format("walk {}: {}", w.name, s.message()));
      }
    }
    if (Status s = w.config.Validate(); !s.ok()) {
      return error(column_of("config"), fmt::format("walk {}: {}", w.name, s.message()));
    }
    walks.push_back(std::move(w));
  }
  if (walks.empty()) return InvalidArgumentError(fmt::format("{}: no walks", path));
  return walks;
}

// The digest of what a walk's outputs depend on; the files are read whole.
StatusOr<std::string> DigestOf(const Walk& w) {
  StatusOr<std::string> steps = ReadWholeFile(w.steps_path);
  if (!steps.ok()) return Status(steps.status().code(), "steps " + steps.status().message());
  uint32_t crc = Crc32(*steps);
  crc = Crc32(std::string_view("\0prior\0", 7), crc);
  if (!w.prior_map_path.empty()) {
    StatusOr<std::string> prior = ReadWholeFile(w.prior_map_path);
    if (!prior.ok()) {
      return Status(prior.status().code(), "prior_map " + prior.status().message());
    }
    crc = Crc32(*prior, crc);
  }
  crc = Crc32(std::string_view("\0config\0", 8), crc);
  crc = Crc32(ResultConfigJson(w.config), crc);
  return fmt::format("{:08x}", crc);
}

// Runs one walk (or skips or resumes it); its `run` errors go to stderr as that command's do.
WalkResult RunWalk(const Walk& w, const FootSlamBatchOptions& options, int64_t memory_budget) {
  WalkResult result;
  const auto start = std::chrono::steady_clock::now();
  auto finish = [&](const char* status, int code) {
    result.status = status;
    result.exit_code = code;
    result.wall_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
  };
  const std::string dir = options.out_dir + "/" + w.name;
  const std::string marker_path = dir + "/batch_walk.json";
  StatusOr<std::string> digest = DigestOf(w);
  if (!digest.ok()) {
    Fail(kExitInput, fmt::format("walk {}: {}", w.name, digest.status().message()));
    return finish("failed", kExitInput);
  }
  nlohmann::json marker;
  if (StatusOr<std::string> text = ReadWholeFile(marker_path); text.ok()) {
    marker = nlohmann::json::parse(*text, nullptr, /*allow_exceptions=*/false);
  }
  const bool same = marker.is_object() && marker.value("digest", "") == *digest;
  if (same && marker.value("done", false) && FileExists(dir + "/summary.json")) {
    return finish("skipped", kExitOk);
  }
  FootSlamRunOptions run;
  run.steps_path = w.steps_path;
  run.run.out_dir = dir;
  run.run.progress = false;
  run.run.handle_signals = false;
  run.run.memory_budget_bytes = memory_budget;
  run.run.checkpoint_every = options.checkpoint_every;
  // A batch has no --resume: it resumes a stopped walk by itself.
  run.run.resume_advice = "run the same batch command again: it resumes this walk";
  result.resumed = same && FileExists(dir + "/checkpoint.grove");
  if (result.resumed) {
    run.run.resume_path = dir + "/checkpoint.grove";  // it holds the prior map
  } else {
    run.prior_map_path = w.prior_map_path;
  }
  Status s = EnsureDirectory(dir);
  if (s.ok()) {
    s = WriteFileAtomically(
        marker_path, nlohmann::json{{"name", w.name}, {"digest", *digest}, {"done", false}}.dump());
  }
  if (!s.ok()) {
    Fail(kExitOutput, fmt::format("walk {}: {}", w.name, s.message()));
    return finish("failed", kExitOutput);
  }
  const int code = RunFootSlamCommand(w.config, run);
  if (code >= kExitSignalBase) return finish("stopped", code);  // with a checkpoint to resume
  if (code != kExitOk) return finish("failed", code);
  s = WriteFileAtomically(
      marker_path, nlohmann::json{{"name", w.name}, {"digest", *digest}, {"done", true}}.dump());
  if (!s.ok()) {
    Fail(kExitOutput, fmt::format("walk {}: {}", w.name, s.message()));
    return finish("failed", kExitOutput);
  }
  return finish("ok", kExitOk);
}

nlohmann::json ResultJson(const Walk& w, const WalkResult& r, const std::string& out_dir) {
  nlohmann::json j = {{"name", w.name},
                      {"line", w.line},
                      {"status", r.status},
                      {"exit_code", r.exit_code},
                      {"resumed", r.resumed},
                      {"wall_time_s", r.wall_time_s},
                      {"out", out_dir + "/" + w.name}};
  if (r.status == "ok" || r.status == "skipped") {
    StatusOr<std::string> text = ReadWholeFile(out_dir + "/" + w.name + "/summary.json");
    if (text.ok()) {
      nlohmann::json s = nlohmann::json::parse(*text, nullptr, false);
      for (const char* key : {"steps", "particles", "ns_per_particle_step", "run_id"}) {
        if (s.is_object() && s.contains(key)) j[key] = s[key];
      }
    }
  }
  return j;
}

}  // namespace

int RunFootSlamBatch(const FootSlamConfig& base, const FootSlamBatchOptions& options) {
  if (options.manifest_path.empty()) return Fail(kExitUsage, "--manifest: the path is empty");
  if (options.out_dir.empty()) return Fail(kExitUsage, "--out: an output directory is required");
  if (options.jobs < 1 || options.jobs > 1024) {
    return Fail(kExitUsage, fmt::format("--jobs = {}: must be in [1, 1024]", options.jobs));
  }
  const int total_threads = base.threads > 0 ? base.threads : UsableCpus();
  const int walk_threads = std::max(1, total_threads / options.jobs);
  const int ranks = options.all_gather ? std::max(1, options.ranks) : 1;
  auto all_gather = [&](const std::string& mine) {
    return ranks > 1 ? options.all_gather(mine) : std::vector<std::string>{mine};
  };
  StatusOr<std::vector<Walk>> walks = ReadManifest(options.manifest_path, base, walk_threads);
  // Every rank reports how its reading went (so none waits for a rank that gave up), and the
  // ranks must have read the same walks and configuration.
  std::string mine;
  if (walks.ok()) {
    uint32_t crc = 0;
    for (const Walk& w : *walks) {
      crc = Crc32(w.name + '\n' + w.steps_path + '\n' + w.prior_map_path + '\n' +
                      ResultConfigJson(w.config) + '\n',
                  crc);
    }
    mine = fmt::format("ok {:08x}", crc);
  } else {
    const StatusCode c = walks.status().code();
    const int code =
        c == StatusCode::kNotFound || c == StatusCode::kIoError ? kExitInput : kExitUsage;
    mine = fmt::format("error {}", code);
  }
  const std::vector<std::string> readings = all_gather(mine);
  if (!walks.ok()) return Fail(std::stoi(mine.substr(6)), walks.status().message());
  for (int r = 0; r < static_cast<int>(readings.size()); ++r) {
    if (readings[static_cast<size_t>(r)].rfind("error ", 0) == 0) {
      return Fail(
          std::stoi(readings[static_cast<size_t>(r)].substr(6)),
          fmt::format("rank {} could not read the manifest (its error is in its output)", r));
    }
    if (readings[static_cast<size_t>(r)] != readings[0]) {
      return Fail(kExitUsage, fmt::format("rank {} read other walks or another configuration "
                                          "than rank 0 from {}: give every rank the same "
                                          "manifest, files and options",
                                          r, options.manifest_path));
    }
  }
  if (Status s = EnsureDirectory(options.out_dir); !s.ok()) return Fail(kExitOutput, s.message());
  const int64_t available = AvailableMemoryBytes();
  const int64_t budget = available > 0 ? available / options.jobs : 0;

  SignalHandlers signals;
  std::vector<WalkResult> results(walks->size(), WalkResult{"not run", 0, false, 0, ""});
  std::atomic<size_t> next{0};
  std::mutex print;
  auto worker = [&] {
    for (;;) {
      if (StopRequested()) return;
      // This rank's walks: every ranks-th from its own.
      const size_t i = next.fetch_add(1) * static_cast<size_t>(ranks) +
                       static_cast<size_t>(ranks > 1 ? options.rank : 0);
      if (i >= walks->size()) return;
      results[i] = RunWalk((*walks)[i], options, budget);
      results[i].line = ResultJson((*walks)[i], results[i], options.out_dir).dump();
      std::lock_guard<std::mutex> lock(print);
      std::printf("%s\n", results[i].line.c_str());
      std::fflush(stdout);
    }
  };
  std::vector<std::thread> threads;
  const size_t jobs = std::min<size_t>(static_cast<size_t>(options.jobs), walks->size());
  for (size_t k = 1; k < jobs; ++k) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();

  // Every rank's results, as "index<TAB>JSON" lines of its walks, then in manifest order.
  std::string own;
  for (size_t i = static_cast<size_t>(ranks > 1 ? options.rank : 0); i < walks->size();
       i += static_cast<size_t>(ranks)) {
    // A walk the batch was stopped before has no line yet.
    if (results[i].line.empty()) {
      results[i].line = ResultJson((*walks)[i], results[i], options.out_dir).dump();
    }
    own += fmt::format("{}\t{}\n", i, results[i].line);
  }
  std::vector<std::string> lines(walks->size());
  std::vector<int> codes(walks->size(), 0);
  for (const std::string& part : all_gather(own)) {
    std::istringstream in(part);
    std::string line;
    while (std::getline(in, line)) {
      const size_t tab = line.find('\t');
      const size_t i = std::stoul(line.substr(0, tab));
      lines[i] = line.substr(tab + 1);
      codes[i] = nlohmann::json::parse(lines[i]).value("exit_code", 0);
    }
  }
  std::string summary;
  bool permanent = false, temporary = false;
  int stopped = 0;
  for (size_t i = 0; i < walks->size(); ++i) {
    summary += lines[i] + "\n";
    const int code = codes[i];
    if (code == kExitUsage || code == kExitInput || code == kExitRun) permanent = true;
    if (code == kExitInternal || code == kExitOutput || code == kExitMemory) temporary = true;
    if (code >= kExitSignalBase) stopped = std::max(stopped, code);
  }
  if (ranks == 1 || options.rank == 0) {
    Status s = WriteFileAtomically(options.out_dir + "/batch_summary.jsonl", summary);
    if (!s.ok()) return Fail(kExitOutput, s.message());
  }
  if (const int signal = StopSignal(); signal != 0) return kExitSignalBase + signal;
  if (stopped != 0) return stopped;
  if (permanent) return kExitRun;
  if (temporary) return 75;  // EX_TEMPFAIL: a retry may succeed
  return kExitOk;
}

}  // namespace grove::tools
