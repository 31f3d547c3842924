// The Victoria Park dataset (Guivant and Nebot, ACFR; the text form of the RFS-SLAM project),
// bundled gzip-compressed in tools/data/victoria_park/: its readers, the filter inputs made from
// it, the seed's defaults, and the error against GPS.
//
// Files (whitespace-separated numbers, one record a line; plain or gzip):
//   inputs.dat        time [s], speed [m/s] (rear left wheel), steering angle [rad]; time
//                     strictly increasing.
//   measurements.dat  time [s], range [m], bearing [rad] (0 .. pi across the laser's view),
//                     tree diameter [m]; one detection a line, time non-decreasing; the rows of
//                     one time are one scan.
//   gps.dat           time [s], x [m], y [m] (local frame; strictly increasing time).
// Errors: "FILE:LINE:COLUMN: field = 'text': rule", as every other reader.
//
// Into the filter: a control per inputs row; the detections of a time as a scan with bearing
// - pi/2 (the vehicle frame), no ids (unknown association). Scans before the first control are
// skipped and counted (the first scan comes 0.12 s before the first control).
#ifndef GROVE_TOOLS_IO_VICTORIA_PARK_H_
#define GROVE_TOOLS_IO_VICTORIA_PARK_H_

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "grove/fastslam.h"
#include "grove/status.h"
#include "tools/io/fastslam_inputs.h"
#include "tools/report/trajectory_metrics.h"

namespace grove::tools {

// The bundled copy: victoria_park/ in the data directory (BundledDataDir()).
std::string BundledVictoriaParkDir();

// A file a run read, as stored: its path, size and CRC-32 (summary.json names them).
struct InputFile {
  std::string path;
  uint64_t bytes = 0;
  uint32_t crc32 = 0;
};

struct VictoriaParkData {
  std::vector<ControlRecord> controls;
  std::vector<ObservationRecord> observations;  // bearing in the vehicle frame, id -1
  std::vector<TimedPoint> gps;
  std::string controls_path, observations_path, gps_path;
  std::vector<InputFile> files;  // the three files read, in that order
};

// The files as summary.json lists them: [{"path", "bytes", "crc32"}], as the outputs are.
nlohmann::json InputFilesJson(const std::vector<InputFile>& files);

// The documented defaults of `grove fastslam victoria-park`: FastSLAM 2.0, 100 particles, the
// guivant_nebot vehicle with L = 2.83 m, H = 0.76 m, a = 3.78 m, b = 0.50 m, the seed's noise
// (sigma_v 0.4 m/s, sigma_gamma 1.4 deg, sigma_r 0.5 m, sigma_b 1.5 deg), unknown association
// with Bailey's gates (4 and 25), evidence within 30 m and the laser's 180 degrees.
FastSlamConfig VictoriaParkConfig();

// Reads `dir`/inputs.dat, measurements.dat and gps.dat (each as NAME or NAME.gz; both present is
// an error), keeping the records with time <= until_s. Lines longer than 64 KiB are errors.
// Times, speeds, steering angles (for `config`'s vehicle) and ranges are checked against
// grove/input_rules.h, the engine's own bounds.
StatusOr<VictoriaParkData> ReadVictoriaPark(const std::string& dir, double until_s,
                                            const FastSlamConfig& config = VictoriaParkConfig());

// The events of the data in the filter's order (a control before a scan at its time).
class VictoriaParkEvents final : public FastSlamEventSource {
 public:
  explicit VictoriaParkEvents(const VictoriaParkData* data) : data_(data) {}
  StatusOr<bool> Next(FastSlamEvent* out) override;
  std::string ControlSource() const override { return data_->controls_path; }
  std::string ScanSource() const override { return data_->observations_path; }
  int64_t skipped_scans() const { return skipped_scans_; }

 private:
  const VictoriaParkData* data_;
  size_t control_ = 0, observation_ = 0;
  int64_t skipped_scans_ = 0;
};

// Error of an estimated path against GPS after a rigid 2-D alignment of the path to the fixes
// inside its time span (tools/report/trajectory_metrics.h), with the statistics of the per-fix
// errors.
struct GpsErrors {
  TrajectoryError alignment;
  std::vector<AlignedPointError> fixes;
  double mean_m = 0, median_m = 0, rmse_m = 0, max_m = 0;
  // The GPS's own trouble: fixes whose jump from the previous fix implies a speed above 10 m/s
  // (the vehicle drives below 4 m/s), and gaps of more than 5 s between fixes; and the mean and
  // maximum error over the fixes that did not jump.
  int64_t jumps = 0;
  int64_t gaps = 0;
  double mean_without_jumps_m = 0, max_without_jumps_m = 0;
};
StatusOr<GpsErrors> CompareWithGps(const std::vector<StampedPose>& path,
                                   const std::vector<TimedPoint>& gps);

// The score of PHD-SLAM (Kaltiokallio et al., IEEE T-RO 2023; their released code's
// performance_summary): at each scan time of `scan_times` (increasing, repeats allowed) at which
// the path has an estimate (its last pose at that time), the GPS fix nearest in time, kept when
// it lies within tolerance_s (25 ms); the RMSE of the distances between the kept pairs. Their
// code starts the filter at a fixed pose in the GPS's frame; this text form of the data has
// another frame, so the estimate is brought into it by the rigid transform that best aligns the
// kept pairs (as CompareWithGps()). InvalidArgument when fewer than 2 pairs are kept.
struct GpsScanErrors {
  int64_t scans = 0;  // scan times with an estimate
  int64_t pairs = 0;  // of them, with a GPS fix within the tolerance
  double rmse_m = 0;
  TrajectoryError alignment;
};
StatusOr<GpsScanErrors> CompareWithGpsAtScans(const std::vector<StampedPose>& path,
                                              const std::vector<double>& scan_times,
                                              const std::vector<TimedPoint>& gps,
                                              double tolerance_s = 0.025);

// The distinct times of `observations` (sorted by time), as CompareWithGpsAtScans() takes them.
std::vector<double> ScanTimes(const std::vector<ObservationRecord>& observations);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_IO_VICTORIA_PARK_H_
