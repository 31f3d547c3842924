// `grove footslam run`: FootSLAM on the generic run loop (tools/run/run_loop.h).
#include "tools/run/footslam_run.h"

#include <fmt/format.h>
#include <sys/stat.h>

#include <algorithm>
#include <fstream>
#include <memory>
#include <string_view>
#include <vector>

#include "grove/collective.h"
#include "grove/config_json.h"
#include "tools/io/filter_outputs.h"
#include "tools/io/footslam_outputs.h"
#include "tools/io/imu_step_source.h"
#include "tools/io/output_readers.h"
#include "tools/io/step_reader.h"
#include "tools/report/map_render.h"
#include "tools/report/truth_score.h"

namespace grove::tools {
namespace {

// The trajectories a run writes; the smoothed path is the one scored against a truth.
constexpr const char* kTrajectoryStems[] = {"trajectory", "mean_trajectory", "smoothed_trajectory"};

class FootSlamJob final : public FacadeRunJob<FootSlam, FootSlamConfig> {
 public:
  FootSlamJob(const FootSlamConfig& config, const FootSlamRunOptions& options)
      : FacadeRunJob(config, options.run.ranks),
        options_(options),
        steps_name_(!options.imu_path.empty()    ? options.imu_path
                    : options.steps_path.empty() ? EmbeddedWalkName()
                                                 : options.steps_path),
        odometry_(Pose2{config.start_x_m, config.start_y_m, config.start_heading_rad}) {}

  // Opens the step file (or the IMU recording); its errors are input errors.
  Status Open() {
    if (!options_.imu_path.empty()) return OpenImu();
    StepReaderOptions reader_options;
    reader_options.max_step_m = options_.max_step_m;
    StatusOr<StepReader> reader = OpenSteps(reader_options);
    if (!reader.ok()) return reader.status();
    reader_ = std::make_unique<StepReader>(std::move(reader).value());
    if (!options_.prior_map_path.empty()) {
      StatusOr<std::vector<HexCounts>> prior =
          ReadPriorMapCsv(options_.prior_map_path, config_.hex_radius_m);
      if (!prior.ok()) return prior.status();
      prior_ = std::move(prior).value();
    }
    if (!options_.truth_path.empty()) {
      StatusOr<TruthTrajectory> truth = ReadTruthTrajectory(options_.truth_path);
      if (!truth.ok()) return truth.status();
      truth_ = std::move(truth).value();
    }
    const int64_t lines = options_.steps_path.empty() ? CountLines(EmbeddedWalkSteps())
                                                      : CountRegularFileLines(options_.steps_path);
    // Lines after the header (comments and blank lines make it an estimate).
    records_ = std::max<int64_t>(lines - 1 - (reader_->positions_form() ? 1 : 0), 0);
    // A file (not a stream, which is read once) is read again to count its steps; an error
    // there is reported when the run comes to it.
    if (records_ > 0) {
      StatusOr<StepReader> again = OpenSteps(reader_options);
      if (again.ok()) steps_ = CountRecords<StepRecord>(*again);
    }
    return Status::Ok();
  }

  std::vector<std::string> InputPaths() const override {
    std::vector<std::string> paths;
    if (!options_.steps_path.empty()) paths.push_back(options_.steps_path);
    if (!options_.imu_path.empty()) paths.push_back(options_.imu_path);
    if (!options_.prior_map_path.empty()) paths.push_back(options_.prior_map_path);
    if (!options_.truth_path.empty()) paths.push_back(options_.truth_path);
    return paths;
  }

  Status Create() override {
    GROVE_RETURN_IF_ERROR(FacadeRunJob::Create());
    if (options_.prior_map_path.empty()) return Status::Ok();
    Status s = engine_->SetPriorMap(prior_);
    if (!s.ok()) return Status(s.code(), options_.prior_map_path + ": " + s.message());
    return Status::Ok();
  }
  std::vector<std::string> OutputNames() const override {
    std::vector<std::string> names = {"map.csv", "map_best.csv"};
    for (std::string& name : TrajectoryFileNames(kTrajectoryStems)) names.push_back(name);
    names.push_back("map.png");
    names.push_back("map.svg");
    if (!options_.truth_path.empty()) {
      for (const char* name : kTruthScoreFiles) names.push_back(name);
    }
    // Storage of diversity: the stored map alone (map.csv and map_best.csv include it).
    if (config_.store_distance_m > 0) names.push_back("stored_map.csv");
    if (imu_) names.push_back("steps.csv");  // the front end's steps
    return names;
  }
  std::string InputName() const override { return steps_name_; }
  std::string Headline() const override { return headline_; }
  const char* RecordsName() const override { return "steps"; }
  int64_t ExpectedRecords() const override { return records_; }
  int64_t ExpectedSteps() const override { return steps_; }
  int64_t PredictPeakBytes(int64_t records) const override {
    FootSlamConfig share = config_;  // across ranks, this rank's particles
    share.particles =
        static_cast<int64_t>(ShareOf(static_cast<uint64_t>(config_.particles), ranks_).count);
    return FootSlam::EstimatePeakBytes(share, records) + records * kCommandBytesPerStep;
  }
  std::string DescribePrediction(int64_t records) const override {
    return fmt::format("{} particles, {} map, {} steps{}", config_.particles,
                       FootSlamMapKindName(config_.map), records,
                       records_ == 0 ? " (a stream: its length is not known before the run)" : "");
  }

  StatusOr<bool> Read(std::string* digest_bytes) override {
    StatusOr<bool> more = imu_ ? ReadImuStep() : reader_->Next(&step_);
    if (!more.ok() || !*more) return more;
    const double v[3] = {step_.t_s, step_.dx_m, step_.dy_m};
    digest_bytes->append(reinterpret_cast<const char*>(v), sizeof(v));
    return true;
  }
  void Replay() override { odometry_.Add(step_.dx_m, step_.dy_m); }
  Status Step() override {
    const double start_s = engine_->steps() > 0 ? 0
                           : imu_               ? imu_->origin_time_s()
                                                : reader_->start_time_s();
    GROVE_RETURN_IF_ERROR(FeedStep(step_, steps_name_, start_s, engine_.get()));
    odometry_.Add(step_.dx_m, step_.dy_m);
    return Status::Ok();
  }

  Status WriteOutputs(OutputSet* out, nlohmann::json* summary) override {
    // Every read-out first: across ranks they are collective, and every rank takes them.
    StatusOr<std::vector<HexCounts>> cumulative = engine_->CumulativeMap();
    if (!cumulative.ok()) return cumulative.status();
    StatusOr<std::vector<HexCounts>> best = engine_->HeaviestMap();
    if (!best.ok()) return best.status();
    StatusOr<std::vector<HexCounts>> stored = engine_->StoredMap();
    if (!stored.ok()) return stored.status();
    StatusOr<std::vector<StampedPose>> trajectory = engine_->HeaviestTrajectory();
    if (!trajectory.ok()) return trajectory.status();
    StatusOr<std::vector<StampedPose>> smoothed = engine_->SmoothedTrajectory();
    if (!smoothed.ok()) return smoothed.status();
    const FootSlamSummary s = engine_->Summary();
    if (out == nullptr) return Status::Ok();  // another rank writes them
    GROVE_RETURN_IF_ERROR(out->Add("map.csv", MapCsv(*cumulative, false)));
    GROVE_RETURN_IF_ERROR(out->Add("map_best.csv", MapCsv(*best, true)));
    if (config_.store_distance_m > 0) {
      GROVE_RETURN_IF_ERROR(out->Add("stored_map.csv", MapCsv(*stored, false)));
    }
    const std::vector<StampedPose>* trajectories[] = {&*trajectory, &engine_->MeanTrajectory(),
                                                      &*smoothed};
    GROVE_RETURN_IF_ERROR(AddTrajectoryFiles(out, kTrajectoryStems, trajectories));
    if (StopRequested()) return Status::Ok();  // the loop checkpoints and stops
    // The smoothed path: the best of the three paths on the simulator's walks
    // (engine/footslam/README.md).
    MapImage image = FootSlamImage(
        config_.hex_radius_m, *cumulative, *smoothed, odometry_.points(),
        fmt::format("FootSLAM, {} particles, {} steps: cumulative map, smoothed path, "
                    "raw odometry{}",
                    config_.particles, engine_->steps(), truth_.poses.empty() ? "" : ", truth"));
    image.path_label = "smoothed path";
    for (const StampedPose& p : truth_.poses) image.truth.push_back({p.pose.x_m, p.pose.y_m});
    image.truth_label = "truth";
    GROVE_RETURN_IF_ERROR(AddMapImages(out, image));
    if (StopRequested()) return Status::Ok();  // the loop checkpoints and stops
    if (!options_.truth_path.empty()) {
      const TruthScore score = ScoreAgainstTruth(truth_, *smoothed);
      GROVE_RETURN_IF_ERROR(AddTruthScoreFiles(
          out, score,
          fmt::format("FootSLAM, {} particles: smoothed path's error against the truth",
                      config_.particles)));
      nlohmann::json accuracy = score.error.ok()
                                    ? TrajectoryErrorObject(*score.error)
                                    : nlohmann::json{{"error", score.error.status().message()}};
      accuracy["estimate"] = "smoothed_trajectory";
      (*summary)["accuracy"] = accuracy;
      headline_ = TruthHeadline(score);
    }
    summary->update(FootSlamSummaryJson(s));
    (*summary)["inputs"] = {{"steps", steps_name_}, {"steps_read", engine_->steps()}};
    if (!options_.truth_path.empty()) (*summary)["inputs"]["truth"] = options_.truth_path;
    if (imu_) {
      GROVE_RETURN_IF_ERROR(out->Add("steps.csv", FootStepsCsv(imu_steps_)));
      const FootImuSummary f = imu_->Summary();
      (*summary)["inputs"]["imu_format"] = imu_->reader().format();
      (*summary)["inputs"]["imu_duplicates_skipped"] = imu_->reader().duplicates();
      (*summary)["foot_imu"] = {{"config", nlohmann::json::parse(ConfigToJson(
                                               FootImuConfigFields(), options_.imu_config))},
                                {"samples", f.samples},
                                {"still_samples", f.still_samples},
                                {"stances", f.stances},
                                {"steps", f.steps},
                                {"alignment_t_s", f.alignment_t_s},
                                {"origin_t_s", f.origin_t_s},
                                {"gravity_mps2", f.gravity_mps2},
                                {"distance_m", f.distance_m},
                                {"seconds", f.seconds}};
    }
    (*summary)["hexagons"] = {{"cumulative", cumulative->size()}, {"heaviest", best->size()}};
    if (s.prior_hexagons + s.prior_hexagons_outside > 0 || !options_.prior_map_path.empty()) {
      (*summary)["prior_map"] = {{"path", options_.prior_map_path},
                                 {"hexagons", s.prior_hexagons},
                                 {"hexagons_outside_grid", s.prior_hexagons_outside},
                                 {"confidence", config_.prior_map_confidence}};
    }
    return Status::Ok();
  }

 private:
  Status OpenImu() {
    StatusOr<ImuStepSource> source =
        ImuStepSource::Open(options_.imu_path, options_.imu_config, options_.imu_reader);
    if (!source.ok()) return source.status();
    imu_ = std::make_unique<ImuStepSource>(std::move(source).value());
    // A regular file is run through the front end once more to count its steps (a stream is
    // read once, by the run); an error there is reported when the run comes to it.
    if (CountRegularFileLines(options_.imu_path) > 0 || options_.imu_path.ends_with(".mat")) {
      StatusOr<ImuStepSource> again =
          ImuStepSource::Open(options_.imu_path, options_.imu_config, options_.imu_reader);
      if (again.ok()) {
        FootStep step;
        int64_t line = 0;
        for (StatusOr<bool> more = again->Next(&step, &line); more.ok() && *more;
             more = again->Next(&step, &line)) {
          ++steps_;
        }
      }
    }
    records_ = steps_;
    return Status::Ok();
  }

  StatusOr<bool> ReadImuStep() {
    FootStep step;
    int64_t line = 0;
    StatusOr<bool> more = imu_->Next(&step, &line);
    if (!more.ok() || !*more) return more;
    imu_steps_.push_back(step);
    step_ = StepRecord{step.t_s, step.dx_m, step.dy_m, line};
    return true;
  }

  // The step file, or the walk bundled in the binary.
  StatusOr<StepReader> OpenSteps(const StepReaderOptions& reader_options) const {
    return options_.steps_path.empty()
               ? StepReader::OpenText(EmbeddedWalkName(), EmbeddedWalkSteps(), reader_options)
               : StepReader::Open(options_.steps_path, reader_options);
  }

  FootSlamRunOptions options_;
  std::string steps_name_;
  std::unique_ptr<StepReader> reader_;
  std::unique_ptr<ImuStepSource> imu_;  // instead of reader_ with an IMU recording
  std::vector<FootStep> imu_steps_;     // its steps so far
  int64_t records_ = 0;                 // input lines after the header
  int64_t steps_ = 0;                   // the steps Read() returns
  std::vector<HexCounts> prior_;
  TruthTrajectory truth_;  // empty without --truth
  std::string headline_;   // the score against the truth
  StepRecord step_;
  OdometryPath odometry_;
};

}  // namespace

Status FeedStep(const StepRecord& step, const std::string& input_name, double start_time_s,
                FootSlam* slam) {
  if (slam->steps() == 0) {
    Status s = slam->SetStartTime(start_time_s);
    if (!s.ok()) return Status(s.code(), fmt::format("{}: {}", input_name, s.message()));
  }
  Status s = slam->Step(step.t_s, step.dx_m, step.dy_m);
  if (!s.ok()) {
    return Status(s.code(), fmt::format("{}:{}: {}", input_name, step.line, s.message()));
  }
  return Status::Ok();
}

int RunFootSlamCommand(const FootSlamConfig& config, const FootSlamRunOptions& options) {
  if (Status s = config.Validate(); !s.ok()) return Fail(kExitUsage, s.message());
  if (!(options.max_step_m > 0) || !std::isfinite(options.max_step_m)) {
    return Fail(kExitUsage,
                fmt::format("--max-step = {}: must be > 0 and finite", options.max_step_m));
  }
  if (!options.imu_path.empty()) {
    if (Status s = options.imu_config.Validate(); !s.ok()) return Fail(kExitUsage, s.message());
  }
  if (!options.prior_map_path.empty() && !options.run.resume_path.empty()) {
    return Fail(kExitUsage,
                "--prior-map with --resume: the checkpoint holds the prior map its run started "
                "with; resume without --prior-map");
  }
  FootSlamJob job(config, options);
  if (Status s = job.Open(); !s.ok()) return Fail(kExitInput, s.message());
  return RunCommand(&job, options.run, ConfigToJson(FootSlamConfigFields(), config));
}

}  // namespace grove::tools
