#include "tools/io/victoria_park.h"

#include <fmt/format.h>
#include <sys/stat.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "tools/io/csv_reader.h"

namespace grove::tools {
namespace {

constexpr double kPi = std::numbers::pi;

// Splits `line` at runs of blanks into fields with 1-based columns.
void SplitBlanks(std::string_view line, std::vector<CsvField>* fields) {
  fields->clear();
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    if (i >= line.size()) break;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    fields->push_back({line.substr(start, i - start), static_cast<int64_t>(start) + 1});
  }
}

// Calls row(fields, line) for every non-blank line of `path`, which must have `names.size()`
// numbers, parsed into `values`.
template <typename F>
Status ForEachRecord(const std::string& path, const std::vector<const char*>& names, F&& row) {
  StatusOr<std::string> text = ReadMaybeCompressed(path);
  if (!text.ok()) return text.status();
  std::vector<CsvField> fields;
  std::vector<double> values(names.size());
  int64_t line_number = 0;
  size_t pos = 0;
  while (pos < text->size()) {
    size_t end = text->find('\n', pos);
    if (end == std::string::npos) end = text->size();
    const std::string_view line(text->data() + pos, end - pos);
    pos = end + 1;
    ++line_number;
    SplitBlanks(line, &fields);
    if (fields.empty()) continue;
    if (fields.size() != names.size()) {
      return LineError(path, line_number,
                       fields.size() < names.size() ? line.size() + 1 : fields[names.size()].column,
                       fmt::format("{} numbers where {} are expected ({})", fields.size(),
                                   names.size(), fmt::join(names, ", ")));
    }
    for (size_t k = 0; k < names.size(); ++k) {
      GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path, line_number, fields[k], names[k], &values[k]));
    }
    GROVE_RETURN_IF_ERROR(row(values, fields, line_number));
  }
  return Status::Ok();
}

// `dir`/name, or `dir`/name.gz when only that exists.
std::string DataFile(const std::string& dir, const std::string& name) {
  const std::string plain = dir + "/" + name;
  struct stat st;
  if (::stat(plain.c_str(), &st) == 0) return plain;
  return plain + ".gz";
}

}  // namespace

const char* BundledVictoriaParkDir() { return GROVE_VICTORIA_PARK_DIR; }

StatusOr<std::string> ReadMaybeCompressed(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) {
    return NotFoundError(fmt::format("{}: no such file", path));
  }
  if (!S_ISREG(st.st_mode))
    return InvalidArgumentError(fmt::format("{}: not a regular file", path));
  gzFile f = gzopen(path.c_str(), "rb");
  if (f == nullptr) return IoError(fmt::format("{}: cannot open", path));
  std::string out;
  char buffer[1 << 16];
  for (;;) {
    const int n = gzread(f, buffer, sizeof(buffer));
    if (n < 0) {
      int code = 0;
      const std::string what = gzerror(f, &code);
      gzclose(f);
      if (code == Z_ERRNO) return IoError(fmt::format("{}: cannot read: {}", path, what));
      return InvalidArgumentError(
          fmt::format("{}: the compressed data is corrupt: {}", path, QuotedField(what)));
    }
    if (n == 0) break;
    out.append(buffer, static_cast<size_t>(n));
  }
  // A truncated gzip stream reads as a short file: gzclose_r reports it.
  const int closed = gzclose(f);
  if (closed == Z_ERRNO) return IoError(fmt::format("{}: cannot read", path));
  if (closed != Z_OK) {
    return InvalidArgumentError(
        fmt::format("{}: the compressed data is truncated or corrupt (zlib {})", path, closed));
  }
  return out;
}

StatusOr<VictoriaParkData> ReadVictoriaPark(const std::string& dir, double until_s) {
  VictoriaParkData d;
  d.controls_path = DataFile(dir, "inputs.dat");
  d.observations_path = DataFile(dir, "measurements.dat");
  d.gps_path = DataFile(dir, "gps.dat");
  auto increasing = [](const std::string& path, int64_t line, const CsvField& f, double t,
                       double previous, bool strict) -> Status {
    if (strict ? !(t > previous) : t < previous) {
      return LineError(path, line, f.column,
                       fmt::format("time = {}: must be {} the previous time {}", t,
                                   strict ? "after" : "at or after", previous));
    }
    return Status::Ok();
  };
  double last = -INFINITY;
  GROVE_RETURN_IF_ERROR(ForEachRecord(
      d.controls_path, {"time", "speed", "steering"},
      [&](const std::vector<double>& v, const std::vector<CsvField>& f, int64_t line) -> Status {
        GROVE_RETURN_IF_ERROR(increasing(d.controls_path, line, f[0], v[0], last, true));
        last = v[0];
        if (!(std::fabs(v[2]) < 0.5 * kPi)) {
          return LineError(d.controls_path, line, f[2].column,
                           fmt::format("steering = {}: must be within (-pi/2, pi/2)", v[2]));
        }
        if (v[0] <= until_s) d.controls.push_back({v[0], v[1], v[2], line});
        return Status::Ok();
      }));
  last = -INFINITY;
  GROVE_RETURN_IF_ERROR(ForEachRecord(
      d.observations_path, {"time", "range", "bearing", "diameter"},
      [&](const std::vector<double>& v, const std::vector<CsvField>& f, int64_t line) -> Status {
        GROVE_RETURN_IF_ERROR(increasing(d.observations_path, line, f[0], v[0], last, false));
        last = v[0];
        if (!(v[1] >= 0)) {
          return LineError(d.observations_path, line, f[1].column,
                           fmt::format("range = {}: must be >= 0", v[1]));
        }
        if (!(v[2] >= 0 && v[2] <= kPi)) {
          return LineError(
              d.observations_path, line, f[2].column,
              fmt::format("bearing = {}: must be in [0, pi] (the laser's view)", v[2]));
        }
        if (!(v[3] >= 0)) {
          return LineError(d.observations_path, line, f[3].column,
                           fmt::format("diameter = {}: must be >= 0", v[3]));
        }
        if (v[0] <= until_s) {
          d.observations.push_back({v[0], LandmarkObservation{v[1], v[2] - 0.5 * kPi, -1}, line});
        }
        return Status::Ok();
      }));
  last = -INFINITY;
  GROVE_RETURN_IF_ERROR(ForEachRecord(
      d.gps_path, {"time", "x", "y"},
      [&](const std::vector<double>& v, const std::vector<CsvField>& f, int64_t line) -> Status {
        GROVE_RETURN_IF_ERROR(increasing(d.gps_path, line, f[0], v[0], last, true));
        last = v[0];
        if (v[0] <= until_s) d.gps.push_back({v[0], v[1], v[2]});
        return Status::Ok();
      }));
  if (d.controls.empty()) {
    return InvalidArgumentError(
        fmt::format("{}: no control at or before {} s", d.controls_path, until_s));
  }
  return d;
}

StatusOr<bool> VictoriaParkEvents::Next(FastSlamEvent* out) {
  const auto& controls = data_->controls;
  const auto& observations = data_->observations;
  for (;;) {
    const bool control = control_ < controls.size();
    const bool scan = observation_ < observations.size();
    if (!control && !scan) return false;
    if (control && (!scan || controls[control_].t_s <= observations[observation_].t_s)) {
      out->is_scan = false;
      out->control = controls[control_++];
      return true;
    }
    const double t = observations[observation_].t_s;
    out->is_scan = true;
    out->scan_t_s = t;
    out->scan_line = observations[observation_].line;
    out->scan.clear();
    while (observation_ < observations.size() && observations[observation_].t_s == t) {
      out->scan.push_back(observations[observation_++].z);
    }
    if (control_ > 0) return true;
    ++skipped_scans_;  // before the first control: the filter has no start yet
  }
}

FastSlamConfig VictoriaParkConfig() {
  FastSlamConfig c;
  c.filter = FastSlamFilter::kFastSlam2;
  c.particles = 100;
  c.vehicle = FastSlamVehicle::kGuivantNebot;
  c.wheelbase_m = 2.83;
  c.encoder_offset_m = 0.76;
  c.laser_forward_m = 3.78;
  c.laser_left_m = 0.50;
  c.sigma_speed_mps = 0.4;
  c.sigma_steer_rad = 1.4 * kPi / 180;
  c.sigma_range_m = 0.5;
  c.sigma_bearing_rad = 1.5 * kPi / 180;
  c.association = FastSlamAssociation::kMaximumLikelihood;
  c.reject_gate = 4;
  c.augment_gate = 25;
  c.sensor_range_m = 30;
  c.sensor_fov_rad = kPi;
  return c;
}

StatusOr<GpsErrors> CompareWithGps(const std::vector<StampedPose>& path,
                                   const std::vector<TimedPoint>& gps) {
  // The path at strictly increasing times: at a repeated time (a scan's update after the
  // prediction to it) the last pose.
  std::vector<TimedPoint> estimate;
  for (const StampedPose& p : path) {
    if (!estimate.empty() && estimate.back().t_s == p.t_s) estimate.pop_back();
    estimate.push_back({p.t_s, p.pose.x_m, p.pose.y_m});
  }
  GpsErrors e;
  StatusOr<TrajectoryError> a = CompareTrajectories(gps, estimate, &e.fixes);
  if (!a.ok()) return a.status();
  e.alignment = *a;
  std::vector<double> errors;
  double sum = 0, sq = 0;
  for (const AlignedPointError& f : e.fixes) {
    errors.push_back(f.error_m);
    sum += f.error_m;
    sq += f.error_m * f.error_m;
    e.max_m = std::max(e.max_m, f.error_m);
  }
  const double n = static_cast<double>(errors.size());
  e.mean_m = sum / n;
  e.rmse_m = std::sqrt(sq / n);
  std::sort(errors.begin(), errors.end());
  const size_t mid = errors.size() / 2;
  e.median_m = errors.size() % 2 == 1 ? errors[mid] : 0.5 * (errors[mid - 1] + errors[mid]);
  std::vector<double> jumped_at;  // times of the fixes that jumped
  for (size_t k = 1; k < gps.size(); ++k) {
    const double dt = gps[k].t_s - gps[k - 1].t_s;
    const double d = std::hypot(gps[k].x_m - gps[k - 1].x_m, gps[k].y_m - gps[k - 1].y_m);
    if (d > 10 * dt) {
      ++e.jumps;
      jumped_at.push_back(gps[k].t_s);
    }
    e.gaps += dt > 5;
  }
  double clean_sum = 0;
  int64_t clean = 0;
  for (const AlignedPointError& f : e.fixes) {
    if (std::binary_search(jumped_at.begin(), jumped_at.end(), f.t_s)) continue;
    clean_sum += f.error_m;
    ++clean;
    e.max_without_jumps_m = std::max(e.max_without_jumps_m, f.error_m);
  }
  e.mean_without_jumps_m = clean > 0 ? clean_sum / clean : 0;
  return e;
}

}  // namespace grove::tools
