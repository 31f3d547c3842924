#include "engine/footslam/hex_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <random>
#include <set>
#include <utility>
#include <vector>

namespace grove::footslam {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kSqrt3 = std::numbers::sqrt3;

struct Point {
  double x = 0;
  double y = 0;
};

// The perturbation direction the grid breaks ties along (10° from +x).
const Point kV{std::cos(kPi / 18), std::sin(kPi / 18)};

Point CenterOf(const HexGrid& g, Hex h) {
  Point p;
  g.Center(h, &p.x, &p.y);
  return p;
}

// Vertex k (0..5) of h, at 30° + 60°*k from its centre.
Point VertexOf(const HexGrid& g, Hex h, int k) {
  const Point c = CenterOf(g, h);
  const double a = kPi / 6 + k * kPi / 3;
  return {c.x + g.radius_m() * std::cos(a), c.y + g.radius_m() * std::sin(a)};
}

// Midpoint of edge e of h, at `offset` metres outward along the centre-to-neighbour direction.
Point EdgePoint(const HexGrid& g, Hex h, int e, double offset) {
  const Point c = CenterOf(g, h);
  const double a = e * kPi / 3;
  const double d = g.radius_m() * kSqrt3 / 2 + offset;
  return {c.x + d * std::cos(a), c.y + d * std::sin(a)};
}

// Nearest centre by brute force over a window, independent of HexAt.
Hex NearestCenter(const HexGrid& g, double x, double y) {
  const double rad = g.radius_m();
  const int r0 = static_cast<int>(std::floor(y / (1.5 * rad)));
  Hex best;
  double best_d2 = INFINITY;
  for (int r = r0 - 1; r <= r0 + 2; ++r) {
    const int q0 = static_cast<int>(std::floor(x / (rad * kSqrt3) - 0.5 * r));
    for (int q = q0 - 1; q <= q0 + 2; ++q) {
      const double cx = rad * kSqrt3 * (q + 0.5 * r);
      const double cy = 1.5 * rad * r;
      const double d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
      if (d2 < best_d2) {
        best_d2 = d2;
        best = Hex{q, r};
      }
    }
  }
  return best;
}

// Checks that the crossings form a chain of neighbours from `start` to `end`, that no edge is
// crossed twice (a straight segment cannot), and returns the hexagons visited.
std::vector<Hex> CheckChain(const std::vector<Crossing>& cs, Hex start, Hex end) {
  std::vector<Hex> visited{start};
  std::set<std::pair<std::pair<int32_t, int32_t>, std::pair<int32_t, int32_t>>> edges;
  Hex at = start;
  for (const Crossing& c : cs) {
    EXPECT_EQ(c.from, at);
    EXPECT_GE(c.edge, 0);
    EXPECT_LT(c.edge, 6);
    const Hex next = HexGrid::Neighbor(c.from, c.edge);
    const std::pair<int32_t, int32_t> u{c.from.q, c.from.r}, w{next.q, next.r};
    const auto key = u < w ? std::pair{u, w} : std::pair{w, u};
    EXPECT_TRUE(edges.insert(key).second) << "edge crossed twice: " << c;
    at = next;
    visited.push_back(at);
  }
  EXPECT_EQ(at, end);
  return visited;
}

// What the reverse walk must report: the same edges, last first, from the other side.
std::vector<Crossing> Reversed(const std::vector<Crossing>& cs) {
  std::vector<Crossing> out;
  for (auto it = cs.rbegin(); it != cs.rend(); ++it) {
    out.push_back(Crossing{HexGrid::Neighbor(it->from, it->edge), HexGrid::OppositeEdge(it->edge)});
  }
  return out;
}

// Distance from p to the segment a-b.
double DistanceToSegment(Point p, Point a, Point b) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? ((p.x - a.x) * dx + (p.y - a.y) * dy) / len2 : 0.0;
  t = std::fmin(1.0, std::fmax(0.0, t));
  const double ex = a.x + t * dx - p.x, ey = a.y + t * dy - p.y;
  return std::sqrt(ex * ex + ey * ey);
}

// Smallest distance from the segment to any hexagon vertex near it.
double DistanceToNearestVertex(const HexGrid& g, Point a, Point b) {
  const Hex ha = NearestCenter(g, a.x, a.y), hb = NearestCenter(g, b.x, b.y);
  double best = INFINITY;
  for (int q = std::min(ha.q, hb.q) - 20; q <= std::max(ha.q, hb.q) + 20; ++q) {
    for (int r = std::min(ha.r, hb.r) - 2; r <= std::max(ha.r, hb.r) + 2; ++r) {
      for (int k = 0; k < 6; ++k) {
        best = std::fmin(best, DistanceToSegment(VertexOf(g, Hex{q, r}, k), a, b));
      }
    }
  }
  return best;
}

Hex Traverse(const HexGrid& g, Point a, Point b, std::vector<Crossing>* out) {
  return g.Traverse(g.HexAt(a.x, a.y), a.x, a.y, b.x, b.y,
                    [out](const Crossing& c) { out->push_back(c); });
}

TEST(HexGridTest, HexAtCentreReturnsThatHex) {
  for (double radius : {0.3, 0.5, 1.0, 7.25}) {
    const HexGrid g(radius);
    for (int q = -12; q <= 12; ++q) {
      for (int r = -12; r <= 12; ++r) {
        const Point c = CenterOf(g, Hex{q, r});
        EXPECT_EQ(g.HexAt(c.x, c.y), (Hex{q, r})) << "radius " << radius;
      }
    }
  }
}

TEST(HexGridTest, CenterMatchesAxialFormula) {
  const HexGrid g(0.5);
  const Point c = CenterOf(g, Hex{3, -2});
  EXPECT_DOUBLE_EQ(c.x, 0.5 * kSqrt3 * (3 - 1.0));
  EXPECT_DOUBLE_EQ(c.y, 1.5 * 0.5 * -2);
}

TEST(HexGridTest, NeighborLiesAtSixtyDegreesTimesEdge) {
  const HexGrid g(2.0);
  const Hex h{4, -7};
  const Point c = CenterOf(g, h);
  for (int e = 0; e < 6; ++e) {
    const Point n = CenterOf(g, HexGrid::Neighbor(h, e));
    EXPECT_NEAR(n.x - c.x, 2.0 * kSqrt3 * std::cos(e * kPi / 3), 1e-12) << "edge " << e;
    EXPECT_NEAR(n.y - c.y, 2.0 * kSqrt3 * std::sin(e * kPi / 3), 1e-12) << "edge " << e;
    EXPECT_EQ(HexGrid::Neighbor(HexGrid::Neighbor(h, e), HexGrid::OppositeEdge(e)), h);
    EXPECT_EQ(HexGrid::OppositeEdge(e), (e + 3) % 6);
  }
}

TEST(HexGridTest, HexAtNearEdgeMidpointPicksTheSideThePointIsOn) {
  const HexGrid g(0.5);
  for (Hex h : {Hex{0, 0}, Hex{5, -3}, Hex{-40, 17}}) {
    for (int e = 0; e < 6; ++e) {
      const Point in = EdgePoint(g, h, e, -1e-6);
      const Point out = EdgePoint(g, h, e, 1e-6);
      EXPECT_EQ(g.HexAt(in.x, in.y), h) << h << " edge " << e;
      EXPECT_EQ(g.HexAt(out.x, out.y), HexGrid::Neighbor(h, e)) << h << " edge " << e;
    }
  }
}

TEST(HexGridTest, PointOnEdgeBelongsToTheHexThePerturbationPointsInto) {
  // v at 10° points into the neighbours across edges 0, 1 and 5 and away from 2, 3 and 4.
  const HexGrid g(0.5);
  for (Hex h : {Hex{0, 0}, Hex{7, 2}, Hex{-3, -9}}) {
    for (int e = 0; e < 6; ++e) {
      const Point m = EdgePoint(g, h, e, 0.0);
      const bool to_neighbor = e == 0 || e == 1 || e == 5;
      EXPECT_EQ(g.HexAt(m.x, m.y), to_neighbor ? HexGrid::Neighbor(h, e) : h) << h << " edge " << e;
    }
  }
}

TEST(HexGridTest, VertexBelongsToTheCellTheTenDegreeDirectionEnters) {
  const HexGrid g(1.0);
  // The top vertex of (0,0) is shared with (0,1) and (-1,1); 10° from it lies in (0,1).
  const Point top = VertexOf(g, Hex{0, 0}, 1);
  EXPECT_EQ(g.HexAt(top.x, top.y), (Hex{0, 1}));
  for (int k = 0; k < 6; ++k) {
    const Point p = VertexOf(g, Hex{2, -1}, k);
    EXPECT_EQ(g.HexAt(p.x, p.y), NearestCenter(g, p.x + 1e-6 * kV.x, p.y + 1e-6 * kV.y))
        << "vertex " << k;
  }
}

TEST(HexGridTest, HexAtMatchesNearestCentreForRandomPoints) {
  for (double radius : {0.5, 1.7}) {
    const HexGrid g(radius);
    for (uint64_t seed = 1; seed <= 20; ++seed) {
      SCOPED_TRACE(testing::Message() << "seed " << seed << " radius " << radius);
      std::mt19937_64 rng(seed);
      const double span = seed % 2 ? 30.0 : 3000.0;
      std::uniform_real_distribution<double> u(-span, span);
      for (int i = 0; i < 2000; ++i) {
        const double x = u(rng), y = u(rng);
        ASSERT_EQ(g.HexAt(x, y), NearestCenter(g, x, y)) << "point " << x << ", " << y;
      }
    }
  }
}

// Random points out to 1e9 radii, the documented range, and the centres of hexagons at its
// edge, still get the hexagon that contains them.
TEST(HexGridTest, HexAtIsExactUpToTheEdgeOfItsRange) {
  const HexGrid g(0.5);
  std::mt19937_64 rng(5);
  const double span = 1e9 * g.radius_m();
  std::uniform_real_distribution<double> u(-span, span);
  for (int i = 0; i < 2000; ++i) {
    const double x = u(rng), y = u(rng);
    ASSERT_EQ(g.HexAt(x, y), NearestCenter(g, x, y)) << "point " << x << ", " << y;
  }
  constexpr int32_t kMax = HexGrid::kMaxAxial;
  for (const Hex h : {Hex{kMax, 0}, Hex{-kMax, 0}, Hex{0, kMax}, Hex{0, -kMax}, Hex{kMax, kMax},
                      Hex{-kMax, -kMax}, Hex{kMax, -kMax}, Hex{kMax - 1, 1}}) {
    const Point c = CenterOf(g, h);
    EXPECT_EQ(g.HexAt(c.x, c.y), h) << "centre of " << h;
  }
}

// Regression: past about 1.86e9 m (R = 0.5) the rounded axial coordinate did
// not fit the int32 it was cast to, which is undefined behaviour (GROVE_SANITIZE builds have
// -fsanitize=float-cast-overflow to catch it). Such points now saturate at +-kMaxAxial.
TEST(HexGridTest, HexAtFarOutsideItsRangeSaturates) {
  const HexGrid g(0.5);
  constexpr int32_t kMax = HexGrid::kMaxAxial;
  struct Case {
    double x, y;
    Hex expected;
  };
  const Case cases[] = {
      {1e10, 0.0, {kMax, 0}},
      {-1e10, 0.0, {-kMax, 0}},
      {0.0, 1e10, {-kMax, kMax}},
      {0.0, -1e10, {kMax, -kMax}},
      {1e10, 1e10, {kMax, kMax}},
      {-1e10, -1e10, {-kMax, -kMax}},
      {1e300, 1e300, {kMax, kMax}},
      {-1e300, 1e300, {-kMax, kMax}},
      {1e300, -1e300, {kMax, -kMax}},
      {-1e300, -1e300, {-kMax, -kMax}},
      {2e9, 0.0, {kMax, 0}},
      {1e300, 0.0, {kMax, 0}},
      {-std::numeric_limits<double>::max(), 0.0, {-kMax, 0}},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(g.HexAt(c.x, c.y), c.expected) << "point " << c.x << ", " << c.y;
  }
  // Not finite: still a defined answer.
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(g.HexAt(inf, 0.0), (Hex{kMax, 0}));
  EXPECT_EQ(g.HexAt(-inf, 0.0), (Hex{-kMax, 0}));
  EXPECT_EQ(g.HexAt(nan, 0.0), (Hex{0, 0}));
  EXPECT_EQ(g.HexAt(0.0, nan).q, 0);
  // A grid of tiny hexagons overflows the axial coordinates already at moderate distances.
  const HexGrid tiny(1e-300);
  EXPECT_EQ(tiny.HexAt(1.0, 0.0), (Hex{kMax, 0}));
}

// Centres, vertices and points on edges, where the tie-breaking is exercised.
Point RandomSpecialPoint(const HexGrid& g, std::mt19937_64& rng) {
  std::uniform_int_distribution<int> coord(-6, 6), six(0, 5), kind(0, 3), frac(1, 7);
  const Hex h{coord(rng), coord(rng)};
  switch (kind(rng)) {
    case 0:
      return CenterOf(g, h);
    case 1:
      return VertexOf(g, h, six(rng));
    case 2:
      return EdgePoint(g, h, six(rng), 0.0);
    default: {  // a point on an edge at k/8 of its length
      const int k = six(rng);
      const Point a = VertexOf(g, h, k), b = VertexOf(g, h, (k + 1) % 6);
      const double f = frac(rng) / 8.0;
      return {a.x + f * (b.x - a.x), a.y + f * (b.y - a.y)};
    }
  }
}

TEST(HexGridTest, DegeneratePointsResolveAlongThePerturbation) {
  const HexGrid g(0.8);
  for (uint64_t seed = 1; seed <= 2000; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    std::mt19937_64 rng(seed);
    const Point p = RandomSpecialPoint(g, rng);
    ASSERT_EQ(g.HexAt(p.x, p.y), NearestCenter(g, p.x + 1e-7 * kV.x, p.y + 1e-7 * kV.y));
  }
}

TEST(HexGridTest, CentreToNeighbourCentreCrossesExactlyThatEdge) {
  const HexGrid g(0.5);
  const Hex h{3, -1};
  const Point c = CenterOf(g, h);
  for (int e = 0; e < 6; ++e) {
    const Point n = CenterOf(g, HexGrid::Neighbor(h, e));
    EXPECT_EQ(g.Crossings(c.x, c.y, n.x, n.y), (std::vector<Crossing>{{h, e}})) << "edge " << e;
  }
}

TEST(HexGridTest, StraightRunAcrossThreeHexesCrossesTwoEdges) {
  const HexGrid g(1.0);
  const Point a = CenterOf(g, Hex{-1, 0});
  const Point b = CenterOf(g, Hex{1, 0});
  EXPECT_EQ(g.Crossings(a.x, a.y, b.x, b.y),
            (std::vector<Crossing>{{Hex{-1, 0}, 0}, {Hex{0, 0}, 0}}));
  // Up the 60° diagonal: (0,0) -> (0,1) -> (0,2).
  const Point d = CenterOf(g, Hex{0, 2});
  const Point o = CenterOf(g, Hex{0, 0});
  EXPECT_EQ(g.Crossings(o.x, o.y, d.x, d.y),
            (std::vector<Crossing>{{Hex{0, 0}, 1}, {Hex{0, 1}, 1}}));
}

TEST(HexGridTest, StepEndingInItsStartHexCrossesNothing) {
  const HexGrid g(1.0);
  int calls = 0;
  const Hex end =
      g.Traverse(Hex{0, 0}, -0.3, 0.2, 0.6, -0.4, [&calls](const Crossing&) { ++calls; });
  EXPECT_EQ(end, (Hex{0, 0}));
  EXPECT_EQ(calls, 0);
}

TEST(HexGridTest, ZeroLengthSegmentCrossesNothing) {
  const HexGrid g(1.0);
  // Also on an edge and on a vertex, where a sloppy walk could step to the other side.
  const Point pts[] = {{0.2, 0.1}, EdgePoint(g, Hex{0, 0}, 0, 0.0), VertexOf(g, Hex{0, 0}, 1)};
  for (const Point& p : pts) {
    EXPECT_TRUE(g.Crossings(p.x, p.y, p.x, p.y).empty()) << p.x << ", " << p.y;
    std::vector<Crossing> cs;
    EXPECT_EQ(Traverse(g, p, p, &cs), g.HexAt(p.x, p.y));
  }
}

TEST(HexGridTest, SegmentAlongAnEdgeStaysOnThePerturbedSide) {
  // The vertical line x = R*sqrt(3)/2 contains the edge between (0,0) and (1,0); v points to
  // +x, so the walk runs up through (1,0) and never enters (0,0).
  const HexGrid g(1.0);
  const double x = kSqrt3 / 2;
  const std::vector<Crossing> up = g.Crossings(x, -1.0, x, 1.0);
  EXPECT_EQ(up, (std::vector<Crossing>{{Hex{1, -1}, 1}, {Hex{1, 0}, 2}}));
  EXPECT_EQ(g.Crossings(x, 1.0, x, -1.0), Reversed(up));
  // Exactly vertex to vertex: both ends and the whole edge belong to (1,0).
  EXPECT_TRUE(g.Crossings(x, -0.5, x, 0.5).empty());
  EXPECT_EQ(g.HexAt(x, 0.5), (Hex{1, 0}));
}

TEST(HexGridTest, SegmentThroughVertexCrossesOneEdgeOfTheStartHex) {
  const HexGrid g(1.0);
  const Point top = VertexOf(g, Hex{0, 0}, 1);  // shared by (0,0), (0,1) and (-1,1)
  auto through = [&](double deg) {
    const double c = 0.5 * std::cos(deg * kPi / 180), s = 0.5 * std::sin(deg * kPi / 180);
    return g.Crossings(top.x - c, top.y - s, top.x + c, top.y + s);
  };
  // At 60° the line leaves (0,0) straight into (0,1).
  EXPECT_EQ(through(60), (std::vector<Crossing>{{Hex{0, 0}, 1}}));
  // At 120° it ends in (-1,1); the perturbed line passes right of the vertex, so it clips
  // (0,1) on the way: one edge of (0,0), then one of (0,1), each into a neighbour.
  EXPECT_EQ(through(120), (std::vector<Crossing>{{Hex{0, 0}, 1}, {Hex{0, 1}, 3}}));
  // Coming back at 300° crosses the same two edges in reverse.
  EXPECT_EQ(through(300), (std::vector<Crossing>{{Hex{-1, 1}, 0}, {Hex{0, 1}, 4}}));
}

// Every hexagon a densely sampled segment visits, in order, by nearest centre.
std::vector<Hex> SampledHexes(const HexGrid& g, Point a, Point b, double step) {
  const double len = std::hypot(b.x - a.x, b.y - a.y);
  const int n = static_cast<int>(std::ceil(len / step));
  std::vector<Hex> out;
  for (int i = 0; i <= n; ++i) {
    const double t = static_cast<double>(i) / n;
    const Hex h = NearestCenter(g, a.x + t * (b.x - a.x), a.y + t * (b.y - a.y));
    if (out.empty() || !(out.back() == h)) out.push_back(h);
  }
  return out;
}

TEST(HexGridTest, LongSegmentsMatchDenseSampling) {
  // A segment at least R/50 from every vertex cuts each cell it enters along a chord of at
  // least ~0.07 R, so sampling every R/500 sees every cell.
  const HexGrid g(0.5);
  const double rad = g.radius_m();
  int checked = 0;
  for (uint64_t seed = 1; checked < 150; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> pos(-20 * rad, 20 * rad), len(0.0, 12 * rad),
        ang(0.0, 2 * kPi);
    const Point a{pos(rng), pos(rng)};
    const double l = len(rng), th = ang(rng);
    const Point b{a.x + l * std::cos(th), a.y + l * std::sin(th)};
    if (DistanceToNearestVertex(g, a, b) < rad / 50) continue;
    ++checked;
    std::vector<Crossing> cs;
    const Hex end = Traverse(g, a, b, &cs);
    const std::vector<Hex> visited = CheckChain(cs, g.HexAt(a.x, a.y), end);
    ASSERT_EQ(visited, SampledHexes(g, a, b, rad / 500));
  }
}

TEST(HexGridTest, RandomSegmentsFormANeighbourChainEndingAtHexAtOfTheEnd) {
  const HexGrid g(0.7);
  for (uint64_t seed = 1; seed <= 3000; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> pos(-15.0, 15.0);
    const Point a{pos(rng), pos(rng)}, b{pos(rng), pos(rng)};
    std::vector<Crossing> cs;
    const Hex end = Traverse(g, a, b, &cs);
    EXPECT_EQ(end, g.HexAt(b.x, b.y));
    CheckChain(cs, g.HexAt(a.x, a.y), end);
    ASSERT_FALSE(testing::Test::HasFailure());
  }
}

TEST(HexGridTest, ReversedSegmentCrossesTheSameEdgesBackwards) {
  const HexGrid g(0.7);
  for (uint64_t seed = 1; seed <= 3000; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> pos(-15.0, 15.0);
    const Point a{pos(rng), pos(rng)}, b{pos(rng), pos(rng)};
    ASSERT_EQ(g.Crossings(b.x, b.y, a.x, a.y), Reversed(g.Crossings(a.x, a.y, b.x, b.y)));
  }
}

TEST(HexGridTest, SplitSegmentCrossesWhatTheWholeSegmentCrosses) {
  // a->m then m->c from the hexagon the first half ended in, with m on a->c.
  const HexGrid g(0.7);
  for (uint64_t seed = 1; seed <= 3000; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> pos(-15.0, 15.0), frac(0.0, 1.0);
    const Point a{pos(rng), pos(rng)}, c{pos(rng), pos(rng)};
    const double f = frac(rng);
    const Point m{a.x + f * (c.x - a.x), a.y + f * (c.y - a.y)};
    std::vector<Crossing> parts;
    const Hex mid = Traverse(g, a, m, &parts);
    ASSERT_EQ(mid, g.HexAt(m.x, m.y));
    const Hex end =
        g.Traverse(mid, m.x, m.y, c.x, c.y, [&parts](const Crossing& x) { parts.push_back(x); });
    ASSERT_EQ(end, g.HexAt(c.x, c.y));
    ASSERT_EQ(parts, g.Crossings(a.x, a.y, c.x, c.y));
  }
}

TEST(HexGridTest, ChainedSegmentsContinueFromTheReturnedHex) {
  const HexGrid g(0.5);
  for (uint64_t seed = 1; seed <= 500; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> step(-1.0, 1.0);
    // A walk whose points are half of the time special (centre, vertex, edge).
    Point p = RandomSpecialPoint(g, rng);
    Hex h = g.HexAt(p.x, p.y);
    for (int i = 0; i < 50; ++i) {
      Point q = (rng() % 2) ? RandomSpecialPoint(g, rng) : Point{p.x + step(rng), p.y + step(rng)};
      std::vector<Crossing> cs;
      const Hex end =
          g.Traverse(h, p.x, p.y, q.x, q.y, [&cs](const Crossing& c) { cs.push_back(c); });
      ASSERT_EQ(end, g.HexAt(q.x, q.y)) << "step " << i;
      CheckChain(cs, h, end);
      ASSERT_FALSE(testing::Test::HasFailure()) << "step " << i;
      p = q;
      h = end;
    }
  }
}

TEST(HexGridTest, DegenerateSegmentsCrossWhatTheirPerturbedCopiesCross) {
  // Segments between centres, vertices and edge points run along edges and through vertices;
  // the walk must match the same segment shifted 1e-7 m along v, which is generic.
  const HexGrid g(1.0);
  for (uint64_t seed = 1; seed <= 4000; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    std::mt19937_64 rng(seed);
    const Point a = RandomSpecialPoint(g, rng), b = RandomSpecialPoint(g, rng);
    const double d = 1e-7;
    const std::vector<Crossing> exact = g.Crossings(a.x, a.y, b.x, b.y);
    ASSERT_EQ(exact, g.Crossings(a.x + d * kV.x, a.y + d * kV.y, b.x + d * kV.x, b.y + d * kV.y));
    ASSERT_EQ(g.Crossings(b.x, b.y, a.x, a.y), Reversed(exact));
    std::vector<Crossing> cs;
    const Hex end = Traverse(g, a, b, &cs);
    ASSERT_EQ(end, g.HexAt(b.x, b.y));
    CheckChain(cs, g.HexAt(a.x, a.y), end);
  }
}

TEST(HexGridTest, WalkFromANeighbourOfTheStartHexStillEndsAtHexAtOfTheEnd) {
  // Outside the REQUIRES, but a caller's stale hexagon must not derail later steps.
  const HexGrid g(0.5);
  for (uint64_t seed = 1; seed <= 1000; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> pos(-5.0, 5.0);
    const Point a{pos(rng), pos(rng)}, b{pos(rng), pos(rng)};
    const Hex wrong = HexGrid::Neighbor(g.HexAt(a.x, a.y), static_cast<int>(rng() % 6));
    std::vector<Crossing> cs;
    const Hex end =
        g.Traverse(wrong, a.x, a.y, b.x, b.y, [&cs](const Crossing& c) { cs.push_back(c); });
    ASSERT_EQ(end, g.HexAt(b.x, b.y));
    CheckChain(cs, wrong, end);
    ASSERT_FALSE(testing::Test::HasFailure());
  }
}

TEST(HexGridTest, WalkFarFromTheOriginMatchesNearestCentres) {
  // Coordinates of ~1e5 radii keep the tolerance meaningful.
  const HexGrid g(0.5);
  const Point a{41234.56, -38765.4}, b{41240.1, -38759.9};
  std::vector<Crossing> cs;
  const Hex end = Traverse(g, a, b, &cs);
  EXPECT_EQ(end, NearestCenter(g, b.x, b.y));
  const std::vector<Hex> visited = CheckChain(cs, NearestCenter(g, a.x, a.y), end);
  EXPECT_EQ(visited, SampledHexes(g, a, b, g.radius_m() / 500));
  EXPECT_GE(cs.size(), 8u);
}

}  // namespace
}  // namespace grove::footslam
