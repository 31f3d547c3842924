#include "tools/run/tracking_run.h"

#include <fmt/format.h>

#include <memory>
#include <optional>
#include <utility>

#include "grove/collective.h"
#include "grove/config_json.h"
#include "tools/io/filter_outputs.h"
#include "tools/io/tracking_inputs.h"

namespace grove::tools {
namespace {

class TrackingJob final : public FacadeRunJob<Tracker, TrackerConfig> {
 public:
  TrackingJob(const TrackerConfig& config, const TrackingRunOptions& options)
      : FacadeRunJob(config, options.run.ranks), options_(options) {}

  // Reads the beacons and opens the measurements (their errors are input errors); a regular
  // file is read once more to count its updates.
  Status Open() {
    StatusOr<std::map<int64_t, IdPoint>> beacons = ReadIdPoints(options_.beacons_path);
    if (!beacons.ok()) return beacons.status();
    beacons_ = std::move(beacons).value();
    StatusOr<MeasurementReader> reader =
        MeasurementReader::Open(options_.measurements_path, beacons_);
    if (!reader.ok()) return reader.status();
    reader_.emplace(std::move(reader).value());
    rows_ = CountRegularFileLines(options_.measurements_path);
    if (rows_ > 0) {
      StatusOr<MeasurementReader> again =
          MeasurementReader::Open(options_.measurements_path, beacons_);
      if (again.ok()) updates_ = CountRecords<TrackingUpdate>(*again);
    }
    return Status::Ok();
  }

  std::vector<std::string> InputPaths() const override {
    return {options_.beacons_path, options_.measurements_path};
  }
  std::string InputName() const override { return options_.measurements_path; }
  const char* RecordsName() const override { return "updates"; }
  int64_t ExpectedRecords() const override { return rows_; }
  int64_t ExpectedSteps() const override { return updates_; }

  StatusOr<bool> Read(std::string* digest_bytes) override {
    StatusOr<bool> more = reader_->Next(&update_);
    if (!more.ok() || !*more) return more;
    digest_bytes->append(reinterpret_cast<const char*>(&update_.t_s), sizeof(update_.t_s));
    digest_bytes->append(reinterpret_cast<const char*>(update_.ranges.data()),
                         update_.ranges.size() * sizeof(RangeMeasurement));
    return true;
  }
  void Replay() override {}
  Status Step() override {
    Status s = engine_->Update(update_.t_s, update_.ranges);
    if (s.ok()) return s;
    return Status(s.code(),
                  fmt::format("{}:{}: {}", options_.measurements_path, update_.line, s.message()));
  }

  std::string DescribePrediction(int64_t records) const override {
    return fmt::format("{} particles, {} measurement rows", config_.particles, records);
  }
  // 32 MiB fixed, this rank's particles' state in two generations with the weights, and per
  // input row the times and mean poses kept and the trajectory built in memory.
  int64_t PredictPeakBytes(int64_t records) const override {
    const uint64_t share = ShareOf(static_cast<uint64_t>(config_.particles), ranks_).count;
    return (int64_t{32} << 20) + static_cast<int64_t>(share) * 128 + records * 160;
  }

  std::vector<std::string> OutputNames() const override { return {"trajectory.csv"}; }
  Status WriteOutputs(OutputSet* out, nlohmann::json* summary) override {
    // The read-outs are collective across ranks: every rank takes them.
    const TrackerSummary s = engine_->Summary();
    if (out == nullptr) return Status::Ok();  // another rank writes them
    // The mean pose after each update (the prior before the first is no estimate).
    const std::vector<StampedPose>& mean = engine_->MeanTrajectory();
    GROVE_RETURN_IF_ERROR(out->Add(
        "trajectory.csv", TrajectoryCsv(std::vector<StampedPose>(mean.begin() + 1, mean.end()))));
    summary->update(FilterSummaryJson(s));
    (*summary)["measurements"] = s.measurements;
    (*summary)["mean_state"] = {{"x_m", s.mean_state.x_m},
                                {"y_m", s.mean_state.y_m},
                                {"vx_mps", s.mean_state.vx_mps},
                                {"vy_mps", s.mean_state.vy_mps}};
    (*summary)["inputs"] = {{"beacons", options_.beacons_path},
                            {"beacon_count", beacons_.size()},
                            {"measurements", options_.measurements_path}};
    return Status::Ok();
  }

 private:
  TrackingRunOptions options_;
  std::map<int64_t, IdPoint> beacons_;
  std::optional<MeasurementReader> reader_;
  int64_t rows_ = 0;     // measurement rows (lines after the header)
  int64_t updates_ = 0;  // the updates Read() returns
  TrackingUpdate update_;
};

}  // namespace

int RunTrackingCommand(const TrackerConfig& config, const TrackingRunOptions& options) {
  if (Status s = config.Validate(); !s.ok()) return Fail(kExitUsage, s.message());
  TrackingJob job(config, options);
  if (Status s = job.Open(); !s.ok()) return Fail(kExitInput, s.message());
  return RunCommand(&job, options.run, ConfigToJson(TrackerConfigFields(), config));
}

}  // namespace grove::tools
