// Property checks for grove's parsers, shared by the libFuzzer targets in tests/fuzz/ and by
// tests/tools/fuzz_regression_test.cc, which replays the committed corpora through them.
//
// Each Check* function feeds one input to one parser and returns "" when every property holds, or
// a one-line description of the first one broken. They never abort (a fuzzer traps on a non-empty
// result, a test fails with it); an exception out of a parser is reported as a broken property.
//
// Properties, beyond "no crash, no sanitizer report":
//   - a reader returns ok, or InvalidArgument with a one-line message (no '\n');
//   - that message starts with the input's name and ':'; when it continues "LINE:COLUMN: " the
//     line exists in the input and the column is at most one past the line's end;
//   - numbers the reader promises finite are finite; times it promises increasing increase;
//   - StepReader: start_time_s() is finite and before the first step, steps are no longer than
//     max_step_m, an error repeats on the next call, the end repeats too;
//   - FootSLAM JSON: a failed apply leaves the configuration unchanged, a successful one sets
//     every key to exactly the value in the text and no other field; Validate() names a field.
//   - Checkpoints: FootSlam::Resume returns ok, or DataLoss / FailedPrecondition with a one-line
//     message starting "NAME: "; a resumed engine steps, reports its maps and paths, and its own
//     checkpoint resumes to an engine whose checkpoint is the same bytes. The input is tried as
//     it is and with its header's length and checksum made to match, so mutations reach the
//     body's parser instead of stopping at the checksum.
#ifndef GROVE_TESTS_FUZZ_FUZZ_CHECKS_H_
#define GROVE_TESTS_FUZZ_FUZZ_CHECKS_H_

#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "engine/io/checkpoint_io.h"
#include "grove/config_json.h"
#include "grove/footslam.h"
#include "grove/status.h"
#include "tools/io/fastslam_inputs.h"
#include "tools/io/output_readers.h"
#include "tools/io/step_reader.h"
#include "tools/io/victoria_park.h"
#include "tools/report/trajectory_metrics.h"

namespace grove::testing {

// Prints `failure` and traps when it is not empty; for the fuzz targets.
inline void TrapIfViolated(const std::string& failure) {
  if (failure.empty()) return;
  std::fprintf(stderr, "fuzz property violated: %s\n", failure.c_str());
  std::fflush(stderr);
  __builtin_trap();
}

namespace fuzz_internal {

// `text` with every byte outside printable ASCII as \xNN, so a report stays on one line.
inline std::string Printable(std::string_view text, size_t max_bytes = 300) {
  std::string out;
  for (size_t i = 0; i < text.size() && i < max_bytes; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7f && c != '\\') {
      out += static_cast<char>(c);
    } else {
      out += fmt::format("\\x{:02x}", c);
    }
  }
  if (text.size() > max_bytes) out += "...";
  return out;
}

// The byte length of each line of `text`: the lines end in '\n', but the last one may not; an
// empty text counts as one empty line (a reader reports "line 1" for it).
inline std::vector<size_t> LineLengths(std::string_view text) {
  std::vector<size_t> lengths;
  size_t start = 0;
  for (;;) {
    const size_t stop = text.find('\n', start);
    if (stop == std::string_view::npos) {
      if (start < text.size() || lengths.empty()) lengths.push_back(text.size() - start);
      return lengths;
    }
    lengths.push_back(stop - start);
    start = stop + 1;
  }
}

// Reads a decimal number > 0 followed by `end` from the front of *text.
inline bool TakeNumber(std::string_view* text, char end, int64_t* value) {
  size_t i = 0;
  int64_t v = 0;
  while (i < text->size() && i < 18 && (*text)[i] >= '0' && (*text)[i] <= '9') {
    v = v * 10 + ((*text)[i] - '0');
    ++i;
  }
  if (i == 0 || i >= text->size() || (*text)[i] != end) return false;
  *value = v;
  text->remove_prefix(i + 1);
  return true;
}

// Checks the error of a reader given the input `text` named `name`: InvalidArgument, one line,
// "name: what" or "name:LINE:COLUMN: what" with the position inside `text`.
inline std::string CheckError(const Status& status, std::string_view name, std::string_view text) {
  const std::string& message = status.message();
  const std::string shown = "\"" + Printable(message) + "\"";
  if (status.code() != StatusCode::kInvalidArgument) {
    return fmt::format("error code {} (expected InvalidArgument): {}",
                       StatusCodeName(status.code()), shown);
  }
  if (message.empty()) return "an error with an empty message";
  if (message.find('\n') != std::string::npos) return "error message spans lines: " + shown;
  if (message.size() <= name.size() || message.compare(0, name.size(), name) != 0 ||
      message[name.size()] != ':') {
    return fmt::format("error message does not start with \"{}:\": {}", name, shown);
  }
  std::string_view rest = std::string_view(message).substr(name.size() + 1);
  if (rest.starts_with(' ')) return "";
  int64_t line = 0;
  int64_t column = 0;
  if (!TakeNumber(&rest, ':', &line) || !TakeNumber(&rest, ':', &column) ||
      !rest.starts_with(' ')) {
    return "error message is neither \"NAME: what\" nor \"NAME:LINE:COLUMN: what\": " + shown;
  }
  const std::vector<size_t> lengths = LineLengths(text);
  if (line < 1 || line > static_cast<int64_t>(lengths.size())) {
    return fmt::format("error names line {} of an input with {} line(s): {}", line, lengths.size(),
                       shown);
  }
  const size_t length = lengths[static_cast<size_t>(line - 1)];
  if (column < 1 || column > static_cast<int64_t>(length) + 1) {
    return fmt::format("error names column {} of line {}, which has {} byte(s): {}", column, line,
                       length, shown);
  }
  return "";
}

inline bool Finite(double a, double b = 0, double c = 0) {
  return std::isfinite(a) && std::isfinite(b) && std::isfinite(c);
}

inline std::string CheckStepReaderUnguarded(const uint8_t* data, size_t size) {
  constexpr char kName[] = "fuzz_steps.csv";
  std::string_view text(reinterpret_cast<const char*>(data), size);
  tools::StepReaderOptions options;
  // A first byte below 8 (never the start of a useful step file) selects options from the next
  // two bytes: small line limits and step limits; 6 and 7 try invalid ones.
  if (size >= 3 && data[0] < 8) {
    const uint8_t mode = data[0];
    options.max_line_bytes = mode == 7 ? data[1] : size_t{16} + data[1];
    constexpr double kInvalidSteps[] = {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(),
                                        std::numeric_limits<double>::infinity()};
    options.max_step_m = mode == 6 ? kInvalidSteps[data[2] % 4] : (data[2] + 1) / 16.0;
    text.remove_prefix(3);
  }
  const bool options_valid =
      options.max_line_bytes >= 16 && options.max_step_m > 0 && std::isfinite(options.max_step_m);

  StatusOr<tools::StepReader> opened =
      tools::StepReader::OpenText(kName, std::string(text), options);
  if (!opened.ok()) {
    const std::string& message = opened.status().message();
    if (!options_valid) {
      if (opened.status().code() == StatusCode::kInvalidArgument &&
          message.find('\n') == std::string::npos &&
          (message.starts_with("max_step_m = ") || message.starts_with("max_line_bytes = "))) {
        return "";
      }
      return "invalid options not reported as such: \"" + Printable(message) + "\"";
    }
    return CheckError(opened.status(), kName, text);
  }
  if (!options_valid) {
    return fmt::format("opened with invalid options max_line_bytes = {}, max_step_m = {}",
                       options.max_line_bytes, options.max_step_m);
  }
  tools::StepReader& reader = *opened;
  if (!Finite(reader.start_time_s(), reader.start_x_m(), reader.start_y_m())) {
    return fmt::format("start not finite: t = {}, x = {}, y = {}", reader.start_time_s(),
                       reader.start_x_m(), reader.start_y_m());
  }
  const std::vector<size_t> lengths = LineLengths(text);
  double previous_t = reader.start_time_s();
  int64_t previous_line = 0;
  int64_t steps = 0;
  for (;;) {
    tools::StepRecord step;
    StatusOr<bool> more = reader.Next(&step);
    if (!more.ok()) {
      std::string failure = CheckError(more.status(), kName, text);
      if (!failure.empty()) return failure;
      StatusOr<bool> again = reader.Next(&step);
      if (again.ok() || again.status().code() != more.status().code() ||
          again.status().message() != more.status().message()) {
        return "the call after an error did not return the same error";
      }
      return "";
    }
    if (!*more) break;
    ++steps;
    if (!Finite(step.t_s, step.dx_m, step.dy_m)) {
      return fmt::format("step {} not finite: t = {}, dx = {}, dy = {}", steps, step.t_s, step.dx_m,
                         step.dy_m);
    }
    if (!(step.t_s > previous_t)) {
      return fmt::format("step {}: t = {} is not after {} ({})", steps, step.t_s, previous_t,
                         steps == 1 ? "start_time_s()" : "the step before");
    }
    if (!(std::hypot(step.dx_m, step.dy_m) <= options.max_step_m)) {
      return fmt::format("step {} of ({}, {}) is longer than max_step_m = {}", steps, step.dx_m,
                         step.dy_m, options.max_step_m);
    }
    if (step.line <= previous_line || step.line > static_cast<int64_t>(lengths.size())) {
      return fmt::format("step {}: line {} after line {} in an input of {} line(s)", steps,
                         step.line, previous_line, lengths.size());
    }
    if (reader.steps_read() != steps) {
      return fmt::format("steps_read() = {} after {} steps", reader.steps_read(), steps);
    }
    previous_t = step.t_s;
    previous_line = step.line;
  }
  if (steps == 0) return "Next() returned false without a single step (expected an error)";
  tools::StepRecord step;
  StatusOr<bool> again = reader.Next(&step);
  if (!again.ok() || *again) return "the call after the end did not return false again";
  return "";
}

// json's == compares a signed and an unsigned integer after casting the unsigned one to signed
// (so -1 == 18446744073709551615); integers are compared by their exact decimal text instead.
inline bool SameValue(const nlohmann::json& a, const nlohmann::json& b) {
  if (a.is_number_integer() && b.is_number_integer()) return a.dump() == b.dump();
  return a == b;
}

inline std::string CheckConfigJsonUnguarded(const uint8_t* data, size_t size) {
  constexpr char kName[] = "fuzz_config.json";
  const std::string text(reinterpret_cast<const char*>(data), size);
  FootSlamConfig config;
  const nlohmann::json before = nlohmann::json::parse(ConfigToJson(FootSlamConfigFields(), config));
  const Status applied = ApplyConfigJson(FootSlamConfigFields(), kName, text, &config);
  const nlohmann::json after = nlohmann::json::parse(ConfigToJson(FootSlamConfigFields(), config));
  if (!applied.ok()) {
    std::string failure = CheckError(applied, kName, text);
    if (!failure.empty()) return failure;
    if (after != before) return "a failed apply changed the configuration to " + after.dump();
    return "";
  }
  // Applied: every key of the text holds exactly its value, every other field is unchanged.
  const nlohmann::json doc = nlohmann::json::parse(text);
  if (!doc.is_object()) return "applied a document that is not an object";
  for (const auto& [key, value] : doc.items()) {
    if (!after.contains(key)) return "applied an unknown key \"" + Printable(key) + "\"";
    if (!SameValue(after[key], value)) {
      return fmt::format("key \"{}\" = {} in the text became {}", Printable(key),
                         Printable(value.dump()), Printable(after[key].dump()));
    }
  }
  for (const auto& [key, value] : before.items()) {
    if (!doc.contains(key) && after[key] != value) {
      return fmt::format("key \"{}\" is not in the text but changed from {} to {}", key,
                         value.dump(), after[key].dump());
    }
  }
  const Status valid = config.Validate();
  if (valid.ok()) return "";
  const std::string& message = valid.message();
  const std::string shown = "\"" + Printable(message) + "\"";
  if (valid.code() != StatusCode::kInvalidArgument) {
    return fmt::format("Validate() returned {}: {}", StatusCodeName(valid.code()), shown);
  }
  if (message.find('\n') != std::string::npos) return "Validate() message spans lines: " + shown;
  for (const auto& [key, value] : before.items()) {
    if (message.starts_with(key + " = ")) return "";
  }
  return "Validate() message does not start with \"FIELD = \": " + shown;
}

// A file name per process, so two fuzzers or tests running at once never share it.
inline std::string CsvInputPath() {
  return fmt::format("/tmp/grove_fuzz_{}.csv", static_cast<long>(::getpid()));
}

// The Victoria Park readers (tools/io/victoria_park.h) on an input with a record separator (0x1e),
// cut at its first two into inputs.dat, measurements.dat and gps.dat (missing parts empty), in a
// directory beside `path`: the data as the readers promise it, or an InvalidArgument naming the
// file (and its line and column when it names one).
inline std::string CheckVictoriaPark(const std::string& path, std::string_view text) {
  // Only inputs with a separator (the seed's mutations): the others would cost three files for
  // what the CSV readers above already parse.
  if (text.find('\x1e') == std::string_view::npos) return "";
  const std::string dir = path + ".park";
  ::mkdir(dir.c_str(), 0700);
  const char* names[] = {"inputs.dat", "measurements.dat", "gps.dat"};
  std::string_view parts[3];
  std::string_view rest = text;
  for (int k = 0; k < 3; ++k) {
    const size_t cut = k < 2 ? rest.find('\x1e') : std::string_view::npos;
    parts[k] = rest.substr(0, cut);
    rest = cut == std::string_view::npos ? std::string_view() : rest.substr(cut + 1);
  }
  for (int k = 0; k < 3; ++k) {
    const std::string file = dir + "/" + names[k];
    std::FILE* f = std::fopen(file.c_str(), "wb");
    if (f == nullptr) return "setup: cannot create " + file;
    const bool written = std::fwrite(parts[k].data(), 1, parts[k].size(), f) == parts[k].size();
    if (std::fclose(f) != 0 || !written) return "setup: cannot write " + file;
  }
  std::string failure;
  StatusOr<tools::VictoriaParkData> d = tools::ReadVictoriaPark(dir, 1e9);
  if (!d.ok()) {
    for (int k = 0; k < 3 && failure.empty(); ++k) {
      const std::string file = dir + "/" + names[k];
      if (d.status().message().rfind(file + ":", 0) == 0) {
        failure = CheckError(d.status(), file, parts[k]);
        if (!failure.empty()) failure = "ReadVictoriaPark: " + failure;
        break;
      }
      if (k == 2) failure = "ReadVictoriaPark: the error names no file: " + d.status().message();
    }
  } else {
    if (d->controls.empty()) failure = "ReadVictoriaPark: ok without a control";
    for (size_t i = 0; i < d->controls.size() && failure.empty(); ++i) {
      const tools::ControlRecord& c = d->controls[i];
      if (!Finite(c.t_s, c.v_mps, c.steer_rad) || !(std::fabs(c.steer_rad) < 0.5 * M_PI) ||
          (i > 0 && !(c.t_s > d->controls[i - 1].t_s))) {
        failure = fmt::format("ReadVictoriaPark: control {} ({}, {}, {})", i, c.t_s, c.v_mps,
                              c.steer_rad);
      }
    }
    for (size_t i = 0; i < d->observations.size() && failure.empty(); ++i) {
      const tools::ObservationRecord& o = d->observations[i];
      if (!Finite(o.t_s, o.z.range_m, o.z.bearing_rad) || o.z.range_m < 0 ||
          !(std::fabs(o.z.bearing_rad) <= 0.5 * M_PI + 1e-12) || o.z.id != -1 ||
          (i > 0 && o.t_s < d->observations[i - 1].t_s)) {
        failure = fmt::format("ReadVictoriaPark: detection {} ({}, {}, {})", i, o.t_s, o.z.range_m,
                              o.z.bearing_rad);
      }
    }
    for (size_t i = 0; i < d->gps.size() && failure.empty(); ++i) {
      const tools::TimedPoint& g = d->gps[i];
      if (!Finite(g.t_s, g.x_m, g.y_m) || (i > 0 && !(g.t_s > d->gps[i - 1].t_s))) {
        failure = fmt::format("ReadVictoriaPark: fix {} ({}, {}, {})", i, g.t_s, g.x_m, g.y_m);
      }
    }
  }
  for (const char* name : names) std::remove((dir + "/" + name).c_str());
  ::rmdir(dir.c_str());
  return failure;
}

inline std::string CheckCsvReadersUnguarded(const std::string& path, std::string_view text) {
  {
    std::FILE* file = std::fopen(path.c_str(), "wb");
    if (file == nullptr) return "setup: cannot create " + path;
    const bool written = std::fwrite(text.data(), 1, text.size(), file) == text.size();
    if (std::fclose(file) != 0 || !written) return "setup: cannot write " + path;
  }

  StatusOr<std::vector<tools::RenderHex>> hexes = tools::ReadMapCsv(path);
  if (!hexes.ok()) {
    std::string failure = CheckError(hexes.status(), path, text);
    if (!failure.empty()) return "ReadMapCsv: " + failure;
  } else {
    std::set<std::pair<int32_t, int32_t>> seen;
    for (const tools::RenderHex& hex : *hexes) {
      if (!std::isfinite(hex.use) || hex.use < 0) {
        return fmt::format("ReadMapCsv: hexagon ({}, {}) has use {}", hex.q, hex.r, hex.use);
      }
      if (!seen.insert({hex.q, hex.r}).second) {
        return fmt::format("ReadMapCsv: hexagon ({}, {}) returned twice", hex.q, hex.r);
      }
    }
  }

  StatusOr<std::vector<tools::RenderPoint>> path_points = tools::ReadPathCsv(path);
  if (!path_points.ok()) {
    std::string failure = CheckError(path_points.status(), path, text);
    if (!failure.empty()) return "ReadPathCsv: " + failure;
  } else {
    for (const tools::RenderPoint& p : *path_points) {
      if (!Finite(p.x_m, p.y_m)) return fmt::format("ReadPathCsv: point ({}, {})", p.x_m, p.y_m);
    }
  }

  StatusOr<std::vector<tools::TimedPoint>> timed = tools::ReadTimedPoints(path);
  if (!timed.ok()) {
    std::string failure = CheckError(timed.status(), path, text);
    if (!failure.empty()) return "ReadTimedPoints: " + failure;
  } else {
    if (timed->empty()) return "ReadTimedPoints: ok without a point";
    for (size_t i = 0; i < timed->size(); ++i) {
      const tools::TimedPoint& p = (*timed)[i];
      if (!Finite(p.t_s, p.x_m, p.y_m)) {
        return fmt::format("ReadTimedPoints: point {} ({}, {}, {})", i, p.t_s, p.x_m, p.y_m);
      }
      if (i > 0 && !(p.t_s > (*timed)[i - 1].t_s)) {
        return fmt::format("ReadTimedPoints: t = {} after {}", p.t_s, (*timed)[i - 1].t_s);
      }
    }
  }

  // FastSLAM's inputs: every row as its reader returns it, or the reader's error.
  if (StatusOr<tools::ControlReader> controls = tools::ControlReader::Open(path); !controls.ok()) {
    std::string failure = CheckError(controls.status(), path, text);
    if (!failure.empty()) return "ControlReader::Open: " + failure;
  } else {
    tools::ControlRecord c, previous;
    for (bool first = true;; first = false) {
      StatusOr<bool> more = controls->Next(&c);
      if (!more.ok()) {
        std::string failure = CheckError(more.status(), path, text);
        if (!failure.empty()) return "ControlReader::Next: " + failure;
        break;
      }
      if (!*more) break;
      if (!Finite(c.t_s, c.v_mps, c.steer_rad) || (!first && !(c.t_s > previous.t_s))) {
        return fmt::format("ControlReader: row ({}, {}, {}) after t = {}", c.t_s, c.v_mps,
                           c.steer_rad, previous.t_s);
      }
      previous = c;
    }
  }
  if (StatusOr<tools::ObservationReader> observations = tools::ObservationReader::Open(path);
      !observations.ok()) {
    std::string failure = CheckError(observations.status(), path, text);
    if (!failure.empty()) return "ObservationReader::Open: " + failure;
  } else {
    tools::ObservationRecord o, previous;
    for (bool first = true;; first = false) {
      StatusOr<bool> more = observations->Next(&o);
      if (!more.ok()) {
        std::string failure = CheckError(more.status(), path, text);
        if (!failure.empty()) return "ObservationReader::Next: " + failure;
        break;
      }
      if (!*more) break;
      const bool bearing_ok = o.z.bearing_rad > -M_PI && o.z.bearing_rad <= M_PI;
      // Without the id column every id is -1 (unknown association).
      const bool id_ok = observations->has_ids() ? o.z.id >= 0 : o.z.id == -1;
      if (!Finite(o.t_s, o.z.range_m, o.z.bearing_rad) || o.z.range_m < 0 || !bearing_ok ||
          !id_ok || (!first && o.t_s < previous.t_s)) {
        return fmt::format("ObservationReader: row ({}, {}, {}, {}) after t = {}", o.t_s,
                           o.z.range_m, o.z.bearing_rad, o.z.id, previous.t_s);
      }
      previous = o;
    }
  }
  return CheckVictoriaPark(path, text);
}

// Runs `check`, turning an exception out of the parser into a broken property.
template <typename Check>
std::string Guarded(const Check& check) {
  try {
    return check();
  } catch (const std::exception& e) {
    return std::string("exception escaped: ") + Printable(e.what());
  } catch (...) {
    return "exception escaped (not a std::exception)";
  }
}

// The configurations of the checkpoint corpus (tests/fuzz/corpus/checkpoint): three particles
// on a 16 x 16 grid, with the default H-tree map, the degree-4 map without alphabet, and the
// naive map.
inline std::vector<FootSlamConfig> CheckpointConfigs() {
  FootSlamConfig base;
  base.particles = 3;
  base.grid_size = 16;
  base.threads = 1;
  std::vector<FootSlamConfig> configs(4, base);
  configs[1].degree = 4;
  configs[1].alphabet = 0;
  configs[2].map = FootSlamMapKind::kNaive;
  configs[3].store_distance_m = 5;  // stored map blocks
  return configs;
}

// The format version this build writes (the header's u32 at offset 8 of any checkpoint of it).
inline uint32_t CurrentCheckpointVersion() {
  static const uint32_t version = [] {
    FootSlamConfig c = CheckpointConfigs()[0];
    auto slam = FootSlam::Create(c);
    StatusOr<std::string> bytes = (*slam)->Checkpoint();
    uint32_t v = 0;
    std::memcpy(&v, bytes->data() + 8, sizeof(v));
    return v;
  }();
  return version;
}

inline std::string CheckResumeError(const Status& status) {
  const std::string shown = "\"" + Printable(status.message()) + "\"";
  if (status.code() != StatusCode::kDataLoss && status.code() != StatusCode::kFailedPrecondition) {
    return fmt::format("error code {} (expected DataLoss or FailedPrecondition): {}",
                       StatusCodeName(status.code()), shown);
  }
  if (status.message().find('\n') != std::string::npos)
    return "error message spans lines: " + shown;
  if (status.message().rfind("fuzz.ckpt: ", 0) != 0) {
    return "error message does not start with \"fuzz.ckpt: \": " + shown;
  }
  return "";
}

inline std::string CheckResumedEngine(const FootSlamConfig& config, FootSlam* slam) {
  for (const Status& s : {slam->CumulativeMap().status(), slam->HeaviestMap().status(),
                          slam->HeaviestTrajectory().status(), slam->CheckInvariants()}) {
    if (!s.ok()) return "a resumed engine's read-out failed: " + s.ToString();
  }
  (void)slam->Summary();
  StatusOr<std::string> again = slam->Checkpoint("u");
  if (!again.ok()) return "a resumed engine has no checkpoint: " + again.status().ToString();
  auto second = FootSlam::Resume(config, *again, "again.ckpt", nullptr);
  if (!second.ok()) return "its own checkpoint does not resume: " + second.status().ToString();
  StatusOr<std::string> third = (*second)->Checkpoint("u");
  if (!third.ok() || *third != *again) return "checkpoint -> resume -> checkpoint changed bytes";
  // Stepping must not crash; leaving the grid is a legitimate outcome here.
  double t = slam->MeanTrajectory().back().t_s;
  for (int k = 1; k <= 4; ++k) {
    Status s = slam->Step(t + k, 0.6, 0.2 * k);
    if (!s.ok()) {
      if (s.code() != StatusCode::kOutOfRange && s.code() != StatusCode::kFailedPrecondition) {
        return "stepping a resumed engine: " + s.ToString();
      }
      break;
    }
  }
  return "";
}

inline std::string CheckCheckpointUnguarded(const uint8_t* data, size_t size) {
  const std::string raw(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> inputs{raw};
  if (raw.size() >= kCheckpointHeaderBytes) {
    // The same magic, this build's format version, a matching length and checksum: the body
    // reaches the parser.
    std::string sealed = SealCheckpoint(std::string_view(raw).substr(kCheckpointHeaderBytes),
                                        CurrentCheckpointVersion());
    std::memcpy(sealed.data(), raw.data(), 8);
    inputs.push_back(sealed);
  }
  for (const std::string& input : inputs) {
    for (const FootSlamConfig& config : CheckpointConfigs()) {
      std::string user;
      auto slam = FootSlam::Resume(config, input, "fuzz.ckpt", &user);
      if (!slam.ok()) {
        if (std::string failure = CheckResumeError(slam.status()); !failure.empty()) {
          return failure;
        }
        continue;
      }
      if (std::string failure = CheckResumedEngine(config, slam->get()); !failure.empty()) {
        return failure;
      }
    }
  }
  return "";
}

}  // namespace fuzz_internal

// FootSlam::Resume on the input (and on it with a matching checksum) under each of
// CheckpointConfigs(), then the resumed engine's outputs, checkpoint round trip and steps.
inline std::string CheckCheckpoint(const uint8_t* data, size_t size) {
  return fuzz_internal::Guarded(
      [&] { return fuzz_internal::CheckCheckpointUnguarded(data, size); });
}

// StepReader::OpenText on the input, then Next() to the end or the first error.
inline std::string CheckStepReader(const uint8_t* data, size_t size) {
  return fuzz_internal::Guarded(
      [&] { return fuzz_internal::CheckStepReaderUnguarded(data, size); });
}

// ApplyConfigJson on the input over the default configuration, then Validate().
inline std::string CheckConfigJson(const uint8_t* data, size_t size) {
  return fuzz_internal::Guarded(
      [&] { return fuzz_internal::CheckConfigJsonUnguarded(data, size); });
}

// Writes the input to CsvInputPath() and reads it with ReadMapCsv, ReadPathCsv, ReadTimedPoints,
// ControlReader and ObservationReader; removes the file afterwards.
inline std::string CheckCsvReaders(const uint8_t* data, size_t size) {
  const std::string path = fuzz_internal::CsvInputPath();
  std::string failure = fuzz_internal::Guarded([&] {
    return fuzz_internal::CheckCsvReadersUnguarded(
        path, std::string_view(reinterpret_cast<const char*>(data), size));
  });
  std::remove(path.c_str());
  return failure;
}

}  // namespace grove::testing

#endif  // GROVE_TESTS_FUZZ_FUZZ_CHECKS_H_
