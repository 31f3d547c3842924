// The input files of `grove fastslam run` (formats fixed so that other simulators can feed
// grove; tools/io/FORMATS.md, "FastSLAM inputs"):
//   controls.csv      `t,v,steer`: time (s, strictly increasing), speed (m/s), steering angle
//                     (rad); the control of row k holds from t_k until t_{k+1}.
//   observations.csv  `t,range,bearing` or `t,range,bearing,id`: one detection a row, rows with
//                     the same t one scan, t non-decreasing; range (m), bearing (rad,
//                     counter-clockwise from the heading), id an integer in [0, 2^31) naming the
//                     landmark (known association; without the column, or under
//                     --association ml, the association is unknown and ids only tag).
// Every value is checked against grove/input_rules.h, the engine's own bounds. The CSV syntax
// and the "FILE:LINE:COLUMN: what" errors are those of tools/io/csv_reader.h.
//
// FastSlamInputReader merges the two files into the order the filter takes them: each control,
// then the scans from its time until the next control's (a control and a scan at the same time:
// the control first). A scan before the first control is an error.
#ifndef GROVE_TOOLS_IO_FASTSLAM_INPUTS_H_
#define GROVE_TOOLS_IO_FASTSLAM_INPUTS_H_

#include <cstdint>
#include <string>
#include <vector>

#include "grove/fastslam.h"
#include "grove/status.h"
#include "tools/io/csv_reader.h"

namespace grove::tools {

struct ControlRecord {
  double t_s = 0;
  double v_mps = 0;
  double steer_rad = 0;
  int64_t line = 0;
};

struct ObservationRecord {
  double t_s = 0;
  LandmarkObservation z;
  int64_t line = 0;
};

class ControlReader {
 public:
  // The steering angles are checked against `config`'s vehicle (grove/input_rules.h).
  static StatusOr<ControlReader> Open(const std::string& path,
                                      const FastSlamConfig& config = FastSlamConfig());
  // The next control: false at the end.
  StatusOr<bool> Next(ControlRecord* out);
  const std::string& path() const { return table_.path(); }

 private:
  ControlReader(CsvTableReader table, const FastSlamConfig& config)
      : table_(std::move(table)), config_(config) {}
  CsvTableReader table_;
  FastSlamConfig config_;
  bool has_previous_ = false;
  double previous_s_ = 0;
};

class ObservationReader {
 public:
  static StatusOr<ObservationReader> Open(const std::string& path);
  // Whether the file has the id column (known association).
  bool has_ids() const { return table_.header() == 1; }
  StatusOr<bool> Next(ObservationRecord* out);
  const std::string& path() const { return table_.path(); }

 private:
  explicit ObservationReader(CsvTableReader table) : table_(std::move(table)) {}
  CsvTableReader table_;
  bool has_previous_ = false;
  double previous_s_ = 0;
};

// One input event: a control, or a scan (all rows of one time).
struct FastSlamEvent {
  bool is_scan = false;
  ControlRecord control;
  double scan_t_s = 0;
  int64_t scan_line = 0;  // the scan's first row
  std::vector<LandmarkObservation> scan;
};

// Where the run loop takes FastSLAM's events from: the CSV files, or a dataset's reader.
class FastSlamEventSource {
 public:
  virtual ~FastSlamEventSource() = default;
  // The next event; false at the end.
  virtual StatusOr<bool> Next(FastSlamEvent* out) = 0;
  // The files the events' lines are in, for error messages.
  virtual std::string ControlSource() const = 0;
  virtual std::string ScanSource() const = 0;
};

class FastSlamInputReader final : public FastSlamEventSource {
 public:
  static StatusOr<FastSlamInputReader> Open(const std::string& controls_path,
                                            const std::string& observations_path,
                                            const FastSlamConfig& config = FastSlamConfig());
  // The next event; false at the end of both files. Without an id column the ids are -1.
  StatusOr<bool> Next(FastSlamEvent* out) override;
  std::string ControlSource() const override { return controls_.path(); }
  std::string ScanSource() const override { return observations_.path(); }
  bool has_ids() const { return observations_.has_ids(); }

 private:
  FastSlamInputReader(ControlReader c, ObservationReader o)
      : controls_(std::move(c)), observations_(std::move(o)) {}
  Status Fill();
  ControlReader controls_;
  ObservationReader observations_;
  bool control_ready_ = false, controls_done_ = false;
  bool observation_ready_ = false, observations_done_ = false;
  bool any_control_ = false;
  ControlRecord control_;
  ObservationRecord observation_;
};

// Observations without ids leave the association unknown: a configuration asking for known
// association runs maximum likelihood instead (`grove fastslam run`'s rule). Returns the line
// that says so, or "" when *config is unchanged.
std::string AdaptAssociationToIds(const FastSlamInputReader& reader, FastSlamConfig* config);

// Feeds `event` to `slam`; an error names the file and line of `source` the event came from.
Status FeedEvent(const FastSlamEvent& event, const FastSlamEventSource& source, FastSlam* slam);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_IO_FASTSLAM_INPUTS_H_
