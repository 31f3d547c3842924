// Unknown data association: spatial keys, the trie's range query and removal, the gates'
// decisions, the candidate search against a scan of the whole map, and existence evidence.
#include "engine/fastslam/data_association.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <vector>

#include "engine/fastslam/spatial_key.h"
#include "engine/persistent/persistent_trie.h"
#include "grove/fastslam.h"

namespace grove::fastslam {
namespace {

constexpr double kPi = std::numbers::pi;
using Trie = PersistentTrie<Landmark, 3>;

TEST(SpatialKey, RoundTripsCellsAndSlots) {
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int64_t> coord(-kMaxCell, kMaxCell);
  for (int k = 0; k < 20000; ++k) {
    const Cell c{k < 100 ? k - 50 : coord(rng), k < 100 ? 50 - k : coord(rng)};
    const int slot = k % kSlotsPerCell;
    const uint64_t key = SpatialKey(c, slot);
    ASSERT_LT(key, uint64_t{1} << 63);
    EXPECT_EQ(CellOfKey(key), c);
    EXPECT_EQ(SlotOfKey(key), slot);
  }
  // Cells near the origin have small keys: a map near its start stays low.
  EXPECT_LT(SpatialKey(Cell{-8, 7}, 7), uint64_t{1} << 11);
  Cell c;
  EXPECT_TRUE(CellOf(-0.1, 9.99, 5, &c));
  EXPECT_EQ(c, (Cell{-1, 1}));
  EXPECT_FALSE(CellOf(NAN, 0, 5, &c));
  EXPECT_FALSE(CellOf(1e300, 0, 5, &c));
}

// KeyRangeMayHit against every key of small aligned blocks: true exactly when a key of the
// block has its cell in the rectangle.
TEST(SpatialKey, BlockTestIsExact) {
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int64_t> corner(-40, 40), side(0, 12);
  for (int trial = 0; trial < 3000; ++trial) {
    const int bits = 3 * static_cast<int>(rng() % 5);  // 1 .. 4096 keys, as a degree-8 trie
    const uint64_t lo = (rng() % (uint64_t{1} << 16)) << bits;
    const uint64_t hi = lo + (uint64_t{1} << bits) - 1;
    const int64_t x0 = corner(rng), y0 = corner(rng);
    const CellRect rect{x0, x0 + side(rng), y0, y0 + side(rng)};
    bool any = false;
    for (uint64_t key = lo; key <= hi && !any; ++key) any = rect.Contains(CellOfKey(key));
    ASSERT_EQ(KeyRangeMayHit(lo, hi, rect), any) << "block " << lo << ".." << hi;
  }
  // The whole key space hits every rectangle.
  EXPECT_TRUE(KeyRangeMayHit(0, ~uint64_t{0}, CellRect{-3, -3, 5, 5}));
}

// ViewBoxOf holds every point InView() admits, and no more than the view needs: a half view
// facing +x is a box R deep and 2R wide, a quarter view facing the diagonal an R square.
TEST(ViewBox, HoldsTheViewAndNoMore) {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int trial = 0; trial < 2000; ++trial) {
    const double x = 200 * unit(rng) - 100, y = 200 * unit(rng) - 100;
    const double heading = 2 * M_PI * unit(rng) - M_PI, fov = 2 * M_PI * (0.01 + 0.99 * unit(rng));
    const double range = 1 + 50 * unit(rng);
    const double hc = std::cos(heading), hs = std::sin(heading), ch = std::cos(0.5 * fov);
    const ViewBox b = ViewBoxOf(x, y, hc, hs, range, ch, std::sin(0.5 * fov));
    for (int k = 0; k < 200; ++k) {
      // Points on the view's edges and inside it.
      const double a = heading + (unit(rng) - 0.5) * fov * (k % 4 == 0 ? 1 : 1 + 1e-9);
      const double r = range * (k % 3 == 0 ? 1 : unit(rng));
      const double lx = r * std::cos(a), ly = r * std::sin(a);
      if (!InView(lx, ly, hc, hs, range * range, ch)) continue;
      ASSERT_GE(x + lx, b.x0) << trial;
      ASSERT_LE(x + lx, b.x1) << trial;
      ASSERT_GE(y + ly, b.y0) << trial;
      ASSERT_LE(y + ly, b.y1) << trial;
    }
    // Every edge of the box is reached by an admitted point of the arc or the apex.
    double lo_x = x, hi_x = x, lo_y = y, hi_y = y;
    for (int j = 0; j <= 1000; ++j) {
      const double a = heading + fov * (j / 1000.0 - 0.5), r = range * (1 - 1e-9);
      const double lx = r * std::cos(a), ly = r * std::sin(a);
      if (!InView(lx, ly, hc, hs, range * range, ch)) continue;
      lo_x = std::min(lo_x, x + lx);
      hi_x = std::max(hi_x, x + lx);
      lo_y = std::min(lo_y, y + ly);
      hi_y = std::max(hi_y, y + ly);
    }
    ASSERT_LT(lo_x - b.x0, 0.01 * range) << trial;
    ASSERT_LT(b.x1 - hi_x, 0.01 * range) << trial;
    ASSERT_LT(lo_y - b.y0, 0.01 * range) << trial;
    ASSERT_LT(b.y1 - hi_y, 0.01 * range) << trial;
  }
  const ViewBox half = ViewBoxOf(0, 0, 1, 0, 10, std::cos(M_PI / 2), std::sin(M_PI / 2));
  EXPECT_NEAR(half.x0, 0, 1e-4);
  EXPECT_NEAR(half.x1, 10, 1e-4);
  EXPECT_NEAR(half.y0, -10, 1e-4);
  EXPECT_NEAR(half.y1, 10, 1e-4);
  const double d = std::sqrt(0.5);
  const ViewBox quarter = ViewBoxOf(0, 0, d, d, 10, std::cos(M_PI / 4), std::sin(M_PI / 4));
  EXPECT_NEAR(quarter.x0, 0, 1e-4);
  EXPECT_NEAR(quarter.x1, 10, 1e-4);
  EXPECT_NEAR(quarter.y0, 0, 1e-4);
  EXPECT_NEAR(quarter.y1, 10, 1e-4);
  const ViewBox full = ViewBoxOf(1, 2, 0, 1, 10, std::cos(M_PI), std::sin(M_PI));
  EXPECT_NEAR(full.x0, -9, 1e-4);
  EXPECT_NEAR(full.x1, 11, 1e-4);
  EXPECT_NEAR(full.y0, -8, 1e-4);
  EXPECT_NEAR(full.y1, 12, 1e-4);
}

Landmark At(double x, double y) {
  Landmark l;
  l.x_m = x;
  l.y_m = y;
  l.xx = l.yy = 0.01;
  return l;
}

// Random insertions and removals in several versions that share nodes, against std::map.
TEST(PersistentTrieErase, MatchesAMapAndFreesEveryNode) {
  std::mt19937_64 rng(3);
  Trie trie(1, 1);
  std::vector<Trie::Node*> versions(4, nullptr);
  std::vector<std::map<uint64_t, double>> models(4);
  for (int op = 0; op < 20000; ++op) {
    const size_t v = rng() % versions.size();
    const uint64_t key = rng() % 600;
    switch (rng() % 4) {
      case 0:
      case 1:
        ASSERT_TRUE(trie.Update(&versions[v], key, 0,
                                [&](Landmark& l, bool) { l = At(static_cast<double>(op), 0); }));
        models[v][key] = op;
        break;
      case 2:
        ASSERT_TRUE(trie.Erase(&versions[v], key, 0));
        models[v].erase(key);
        break;
      default: {  // copy a version over another
        const size_t from = rng() % versions.size();
        Trie::Node* copy = Trie::Share(versions[from]);
        trie.Release(versions[v], 0);
        versions[v] = copy;
        models[v] = models[from];
      }
    }
    if (op % 1000 == 0) {
      ASSERT_TRUE(trie.CheckCounts(versions).ok());
    }
  }
  for (size_t v = 0; v < versions.size(); ++v) {
    std::map<uint64_t, double> seen;
    trie.ForEach(versions[v], [&](uint64_t key, const Landmark& l) { seen[key] = l.x_m; });
    EXPECT_EQ(seen, models[v]) << "version " << v;
  }
  // Erasing every key empties a version to nullptr and frees its nodes.
  for (size_t v = 0; v < versions.size(); ++v) {
    for (const auto& [key, unused] : models[v]) ASSERT_TRUE(trie.Erase(&versions[v], key, 0));
    EXPECT_EQ(versions[v], nullptr);
  }
  EXPECT_EQ(trie.live_nodes(), 0);
}

// The range query visits exactly the landmarks of the rectangle's cells, in key order.
TEST(PersistentTrieForEachIf, SpatialQueryEqualsAFilteredScan) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> pos(-300, 300);
  for (int trial = 0; trial < 50; ++trial) {
    Trie trie(1, 1);
    Trie::Node* root = nullptr;
    const double cell = 1 + static_cast<double>(rng() % 8);
    for (int k = 0; k < 400; ++k) {
      Cell c;
      const double x = pos(rng), y = pos(rng);
      ASSERT_TRUE(CellOf(x, y, cell, &c));
      ASSERT_TRUE(trie.Update(&root, SpatialKey(c, static_cast<int>(rng() % 8)), 0,
                              [&](Landmark& l, bool) { l = At(x, y); }));
    }
    for (int q = 0; q < 20; ++q) {
      const CellRect rect = CellsAround(pos(rng), pos(rng), std::fabs(pos(rng)) / 3, cell);
      std::vector<uint64_t> expected, got;
      trie.ForEach(root, [&](uint64_t key, const Landmark&) {
        if (rect.Contains(CellOfKey(key))) expected.push_back(key);
      });
      trie.ForEachIf(
          root, [&](uint64_t lo, uint64_t hi) { return KeyRangeMayHit(lo, hi, rect); },
          [&](uint64_t key, const Landmark&) { got.push_back(key); });
      ASSERT_EQ(got, expected);
    }
    trie.Release(root, 0);
  }
}

Match M(uint32_t detection, uint64_t key, double ll, double d2) { return {detection, key, ll, d2}; }

TEST(Decide, GatesPickTheMostLikelyInsideAndNewBeyond) {
  AssociationParams p;  // gates 4 and 25
  std::vector<Decision> out;
  std::vector<Match> m = {
      M(0, 10, -3.0, 1.0),  M(0, 11, -2.5, 2.0),  // two candidates in the gate: 11 more likely
      M(1, 12, -4.0, 4.01),                       // just outside the reject gate: ignored
      M(3, 13, -9.0, 24.9),                       // inside the augment gate only: ignored
      M(4, 14, -1.0, 3.99),                       // just inside: associated
  };
  Decide(m, 6, p, &out);  // detections 2 and 5 have no landmark within 25: new
  ASSERT_EQ(out.size(), 6u);
  EXPECT_EQ(out[0].kind, Decision::kAssociated);
  EXPECT_EQ(out[0].key, 11u);
  EXPECT_EQ(out[0].log_likelihood, -2.5);
  EXPECT_EQ(out[1].kind, Decision::kIgnored);
  EXPECT_EQ(out[2].kind, Decision::kNew);
  EXPECT_EQ(out[3].kind, Decision::kIgnored);
  EXPECT_EQ(out[4].kind, Decision::kAssociated);
  EXPECT_EQ(out[4].key, 14u);
  EXPECT_EQ(out[5].kind, Decision::kNew);
}

TEST(Decide, MutualExclusionGivesALandmarkToItsMostLikelyDetection) {
  AssociationParams p;
  std::vector<Decision> out;
  // Both detections prefer landmark 20; detection 1 is the better match for it, so detection 0
  // falls back to landmark 21. Detection 2's only candidate is taken: ignored, not new.
  std::vector<Match> m = {M(0, 20, -1.0, 0.5), M(0, 21, -2.0, 1.5), M(1, 20, -0.5, 0.2),
                          M(2, 20, -3.0, 3.0)};
  Decide(m, 3, p, &out);
  EXPECT_EQ(out[0].key, 20u);  // without exclusion every detection takes its best
  EXPECT_EQ(out[1].key, 20u);
  EXPECT_EQ(out[2].key, 20u);
  p.exclusive = true;
  Decide(m, 3, p, &out);
  EXPECT_EQ(out[1].kind, Decision::kAssociated);
  EXPECT_EQ(out[1].key, 20u);
  EXPECT_EQ(out[0].kind, Decision::kAssociated);
  EXPECT_EQ(out[0].key, 21u);
  EXPECT_EQ(out[2].kind, Decision::kIgnored);
}

TEST(SearchRadius, GrowsWithRangeAndIsInfiniteWithoutABound) {
  const SensorNoise noise{0.1, kPi / 180};
  const double near = SearchRadius(5, 30, noise, 25), far = SearchRadius(30, 30, noise, 25);
  EXPECT_GT(far, near);
  EXPECT_GT(near, 0);
  EXPECT_LT(far, 10);
  EXPECT_TRUE(std::isinf(SearchRadius(10, 30, SensorNoise{0.1, 0.2}, 25)));
}

// Random maps built as a filter builds them (landmarks initialised from detections and updated),
// random poses and detections: the candidates of the spatial index and radius give the same
// matches and decisions as comparing every landmark of the map. For both layouts of a map: a
// bottom node per cell, and (as FastSLAM keeps spatial maps) a packed one per 8 cells, whose
// range query hands the matching some landmarks of cells outside the query.
template <typename T>
class FindMatchesTest : public testing::Test {};
using MapLayouts = testing::Types<PersistentTrie<Landmark, 3>, PersistentTrie<Landmark, 3, 6>>;
TYPED_TEST_SUITE(FindMatchesTest, MapLayouts);

TYPED_TEST(FindMatchesTest, IndexGivesTheSameMatchesAsTheWholeMap) {
  using Trie = TypeParam;
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> pos(-80, 80), unit(0, 1);
  int associated = 0, created = 0, ignored = 0;
  for (int trial = 0; trial < 60; ++trial) {
    AssociationParams p;
    p.noise = SensorNoise{0.05 + 0.5 * unit(rng), (0.2 + 1.5 * unit(rng)) * kPi / 180};
    p.cell_m = 1 + 6 * unit(rng);
    p.exclusive = trial % 2 == 1;
    const double max_range = 40;
    Trie trie(1, 1);
    typename Trie::Node* root = nullptr;
    for (int k = 0; k < 300; ++k) {
      const VehiclePose from{pos(rng), pos(rng), (2 * unit(rng) - 1) * kPi};
      Landmark l = InitLandmark(
          from, RangeBearing{max_range * unit(rng), (2 * unit(rng) - 1) * kPi}, p.noise);
      for (int u = static_cast<int>(rng() % 3); u > 0; --u) {
        const RangeBearing z = Observe(from, l.x_m + 0.1, l.y_m);
        ASSERT_TRUE(UpdateLandmark(from, z, p.noise, &l, nullptr).ok());
      }
      Cell c;
      ASSERT_TRUE(CellOf(l.x_m, l.y_m, p.cell_m, &c));
      const uint64_t key = SpatialKey(c, static_cast<int>(rng() % 8));
      if (trie.Find(root, key) != nullptr) continue;
      ASSERT_TRUE(trie.Update(&root, key, 0, [&](Landmark& leaf, bool) { leaf = l; }));
    }
    const VehiclePose pose{pos(rng) / 2, pos(rng) / 2, (2 * unit(rng) - 1) * kPi};
    std::vector<LandmarkObservation> scan;
    trie.ForEach(root, [&](uint64_t, const Landmark& l) {
      const RangeBearing z = Observe(pose, l.x_m, l.y_m);
      if (z.range_m < max_range && unit(rng) < 0.5) {
        // Near a landmark: a few sigmas off, so some fall inside, between and beyond the gates.
        const double k = 4 * unit(rng);
        scan.push_back(
            {std::max(0.0, z.range_m + k * p.noise.sigma_range_m * (2 * unit(rng) - 1)),
             WrapAngle(z.bearing_rad + k * p.noise.sigma_bearing_rad * (2 * unit(rng) - 1)), -1});
      }
    });
    for (int k = 0; k < 5; ++k) {
      scan.push_back({max_range * unit(rng), WrapAngle((2 * unit(rng) - 1) * kPi), -1});
    }
    std::vector<Match> indexed, all;
    MatchScratch scratch;
    ASSERT_TRUE(FindMatches(trie, root, pose, scan, p, max_range, true, &indexed, &scratch).ok());
    ASSERT_TRUE(FindMatches(trie, root, pose, scan, p, max_range, false, &all, &scratch).ok());
    auto order = [](const Match& a, const Match& b) {
      return a.detection != b.detection ? a.detection < b.detection : a.key < b.key;
    };
    std::sort(indexed.begin(), indexed.end(), order);
    std::sort(all.begin(), all.end(), order);
    ASSERT_EQ(indexed.size(), all.size()) << "trial " << trial;
    for (size_t k = 0; k < all.size(); ++k) {
      ASSERT_EQ(indexed[k].detection, all[k].detection);
      ASSERT_EQ(indexed[k].key, all[k].key);
      ASSERT_EQ(indexed[k].d2, all[k].d2);
    }
    std::vector<Decision> a, b;
    Decide(indexed, scan.size(), p, &a);
    Decide(all, scan.size(), p, &b);
    for (size_t j = 0; j < scan.size(); ++j) {
      ASSERT_EQ(a[j].kind, b[j].kind);
      ASSERT_EQ(a[j].key, b[j].key);
      associated += a[j].kind == Decision::kAssociated;
      created += a[j].kind == Decision::kNew;
      ignored += a[j].kind == Decision::kIgnored;
    }
    trie.Release(root, 0);
  }
  // The cases cover every decision.
  EXPECT_GT(associated, 100);
  EXPECT_GT(created, 100);
  EXPECT_GT(ignored, 20);
}

// Through the facade

FastSlamConfig Unknown(FastSlamFilter filter) {
  FastSlamConfig c;
  c.filter = filter;
  c.particles = 1;
  c.threads = 1;
  c.association = FastSlamAssociation::kMaximumLikelihood;
  c.sigma_speed_mps = c.sigma_steer_rad = 0;
  return c;
}

class Evidence : public ::testing::TestWithParam<FastSlamFilter> {};
INSTANTIATE_TEST_SUITE_P(Filters, Evidence,
                         ::testing::Values(FastSlamFilter::kFastSlam1, FastSlamFilter::kFastSlam2,
                                           FastSlamFilter::kUnscented, FastSlamFilter::kSrcd,
                                           FastSlamFilter::kSrcdAided,
                                           FastSlamFilter::kSrcdParticle, FastSlamFilter::kDeSrcd),
                         [](const auto& info) { return FastSlamFilterName(info.param); });

// A standing vehicle: a landmark seen once and then in view but never detected again is
// removed at the second scan without it (evidence 1, 0, -1 < 0); one behind the vehicle (out of
// the field of view) stays, and so does everything with evidence off.
TEST_P(Evidence, ALandmarkInViewAndNeverSeenAgainIsRemoved) {
  for (FastSlamEvidence evidence : {FastSlamEvidence::kOn, FastSlamEvidence::kOff}) {
    FastSlamConfig config = Unknown(GetParam());
    config.evidence = evidence;
    auto slam = FastSlam::Create(config);
    ASSERT_TRUE(slam.ok());
    ASSERT_TRUE((*slam)->Control(0, 0, 0).ok());
    const LandmarkObservation ahead{10, 0.2, 1}, behind{12, 3.0, 2};
    ASSERT_TRUE((*slam)->Scan(0.2, std::vector{ahead, behind}).ok());
    EXPECT_EQ((*slam)->Summary().landmarks, 2);
    ASSERT_TRUE((*slam)->Scan(0.4, std::vector{behind}).ok());  // behind: seen, but from a
    // landmark out of view; the one ahead is missed once: evidence 0, kept
    EXPECT_EQ((*slam)->Summary().landmarks, 2);
    ASSERT_TRUE((*slam)->Scan(0.6, std::vector<LandmarkObservation>{}).ok());
    const FastSlamSummary s = (*slam)->Summary();
    auto landmarks = (*slam)->HeaviestLandmarks();
    ASSERT_TRUE(landmarks.ok());
    if (evidence == FastSlamEvidence::kOn) {
      EXPECT_EQ(s.landmarks, 1);
      EXPECT_EQ(s.association.removed, 1);
      ASSERT_EQ(landmarks->size(), 1u);
      EXPECT_EQ(landmarks->front().source_id, 2);  // the one behind stays
    } else {
      EXPECT_EQ(s.landmarks, 2);
      EXPECT_EQ(s.association.removed, 0);
    }
    EXPECT_EQ(s.association.created, 2);
    EXPECT_EQ(s.association.associated, 1);
    EXPECT_EQ(s.association.tagged, 1);
    EXPECT_EQ(s.association.wrong, 0);
    EXPECT_TRUE((*slam)->CheckInvariants().ok());
  }
}

// Two scans of the same two landmarks from a standing vehicle: associated, not duplicated; a
// third detection far from both starts a third landmark.
TEST_P(Evidence, RepeatedDetectionsAssociateAndAFarOneIsNew) {
  auto slam = FastSlam::Create(Unknown(GetParam()));
  ASSERT_TRUE(slam.ok());
  ASSERT_TRUE((*slam)->Control(0, 0, 0).ok());
  const LandmarkObservation a{10, 0.2, 7}, b{10.5, 0.25, 8}, c{20, -0.5, 9};
  ASSERT_TRUE((*slam)->Scan(0.2, std::vector{a, b}).ok());
  ASSERT_TRUE((*slam)->Scan(0.4, std::vector{b, a, c}).ok());
  const FastSlamSummary s = (*slam)->Summary();
  EXPECT_EQ(s.landmarks, 3);
  EXPECT_EQ(s.association.associated, 2);
  EXPECT_EQ(s.association.created, 3);
  EXPECT_EQ(s.association.wrong, 0);
  EXPECT_EQ(s.association.tagged, 2);
}

TEST(UnknownAssociationInput, IdsMustBeMinusOneOrATag) {
  auto slam = FastSlam::Create(Unknown(FastSlamFilter::kFastSlam2));
  ASSERT_TRUE(slam.ok());
  ASSERT_TRUE((*slam)->Control(0, 0, 0).ok());
  Status s = (*slam)->Scan(0.2, std::vector<LandmarkObservation>{{10, 0, -2}});
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("id = -2"), std::string::npos) << s.message();
  EXPECT_TRUE((*slam)->Scan(0.2, std::vector<LandmarkObservation>{{10, 0, -1}}).ok());
}

TEST(UnknownAssociationConfig, GatesAreCheckedAndConverted) {
  FastSlamConfig c = Unknown(FastSlamFilter::kFastSlam2);
  c.augment_gate = 3;
  Status s = c.Validate();
  EXPECT_NE(s.message().find("augment_gate = 3"), std::string::npos) << s.message();
  c.gate_unit = FastSlamGateUnit::kProbability;
  c.reject_gate = 0.5;
  c.augment_gate = 2;
  EXPECT_NE(c.Validate().message().find("augment_gate = 2"), std::string::npos);
  c.augment_gate = 0.99;
  EXPECT_TRUE(c.Validate().ok());
  // Bailey's gate of 4 is the 86.47 % point of the chi-square with 2 degrees of freedom.
  EXPECT_NEAR(FastSlamGateDistance2(1 - std::exp(-2.0), FastSlamGateUnit::kProbability), 4, 1e-12);
  EXPECT_EQ(FastSlamGateDistance2(25, FastSlamGateUnit::kDistance2), 25);
}

}  // namespace
}  // namespace grove::fastslam
