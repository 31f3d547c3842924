// `grove fastslam run` (FastSLAM on the generic run loop, tools/run/run_loop.h) and
// `grove fastslam evaluate`.
#include "tools/run/fastslam_run.h"

#include <fmt/format.h>
#include <sys/stat.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <numbers>

#include "grove/collective.h"
#include "grove/config_json.h"
#include "tools/io/fastslam_inputs.h"
#include "tools/io/filter_outputs.h"
#include "tools/io/id_points.h"
#include "tools/io/victoria_park.h"
#include "tools/report/map_render.h"
#include "tools/report/truth_score.h"

namespace grove::tools {
namespace {

double Wrap(double a) { return std::remainder(a, 2 * std::numbers::pi); }

// The trajectories a run writes: the weighted mean's (scored against a truth) and the heaviest
// particle's.
constexpr const char* kTrajectoryStems[] = {"trajectory", "heaviest_trajectory"};

// A pose file `t,x,y,heading` (trajectory.csv, truth.csv), times non-decreasing; at a repeated
// time the last row wins (a scan's update follows the prediction to its time).
StatusOr<std::map<double, Pose2>> ReadPoses(const std::string& path) {
  StatusOr<CsvTableReader> table = CsvTableReader::Open(path, {{"t", "x", "y", "heading"}});
  if (!table.ok()) return table.status();
  std::map<double, Pose2> poses;
  double last = -INFINITY;
  GROVE_RETURN_IF_ERROR(
      table->ForEachRow([&](const std::vector<CsvField>& f, int64_t line) -> Status {
        double t = 0;
        Pose2 p;
        GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path, line, f[0], "t", &t));
        GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path, line, f[1], "x", &p.x_m));
        GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path, line, f[2], "y", &p.y_m));
        GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path, line, f[3], "heading", &p.heading_rad));
        if (t < last) {
          return LineError(path, line, f[0].column,
                           fmt::format("t = {} is before the previous time {}", t, last));
        }
        last = t;
        poses[t] = p;
        return Status::Ok();
      }));
  if (poses.empty()) return InvalidArgumentError(fmt::format("{}: no poses", path));
  return poses;
}

// An integer field in [lo, 2^63).
Status ParseInt64(const std::string& path, int64_t line, const CsvField& f, const char* name,
                  int64_t lo, int64_t* value) {
  const char* end = f.text.data() + f.text.size();
  auto [ptr, ec] = std::from_chars(f.text.data(), end, *value);
  if (ec != std::errc() || ptr != end || *value < lo) {
    return LineError(
        path, line, f.column,
        fmt::format("{}: {} is not an integer in [{}, 2^63)", name, QuotedField(f.text), lo));
  }
  return Status::Ok();
}

// landmarks.csv: `id,x,y,sxx,sxy,syy[,source_id]`.
StatusOr<std::vector<LandmarkEstimate>> ReadLandmarkEstimates(const std::string& path) {
  StatusOr<CsvTableReader> table = CsvTableReader::Open(
      path,
      {{"id", "x", "y", "sxx", "sxy", "syy"}, {"id", "x", "y", "sxx", "sxy", "syy", "source_id"}});
  if (!table.ok()) return table.status();
  const bool sources = table->header() == 1;
  std::vector<LandmarkEstimate> out;
  GROVE_RETURN_IF_ERROR(
      table->ForEachRow([&](const std::vector<CsvField>& f, int64_t line) -> Status {
        LandmarkEstimate l;
        GROVE_RETURN_IF_ERROR(ParseInt64(path, line, f[0], "id", 0, &l.id));
        if (sources)
          GROVE_RETURN_IF_ERROR(ParseInt64(path, line, f[6], "source_id", -1, &l.source_id));
        const char* names[] = {"x", "y", "sxx", "sxy", "syy"};
        double* values[] = {&l.x_m, &l.y_m, &l.sxx, &l.sxy, &l.syy};
        for (int k = 0; k < 5; ++k) {
          GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path, line, f[k + 1], names[k], values[k]));
        }
        out.push_back(l);
        return Status::Ok();
      }));
  return out;
}

nlohmann::json PoseErrorsJson(const PoseErrors& e) {
  return {{"matched", e.matched},
          {"truth_without_estimate", e.unmatched},
          {"position_rmse_m", e.position_rmse_m},
          {"heading_rmse_rad", e.heading_rmse_rad},
          {"max_position_error_m", e.max_position_m},
          {"position_mse_mean_m2", e.position_mse_mean_m2},
          {"position_mse_variance_m4", e.position_mse_variance_m4}};
}

// Estimates matched to the truth by id, or under unknown association by the id of the
// detection that created them (source_id): then several estimates of one true landmark are
// duplicates (associations the filter missed) and true landmarks without one are missing.
nlohmann::json LandmarkErrorsJson(const std::vector<LandmarkEstimate>& estimates,
                                  const std::map<int64_t, IdPoint>& truth) {
  int64_t matched = 0, unknown = 0;
  double sq = 0, worst = 0;
  const bool by_source = std::any_of(estimates.begin(), estimates.end(),
                                     [](const LandmarkEstimate& l) { return l.source_id >= 0; });
  std::map<int64_t, int64_t> per_truth;
  for (const LandmarkEstimate& l : estimates) {
    auto it = truth.find(by_source ? l.source_id : l.id);
    if (it == truth.end()) {
      ++unknown;
      continue;
    }
    ++per_truth[it->first];
    const double d = std::hypot(l.x_m - it->second.x_m, l.y_m - it->second.y_m);
    sq += d * d;
    worst = std::max(worst, d);
    ++matched;
  }
  nlohmann::json j = {{"estimated", estimates.size()},
                      {"true", truth.size()},
                      {"matched", matched},
                      {"estimated_without_truth", unknown},
                      {"rmse_m", matched > 0 ? std::sqrt(sq / matched) : 0.0},
                      {"max_error_m", worst}};
  if (by_source) {
    int64_t duplicates = 0;
    for (const auto& [id, n] : per_truth) duplicates += n - 1;
    j["matched_by"] = "source_id";
    j["duplicates"] = duplicates;
    j["true_without_estimate"] = static_cast<int64_t>(truth.size() - per_truth.size());
  }
  return j;
}

nlohmann::json FastSlamSummaryJson(const FastSlamSummary& s) {
  nlohmann::json j = FilterSummaryJson(s);
  j["controls"] = s.controls;
  j["scans"] = s.scans;
  j["observations"] = s.observations;
  j["predict_steps"] = s.predict_steps;
  j["landmarks"] = s.landmarks;
  const AssociationCounts& a = s.association;
  if (a.associated + a.created + a.ignored > 0) {
    j["association"] = {
        {"associated", a.associated},
        {"created", a.created},
        {"ignored", a.ignored},
        {"removed", a.removed},
        {"dropped", a.dropped},
        {"tagged", a.tagged},
        {"wrong", a.wrong},
        {"truncated", a.truncated},
        {"error_rate", a.tagged > 0 ? nlohmann::json(static_cast<double>(a.wrong) / a.tagged)
                                    : nlohmann::json(nullptr)}};
  }
  j["map_memory"] = MemoryUseJson(s.map_memory);
  j["trajectory_memory"] = MemoryUseJson(s.trajectory_memory);
  return j;
}

nlohmann::json GpsErrorsJson(const GpsErrors& e) {
  return {{"fixes", e.fixes.size()},
          {"mean_m", e.mean_m},
          {"median_m", e.median_m},
          {"rmse_m", e.rmse_m},
          {"max_m", e.max_m},
          {"alignment_rotation_rad", e.alignment.rotation_rad},
          {"alignment_translation_m", {e.alignment.translation_x_m, e.alignment.translation_y_m}},
          {"gps_jumps_over_10_mps", e.jumps},
          {"gps_gaps_over_5_s", e.gaps},
          {"mean_without_jumps_m", e.mean_without_jumps_m},
          {"max_without_jumps_m", e.max_without_jumps_m}};
}

nlohmann::json GpsScanErrorsJson(const GpsScanErrors& e) {
  return {{"scans", e.scans},
          {"pairs", e.pairs},
          {"tolerance_s", 0.025},
          {"rmse_m", e.rmse_m},
          {"alignment_rotation_rad", e.alignment.rotation_rad},
          {"alignment_translation_m", {e.alignment.translation_x_m, e.alignment.translation_y_m}}};
}

std::string GpsErrorCsv(const GpsErrors& e) {
  std::string out = "t,gps_x,gps_y,x,y,error\n";
  for (const AlignedPointError& f : e.fixes) {
    fmt::format_to(std::back_inserter(out), "{:.3f},{:.3f},{:.3f},{:.3f},{:.3f},{:.3f}\n", f.t_s,
                   f.truth_x_m, f.truth_y_m, f.estimate_x_m, f.estimate_y_m, f.error_m);
  }
  return out;
}

// A filter's name for a chart's title.
const char* FilterTitle(FastSlamFilter filter) {
  switch (filter) {
    case FastSlamFilter::kFastSlam1:
      return "FastSLAM 1.0";
    case FastSlamFilter::kFastSlam2:
      return "FastSLAM 2.0";
    case FastSlamFilter::kUnscented:
      return "U-FastSLAM";
    case FastSlamFilter::kSrcd:
      return "SRCD-FastSLAM";
    case FastSlamFilter::kSrcdAided:
      return "SRCD-aided FastSLAM";
    case FastSlamFilter::kSrcdParticle:
      return "SRCD-PF";
    case FastSlamFilter::kDeSrcd:
      return "DE-SRCD-FastSLAM";
  }
  return FastSlamFilterName(filter);
}

// What the command keeps per input row besides the engine: the rows of a dataset read whole
// and the outputs built in memory (measured on Victoria Park and the webmap).
constexpr int64_t kCommandBytesPerRow = 256;

class FastSlamJob final : public FacadeRunJob<FastSlam, FastSlamConfig> {
 public:
  FastSlamJob(const FastSlamConfig& config, const FastSlamRunOptions& options)
      : FacadeRunJob(config, options.run.ranks), options_(options) {}

  const FastSlamConfig& config() const { return config_; }
  std::string Headline() const override { return headline_; }

  // Opens the inputs (their errors are input errors) and reads the optional truth. Observations
  // without ids select unknown association (config() says which ran).
  Status Open() {
    if (!options_.victoria_park_dir.empty()) {
      StatusOr<VictoriaParkData> data =
          ReadVictoriaPark(options_.victoria_park_dir, options_.until_s, config_);
      if (!data.ok()) return data.status();
      park_ = std::make_unique<VictoriaParkData>(std::move(data).value());
      park_events_ = new VictoriaParkEvents(park_.get());
      source_.reset(park_events_);
      records_ = static_cast<int64_t>(park_->controls.size() + park_->observations.size());
      VictoriaParkEvents events(park_.get());
      CountWorkload(events);
      return Status::Ok();
    }
    StatusOr<FastSlamInputReader> reader =
        FastSlamInputReader::Open(options_.controls_path, options_.observations_path, config_);
    if (!reader.ok()) return reader.status();
    const std::string note = AdaptAssociationToIds(*reader, &config_);
    if (!note.empty() && (ranks_ == nullptr || ranks_->rank() == 0)) {  // one line, not per rank
      std::fprintf(stderr, "%s\n", note.c_str());
    }
    source_ = std::make_unique<FastSlamInputReader>(std::move(reader).value());
    records_ = CountRegularFileLines(options_.controls_path) +
               CountRegularFileLines(options_.observations_path);
    if (records_ > 0) {
      // Regular files: read them once more to count the scans among the rows.
      StatusOr<FastSlamInputReader> events =
          FastSlamInputReader::Open(options_.controls_path, options_.observations_path, config_);
      if (events.ok()) CountWorkload(*events);
    }
    if (!options_.truth_path.empty()) {
      StatusOr<TruthTrajectory> truth = ReadTruthTrajectory(options_.truth_path);
      if (!truth.ok()) return truth.status();
      truth_ = std::move(truth).value();
    }
    if (!options_.landmarks_truth_path.empty()) {
      StatusOr<std::map<int64_t, IdPoint>> l = ReadIdPoints(options_.landmarks_truth_path);
      if (!l.ok()) return l.status();
      landmarks_truth_ = std::move(l).value();
    }
    return Status::Ok();
  }

  // Counts the workload of `events` (a second reader of the input) into work_: none when it
  // fails before its end (the run reports that error).
  void CountWorkload(FastSlamEventSource& events) {
    FastSlamWorkload work;
    FastSlamEvent e;
    for (;;) {
      StatusOr<bool> more = events.Next(&e);
      if (!more.ok()) return;
      if (!*more) break;
      if (!e.is_scan) {
        ++work.controls;
        continue;
      }
      ++work.scans;
      work.observations += static_cast<int64_t>(e.scan.size());
    }
    work_ = work;
  }

  std::vector<std::string> InputPaths() const override {
    if (park_ != nullptr) return {park_->controls_path, park_->observations_path, park_->gps_path};
    std::vector<std::string> paths = {options_.controls_path, options_.observations_path};
    for (const std::string* p : {&options_.truth_path, &options_.landmarks_truth_path}) {
      if (!p->empty()) paths.push_back(*p);
    }
    return paths;
  }
  std::vector<std::string> OutputNames() const override {
    std::vector<std::string> names = TrajectoryFileNames(kTrajectoryStems);
    for (const char* name : {"landmarks.csv", "map.png", "map.svg"}) names.push_back(name);
    if (park_ != nullptr) names.push_back("gps_error.csv");
    if (!options_.truth_path.empty()) {
      for (const char* name : kTruthScoreFiles) names.push_back(name);
    }
    return names;
  }
  std::string InputName() const override {
    if (park_ != nullptr) return "Victoria Park (" + options_.victoria_park_dir + ")";
    return options_.controls_path + " + " + options_.observations_path;
  }
  const char* RecordsName() const override { return "input rows"; }
  int64_t ExpectedRecords() const override { return records_; }
  int64_t ExpectedSteps() const override { return work_.controls + work_.scans; }
  // The process and engine (FastSlam::EstimatePeakBytes of the counted workload; across ranks,
  // of this rank's particles) and what the command keeps per input row (the records of a
  // dataset read whole, the outputs built in memory).
  int64_t PredictPeakBytes(int64_t records) const override {
    FastSlamConfig share = config_;
    share.particles =
        static_cast<int64_t>(ShareOf(static_cast<uint64_t>(config_.particles), ranks_).count);
    return FastSlam::EstimatePeakBytes(share, work_) + records * kCommandBytesPerRow;
  }
  std::string DescribePrediction(int64_t records) const override {
    return fmt::format("{} particles, {} input rows: {} controls, {} scans, {} detections{}",
                       config_.particles, records, work_.controls, work_.scans, work_.observations,
                       records_ == 0 ? " (a stream: its length is not known before the run)" : "");
  }

  StatusOr<bool> Read(std::string* digest_bytes) override {
    StatusOr<bool> more = source_->Next(&event_);
    if (!more.ok() || !*more) return more;
    if (event_.is_scan) {
      const double t = event_.scan_t_s;
      digest_bytes->append(reinterpret_cast<const char*>(&t), sizeof(t));
      for (const LandmarkObservation& z : event_.scan) {
        const double v[3] = {z.range_m, z.bearing_rad, static_cast<double>(z.id)};
        digest_bytes->append(reinterpret_cast<const char*>(v), sizeof(v));
      }
    } else {
      const double v[3] = {event_.control.t_s, event_.control.v_mps, event_.control.steer_rad};
      digest_bytes->append(reinterpret_cast<const char*>(v), sizeof(v));
    }
    return true;
  }
  void Replay() override {}
  Status Step() override { return FeedEvent(event_, *source_, engine_.get()); }

  Status WriteOutputs(OutputSet* out, nlohmann::json* summary) override {
    // Every read-out first: across ranks they are collective, and every rank takes them.
    const std::vector<StampedPose>& mean = engine_->MeanTrajectory();
    StatusOr<std::vector<StampedPose>> heaviest = engine_->HeaviestTrajectory();
    if (!heaviest.ok()) return heaviest.status();
    StatusOr<std::vector<LandmarkEstimate>> landmarks = engine_->HeaviestLandmarks();
    if (!landmarks.ok()) return landmarks.status();
    const FastSlamSummary engine_summary = engine_->Summary();
    if (out == nullptr) return Status::Ok();  // not rank 0
    const std::vector<StampedPose>* trajectories[] = {&mean, &*heaviest};
    GROVE_RETURN_IF_ERROR(AddTrajectoryFiles(out, kTrajectoryStems, trajectories));
    GROVE_RETURN_IF_ERROR(out->Add("landmarks.csv", LandmarksCsv(*landmarks)));
    if (StopRequested()) return Status::Ok();
    MapImage image;
    for (const StampedPose& p : *heaviest) image.path.push_back({p.pose.x_m, p.pose.y_m});
    for (const StampedPose& p : truth_.poses) image.truth.push_back({p.pose.x_m, p.pose.y_m});
    for (const LandmarkEstimate& l : *landmarks) {
      image.landmarks.push_back({l.x_m, l.y_m, l.sxx, l.sxy, l.syy});
    }
    for (const auto& [id, l] : landmarks_truth_) image.landmarks_truth.push_back({l.x_m, l.y_m});
    const char* filter = FilterTitle(config_.filter);
    image.title = fmt::format("{}, {} particles: heaviest particle's path and landmarks", filter,
                              config_.particles);
    StatusOr<GpsErrors> gps_mean = InvalidArgumentError("no GPS"), gps_heaviest = gps_mean;
    if (park_ != nullptr) {
      gps_mean = CompareWithGps(mean, park_->gps);
      gps_heaviest = CompareWithGps(*heaviest, park_->gps);
      if (gps_mean.ok() && gps_heaviest.ok()) {
        GROVE_RETURN_IF_ERROR(out->Add("gps_error.csv", GpsErrorCsv(*gps_mean)));
        // The GPS drawn in the filter's frame: the inverse of the heaviest path's alignment.
        const TrajectoryError& a = gps_heaviest->alignment;
        const double c = std::cos(a.rotation_rad), s = std::sin(a.rotation_rad);
        for (const TimedPoint& g : park_->gps) {
          const double dx = g.x_m - a.translation_x_m, dy = g.y_m - a.translation_y_m;
          image.truth.push_back({c * dx + s * dy, -s * dx + c * dy});
        }
        image.truth_label = "GPS (rigidly aligned)";
      } else {
        GROVE_RETURN_IF_ERROR(out->Add("gps_error.csv", "t,gps_x,gps_y,x,y,error\n"));
      }
      image.title = fmt::format("Victoria Park, {}, {} particles: heaviest path, landmarks, GPS",
                                filter, config_.particles);
    }
    GROVE_RETURN_IF_ERROR(AddMapImages(out, image));
    if (StopRequested()) return Status::Ok();  // the loop checkpoints and stops
    summary->update(FastSlamSummaryJson(engine_summary));
    if (park_ != nullptr) {
      (*summary)["inputs"] = {
          {"victoria_park", options_.victoria_park_dir},
          {"files", InputFilesJson(park_->files)},
          {"until_s", std::isfinite(options_.until_s) ? nlohmann::json(options_.until_s)
                                                      : nlohmann::json(nullptr)},
          {"scans_before_the_first_control", park_events_->skipped_scans()}};
      (*summary)["gps"] =
          gps_mean.ok() ? GpsErrorsJson(*gps_mean) : nlohmann::json(gps_mean.status().message());
      (*summary)["gps_heaviest"] = gps_heaviest.ok()
                                       ? GpsErrorsJson(*gps_heaviest)
                                       : nlohmann::json(gps_heaviest.status().message());
      const std::vector<double> scans = ScanTimes(park_->observations);
      StatusOr<GpsScanErrors> phd = CompareWithGpsAtScans(mean, scans, park_->gps);
      StatusOr<GpsScanErrors> phd_heaviest = CompareWithGpsAtScans(*heaviest, scans, park_->gps);
      (*summary)["gps_phd_slam"] =
          phd.ok() ? GpsScanErrorsJson(*phd) : nlohmann::json(phd.status().message());
      (*summary)["gps_phd_slam_heaviest"] = phd_heaviest.ok()
                                                ? GpsScanErrorsJson(*phd_heaviest)
                                                : nlohmann::json(phd_heaviest.status().message());
      if (gps_mean.ok() && phd.ok()) {
        headline_ = fmt::format(
            "Against GPS (weighted-mean path): mean error {:.2f} m, RMSE {:.2f} m over {} fixes "
            "after a rigid alignment; PHD-SLAM's score (fixes within 25 ms of a scan's estimate): "
            "RMSE {:.2f} m over {} of {} scans.",
            gps_mean->mean_m, gps_mean->rmse_m, gps_mean->fixes.size(), phd->rmse_m, phd->pairs,
            phd->scans);
      }
    } else {
      (*summary)["inputs"] = {{"controls", options_.controls_path},
                              {"observations", options_.observations_path}};
    }
    if (!options_.truth_path.empty()) {
      std::map<double, Pose2> estimate, truth;
      for (const StampedPose& p : mean) estimate[p.t_s] = p.pose;
      for (const StampedPose& p : truth_.poses) truth[p.t_s] = p.pose;
      nlohmann::json accuracy = PoseErrorsJson(ComparePoses(truth, estimate));
      // Without a heading in the truth there is none to compare.
      if (!truth_.has_heading) accuracy["heading_rmse_rad"] = nullptr;
      const TruthScore score = ScoreAgainstTruth(truth_, mean);
      GROVE_RETURN_IF_ERROR(AddTruthScoreFiles(
          out, score,
          fmt::format("{}, {} particles: weighted-mean path's error against the truth",
                      FilterTitle(config_.filter), config_.particles)));
      if (score.error.ok()) {
        const TrajectoryError& e = *score.error;
        accuracy["aligned_matched"] = e.matched;
        accuracy["aligned_position_rmse_m"] = e.aligned_rmse_m;
        accuracy["aligned_max_position_error_m"] = e.aligned_max_m;
        accuracy["alignment_rotation_rad"] = e.rotation_rad;
        accuracy["alignment_translation_m"] = {e.translation_x_m, e.translation_y_m};
      } else {
        accuracy["aligned_error"] = score.error.status().message();
      }
      (*summary)["accuracy"] = accuracy;
      headline_ = TruthHeadline(score);
    }
    if (!landmarks_truth_.empty()) {
      (*summary)["landmark_accuracy"] = LandmarkErrorsJson(*landmarks, landmarks_truth_);
    }
    return Status::Ok();
  }

 private:
  FastSlamRunOptions options_;
  std::unique_ptr<FastSlamEventSource> source_;
  std::unique_ptr<VictoriaParkData> park_;
  VictoriaParkEvents* park_events_ = nullptr;  // source_, for Victoria Park
  std::string headline_;   // the score against the GPS (Victoria Park) or the truth
  int64_t records_ = 0;    // input rows
  FastSlamWorkload work_;  // counted before the run: controls and scans are the events Read() gives
  FastSlamEvent event_;
  TruthTrajectory truth_;  // empty without --truth
  std::map<int64_t, IdPoint> landmarks_truth_;
};

}  // namespace

PoseErrors ComparePoses(const std::map<double, Pose2>& truth,
                        const std::map<double, Pose2>& estimate) {
  PoseErrors e;
  std::vector<double> sq;
  double heading_sq = 0;
  for (const auto& [t, p] : truth) {
    auto it = estimate.find(t);
    if (it == estimate.end()) {
      ++e.unmatched;
      continue;
    }
    const double d2 = (it->second.x_m - p.x_m) * (it->second.x_m - p.x_m) +
                      (it->second.y_m - p.y_m) * (it->second.y_m - p.y_m);
    sq.push_back(d2);
    const double dh = Wrap(it->second.heading_rad - p.heading_rad);
    heading_sq += dh * dh;
    e.max_position_m = std::max(e.max_position_m, std::sqrt(d2));
  }
  e.matched = static_cast<int64_t>(sq.size());
  if (sq.empty()) return e;
  double sum = 0;
  for (double v : sq) sum += v;
  const double mean = sum / sq.size();
  double var = 0;
  for (double v : sq) var += (v - mean) * (v - mean);
  e.position_mse_mean_m2 = mean;
  e.position_mse_variance_m4 = var / sq.size();
  e.position_rmse_m = std::sqrt(mean);
  e.heading_rmse_rad = std::sqrt(heading_sq / sq.size());
  return e;
}

std::string LandmarksCsv(const std::vector<LandmarkEstimate>& landmarks) {
  std::string out = "id,x,y,sxx,sxy,syy,source_id\n";
  for (const LandmarkEstimate& l : landmarks) {
    fmt::format_to(std::back_inserter(out), "{},{:.6f},{:.6f},{:.9g},{:.9g},{:.9g},{}\n", l.id,
                   l.x_m, l.y_m, l.sxx, l.sxy, l.syy, l.source_id);
  }
  return out;
}

int RunFastSlamCommand(const FastSlamConfig& config, const FastSlamRunOptions& options) {
  if (Status s = config.Validate(); !s.ok()) return Fail(kExitUsage, s.message());
  FastSlamJob job(config, options);
  if (Status s = job.Open(); !s.ok()) return Fail(kExitInput, s.message());
  return RunCommand(&job, options.run, ConfigToJson(FastSlamConfigFields(), job.config()));
}

int FastSlamEvaluateCommand(const std::string& truth_path, const std::string& trajectory_path,
                            const std::string& landmarks_path,
                            const std::string& landmarks_truth_path) {
  StatusOr<std::map<double, Pose2>> truth = ReadPoses(truth_path);
  if (!truth.ok()) return Fail(kExitInput, truth.status().message());
  StatusOr<std::map<double, Pose2>> estimate = ReadPoses(trajectory_path);
  if (!estimate.ok()) return Fail(kExitInput, estimate.status().message());
  const PoseErrors e = ComparePoses(*truth, *estimate);
  if (e.matched == 0) {
    return Fail(kExitInput, fmt::format("{} and {} share no time", truth_path, trajectory_path));
  }
  nlohmann::json report = {{"pose", PoseErrorsJson(e)},
                           {"nees", "not computed: the run writes no particle covariance"}};
  if (!landmarks_path.empty()) {
    if (landmarks_truth_path.empty()) {
      return Fail(kExitUsage, "--landmarks needs --landmarks-truth");
    }
    StatusOr<std::vector<LandmarkEstimate>> l = ReadLandmarkEstimates(landmarks_path);
    if (!l.ok()) return Fail(kExitInput, l.status().message());
    StatusOr<std::map<int64_t, IdPoint>> t = ReadIdPoints(landmarks_truth_path);
    if (!t.ok()) return Fail(kExitInput, t.status().message());
    report["landmarks"] = LandmarkErrorsJson(*l, *t);
  }
  std::printf("%s\n", report.dump(2).c_str());
  return kExitOk;
}

}  // namespace grove::tools
