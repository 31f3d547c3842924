// HTreeLayout: where each hexagon sits in the global H-tree, computed, never stored.
//
// Source: Garcia Puyol, Robertson, Heirich, "Complexity-reduced FootSLAM for indoor pedestrian
// navigation", Sec. IV-A and Fig. 1. The grid of N x N hexagons is a balanced tree of degree
// s = s_x * s_x; each level splits a block of cells into s_x columns by s_x rows. The paper keeps a
// hash table of paths; here the path is the key itself: its base-s digits, most significant first,
// are the child taken at each level from the root, digit = col_digit * s_x + row_digit, where
// col_digit and row_digit are the base-s_x digits of the cell's column and row at that level.
// Nearby hexagons therefore share long key prefixes.
//
// The grid is centred on hexagon (0,0) with offset rows, so it is a rectangle in metres:
// col = q + floor(r/2) + N/2, row = r + N/2.
//
// A growing layout nests that grid in ever larger ones, up to the largest that fits (at most
// 2^26 hexagons per side): the grid of height h is the block (g_h, g_h) of the grid of height
// h + 1, g_h alternating between s_x/2 - 1 and s_x/2 so the start stays near the middle. Keys
// are those of the largest grid, col = q + floor(r/2) + offset: a hexagon of the first grid
// keeps its fixed layout's digits below the first grid's height, and every key of the first
// grid has the digits (g_h, g_h) above it, the fill key of a trie that grows (PersistentTrie).
//
// Thread safety: immutable after Create; all methods may be called concurrently.
#ifndef GROVE_ENGINE_FOOTSLAM_HTREE_LAYOUT_H_
#define GROVE_ENGINE_FOOTSLAM_HTREE_LAYOUT_H_

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>

#include "engine/footslam/hex_grid.h"
#include "grove/footslam.h"
#include "grove/status.h"

namespace grove::footslam {

class HTreeLayout {
 public:
  // The largest grid a growing layout nests its first grid in: 2^26 hexagons per side, or the
  // largest power of s_x below it (58,000 km at a 0.5 m radius).
  static constexpr int64_t kMaxGrowingSize = int64_t{1} << 26;

  // degree must be 4, 16, 64 or 256 (s_x = 2, 4, 8, 16); grid_size N must be a power of s_x and
  // at least s_x. An int N is at most 2^30, so keys (< N*N) fit 60 bits and hexagon coordinates
  // of every cell fit int32. InvalidArgument naming the field, its value and the rule otherwise.
  // With kGrowing, N is the first grid's size, nested in grids up to kMaxGrowingSize.
  static StatusOr<HTreeLayout> Create(int grid_size, int degree,
                                      FootSlamGrid grid = FootSlamGrid::kFixed);

  // The first grid's hexagons per side, N.
  int grid_size() const { return grid_size_; }
  // Hexagons per side of the largest grid: N when fixed.
  int64_t max_grid_size() const { return max_size_; }
  int degree() const { return 1 << (2 * side_bits_); }
  int log2_degree() const { return 2 * side_bits_; }
  // Levels from the root to the leaves of the first grid: log_{s_x} N.
  int height() const { return height_; }
  // Levels of the largest grid: height() when fixed.
  int max_height() const { return max_height_; }
  // Number of keys, the largest grid's size squared: every key below it is a hexagon of it.
  uint64_t key_count() const { return static_cast<uint64_t>(max_size_) * max_size_; }
  // The key of hexagon (0, 0): above height() its digits are those of every first-grid key.
  uint64_t fill_key() const {
    const uint64_t spread = Spread(static_cast<uint32_t>(offset_));
    return (spread << side_bits_) | spread;
  }

  // Levels of the smallest nested grid that holds `key`'s hexagon: at least height().
  // REQUIRES: key < key_count().
  int HeightOf(uint64_t key) const {
    const int bits = std::bit_width(key ^ fill_key());
    return std::max(height_, (bits + 2 * side_bits_ - 1) / (2 * side_bits_));
  }

  // The cell of h in the largest grid; false if h is outside it.
  bool CellOf(Hex h, uint32_t* col, uint32_t* row) const {
    const int64_t r = h.r;
    const int64_t c = int64_t{h.q} + (r >> 1) + offset_;  // >> floors negative r (C++20)
    const int64_t w = r + offset_;
    if (static_cast<uint64_t>(c) >= static_cast<uint64_t>(max_size_) ||
        static_cast<uint64_t>(w) >= static_cast<uint64_t>(max_size_)) {
      return false;
    }
    *col = static_cast<uint32_t>(c);
    *row = static_cast<uint32_t>(w);
    return true;
  }

  // The leaf key (path) of h in [0, key_count()); false if h is outside the largest grid.
  bool KeyOf(Hex h, uint64_t* key) const {
    uint32_t col, row;
    if (!CellOf(h, &col, &row)) return false;
    *key = (Spread(col) << side_bits_) | Spread(row);
    return true;
  }

  // REQUIRES: key < key_count().
  Hex HexOfKey(uint64_t key) const;

 private:
  HTreeLayout(int grid_size, int side_bits, int height, int max_height);

  // Moves base-s_x digit i of v (side_bits_ bits) to bit 2*side_bits_*i, leaving gaps for the
  // row digits: the Morton-order bit spread with digits in place of bits, in ceil(log2(height))
  // shift-and-mask rounds (Warren, "Hacker's Delight", 2nd ed., Sec. 7-2, outer perfect shuffle).
  uint64_t Spread(uint32_t v) const {
    uint64_t x = v;
    for (int j = rounds_ - 1; j >= 0; --j) x = (x | (x << (side_bits_ << j))) & masks_[j];
    return x;
  }
  // The inverse of Spread; ignores the bits between digits.
  uint32_t Compact(uint64_t x) const;

  int grid_size_;
  int side_bits_;  // log2(s_x)
  int height_;
  int max_height_;
  int64_t max_size_;  // s_x^max_height_
  int64_t offset_;    // the cell of hexagon (0, 0) on each axis: N/2 when fixed
  int rounds_;        // ceil(log2(max_height_))
  // masks_[j]: where the digits sit once rounds j.. have run; masks_[rounds_] is the packed form.
  std::array<uint64_t, 6> masks_{};
};

}  // namespace grove::footslam

#endif  // GROVE_ENGINE_FOOTSLAM_HTREE_LAYOUT_H_
