// The FootSLAM facade: FootSlam's public methods. Create() and Resume() build the engine of the
// configured map kind (FootSlamEngine), the others forward to it; EstimatePeakBytes() predicts
// a run's memory.
#include "grove/footslam.h"

#include <algorithm>
#include <memory>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "engine/filter/filter_driver.h"
#include "engine/filter/resampler.h"
#include "engine/footslam/alphabet_htree_map.h"
#include "engine/footslam/footslam_engine.h"
#include "engine/footslam/footslam_model.h"
#include "engine/footslam/htree_layout.h"
#include "engine/footslam/htree_map.h"
#include "engine/io/checkpoint_io.h"
#include "engine/ranks/collective.h"

namespace grove {

using footslam::HTreeLayout;
using footslam::kFootSlamFormatVersion;
using footslam::MakeFootSlamEngine;

namespace {

// Bytes one particle's own copy of a path costs: the inner nodes above the bottom one plus the
// bottom node, for a trie `height` levels high. A packed bottom node is counted at the size of
// one holding a narrow node's digits (16 symbols at s = 16: 128 bytes; at the end of the paper's
// walk, 30,000 particles, 65 % of the live symbol bottom nodes were of 64 bytes and 35 % of 128).
template <typename Trie>
int64_t PathBytes(int height) {
  return (height - 1) * static_cast<int64_t>(Trie::kInnerNodeBytes) +
         static_cast<int64_t>(Trie::BottomBytesFor(Trie::kDegree));
}

template <int kLog2Degree>
int64_t PathBytesFor(const FootSlamConfig& config, int height) {
  using Alphabet = footslam::AlphabetHTreeMap<kLog2Degree>;
  return config.alphabet > 0
             ? PathBytes<typename Alphabet::SymbolTrie>(Alphabet::SymbolHeight(height))
             : PathBytes<typename footslam::HTreeMap<kLog2Degree>::Trie>(height);
}

}  // namespace

int64_t FootSlam::EstimatePeakBytes(const FootSlamConfig& config, int64_t steps) {
  const int64_t n = config.particles;
  // Calibrated on `grove footslam run` over the paper walk (13 minutes; s = 16, T = 5; 2
  // threads; bench/results/amd-epyc-2c/paper_targets/memory_prediction.md): at 30,000,
  // 300,000 and 1,000,000 particles the pools reserved 1,398, 909 and 826 bytes of map and
  // 1,258, 783 and 797 bytes of path history per particle; the rest of the peak RSS was 30 MiB
  // at 30,000 particles and about 18 MiB plus 410 to 417 bytes per particle at the others.
  const int64_t fixed = int64_t{48} << 20;
  // Pose (and its heading's cosine and sine), errors, hexagon and key, each with the gather's
  // spare buffer; the versions of the maps and paths, the weights and parents; the allocator's
  // slack on all of them.
  const int64_t state = 448;
  // Live poses: the walk's common ancestry (one node a step, below) plus the branches since the
  // particles' paths last met, which peaked at 18.6 to 33.3 nodes per particle on the bundled
  // and paper walks at 30,000 to 1,000,000 particles.
  const int64_t pose_node = (sizeof(footslam::PoseHistory::Node) + 15) / 16 * 16;
  const int64_t history = 32 * pose_node;
  // What grows with the walk whatever the particles: the time and mean pose of every step
  // (40 bytes), the common ancestry of the paths (one pose node a step) and the map nodes of
  // the area walked, shared by all particles (about 1.2 new hexagons a step, 64 bytes each
  // with the inner nodes above them).
  const int64_t per_step = 40 + pose_node + 77;
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
  return fixed + n * (state + history + map) + steps * per_step;
}

FootSlam::FootSlam(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
FootSlam::~FootSlam() = default;

Status FootSlam::CheckAcrossRanks(const FootSlamConfig& config, int ranks) {
  GROVE_RETURN_IF_ERROR(
      CheckIslands(static_cast<uint64_t>(config.particles), config.islands, ranks, kSumBlock));
  return CheckRankShares(static_cast<uint64_t>(config.particles), ranks, kSumBlock);
}

StatusOr<std::unique_ptr<FootSlam>> FootSlam::Create(const FootSlamConfig& config) {
  return Create(config, nullptr);
}

StatusOr<std::unique_ptr<FootSlam>> FootSlam::Create(const FootSlamConfig& config,
                                                     Collective* ranks) {
  GROVE_RETURN_IF_ERROR(config.Validate());
  if (ranks != nullptr && ranks->size() > 1) {
    GROVE_RETURN_IF_ERROR(CheckAcrossRanks(config, ranks->size()));
  } else {
    ranks = nullptr;
  }
  return NoThrow([&]() -> StatusOr<std::unique_ptr<FootSlam>> {
    int threads = config.threads > 0
                      ? config.threads
                      : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
    StatusOr<HTreeLayout> layout =
        HTreeLayout::Create(config.grid_size, config.degree, config.grid);
    if (!layout.ok()) return layout.status();
    std::unique_ptr<Impl> impl = MakeFootSlamEngine(config, threads, std::move(*layout), ranks);
    GROVE_RETURN_IF_ERROR(impl->Init());
    return std::unique_ptr<FootSlam>(new FootSlam(std::move(impl)));
  });
}

Status FootSlam::Step(double t_s, double dx_m, double dy_m) { return impl_->Step(t_s, dx_m, dy_m); }
Status FootSlam::SetStartTime(double t_s) { return impl_->SetStartTime(t_s); }
Status FootSlam::SetPriorMap(const std::vector<HexCounts>& map) {
  return NoThrow([&] { return impl_->SetPriorMap(map); });
}
const FootSlamConfig& FootSlam::config() const { return impl_->config(); }
int64_t FootSlam::steps() const { return impl_->steps(); }
Pose2 FootSlam::HeaviestPose() const { return impl_->HeaviestPose(); }
Pose2 FootSlam::MeanPose() const { return impl_->MeanPose(); }
StatusOr<std::vector<StampedPose>> FootSlam::HeaviestTrajectory() const {
  return NoThrow([&]() { return impl_->HeaviestTrajectory(); });
}

StatusOr<std::vector<StampedPose>> FootSlam::SmoothedTrajectory() const {
  return NoThrow([&]() { return impl_->SmoothedTrajectory(); });
}
const std::vector<StampedPose>& FootSlam::MeanTrajectory() const { return impl_->MeanTrajectory(); }
StatusOr<std::vector<HexCounts>> FootSlam::CumulativeMap() const {
  return NoThrow([&]() { return impl_->CumulativeMap(); });
}
StatusOr<std::vector<HexCounts>> FootSlam::HeaviestMap() const {
  return NoThrow([&]() { return impl_->HeaviestMap(); });
}
StatusOr<std::vector<HexCounts>> FootSlam::StoredMap() const {
  return NoThrow([&]() -> StatusOr<std::vector<HexCounts>> { return impl_->StoredMap(); });
}
FootSlamSummary FootSlam::Summary() const { return impl_->Summary(); }
Status FootSlam::CheckInvariants() const { return impl_->CheckInvariants(); }

StatusOr<std::string> FootSlam::Checkpoint(std::string_view user_data) const {
  return NoThrow([&]() -> StatusOr<std::string> {
    StatusOr<std::string> body = impl_->Save(user_data);
    if (!body.ok()) return body.status();
    return SealCheckpoint(*body, kFootSlamFormatVersion);
  });
}

StatusOr<std::unique_ptr<FootSlam>> FootSlam::Resume(const FootSlamConfig& config,
                                                     std::string_view checkpoint,
                                                     const std::string& name,
                                                     std::string* user_data) {
  return Resume(config, checkpoint, name, user_data, nullptr);
}

StatusOr<std::unique_ptr<FootSlam>> FootSlam::Resume(const FootSlamConfig& config,
                                                     std::string_view checkpoint,
                                                     const std::string& name,
                                                     std::string* user_data, Collective* ranks) {
  return ResumeOnRanks<FootSlam>(
      ranks, [&](Collective* r) { return ResumeShare(config, checkpoint, name, user_data, r); });
}

StatusOr<std::unique_ptr<FootSlam>> FootSlam::ResumeShare(const FootSlamConfig& config,
                                                          std::string_view checkpoint,
                                                          const std::string& name,
                                                          std::string* user_data,
                                                          Collective* ranks) {
  GROVE_RETURN_IF_ERROR(config.Validate());
  return NoThrow([&]() -> StatusOr<std::unique_ptr<FootSlam>> {
    StatusOr<UnsealedCheckpoint> file = UnsealCheckpoint(checkpoint, name);
    if (!file.ok()) return file.status();
    ByteReader reader(file->body, name);
    // The kind, format and configuration first: a checkpoint of another run costs no engine.
    std::string user;
    GROVE_RETURN_IF_ERROR(ReadCheckpointHead(
        &reader, footslam::kCheckpointKind, "FootSLAM", file->format_version,
        kFootSlamFormatVersion, CheckpointFieldsOf(FootSlamConfigFields(), config), &user));
    StatusOr<std::unique_ptr<FootSlam>> slam = Create(config, ranks);
    if (!slam.ok()) return slam.status();
    GROVE_RETURN_IF_ERROR((*slam)->impl_->Load(&reader));
    if (user_data != nullptr) user_data->swap(user);
    return slam;
  });
}

}  // namespace grove
