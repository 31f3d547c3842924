#include "tools/io/imu_step_source.h"

#include <fmt/format.h>

#include <iterator>
#include <utility>

namespace grove::tools {

StatusOr<ImuStepSource> ImuStepSource::Open(const std::string& path, const FootImuConfig& config,
                                            const ImuReaderOptions& options) {
  StatusOr<std::unique_ptr<FootImu>> engine = FootImu::Create(config);
  if (!engine.ok()) return engine.status();
  StatusOr<ImuReader> reader = ImuReader::Open(path, options);
  if (!reader.ok()) return reader.status();
  return ImuStepSource(std::move(reader).value(), std::move(engine).value());
}

Status ImuStepSource::Fill() {
  ImuRecord record;
  while (ready_.empty() && !ended_) {
    StatusOr<bool> more = reader_.Next(&record);
    if (!more.ok()) return more.status();
    if (!*more) {
      ended_ = true;
      GROVE_RETURN_IF_ERROR(engine_->Finish());
    } else if (Status s = engine_->AddSample(record.sample); !s.ok()) {
      return Status(s.code(), fmt::format("{}: {}", reader_.Where(record), s.message()));
    }
    for (FootStep& step : engine_->TakeSteps()) {
      ready_.push_back(step);
      ready_lines_.push_back(record.line);
    }
  }
  return Status::Ok();
}

StatusOr<bool> ImuStepSource::Next(FootStep* step, int64_t* line) {
  if (!error_.ok()) return error_;
  if (Status s = Fill(); !s.ok()) {
    error_ = s;
    return s;
  }
  if (ready_.empty()) {
    if (steps_returned_ > 0) return false;
    const FootImuSummary s = engine_->Summary();
    error_ = InvalidArgumentError(
        s.aligned ? fmt::format("{}: no steps: {} stances in {} samples (a step is the walk from "
                                "one stance to the next; see detector_threshold)",
                                reader_.path(), s.stances, s.samples)
                  : fmt::format("{}: no steps: the foot was never still for alignment_s = {} s "
                                "at the start ({} samples, {} still)",
                                reader_.path(), engine_->config().alignment_s, s.samples,
                                s.still_samples));
    return error_;
  }
  *step = ready_.front();
  *line = ready_lines_.front();
  ready_.pop_front();
  ready_lines_.pop_front();
  ++steps_returned_;
  return true;
}

std::string FootStepsCsv(const std::vector<FootStep>& steps) {
  std::string out =
      "t,dx,dy,dz,dheading,var_dx,cov_dx_dy,var_dy,cov_dx_dheading,cov_dy_dheading,"
      "var_dheading\n";
  auto it = std::back_inserter(out);
  for (const FootStep& s : steps) {
    const Pose2Covariance& c = s.covariance;
    fmt::format_to(it, "{},{},{},{},{},{},{},{},{},{},{}\n", s.t_s, s.dx_m, s.dy_m, s.dz_m,
                   s.dheading_rad, c.xx, c.xy, c.yy, c.xh, c.yh, c.hh);
  }
  return out;
}

}  // namespace grove::tools
