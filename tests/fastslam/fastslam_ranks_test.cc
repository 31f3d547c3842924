// The landmark FastSLAM facade across ranks (threads of this process, joined by
// InProcessCollective): every read-out of a filter split over 2 and 3 ranks is, on every rank,
// bit for bit what one process gives, for every filter of the seed's family under known and
// unknown association, and so is a run resumed from each rank's checkpoint.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "engine/ranks/collective.h"
#include "grove/fastslam.h"
#include "tests/api/ranks_testing.h"
#include "tools/sim/fastslam_simulator.h"

namespace grove {
namespace {

using testing::OnRanks;
using testing::SameBits;
using tools::BaileySimulation;

// A short drive of the webmap with the paper's noise: enough scans for several resamplings.
const BaileySimulation& Simulation() {
  static const BaileySimulation sim = [] {
    StatusOr<tools::BaileyMap> map = tools::ParseBaileyMap("webmap", tools::EmbeddedBaileyWebmap());
    EXPECT_TRUE(map.ok());
    tools::BaileySimOptions o = tools::WebmapPreset();
    o.loops = 1;
    StatusOr<BaileySimulation> s = tools::SimulateBailey(*map, o);
    EXPECT_TRUE(s.ok());
    return std::move(s).value();
  }();
  return sim;
}
constexpr size_t kControls = 120;

// Every read-out as numbers, and the summary's counts.
struct ReadOuts {
  Status status;
  std::vector<double> values;
  int64_t resamplings = 0, landmarks = 0, trials = 0, accepted = 0;
};

ReadOuts ReadAll(const FastSlam& slam) {
  ReadOuts r;
  std::vector<double>& v = r.values;
  for (const StampedPose& p : slam.MeanTrajectory()) {
    v.insert(v.end(), {p.t_s, p.pose.x_m, p.pose.y_m, p.pose.heading_rad});
  }
  const Pose2 h = slam.HeaviestPose();
  const Pose2Covariance c = slam.PoseCovariance();
  v.insert(v.end(), {h.x_m, h.y_m, h.heading_rad, c.xx, c.xy, c.xh, c.yy, c.yh, c.hh});
  StatusOr<std::vector<StampedPose>> path = slam.HeaviestTrajectory();
  StatusOr<std::vector<LandmarkEstimate>> landmarks = slam.HeaviestLandmarks();
  if (!path.ok() || !landmarks.ok()) {
    r.status = path.ok() ? landmarks.status() : path.status();
    return r;
  }
  for (const StampedPose& p : *path) {
    v.insert(v.end(), {p.t_s, p.pose.x_m, p.pose.y_m, p.pose.heading_rad});
  }
  for (const LandmarkEstimate& l : *landmarks) {
    v.insert(v.end(), {static_cast<double>(l.id), l.x_m, l.y_m, l.sxx, l.sxy, l.syy,
                       static_cast<double>(l.source_id)});
  }
  const FastSlamSummary s = slam.Summary();
  const AssociationCounts& a = s.association;
  for (int64_t n : {a.associated, a.created, a.ignored, a.removed, a.dropped, a.tagged, a.wrong}) {
    v.push_back(static_cast<double>(n));
  }
  v.push_back(s.mean_ess);
  r.resamplings = s.resamplings;
  r.landmarks = s.landmarks;
  r.trials = s.evolution.trials;
  r.accepted = s.evolution.accepted;
  return r;
}

ReadOuts Drive(const FastSlamConfig& config, Collective* ranks, size_t from = 0,
               std::unique_ptr<FastSlam> slam = nullptr) {
  ReadOuts r;
  if (slam == nullptr) {
    StatusOr<std::unique_ptr<FastSlam>> made = FastSlam::Create(config, ranks);
    if (!made.ok()) {
      r.status = made.status();
      return r;
    }
    slam = std::move(made).value();
  }
  BaileySimulation rest = Simulation();
  rest.controls.erase(rest.controls.begin(), rest.controls.begin() + static_cast<ptrdiff_t>(from));
  r.status = tools::FeedSimulation(rest, slam.get(), kControls - from);
  if (!r.status.ok()) return r;
  return ReadAll(*slam);
}

std::vector<ReadOuts> RunRanks(const FastSlamConfig& config, int ranks) {
  std::vector<ReadOuts> out(static_cast<size_t>(ranks));
  OnRanks(ranks, [&](int r, Collective* c) { out[static_cast<size_t>(r)] = Drive(config, c); });
  return out;
}

void ExpectSame(const ReadOuts& a, const ReadOuts& b, const std::string& what) {
  ASSERT_TRUE(a.status.ok()) << what << ": " << a.status.ToString();
  ASSERT_TRUE(b.status.ok()) << what << ": " << b.status.ToString();
  EXPECT_EQ(a.resamplings, b.resamplings) << what;
  EXPECT_EQ(a.landmarks, b.landmarks) << what;
  EXPECT_EQ(a.trials, b.trials) << what;
  EXPECT_EQ(a.accepted, b.accepted) << what;
  ASSERT_EQ(a.values.size(), b.values.size()) << what;
  size_t k = 0;
  while (k < a.values.size() && SameBits(a.values[k], b.values[k])) ++k;
  EXPECT_EQ(k, a.values.size()) << what << ": first difference at value " << k << " of "
                                << a.values.size();
}

FastSlamConfig ConfigOf(FastSlamFilter filter, FastSlamAssociation association, int64_t particles) {
  FastSlamConfig c;
  c.filter = filter;
  c.association = association;
  c.particles = particles;
  c.threads = 1;
  c.batch = 512;
  c.resample_threshold = 1;  // resample at every scan: particles move every time
  return c;
}

using FilterAndAssociation = std::tuple<FastSlamFilter, FastSlamAssociation>;
std::string ParamName(const FilterAndAssociation& p) {
  const char* names[] = {"_known", "_ml", "_ml_exclusive", "_sampled", "_jcbb"};
  return std::string(FastSlamFilterName(std::get<0>(p))) + names[static_cast<int>(std::get<1>(p))];
}
class AcrossRanks : public ::testing::TestWithParam<FilterAndAssociation> {};
INSTANTIATE_TEST_SUITE_P(
    Filters, AcrossRanks,
    ::testing::Combine(::testing::Values(FastSlamFilter::kFastSlam1, FastSlamFilter::kFastSlam2,
                                         FastSlamFilter::kUnscented, FastSlamFilter::kSrcd,
                                         FastSlamFilter::kSrcdAided, FastSlamFilter::kSrcdParticle,
                                         FastSlamFilter::kDeSrcd),
                       ::testing::Values(FastSlamAssociation::kKnown,
                                         FastSlamAssociation::kMaximumLikelihood,
                                         FastSlamAssociation::kSampled,
                                         FastSlamAssociation::kJointCompatibility)),
    [](const auto& info) { return ParamName(info.param); });

// 4,100 particles on 2 ranks: the second holds 4, so every resampling moves particles.
TEST_P(AcrossRanks, TwoRanksGiveOneProcessesBits) {
  const auto [filter, association] = GetParam();
  const FastSlamConfig config = ConfigOf(filter, association, 4100);
  const ReadOuts one = Drive(config, nullptr);
  ASSERT_TRUE(one.status.ok()) << one.status.ToString();
  EXPECT_GT(one.resamplings, 2);
  EXPECT_GT(one.landmarks, 0);
  const std::vector<ReadOuts> two = RunRanks(config, 2);
  for (size_t r = 0; r < two.size(); ++r) ExpectSame(one, two[r], "rank " + std::to_string(r));
}

// 3 ranks (two blocks and 8 particles), and each rank's checkpoint resumed.
TEST(FastSlamAcrossRanks, ThreeRanksAndTheirCheckpoints) {
  for (FastSlamFilter filter : {FastSlamFilter::kFastSlam2, FastSlamFilter::kDeSrcd}) {
    const FastSlamConfig config = ConfigOf(filter, FastSlamAssociation::kMaximumLikelihood, 8200);
    const std::string name = FastSlamFilterName(filter);
    const ReadOuts one = Drive(config, nullptr);
    const std::vector<ReadOuts> three = RunRanks(config, 3);
    for (size_t r = 0; r < three.size(); ++r) {
      ExpectSame(one, three[r], name + " rank " + std::to_string(r));
    }
    // Checkpoints after 60 controls, resumed on as many ranks.
    constexpr size_t kCut = 60;
    std::vector<std::string> files(3);
    OnRanks(3, [&](int r, Collective* c) {
      StatusOr<std::unique_ptr<FastSlam>> slam = FastSlam::Create(config, c);
      ASSERT_TRUE(slam.ok());
      ASSERT_TRUE(tools::FeedSimulation(Simulation(), slam->get(), kCut).ok());
      StatusOr<std::string> bytes = (*slam)->Checkpoint("user");
      ASSERT_TRUE(bytes.ok()) << bytes.status().ToString();
      files[static_cast<size_t>(r)] = *bytes;
    });
    std::vector<ReadOuts> resumed(3);
    OnRanks(3, [&](int r, Collective* c) {
      std::string user;
      StatusOr<std::unique_ptr<FastSlam>> slam =
          FastSlam::Resume(config, files[static_cast<size_t>(r)], "c.ckpt", &user, c);
      if (!slam.ok()) {
        resumed[static_cast<size_t>(r)].status = slam.status();
        return;
      }
      EXPECT_EQ(user, "user");
      resumed[static_cast<size_t>(r)] = Drive(config, c, kCut, std::move(slam).value());
    });
    for (size_t r = 0; r < resumed.size(); ++r) {
      ExpectSame(one, resumed[r], name + " resumed, rank " + std::to_string(r));
    }
    // Swapped files are refused on every rank, naming the rank.
    std::swap(files[0], files[1]);
    std::vector<Status> refused(3);
    OnRanks(3, [&](int r, Collective* c) {
      refused[static_cast<size_t>(r)] =
          FastSlam::Resume(config, files[static_cast<size_t>(r)], "c.ckpt", nullptr, c).status();
    });
    for (const Status& s : refused) {
      EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition) << s.ToString();
      EXPECT_NE(s.message().find("rank 1 of 3"), std::string::npos) << s.ToString();
    }
  }
}

TEST(FastSlamAcrossRanks, EveryRankNeedsABlock) {
  const FastSlamConfig config =
      ConfigOf(FastSlamFilter::kFastSlam2, FastSlamAssociation::kKnown, 4096);
  std::vector<Status> got(2);
  OnRanks(2, [&](int r, Collective* c) {
    got[static_cast<size_t>(r)] = FastSlam::Create(config, c).status();
  });
  for (const Status& s : got) {
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(s.message().find("particles = 4096"), std::string::npos) << s.ToString();
  }
}

}  // namespace
}  // namespace grove
