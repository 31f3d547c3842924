#include "grove/footslam.h"

#include <fmt/format.h>
#include <oneapi/tbb/info.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <thread>
#include <unordered_map>

#include "concurrency/worker_pool.h"
#include "engine/checkpoint_io.h"
#include "engine/footslam/alphabet.h"
#include "engine/footslam/alphabet_htree_map.h"
#include "engine/footslam/footslam_model.h"
#include "engine/footslam/hex_grid.h"
#include "engine/footslam/htree_layout.h"
#include "engine/footslam/htree_map.h"
#include "engine/footslam/naive_map.h"
#include "engine/particle_filter.h"
#include "engine/persistent_trie.h"

namespace grove {

using footslam::Alphabet;
using footslam::AlphabetHTreeMap;
using footslam::FootSlamModel;
using footslam::Hex;
using footslam::HexGrid;
using footslam::Htc;
using footslam::HTreeLayout;
using footslam::HTreeMap;
using footslam::NaiveMap;
using footslam::StepInput;

namespace {

Status FieldError(const char* field, const std::string& value, const char* rule) {
  return InvalidArgumentError(fmt::format("{} = {}: {}", field, value, rule));
}

Status CheckSigma(const char* field, double v) {
  if (!std::isfinite(v) || v < 0) return FieldError(field, fmt::format("{}", v), "must be >= 0");
  return Status::Ok();
}

// Weights in fixed point (2^-52 units) make the cumulative map an exact integer sum, the same
// whichever nodes happen to be shared, so it is bit-identical at any thread count.
constexpr double kWeightScale = 4503599627370496.0;  // 2^52

// The configuration fields that change results or the checkpoint's layout, in a fixed order:
// a checkpoint stores them and resumes only under equal values. Threads and batch change
// neither and may differ.
struct ConfigField {
  const char* name;
  bool integer;
  uint64_t bits;  // the int64 value, or the double's bits
};

std::vector<ConfigField> CheckpointFields(const FootSlamConfig& c) {
  auto i = [](const char* name, int64_t v) {
    return ConfigField{name, true, static_cast<uint64_t>(v)};
  };
  auto d = [](const char* name, double v) {
    uint64_t bits;
    std::memcpy(&bits, &v, sizeof(bits));
    return ConfigField{name, false, bits};
  };
  return {i("particles", c.particles),
          i("seed", static_cast<int64_t>(c.seed)),
          d("hex_radius_m", c.hex_radius_m),
          d("prior_count", c.prior_count),
          i("weighting", static_cast<int64_t>(c.weighting)),
          d("start_x_m", c.start_x_m),
          d("start_y_m", c.start_y_m),
          d("start_heading_rad", c.start_heading_rad),
          d("initial_heading_sigma_rad", c.initial_heading_sigma_rad),
          d("heading_drift_sigma_rad", c.heading_drift_sigma_rad),
          d("heading_sigma_rad", c.heading_sigma_rad),
          d("scale_sigma", c.scale_sigma),
          d("scale_drift_sigma", c.scale_drift_sigma),
          d("step_length_sigma_m", c.step_length_sigma_m),
          d("position_sigma_m", c.position_sigma_m),
          i("resampling", static_cast<int64_t>(c.resampling)),
          d("resample_threshold", c.resample_threshold),
          i("map", static_cast<int64_t>(c.map)),
          i("degree", c.degree),
          i("grid_size", c.grid_size),
          i("alphabet", c.alphabet)};
}

std::string FieldValue(bool integer, uint64_t bits) {
  if (integer) return std::to_string(static_cast<int64_t>(bits));
  double v;
  std::memcpy(&v, &bits, sizeof(v));
  return fmt::format("{}", v);
}

// The block of fields as written, and its CRC-32: the configuration hash.
std::string FieldBlock(const std::vector<ConfigField>& fields) {
  ByteWriter w;
  w.Put<uint64_t>(fields.size());
  for (const ConfigField& f : fields) {
    w.PutString(f.name);
    w.Put<uint8_t>(f.integer ? 1 : 0);
    w.Put<uint64_t>(f.bits);
  }
  return w.Take();
}

uint32_t ConfigHash(const std::string& block) {
  return static_cast<uint32_t>(crc32(crc32(0L, Z_NULL, 0),
                                     reinterpret_cast<const Bytef*>(block.data()),
                                     static_cast<uInt>(block.size())));
}

constexpr char kCheckpointKind[] = "grove footslam";
constexpr uint32_t kEndMarker = 0x21444E45;  // "END!"

}  // namespace

Status FootSlamConfig::Validate() const {
  if (particles < 1 || particles > (int64_t{1} << 31)) {
    return FieldError("particles", std::to_string(particles), "must be in 1..2147483648");
  }
  if (!std::isfinite(hex_radius_m) || hex_radius_m <= 0) {
    return FieldError("hex_radius_m", fmt::format("{}", hex_radius_m), "must be > 0");
  }
  if (!std::isfinite(prior_count) || prior_count <= 0) {
    return FieldError("prior_count", fmt::format("{}", prior_count), "must be > 0");
  }
  for (auto [name, v] : {std::pair{"start_x_m", start_x_m}, std::pair{"start_y_m", start_y_m},
                         std::pair{"start_heading_rad", start_heading_rad}}) {
    if (!std::isfinite(v)) return FieldError(name, fmt::format("{}", v), "must be finite");
  }
  GROVE_RETURN_IF_ERROR(CheckSigma("initial_heading_sigma_rad", initial_heading_sigma_rad));
  GROVE_RETURN_IF_ERROR(CheckSigma("heading_drift_sigma_rad", heading_drift_sigma_rad));
  GROVE_RETURN_IF_ERROR(CheckSigma("heading_sigma_rad", heading_sigma_rad));
  GROVE_RETURN_IF_ERROR(CheckSigma("scale_sigma", scale_sigma));
  GROVE_RETURN_IF_ERROR(CheckSigma("scale_drift_sigma", scale_drift_sigma));
  GROVE_RETURN_IF_ERROR(CheckSigma("step_length_sigma_m", step_length_sigma_m));
  GROVE_RETURN_IF_ERROR(CheckSigma("position_sigma_m", position_sigma_m));
  if (!(resample_threshold > 0 && resample_threshold <= 1)) {
    return FieldError("resample_threshold", fmt::format("{}", resample_threshold),
                      "must be in (0, 1]");
  }
  auto layout = HTreeLayout::Create(grid_size, degree);
  if (!layout.ok()) return layout.status();
  if (alphabet < 0 || alphabet > 5) {
    return FieldError("alphabet", std::to_string(alphabet),
                      "must be in 0..5 (0 switches the alphabet off)");
  }
  if (threads < 0) return FieldError("threads", std::to_string(threads), "must be >= 0");
  if (batch < 1) return FieldError("batch", std::to_string(batch), "must be >= 1");
  return Status::Ok();
}

const char* FootSlamMapKindName(FootSlamMapKind kind) {
  return kind == FootSlamMapKind::kNaive ? "naive" : "htree";
}
bool ParseFootSlamMapKind(const std::string& name, FootSlamMapKind* kind) {
  if (name == "htree")
    *kind = FootSlamMapKind::kHTree;
  else if (name == "naive")
    *kind = FootSlamMapKind::kNaive;
  else
    return false;
  return true;
}
const char* FootSlamWeightingName(FootSlamWeighting w) {
  return w == FootSlamWeighting::kPaper ? "paper" : "prior_ratio";
}
bool ParseFootSlamWeighting(const std::string& name, FootSlamWeighting* w) {
  if (name == "paper")
    *w = FootSlamWeighting::kPaper;
  else if (name == "prior_ratio")
    *w = FootSlamWeighting::kPriorRatio;
  else
    return false;
  return true;
}

std::string FootSlamSummary::BriefReport() const {
  double total = advance_s + normalize_s + resample_s + release_s + bookkeeping_s;
  double rate = total > 0 ? static_cast<double>(particles) * steps / total : 0;
  return fmt::format(
      "FootSLAM: {} particles x {} steps on {} thread(s) in {:.2f} s ({:.2f} M particle-steps/s, "
      "{:.0f} ns per particle-step); {} resamplings, mean ESS {:.0f} ({:.1f} %); phases: advance "
      "{:.2f} s, normalise {:.2f} s, resample {:.2f} s, release {:.2f} s, bookkeeping {:.2f} s; "
      "map {} live nodes ({:.1f} MiB, peak {:.1f} MiB), trajectory {} live nodes ({:.1f} MiB).",
      particles, steps, threads_used, total, rate / 1e6, rate > 0 ? 1e9 / rate : 0.0, resamplings,
      mean_ess, particles > 0 ? 100.0 * mean_ess / particles : 0.0, advance_s, normalize_s,
      resample_s, release_s, bookkeeping_s, map_memory.live_nodes,
      map_memory.live_bytes / 1048576.0, map_memory.peak_live_bytes / 1048576.0,
      trajectory_memory.live_nodes, trajectory_memory.live_bytes / 1048576.0);
}

class FootSlam::Impl {
 public:
  virtual ~Impl() = default;
  virtual Status Step(double t_s, double dx_m, double dy_m) = 0;
  virtual Status SetStartTime(double t_s) = 0;
  virtual const FootSlamConfig& config() const = 0;
  virtual int64_t steps() const = 0;
  virtual Pose2 HeaviestPose() const = 0;
  virtual Pose2 MeanPose() const = 0;
  virtual std::vector<StampedPose> HeaviestTrajectory() const = 0;
  virtual const std::vector<StampedPose>& MeanTrajectory() const = 0;
  virtual std::vector<HexCounts> CumulativeMap() const = 0;
  virtual std::vector<HexCounts> HeaviestMap() const = 0;
  virtual FootSlamSummary Summary() const = 0;
  virtual StatusOr<std::string> Save(std::string_view user_data) const = 0;
  // Replaces the state of a freshly created engine with the checkpoint body read by `r`.
  virtual Status Load(ByteReader* r, std::string* user_data) = 0;
};

namespace {

// Reads the kind and the stored configuration fields of a checkpoint body and compares them
// with `config`: done before an engine is built for it.
Status CheckCheckpointConfig(ByteReader* r, const FootSlamConfig& config) {
  std::string kind;
  GROVE_RETURN_IF_ERROR(r->GetString("kind", &kind));
  if (kind != kCheckpointKind) {
    return r->Error("kind", QuoteForMessage(kind, 40) + " is not a FootSLAM checkpoint");
  }
  uint32_t hash = 0;
  uint64_t count = 0;
  GROVE_RETURN_IF_ERROR(r->Get("configuration hash", &hash));
  GROVE_RETURN_IF_ERROR(r->GetCount("configuration field count", 17, &count));
  std::vector<ConfigField> mine = CheckpointFields(config);
  if (count != mine.size()) {
    return r->Error("configuration field count",
                    std::to_string(count) + ", expected " + std::to_string(mine.size()));
  }
  for (const ConfigField& f : mine) {
    std::string name;
    uint8_t integer = 0;
    uint64_t bits = 0;
    GROVE_RETURN_IF_ERROR(r->GetString("configuration field name", &name));
    GROVE_RETURN_IF_ERROR(r->Get("configuration field type", &integer));
    GROVE_RETURN_IF_ERROR(r->Get("configuration field value", &bits));
    if (name != f.name || integer != (f.integer ? 1 : 0)) {
      return r->Error("configuration field name", QuoteForMessage(name, 40) + ", expected \"" + f.name + "\"");
    }
    if (bits != f.bits) {
      return FailedPreconditionError(fmt::format(
          "the checkpoint was made with {} = {}, this configuration has {} = {}: resume with "
          "the configuration of the interrupted run (only threads and batch may change)",
          f.name, FieldValue(f.integer, bits), f.name, FieldValue(f.integer, f.bits)));
    }
  }
  if (hash != ConfigHash(FieldBlock(mine))) {
    return r->Error("configuration hash", "does not match the fields");
  }
  return Status::Ok();
}

template <typename Map>
class Engine final : public FootSlam::Impl {
 public:
  Engine(const FootSlamConfig& config, int threads, HTreeLayout layout,
         std::unique_ptr<const Alphabet> alphabet)
      : config_(config),
        threads_(threads),
        workers_(threads),
        grid_(config.hex_radius_m),
        layout_(std::move(layout)),
        alphabet_(std::move(alphabet)),
        map_(layout_.height(), workers_.num_slots(), static_cast<size_t>(config.particles),
             alphabet_.get()),
        model_(config, &grid_, &layout_, &map_, workers_.num_slots()),
        filter_(&model_, &workers_, FilterOptionsOf(config)) {
    times_.push_back(0.0);
    mean_.push_back({0.0, Pose2{config.start_x_m, config.start_y_m, config.start_heading_rad}});
  }

  Status Step(double t_s, double dx_m, double dy_m) override {
    if (!std::isfinite(t_s) || !std::isfinite(dx_m) || !std::isfinite(dy_m)) {
      return InvalidArgumentError(
          fmt::format("step {}: t = {}, dx = {}, dy = {}: every value must be finite",
                      filter_.steps() + 1, t_s, dx_m, dy_m));
    }
    if (failed_) {
      return FailedPreconditionError(
          "the engine stopped at an earlier error and cannot be stepped again");
    }
    if (start_time_unset_) {
      times_.front() = t_s;
      mean_.front().t_s = t_s;
    } else if (!(t_s > times_.back())) {
      return InvalidArgumentError(
          fmt::format("step {}: t = {} is not after the previous time {}: times must be "
                      "strictly increasing",
                      filter_.steps() + 1, t_s, times_.back()));
    }
    start_time_unset_ = false;
    Status status = filter_.Step(StepInput{dx_m, dy_m});
    int64_t outside = model_.TakeFirstOutside();
    times_.push_back(t_s);
    if (outside >= 0) {
      failed_ = true;
      return OutOfRangeError(fmt::format(
          "step {} (t = {} s): particle {} at ({:.7g}, {:.7g}) m left the {} x {} hexagon grid "
          "centred on the start; raise grid_size",
          filter_.steps(), t_s, outside, model_.x(outside), model_.y(outside), layout_.grid_size(),
          layout_.grid_size()));
    }
    if (!status.ok()) {
      failed_ = true;
      return status;
    }
    auto t0 = std::chrono::steady_clock::now();
    mean_.push_back({t_s, ComputeMeanPose()});
    bookkeeping_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return Status::Ok();
  }

  Status SetStartTime(double t_s) override {
    if (!std::isfinite(t_s)) {
      return InvalidArgumentError(fmt::format("start time = {}: must be finite", t_s));
    }
    if (filter_.steps() > 0) {
      return FailedPreconditionError("the start time must be set before the first step");
    }
    start_time_unset_ = false;
    times_.front() = t_s;
    mean_.front().t_s = t_s;
    return Status::Ok();
  }
  const FootSlamConfig& config() const override { return config_; }
  int64_t steps() const override { return static_cast<int64_t>(filter_.steps()); }

  Pose2 HeaviestPose() const override {
    size_t i = filter_.heaviest();
    return Pose2{model_.x(i), model_.y(i), model_.heading(i)};
  }
  Pose2 MeanPose() const override { return mean_.back().pose; }

  std::vector<StampedPose> HeaviestTrajectory() const override {
    std::vector<StampedPose> out;
    for (const auto* n : footslam::PoseHistory::Path(model_.history(filter_.heaviest()))) {
      out.push_back({times_[n->step], Pose2{n->x_m, n->y_m, n->heading_rad}});
    }
    return out;
  }
  const std::vector<StampedPose>& MeanTrajectory() const override { return mean_; }

  std::vector<HexCounts> CumulativeMap() const override {
    std::vector<uint64_t> fixed(model_.size());
    auto lw = filter_.log_weights();
    for (size_t i = 0; i < fixed.size(); ++i) {
      fixed[i] = static_cast<uint64_t>(std::llround(std::exp(lw[i]) * kWeightScale));
    }
    std::unordered_map<uint64_t, std::array<unsigned __int128, 6>> sums;
    map_.Cumulative(fixed, [&](uint64_t key, const Htc& h, uint64_t w) {
      auto& s = sums[key];
      for (int e = 0; e < 6; ++e) s[e] += static_cast<unsigned __int128>(h.c[e]) * w;
    });
    std::vector<uint64_t> keys;
    keys.reserve(sums.size());
    for (const auto& kv : sums) keys.push_back(kv.first);
    std::sort(keys.begin(), keys.end());
    std::vector<HexCounts> out;
    out.reserve(keys.size());
    for (uint64_t key : keys) {
      HexCounts hc = HexOf(key);
      for (int e = 0; e < 6; ++e) hc.counts[e] = static_cast<double>(sums[key][e]) / kWeightScale;
      out.push_back(hc);
    }
    return out;
  }

  std::vector<HexCounts> HeaviestMap() const override {
    std::vector<HexCounts> out;
    map_.ForEachHex(filter_.heaviest(), [&](uint64_t key, const Htc& h) {
      HexCounts hc = HexOf(key);
      for (int e = 0; e < 6; ++e) hc.counts[e] = h.c[e];
      out.push_back(hc);
    });
    return out;
  }

  FootSlamSummary Summary() const override {
    FootSlamSummary s;
    s.particles = config_.particles;
    s.threads_requested = config_.threads;
    // oneTBB never runs more threads than the process may use, whatever the arena asks for.
    s.threads_used = std::min(threads_, tbb::info::default_concurrency());
    s.steps = steps();
    s.resamplings = static_cast<int64_t>(filter_.resamplings());
    s.mean_ess = filter_.mean_ess();
    const PhaseTimes& t = filter_.phase_times();
    s.advance_s = t.advance_s;
    s.normalize_s = t.normalize_s;
    s.resample_s = t.resample_s;
    s.release_s = t.release_s;
    s.bookkeeping_s = bookkeeping_s_;
    auto lw = filter_.log_weights();
    double w_sum = 0, scale_sum = 0, heading_sum = 0;
    for (size_t i = 0; i < model_.size(); ++i) {
      double w = std::exp(lw[i]);
      w_sum += w;
      scale_sum += w * model_.scale(i);
      heading_sum += w * model_.heading_error(i);
    }
    s.mean_scale = scale_sum / w_sum;
    s.mean_heading_error_rad = heading_sum / w_sum;
    s.map_memory = map_.memory();
    footslam::AddPoolStats(model_.history().stats(), &s.trajectory_memory);
    return s;
  }

  StatusOr<std::string> Save(std::string_view user_data) const override {
    if (failed_) {
      return FailedPreconditionError("the engine stopped at an error: there is no state to save");
    }
    ByteWriter w;
    w.PutString(kCheckpointKind);
    std::string fields = FieldBlock(CheckpointFields(config_));
    w.Put<uint32_t>(ConfigHash(fields));
    w.PutBytes(fields.data(), fields.size());
    w.PutString(user_data);
    w.Put<uint64_t>(times_.size());
    w.PutBytes(times_.data(), times_.size() * sizeof(double));
    w.Put<uint64_t>(mean_.size());
    for (const StampedPose& p : mean_) {
      w.Put(p.t_s);
      w.Put(p.pose.x_m);
      w.Put(p.pose.y_m);
      w.Put(p.pose.heading_rad);
    }
    w.Put<double>(bookkeeping_s_);
    w.Put<uint8_t>(start_time_unset_ ? 1 : 0);
    filter_.Save(&w);
    model_.Save(&w);
    map_.Save(&w);
    w.Put<uint32_t>(kEndMarker);
    return w.Take();
  }

  Status Load(ByteReader* r, std::string* user_data) override {
    std::string user;
    GROVE_RETURN_IF_ERROR(r->GetString("user data", &user));
    uint64_t count = 0;
    GROVE_RETURN_IF_ERROR(r->GetCount("time count", sizeof(double), &count));
    std::vector<double> times(count);
    GROVE_RETURN_IF_ERROR(r->GetBytes("times", times.data(), count * sizeof(double)));
    GROVE_RETURN_IF_ERROR(r->GetCount("mean pose count", 4 * sizeof(double), &count));
    std::vector<StampedPose> mean(count);
    for (StampedPose& p : mean) {
      double v[4];
      GROVE_RETURN_IF_ERROR(r->GetBytes("mean pose", v, sizeof(v)));
      p = {v[0], Pose2{v[1], v[2], v[3]}};
    }
    double bookkeeping_s = 0;
    uint8_t unset = 0;
    GROVE_RETURN_IF_ERROR(r->Get("bookkeeping time", &bookkeeping_s));
    GROVE_RETURN_IF_ERROR(r->Get("start time unset", &unset));
    if (!(bookkeeping_s >= 0 && bookkeeping_s < 1e12)) {
      return r->Error("bookkeeping time", "not a duration");
    }
    GROVE_RETURN_IF_ERROR(filter_.Load(r));
    const uint64_t steps = filter_.steps();
    if (times.size() != steps + 1 || mean.size() != steps + 1) {
      return r->Error("times", "not one per pose (" + std::to_string(steps + 1) + ")");
    }
    for (size_t k = 0; k < times.size(); ++k) {
      bool ordered = k == 0 || (k == 1 ? times[1] >= times[0] : times[k] > times[k - 1]);
      if (!std::isfinite(times[k]) || !ordered || mean[k].t_s != times[k]) {
        return r->Error("times", "not finite and increasing");
      }
      const Pose2& p = mean[k].pose;
      if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !std::isfinite(p.heading_rad)) {
        return r->Error("mean pose", "not finite");
      }
    }
    if (unset > 1 || (unset == 1 && steps > 0)) return r->Error("start time unset", "invalid");
    GROVE_RETURN_IF_ERROR(model_.Load(r, steps));
    GROVE_RETURN_IF_ERROR(map_.Load(r, layout_.key_count()));
    uint32_t end = 0;
    GROVE_RETURN_IF_ERROR(r->Get("end marker", &end));
    if (end != kEndMarker || !r->at_end()) {
      return r->Error("end marker", "missing, or bytes follow it");
    }
    times_.swap(times);
    mean_.swap(mean);
    bookkeeping_s_ = bookkeeping_s;
    start_time_unset_ = unset == 1;
    if (user_data != nullptr) user_data->swap(user);
    return Status::Ok();
  }

 private:
  static FilterOptions FilterOptionsOf(const FootSlamConfig& c) {
    FilterOptions o;
    o.resampling = c.resampling;
    o.resample_threshold = c.resample_threshold;
    o.batch = static_cast<size_t>(c.batch);
    o.seed = c.seed;
    return o;
  }

  HexCounts HexOf(uint64_t key) const {
    Hex h = model_.HexOfKey(key);
    HexCounts hc;
    hc.q = h.q;
    hc.r = h.r;
    grid_.Center(h, &hc.x_m, &hc.y_m);
    return hc;
  }

  // Weighted mean pose over fixed blocks (circular mean for the heading).
  Pose2 ComputeMeanPose() {
    auto lw = filter_.log_weights();
    struct Sum {
      double w = 0, x = 0, y = 0, c = 0, s = 0;
    };
    std::vector<Sum> sums =
        workers_.MapBlocks<Sum>(model_.size(), kSumBlock, [&](size_t, size_t b, size_t e) {
          Sum s;
          double w = 0;
          for (size_t i = b; i < e; ++i) {
            // After resampling every weight is the same: one exp, not one per particle.
            if (i == b || lw[i] != lw[i - 1]) w = std::exp(lw[i]);
            s.w += w;
            s.x += w * model_.x(i);
            s.y += w * model_.y(i);
            s.c += w * model_.cos_heading(i);
            s.s += w * model_.sin_heading(i);
          }
          return s;
        });
    Sum total;
    for (const Sum& s : sums) {
      total.w += s.w;
      total.x += s.x;
      total.y += s.y;
      total.c += s.c;
      total.s += s.s;
    }
    return Pose2{total.x / total.w, total.y / total.w, std::atan2(total.s, total.c)};
  }

  FootSlamConfig config_;
  int threads_;
  WorkerPool workers_;
  HexGrid grid_;
  HTreeLayout layout_;
  std::unique_ptr<const Alphabet> alphabet_;  // null unless the map uses the alphabet
  Map map_;
  FootSlamModel<Map> model_;
  ParticleFilter<FootSlamModel<Map>> filter_;
  std::vector<double> times_;  // times_[k]: time of the pose after step k (k = 0: the start)
  std::vector<StampedPose> mean_;
  double bookkeeping_s_ = 0;
  bool start_time_unset_ = true;
  bool failed_ = false;
};

template <int kLog2Degree>
std::unique_ptr<FootSlam::Impl> MakeHTreeEngine(const FootSlamConfig& config, int threads,
                                                HTreeLayout layout) {
  if (config.alphabet > 0) {
    auto alphabet = std::make_unique<const Alphabet>(*Alphabet::Create(config.alphabet));
    return std::make_unique<Engine<AlphabetHTreeMap<kLog2Degree>>>(
        config, threads, std::move(layout), std::move(alphabet));
  }
  return std::make_unique<Engine<HTreeMap<kLog2Degree>>>(config, threads, std::move(layout),
                                                         nullptr);
}

// Bytes one particle's own copy of a path costs: the inner nodes above the bottom one plus the
// bottom node, for a trie of this degree and leaf.
template <int kLog2Degree, typename Leaf>
int64_t PathBytes(int height) {
  using Trie = PersistentTrie<Leaf, kLog2Degree>;
  return (height - 1) * static_cast<int64_t>(Trie::kInnerNodeBytes) +
         static_cast<int64_t>(Trie::kBottomNodeBytes);
}

template <int kLog2Degree>
int64_t PathBytesFor(const FootSlamConfig& config, int height) {
  return config.alphabet > 0 ? PathBytes<kLog2Degree, uint16_t>(height)
                             : PathBytes<kLog2Degree, Htc>(height);
}

}  // namespace

int64_t FootSlam::EstimatePeakBytes(const FootSlamConfig& config, int64_t steps) {
  const int64_t n = config.particles;
  const int64_t fixed = int64_t{64} << 20;
  // Pose (and its heading's cosine and sine), errors, hexagon, weights, parents and the
  // gather's temporaries.
  const int64_t state = 176;
  // Live poses stay near steps + C N log N (tests/stress/footslam_long_run_test.cc): with the
  // 32-byte nodes of two generations, about 3 nodes per particle at 30,000 to 1,000,000.
  const int64_t history = 3 * 32;
  int64_t map;
  if (config.map == FootSlamMapKind::kNaive) {
    const int64_t grid = int64_t{config.grid_size} * config.grid_size;
    const int64_t hexes = std::min(grid, steps + steps / 5 + 16);
    // 32-byte slots at most half full, two generations alive while resampling.
    map = hexes * 32 * 2 * 2;
  } else {
    StatusOr<HTreeLayout> layout = HTreeLayout::Create(config.grid_size, config.degree);
    const int height = layout.ok() ? layout->height() : 1;
    int64_t path = 0;
    switch (config.degree) {
      case 4:
        path = PathBytesFor<2>(config, height);
        break;
      case 16:
        path = PathBytesFor<4>(config, height);
        break;
      case 64:
        path = PathBytesFor<6>(config, height);
        break;
      default:
        path = PathBytesFor<8>(config, height);
        break;
    }
    // Every particle owns the path it updated last, in two generations while resampling.
    map = 2 * path;
  }
  return fixed + n * (state + history + map);
}

FootSlam::FootSlam(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
FootSlam::~FootSlam() = default;

StatusOr<std::unique_ptr<FootSlam>> FootSlam::Create(const FootSlamConfig& config) {
  GROVE_RETURN_IF_ERROR(config.Validate());
  int threads = config.threads > 0
                    ? config.threads
                    : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  StatusOr<HTreeLayout> layout = HTreeLayout::Create(config.grid_size, config.degree);
  if (!layout.ok()) return layout.status();
  std::unique_ptr<Impl> impl;
  if (config.map == FootSlamMapKind::kNaive) {
    impl = std::make_unique<Engine<NaiveMap>>(config, threads, std::move(*layout), nullptr);
  } else {
    switch (config.degree) {
      case 4:
        impl = MakeHTreeEngine<2>(config, threads, std::move(*layout));
        break;
      case 16:
        impl = MakeHTreeEngine<4>(config, threads, std::move(*layout));
        break;
      case 64:
        impl = MakeHTreeEngine<6>(config, threads, std::move(*layout));
        break;
      default:
        impl = MakeHTreeEngine<8>(config, threads, std::move(*layout));
        break;
    }
  }
  return std::unique_ptr<FootSlam>(new FootSlam(std::move(impl)));
}

Status FootSlam::Step(double t_s, double dx_m, double dy_m) { return impl_->Step(t_s, dx_m, dy_m); }
Status FootSlam::SetStartTime(double t_s) { return impl_->SetStartTime(t_s); }
const FootSlamConfig& FootSlam::config() const { return impl_->config(); }
int64_t FootSlam::steps() const { return impl_->steps(); }
Pose2 FootSlam::HeaviestPose() const { return impl_->HeaviestPose(); }
Pose2 FootSlam::MeanPose() const { return impl_->MeanPose(); }
std::vector<StampedPose> FootSlam::HeaviestTrajectory() const {
  return impl_->HeaviestTrajectory();
}
const std::vector<StampedPose>& FootSlam::MeanTrajectory() const { return impl_->MeanTrajectory(); }
std::vector<HexCounts> FootSlam::CumulativeMap() const { return impl_->CumulativeMap(); }
std::vector<HexCounts> FootSlam::HeaviestMap() const { return impl_->HeaviestMap(); }
FootSlamSummary FootSlam::Summary() const { return impl_->Summary(); }

StatusOr<std::string> FootSlam::Checkpoint(std::string_view user_data) const {
  StatusOr<std::string> body = impl_->Save(user_data);
  if (!body.ok()) return body.status();
  return SealCheckpoint(*body);
}

StatusOr<std::unique_ptr<FootSlam>> FootSlam::Resume(const FootSlamConfig& config,
                                                     std::string_view checkpoint,
                                                     const std::string& name,
                                                     std::string* user_data) {
  GROVE_RETURN_IF_ERROR(config.Validate());
  StatusOr<std::string_view> body = UnsealCheckpoint(checkpoint, name);
  if (!body.ok()) return body.status();
  ByteReader reader(*body, name);
  // The configuration first: a checkpoint of another run costs no engine.
  Status s = CheckCheckpointConfig(&reader, config);
  if (s.code() == StatusCode::kFailedPrecondition) {
    return FailedPreconditionError(name + ": " + s.message());
  }
  GROVE_RETURN_IF_ERROR(s);
  StatusOr<std::unique_ptr<FootSlam>> slam = Create(config);
  if (!slam.ok()) return slam.status();
  GROVE_RETURN_IF_ERROR((*slam)->impl_->Load(&reader, user_data));  // DataLoss only
  return slam;
}

}  // namespace grove
