#include "engine/footslam/hex_grid.h"

#include <cmath>
#include <ostream>

namespace grove::footslam {
namespace {

// A rounded axial coordinate as an int32, saturated at +-kMaxAxial (NaN gives 0): a double
// outside int32 would make the cast undefined. Sets *saturated when it clamps.
int32_t SaturatedAxial(double v, bool* saturated) {
  constexpr double kMax = HexGrid::kMaxAxial;
  if (v >= -kMax && v <= kMax) return static_cast<int32_t>(v);
  *saturated = true;
  if (std::isnan(v)) return 0;
  return v < 0 ? -HexGrid::kMaxAxial : HexGrid::kMaxAxial;
}

}  // namespace

std::ostream& operator<<(std::ostream& os, Hex h) { return os << '(' << h.q << ", " << h.r << ')'; }

std::ostream& operator<<(std::ostream& os, const Crossing& c) {
  return os << c.from << " across edge " << c.edge;
}

HexGrid::HexGrid(double radius_m)
    : radius_m_(radius_m),
      half_width_m_(radius_m * kHalfSqrt3),
      row_step_m_(1.5 * radius_m),
      quarter_width_m_(0.5 * half_width_m_),
      half_row_step_m_(0.75 * radius_m),
      tol_m_(1e-9 * radius_m),
      inner_radius2_m2_((half_width_m_ - 1e-6 * radius_m) * (half_width_m_ - 1e-6 * radius_m)) {}

Hex HexGrid::HexAt(double x, double y) const {
  // Cube-coordinate rounding of the fractional axial position (Patel, "Hexagonal Grids", Red
  // Blob Games, 2013) lands on the cell or, near a boundary, on a neighbour of it.
  const double fr = y / row_step_m_;
  const double fq = x / (2.0 * half_width_m_) - 0.5 * fr;
  const double fs = -fq - fr;
  double q = std::round(fq);
  double r = std::round(fr);
  const double s = std::round(fs);
  const double dq = std::abs(q - fq);
  const double dr = std::abs(r - fr);
  const double ds = std::abs(s - fs);
  if (dq > dr && dq > ds) {
    q = -r - s;
  } else if (dr > ds) {
    r = -q - s;
  }
  bool saturated = false;
  Hex h{SaturatedAxial(q, &saturated), SaturatedAxial(r, &saturated)};
  // Out of range: the bisector tests would walk toward a point that cannot be reached.
  if (saturated) return h;
  // Settle boundary points with the same bisector test Traverse stops on. Within 1e-9*R of a
  // vertex the tolerant test can in principle cycle, hence the bound.
  for (int step = 0; step < 8; ++step) {
    const Base base = BisectorBase(h);
    int past = -1;
    for (int e = 0; e < kEdges && past < 0; ++e) {
      if (IsPast(PastBisector(base, e, x, y), e)) past = e;
    }
    if (past < 0) break;
    h = Neighbor(h, past);
  }
  return h;
}

std::vector<Crossing> HexGrid::Crossings(double x0, double y0, double x1, double y1) const {
  std::vector<Crossing> out;
  Traverse(HexAt(x0, y0), x0, y0, x1, y1, [&out](const Crossing& c) { out.push_back(c); });
  return out;
}

}  // namespace grove::footslam
