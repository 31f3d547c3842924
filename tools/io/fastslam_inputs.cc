#include "tools/io/fastslam_inputs.h"

#include <fmt/format.h>

#include "grove/input_rules.h"

namespace grove::tools {
namespace {

Status ParseTime(const std::string& path, int64_t line, const CsvField& f, double* t) {
  GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path, line, f, "t", t));
  return AtField(path, line, f, CheckInput(InputField::kTime, *t));
}

}  // namespace

StatusOr<ControlReader> ControlReader::Open(const std::string& path, const FastSlamConfig& config) {
  StatusOr<CsvTableReader> table = CsvTableReader::Open(path, {{"t", "v", "steer"}});
  if (!table.ok()) return table.status();
  return ControlReader(std::move(table).value(), config);
}

StatusOr<bool> ControlReader::Next(ControlRecord* out) {
  const std::vector<CsvField>* f = nullptr;
  StatusOr<bool> more = table_.Next(&f);
  if (!more.ok() || !*more) return more;
  const std::string& path = table_.path();
  const int64_t line = table_.line_number();
  ControlRecord r;
  r.line = line;
  GROVE_RETURN_IF_ERROR(ParseTime(path, line, (*f)[0], &r.t_s));
  GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path, line, (*f)[1], "v", &r.v_mps));
  GROVE_RETURN_IF_ERROR(AtField(path, line, (*f)[1], CheckInput(InputField::kSpeed, r.v_mps)));
  GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path, line, (*f)[2], "steer", &r.steer_rad));
  GROVE_RETURN_IF_ERROR(AtField(path, line, (*f)[2], CheckSteering(config_, r.steer_rad)));
  if (has_previous_ && !(r.t_s > previous_s_)) {
    return LineError(
        path, line, (*f)[0].column,
        fmt::format("t = {} is not after the previous time {}: times must be strictly increasing",
                    r.t_s, previous_s_));
  }
  has_previous_ = true;
  previous_s_ = r.t_s;
  *out = r;
  return true;
}

StatusOr<ObservationReader> ObservationReader::Open(const std::string& path) {
  StatusOr<CsvTableReader> table =
      CsvTableReader::Open(path, {{"t", "range", "bearing"}, {"t", "range", "bearing", "id"}});
  if (!table.ok()) return table.status();
  return ObservationReader(std::move(table).value());
}

StatusOr<bool> ObservationReader::Next(ObservationRecord* out) {
  const std::vector<CsvField>* f = nullptr;
  StatusOr<bool> more = table_.Next(&f);
  if (!more.ok() || !*more) return more;
  const std::string& path = table_.path();
  const int64_t line = table_.line_number();
  ObservationRecord r;
  r.line = line;
  GROVE_RETURN_IF_ERROR(ParseTime(path, line, (*f)[0], &r.t_s));
  GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path, line, (*f)[1], "range", &r.z.range_m));
  GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path, line, (*f)[2], "bearing", &r.z.bearing_rad));
  GROVE_RETURN_IF_ERROR(AtField(path, line, (*f)[1], CheckInput(InputField::kRange, r.z.range_m)));
  GROVE_RETURN_IF_ERROR(
      AtField(path, line, (*f)[2], CheckInput(InputField::kBearing, r.z.bearing_rad)));
  if (has_ids()) {
    int32_t id = 0;
    GROVE_RETURN_IF_ERROR(ParseCsvId(path, line, (*f)[3], "id", &id));
    r.z.id = id;
  } else {
    r.z.id = -1;
  }
  if (has_previous_ && r.t_s < previous_s_) {
    return LineError(path, line, (*f)[0].column,
                     fmt::format("t = {} is before the previous time {}: times must not decrease",
                                 r.t_s, previous_s_));
  }
  has_previous_ = true;
  previous_s_ = r.t_s;
  *out = r;
  return true;
}

StatusOr<FastSlamInputReader> FastSlamInputReader::Open(const std::string& controls_path,
                                                        const std::string& observations_path,
                                                        const FastSlamConfig& config) {
  StatusOr<ControlReader> c = ControlReader::Open(controls_path, config);
  if (!c.ok()) return c.status();
  StatusOr<ObservationReader> o = ObservationReader::Open(observations_path);
  if (!o.ok()) return o.status();
  return FastSlamInputReader(std::move(c).value(), std::move(o).value());
}

Status FastSlamInputReader::Fill() {
  if (!control_ready_ && !controls_done_) {
    StatusOr<bool> more = controls_.Next(&control_);
    if (!more.ok()) return more.status();
    control_ready_ = *more;
    controls_done_ = !*more;
  }
  if (!observation_ready_ && !observations_done_) {
    StatusOr<bool> more = observations_.Next(&observation_);
    if (!more.ok()) return more.status();
    observation_ready_ = *more;
    observations_done_ = !*more;
  }
  return Status::Ok();
}

StatusOr<bool> FastSlamInputReader::Next(FastSlamEvent* out) {
  GROVE_RETURN_IF_ERROR(Fill());
  // A controls file with no rows: say so, not that the first scan is early.
  if (controls_done_ && !any_control_ && !control_ready_) {
    return InvalidArgumentError(fmt::format(
        "{}: no controls (the file has no rows after its header): a run needs at least one",
        controls_.path()));
  }
  if (!control_ready_ && !observation_ready_) return false;
  // A control first when it comes no later than the next scan.
  if (control_ready_ && (!observation_ready_ || control_.t_s <= observation_.t_s)) {
    out->is_scan = false;
    out->control = control_;
    control_ready_ = false;
    any_control_ = true;
    return true;
  }
  if (!any_control_) {
    return LineError(
        observations_.path(), observation_.line, 1,
        fmt::format("t = {} comes before the first control{}: the filter has no "
                    "start time and no control to predict with",
                    observation_.t_s,
                    control_ready_ ? fmt::format(" (t = {} in {})", control_.t_s, controls_.path())
                                   : std::string()));
  }
  out->is_scan = true;
  out->scan_t_s = observation_.t_s;
  out->scan_line = observation_.line;
  out->scan.clear();
  while (observation_ready_ && observation_.t_s == out->scan_t_s) {
    out->scan.push_back(observation_.z);
    observation_ready_ = false;
    GROVE_RETURN_IF_ERROR(Fill());
  }
  return true;
}

std::string AdaptAssociationToIds(const FastSlamInputReader& reader, FastSlamConfig* config) {
  if (reader.has_ids() || config->association != FastSlamAssociation::kKnown) return "";
  config->association = FastSlamAssociation::kMaximumLikelihood;
  return reader.ScanSource() + " has no id column: unknown association (association = ml)";
}

Status FeedEvent(const FastSlamEvent& event, const FastSlamEventSource& source, FastSlam* slam) {
  if (event.is_scan) {
    Status s = slam->Scan(event.scan_t_s, event.scan);
    if (!s.ok()) {
      return Status(s.code(),
                    fmt::format("{}:{}: {}", source.ScanSource(), event.scan_line, s.message()));
    }
    return Status::Ok();
  }
  Status s = slam->Control(event.control.t_s, event.control.v_mps, event.control.steer_rad);
  if (!s.ok()) {
    return Status(s.code(), fmt::format("{}:{}: {}", source.ControlSource(), event.control.line,
                                        s.message()));
  }
  return Status::Ok();
}

}  // namespace grove::tools
