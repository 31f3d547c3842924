#include "tools/io/victoria_park.h"

#include <fmt/format.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "grove/checksum.h"
#include "grove/input_rules.h"
#include "tools/io/bundled_data.h"
#include "tools/io/csv_reader.h"
#include "tools/io/gzip_line_reader.h"

namespace grove::tools {
namespace {

constexpr double kPi = std::numbers::pi;
// The longest line a data file may have: as the CSV readers.
constexpr size_t kMaxLineBytes = size_t{64} << 10;

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

// Calls row(values, fields, line) for every non-blank line of `path` (plain or gzip), which must
// have `names.size()` numbers. Lines are read through a bounded buffer: a line longer than
// kMaxLineBytes is an error, never held whole.
template <typename F>
Status ForEachRecord(const std::string& path, const std::vector<const char*>& names, F&& row) {
  StatusOr<LineReader> lines = OpenMaybeCompressed(path, kMaxLineBytes);
  if (!lines.ok()) return lines.status();
  std::vector<CsvField> fields;
  std::vector<double> values(names.size());
  std::string_view line;
  for (;;) {
    StatusOr<bool> more = lines->Next(&line);
    if (!more.ok()) return more.status();
    if (!*more) break;
    const int64_t line_number = lines->line_number();
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

bool Exists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

// `dir`/name, or `dir`/name.gz when only that exists; both is an error (which one is meant?).
StatusOr<std::string> DataFile(const std::string& dir, const std::string& name) {
  const std::string plain = dir + "/" + name;
  const std::string gz = plain + ".gz";
  if (Exists(plain) && Exists(gz)) {
    return InvalidArgumentError(
        fmt::format("{}: both {} and {}.gz exist: keep one, so that which one is read is not a "
                    "guess",
                    dir, name, name));
  }
  return Exists(plain) ? plain : gz;
}

// The size and CRC-32 of the file's bytes as stored (compressed or not).
StatusOr<InputFile> DescribeFile(const std::string& path) {
  StatusOr<std::string> bytes = ReadWholeFile(path);
  if (!bytes.ok()) return bytes.status();
  return InputFile{path, static_cast<uint64_t>(bytes->size()), Crc32(*bytes)};
}

}  // namespace

std::string BundledVictoriaParkDir() { return BundledDataDir() + "/victoria_park"; }

nlohmann::json InputFilesJson(const std::vector<InputFile>& files) {
  nlohmann::json out = nlohmann::json::array();
  for (const InputFile& f : files) {
    out.push_back({{"path", f.path}, {"bytes", f.bytes}, {"crc32", f.crc32}});
  }
  return out;
}

StatusOr<VictoriaParkData> ReadVictoriaPark(const std::string& dir, double until_s,
                                            const FastSlamConfig& config) {
  VictoriaParkData d;
  for (auto [name, path] :
       {std::pair{"inputs.dat", &d.controls_path},
        std::pair{"measurements.dat", &d.observations_path}, std::pair{"gps.dat", &d.gps_path}}) {
    StatusOr<std::string> file = DataFile(dir, name);
    if (!file.ok()) return file.status();
    *path = *file;
  }
  auto increasing = [](const std::string& path, int64_t line, const CsvField& f, double t,
                       double previous, bool strict) -> Status {
    GROVE_RETURN_IF_ERROR(AtField(path, line, f, CheckInput(InputField::kTime, t)));
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
        GROVE_RETURN_IF_ERROR(
            AtField(d.controls_path, line, f[1], CheckInput(InputField::kSpeed, v[1])));
        GROVE_RETURN_IF_ERROR(AtField(d.controls_path, line, f[2], CheckSteering(config, v[2])));
        if (v[0] <= until_s) d.controls.push_back({v[0], v[1], v[2], line});
        return Status::Ok();
      }));
  last = -INFINITY;
  GROVE_RETURN_IF_ERROR(ForEachRecord(
      d.observations_path, {"time", "range", "bearing", "diameter"},
      [&](const std::vector<double>& v, const std::vector<CsvField>& f, int64_t line) -> Status {
        GROVE_RETURN_IF_ERROR(increasing(d.observations_path, line, f[0], v[0], last, false));
        last = v[0];
        GROVE_RETURN_IF_ERROR(
            AtField(d.observations_path, line, f[1], CheckInput(InputField::kRange, v[1])));
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
  for (const std::string* path : {&d.controls_path, &d.observations_path, &d.gps_path}) {
    StatusOr<InputFile> file = DescribeFile(*path);
    if (!file.ok()) return file.status();
    d.files.push_back(*file);
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

StatusOr<GpsScanErrors> CompareWithGpsAtScans(const std::vector<StampedPose>& path,
                                              const std::vector<double>& scan_times,
                                              const std::vector<TimedPoint>& gps,
                                              double tolerance_s) {
  // The path's last pose at each of its times.
  std::vector<StampedPose> last;
  for (const StampedPose& p : path) {
    if (!last.empty() && last.back().t_s == p.t_s) last.pop_back();
    last.push_back(p);
  }
  GpsScanErrors e;
  std::vector<TimedPoint> fixes, estimates;  // the kept pairs, at the scan's time
  auto by_time = [](const auto& a, double t) { return a.t_s < t; };
  for (size_t k = 0; k < scan_times.size(); ++k) {
    const double t = scan_times[k];
    if (k > 0 && t == scan_times[k - 1]) continue;
    auto p = std::lower_bound(last.begin(), last.end(), t, by_time);
    if (p == last.end() || p->t_s != t) continue;
    ++e.scans;
    auto g = std::lower_bound(gps.begin(), gps.end(), t, by_time);
    const TimedPoint* nearest = nullptr;
    if (g != gps.end()) nearest = &*g;
    if (g != gps.begin() && (nearest == nullptr || t - (g - 1)->t_s < nearest->t_s - t)) {
      nearest = &*(g - 1);
    }
    if (nearest == nullptr || !(std::abs(nearest->t_s - t) <= tolerance_s)) continue;
    fixes.push_back({t, nearest->x_m, nearest->y_m});
    estimates.push_back({t, p->pose.x_m, p->pose.y_m});
  }
  e.pairs = static_cast<int64_t>(fixes.size());
  StatusOr<TrajectoryError> a = CompareTrajectories(fixes, estimates);
  if (!a.ok()) return a.status();
  e.alignment = *a;
  e.rmse_m = a->aligned_rmse_m;
  return e;
}

std::vector<double> ScanTimes(const std::vector<ObservationRecord>& observations) {
  std::vector<double> times;
  for (const ObservationRecord& o : observations) {
    if (times.empty() || times.back() != o.t_s) times.push_back(o.t_s);
  }
  return times;
}

}  // namespace grove::tools
