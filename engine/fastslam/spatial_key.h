// Spatial keys for landmark maps: a landmark trie keyed by position, so that the landmarks near
// a point are a range query over the trie (PersistentTrie::ForEachIf) whose cost is the cells it
// visits, not the size of the map, and a particle copy stays one reference.
//
// The plane is cut into square cells of side cell_m; cell (cx, cy) holds the points with
// floor(x / cell_m) = cx, floor(y / cell_m) = cy. A key is
//   key = Morton(zigzag(cx), zigzag(cy)) << kSlotBits | slot,
// zigzag mapping 0, -1, 1, -2, 2, ... to 0, 1, 2, 3, 4, ... and Morton interleaving the bits (x
// in the even bits). Keys near the origin are small, so a map grows in height with its extent
// (the trie grows above its root), and a cell's kSlotsPerCell slots are consecutive keys: one
// bottom node of a degree-8 trie, or an eighth of a packed bottom node of 64 (FastSLAM's spatial
// maps; PersistentTrie::ForEachIf, which asks about nodes, then decides per 8 cells). A block
// of keys sharing a prefix covers, on each axis, at most two intervals of cells (the non-negative
// and the negative ones): KeyRangeMayHit() tests such a block against a rectangle of cells exactly.
//
// Extent: |cx|, |cy| <= kMaxCell (2^29 - 1), so keys use at most 63 bits.
#ifndef GROVE_ENGINE_FASTSLAM_SPATIAL_KEY_H_
#define GROVE_ENGINE_FASTSLAM_SPATIAL_KEY_H_

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

namespace grove::fastslam {

inline constexpr int kSlotBits = 3;  // = the landmark trie's log2 degree
inline constexpr int kSlotsPerCell = 1 << kSlotBits;
inline constexpr int64_t kMaxCell = (int64_t{1} << 29) - 1;

struct Cell {
  int64_t x = 0;
  int64_t y = 0;
  bool operator==(const Cell&) const = default;
};

// Cells [x0, x1] x [y0, y1], inclusive.
struct CellRect {
  int64_t x0 = 0, x1 = -1, y0 = 0, y1 = -1;
  bool Contains(const Cell& c) const { return c.x >= x0 && c.x <= x1 && c.y >= y0 && c.y <= y1; }
};

namespace spatial_detail {

inline uint64_t Zigzag(int64_t v) {
  return v >= 0 ? static_cast<uint64_t>(v) << 1 : (static_cast<uint64_t>(-(v + 1)) << 1) | 1;
}
inline int64_t Unzigzag(uint64_t z) {
  return (z & 1) == 0 ? static_cast<int64_t>(z >> 1) : -static_cast<int64_t>(z >> 1) - 1;
}
// The low 32 bits of v spread to the even bits of the result.
inline uint64_t Spread(uint64_t v) {
  v &= 0xFFFFFFFFu;
  v = (v | (v << 16)) & 0x0000FFFF0000FFFFull;
  v = (v | (v << 8)) & 0x00FF00FF00FF00FFull;
  v = (v | (v << 4)) & 0x0F0F0F0F0F0F0F0Full;
  v = (v | (v << 2)) & 0x3333333333333333ull;
  v = (v | (v << 1)) & 0x5555555555555555ull;
  return v;
}
// The even bits of v packed into the low 32 bits.
inline uint64_t Compact(uint64_t v) {
  v &= 0x5555555555555555ull;
  v = (v | (v >> 1)) & 0x3333333333333333ull;
  v = (v | (v >> 2)) & 0x0F0F0F0F0F0F0F0Full;
  v = (v | (v >> 4)) & 0x00FF00FF00FF00FFull;
  v = (v | (v >> 8)) & 0x0000FFFF0000FFFFull;
  v = (v | (v >> 16)) & 0x00000000FFFFFFFFull;
  return v;
}
}  // namespace spatial_detail

// The cell of (x, y); false when a coordinate is not finite or the cell is beyond kMaxCell.
// REQUIRES: cell_m > 0.
inline bool CellOf(double x, double y, double cell_m, Cell* out) {
  const double cx = std::floor(x / cell_m), cy = std::floor(y / cell_m);
  constexpr double kLimit = static_cast<double>(kMaxCell);
  if (!(std::fabs(cx) <= kLimit && std::fabs(cy) <= kLimit)) return false;
  *out = Cell{static_cast<int64_t>(cx), static_cast<int64_t>(cy)};
  return true;
}

// The key of slot `slot` of cell `c`. REQUIRES: |c.x|, |c.y| <= kMaxCell, 0 <= slot < 8.
inline uint64_t SpatialKey(const Cell& c, int slot) {
  using namespace spatial_detail;
  return ((Spread(Zigzag(c.x)) | (Spread(Zigzag(c.y)) << 1)) << kSlotBits) |
         static_cast<uint64_t>(slot);
}
inline Cell CellOfKey(uint64_t key) {
  using namespace spatial_detail;
  const uint64_t m = key >> kSlotBits;
  return Cell{Unzigzag(Compact(m)), Unzigzag(Compact(m >> 1))};
}
inline int SlotOfKey(uint64_t key) { return static_cast<int>(key & (kSlotsPerCell - 1)); }

// The cells that meet the box [x0, x1] x [y0, y1], clamped to the extent.
inline CellRect CellsBetween(double x0, double x1, double y0, double y1, double cell_m) {
  auto cell = [&](double v) {
    const double c = std::floor(v / cell_m);
    return static_cast<int64_t>(
        std::clamp(c, -static_cast<double>(kMaxCell) - 1, static_cast<double>(kMaxCell) + 1));
  };
  return CellRect{cell(x0), cell(x1), cell(y0), cell(y1)};
}
// The cells that meet the square of half-side `radius` around (x, y).
inline CellRect CellsAround(double x, double y, double radius, double cell_m) {
  return CellsBetween(x - radius, x + radius, y - radius, y + radius, cell_m);
}

// The cells of a key block [lo, hi] of the trie (hi - lo + 1 a power of two, lo a multiple of
// it): on each axis at most two intervals (the non-negative and the negative cells).
struct CellBlock {
  int64_t x_lo[2], x_hi[2], y_lo[2], y_hi[2];
  int x_count, y_count;
  bool Meets(const CellRect& r) const {
    bool x = false, y = false;
    for (int k = 0; k < x_count; ++k) x = x || (x_lo[k] <= r.x1 && x_hi[k] >= r.x0);
    for (int k = 0; k < y_count; ++k) y = y || (y_lo[k] <= r.y1 && y_hi[k] >= r.y0);
    return x && y;
  }
};

namespace spatial_detail {
// The cells whose zigzag codes are [a, a + 2^bits). REQUIRES: a a multiple of 2^bits, bits <= 40.
inline int ZigzagBlock(uint64_t a, int bits, int64_t* lo, int64_t* hi) {
  if (bits == 0) {
    lo[0] = hi[0] = Unzigzag(a);
    return 1;
  }
  const int64_t half = int64_t{1} << (bits - 1);  // codes of each sign in the block
  const int64_t base = static_cast<int64_t>(a >> 1);
  // Even codes: cells base .. base + half - 1; odd codes: cells -base - half .. -base - 1.
  lo[0] = base;
  hi[0] = base + half - 1;
  lo[1] = -base - half;
  hi[1] = -base - 1;
  return 2;
}
}  // namespace spatial_detail

inline CellBlock BlockOf(uint64_t lo, uint64_t hi) {
  using namespace spatial_detail;
  const uint64_t span = hi - lo;  // 2^s - 1
  const int s = span == ~uint64_t{0} ? 64 : std::countr_one(span);
  const int free_bits = std::max(s - kSlotBits, 0);  // low Morton bits free in the block
  const int x_bits = std::min((free_bits + 1) / 2, 40), y_bits = std::min(free_bits / 2, 40);
  const uint64_t m = lo >> kSlotBits;
  CellBlock b;
  b.x_count = ZigzagBlock(Compact(m), x_bits, b.x_lo, b.x_hi);
  b.y_count = ZigzagBlock(Compact(m >> 1), y_bits, b.y_lo, b.y_hi);
  return b;
}

// Whether the key block [lo, hi] holds a key of a cell in `rect`. Exact: false only when no
// key of the block lies in it.
inline bool KeyRangeMayHit(uint64_t lo, uint64_t hi, const CellRect& rect) {
  return BlockOf(lo, hi).Meets(rect);
}

}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_SPATIAL_KEY_H_
