#include "engine/footslam/htree_layout.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "engine/footslam/hex_grid.h"

namespace grove::footslam {
namespace {

HTreeLayout Make(int grid_size, int degree) {
  StatusOr<HTreeLayout> l = HTreeLayout::Create(grid_size, degree);
  EXPECT_TRUE(l.ok()) << l.status().ToString();
  return *std::move(l);
}

int SideOf(int degree) { return static_cast<int>(std::lround(std::sqrt(degree))); }

// The hexagon of a cell, straight from the layout's definition.
Hex HexOfCell(int n, int64_t col, int64_t row) {
  const int64_t r = row - n / 2;
  const int64_t q = col - n / 2 - static_cast<int64_t>(std::floor(r / 2.0));
  return Hex{static_cast<int32_t>(q), static_cast<int32_t>(r)};
}

// The key by its definition: base-s digits from the root, col_digit * s_x + row_digit.
uint64_t KeyByDigits(int n, int degree, uint64_t col, uint64_t row) {
  const uint64_t side = SideOf(degree);
  uint64_t key = 0;
  for (uint64_t div = n / side; div >= 1; div /= side) {
    key = key * degree + ((col / div) % side) * side + (row / div) % side;
  }
  return key;
}

TEST(HTreeLayoutTest, AccessorsDescribeTheTree) {
  const HTreeLayout a = Make(256, 4);
  EXPECT_EQ(a.grid_size(), 256);
  EXPECT_EQ(a.degree(), 4);
  EXPECT_EQ(a.log2_degree(), 2);
  EXPECT_EQ(a.height(), 8);
  EXPECT_EQ(Make(256, 16).height(), 4);
  EXPECT_EQ(Make(256, 256).height(), 2);
  EXPECT_EQ(Make(512, 64).height(), 3);
  EXPECT_EQ(Make(512, 64).log2_degree(), 6);
  EXPECT_EQ(Make(16, 256).height(), 1);
}

TEST(HTreeLayoutTest, KeysFollowTheDigitsOfColumnAndRowOverTheWholeGrid) {
  for (int degree : {4, 16, 64, 256}) {
    const int side = SideOf(degree);
    for (int n = side; n <= 512; n *= side) {
      SCOPED_TRACE(testing::Message() << "degree " << degree << " grid " << n);
      const HTreeLayout l = Make(n, degree);
      std::vector<bool> seen(static_cast<size_t>(n) * n, false);
      for (int col = 0; col < n; ++col) {
        for (int row = 0; row < n; ++row) {
          const Hex h = HexOfCell(n, col, row);
          uint32_t c, w;
          ASSERT_TRUE(l.CellOf(h, &c, &w));
          ASSERT_EQ(c, static_cast<uint32_t>(col));
          ASSERT_EQ(w, static_cast<uint32_t>(row));
          uint64_t key;
          ASSERT_TRUE(l.KeyOf(h, &key));
          ASSERT_EQ(key, KeyByDigits(n, degree, col, row)) << "cell " << col << ", " << row;
          ASSERT_LT(key, seen.size());
          ASSERT_FALSE(seen[key]) << "key " << key << " used twice";
          seen[key] = true;
          ASSERT_EQ(l.HexOfKey(key), h);
        }
      }
    }
  }
}

TEST(HTreeLayoutTest, TwoByTwoBlockSharesAllButTheLastDigit) {
  // The paper's Fig. 1: a 4 x 4 grid of degree 4; hexagons 1, 2, 5, 6 hang from one node.
  const HTreeLayout l = Make(4, 4);
  for (int bc = 0; bc < 2; ++bc) {
    for (int br = 0; br < 2; ++br) {
      std::vector<uint64_t> lasts;
      for (int dc = 0; dc < 2; ++dc) {
        for (int dr = 0; dr < 2; ++dr) {
          uint64_t key;
          ASSERT_TRUE(l.KeyOf(HexOfCell(4, 2 * bc + dc, 2 * br + dr), &key));
          EXPECT_EQ(key / 4, static_cast<uint64_t>(bc * 2 + br));  // the root's child
          lasts.push_back(key % 4);
        }
      }
      EXPECT_EQ(lasts, (std::vector<uint64_t>{0, 1, 2, 3}));
    }
  }
  uint64_t key;
  ASSERT_TRUE(l.KeyOf(HexOfCell(4, 3, 1), &key));  // col 11b, row 01b: digits 2 then 3
  EXPECT_EQ(key, 2u * 4 + 3);
}

TEST(HTreeLayoutTest, HexagonZeroIsTheCentreCell) {
  const HTreeLayout l = Make(64, 16);
  uint32_t col, row;
  ASSERT_TRUE(l.CellOf(Hex{0, 0}, &col, &row));
  EXPECT_EQ(col, 32u);
  EXPECT_EQ(row, 32u);
}

TEST(HTreeLayoutTest, GridIsARectangleInMetres) {
  // Column c holds the centres with x in [sqrt(3)*(c - N/2), +sqrt(3)/2] (R = 1), row w those
  // with y = 1.5*(w - N/2).
  const HexGrid g(1.0);
  const int n = 16;
  const HTreeLayout l = Make(n, 4);
  int inside = 0;
  for (int q = -30; q <= 30; ++q) {
    for (int r = -20; r <= 20; ++r) {
      uint32_t col, row;
      if (!l.CellOf(Hex{q, r}, &col, &row)) continue;
      ++inside;
      double x, y;
      g.Center(Hex{q, r}, &x, &y);
      const double left = std::sqrt(3.0) * (static_cast<double>(col) - n / 2);
      EXPECT_GE(x, left - 1e-9) << Hex{q, r};
      EXPECT_LE(x, left + std::sqrt(3.0) / 2 + 1e-9) << Hex{q, r};
      EXPECT_NEAR(y, 1.5 * (static_cast<double>(row) - n / 2), 1e-9) << Hex{q, r};
    }
  }
  EXPECT_EQ(inside, n * n);
}

TEST(HTreeLayoutTest, HexagonsOutsideTheGridHaveNoKey) {
  for (int degree : {4, 16}) {
    const int n = 16;
    const HTreeLayout l = Make(n, degree);
    int inside = 0;
    for (int q = -30; q <= 30; ++q) {
      for (int r = -20; r <= 20; ++r) {
        const Hex h{q, r};
        const int64_t row = r + n / 2;
        const int64_t col = q + static_cast<int64_t>(std::floor(r / 2.0)) + n / 2;
        const bool expected = row >= 0 && row < n && col >= 0 && col < n;
        uint32_t c, w;
        uint64_t key;
        EXPECT_EQ(l.CellOf(h, &c, &w), expected) << h;
        EXPECT_EQ(l.KeyOf(h, &key), expected) << h;
        inside += expected;
      }
    }
    EXPECT_EQ(inside, n * n);
  }
  const HTreeLayout l = Make(4, 4);
  uint64_t key;
  EXPECT_FALSE(l.KeyOf(Hex{INT32_MAX, INT32_MIN}, &key));
  EXPECT_FALSE(l.KeyOf(Hex{INT32_MIN, INT32_MAX}, &key));
}

TEST(HTreeLayoutTest, LargestGridsRoundTripTheirCorners) {
  const std::pair<int, int> grids[] = {{1 << 30, 4}, {1 << 30, 16}, {1 << 30, 64}, {1 << 28, 256}};
  for (const auto& [n, degree] : grids) {
    SCOPED_TRACE(testing::Message() << "degree " << degree << " grid " << n);
    const HTreeLayout l = Make(n, degree);
    const int64_t last = n - 1;
    const std::pair<int64_t, int64_t> cells[] = {{0, 0},       {last, 0},      {0, last},
                                                 {last, last}, {n / 2, n / 2}, {12345, last - 777}};
    for (const auto& [col, row] : cells) {
      const Hex h = HexOfCell(n, col, row);
      uint64_t key;
      ASSERT_TRUE(l.KeyOf(h, &key));
      EXPECT_EQ(key, KeyByDigits(n, degree, col, row));
      EXPECT_EQ(l.HexOfKey(key), h);
    }
    uint64_t key;
    ASSERT_TRUE(l.KeyOf(HexOfCell(n, last, last), &key));
    EXPECT_EQ(key, static_cast<uint64_t>(n) * n - 1);
  }
}

// A growing layout nests the first grid in ever larger ones: a hexagon of the first grid keeps
// its fixed key's digits below the first grid's height, every first-grid key has the fill key's
// digits above it, each nested grid holds the last one, and far hexagons round-trip.
TEST(HTreeLayoutTest, AGrowingLayoutNestsTheFirstGridAndKeepsItsKeys) {
  for (int degree : {4, 16, 64, 256}) {
    const int side = SideOf(degree);
    const int n = side * side;
    SCOPED_TRACE(testing::Message() << "degree " << degree);
    const HTreeLayout fixed = Make(n, degree);
    StatusOr<HTreeLayout> made = HTreeLayout::Create(n, degree, FootSlamGrid::kGrowing);
    ASSERT_TRUE(made.ok());
    const HTreeLayout& grow = *made;
    EXPECT_EQ(grow.height(), fixed.height());
    EXPECT_EQ(fixed.max_grid_size(), n);
    EXPECT_LE(grow.max_grid_size(), HTreeLayout::kMaxGrowingSize);
    EXPECT_GT(grow.max_grid_size() * side, HTreeLayout::kMaxGrowingSize);
    const int low_bits = fixed.log2_degree() * fixed.height();
    const uint64_t low_mask = (uint64_t{1} << low_bits) - 1;
    for (int64_t col = 0; col < n; ++col) {
      for (int64_t row = 0; row < n; ++row) {
        const Hex h = HexOfCell(n, col, row);
        uint64_t fixed_key, key;
        ASSERT_TRUE(fixed.KeyOf(h, &fixed_key));
        ASSERT_TRUE(grow.KeyOf(h, &key));
        ASSERT_EQ(key & low_mask, fixed_key) << h;
        ASSERT_EQ(key >> low_bits, grow.fill_key() >> low_bits) << h;
        ASSERT_EQ(grow.HeightOf(key), grow.height()) << h;
        ASSERT_EQ(grow.HexOfKey(key), h);
      }
    }
    // Walking out along the axes the nested grid needed never shrinks (with s_x = 2 a grid
    // reaches past the last on one side only, so a level can be skipped), and the start stays
    // well inside the largest grid (between 1/4 and 3/4 of it on each axis).
    for (const Hex dir : {Hex{1, 0}, Hex{-1, 0}, Hex{0, 1}, Hex{0, -1}}) {
      int last = grow.height();
      for (int32_t k = 0; k < 4 * n * side; ++k) {
        const Hex h{dir.q * k, dir.r * k};
        uint64_t key;
        ASSERT_TRUE(grow.KeyOf(h, &key));
        const int height = grow.HeightOf(key);
        ASSERT_GE(height, last) << h;
        ASSERT_LE(height, grow.max_height()) << h;
        last = height;
        ASSERT_EQ(grow.HexOfKey(key), h);
      }
      EXPECT_GT(last, grow.height());
    }
    uint32_t col, row;
    ASSERT_TRUE(grow.CellOf(Hex{0, 0}, &col, &row));
    EXPECT_GT(col, grow.max_grid_size() / 4);
    EXPECT_LT(col, 3 * grow.max_grid_size() / 4);
    // The corners of the largest grid round-trip; beyond it there is no key.
    const int64_t m = grow.max_grid_size();
    for (const auto& [c, r] :
         {std::pair<int64_t, int64_t>{0, 0}, {m - 1, 0}, {0, m - 1}, {m - 1, m - 1}}) {
      const int64_t rr = r - row;
      const Hex h{static_cast<int32_t>(c - col - (rr >> 1)), static_cast<int32_t>(rr)};
      uint64_t key;
      ASSERT_TRUE(grow.KeyOf(h, &key)) << h;
      EXPECT_LT(key, grow.key_count());
      EXPECT_LE(grow.HeightOf(key), grow.max_height());
      EXPECT_EQ(grow.HexOfKey(key), h);
      uint64_t outside;
      EXPECT_FALSE(grow.KeyOf(Hex{h.q + (c == 0 ? -1 : 1), h.r}, &outside));
    }
  }
}

void ExpectRejected(int grid_size, int degree, const std::string& message) {
  const StatusOr<HTreeLayout> l = HTreeLayout::Create(grid_size, degree);
  ASSERT_FALSE(l.ok()) << grid_size << ", " << degree;
  EXPECT_EQ(l.status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(l.status().message(), message);
}

TEST(HTreeLayoutTest, CreateRejectsBadDegreesAndSizesNamingTheField) {
  ExpectRejected(256, 8, "degree = 8: must be one of 4, 16, 64, 256");
  ExpectRejected(256, 2, "degree = 2: must be one of 4, 16, 64, 256");
  ExpectRejected(256, 0, "degree = 0: must be one of 4, 16, 64, 256");
  ExpectRejected(256, 1024, "degree = 1024: must be one of 4, 16, 64, 256");
  ExpectRejected(100, 16, "grid_size = 100: must be a power of the degree's side 4 (degree 16)");
  ExpectRejected(8, 16, "grid_size = 8: must be a power of the degree's side 4 (degree 16)");
  ExpectRejected(0, 4, "grid_size = 0: must be a power of the degree's side 2 (degree 4)");
  ExpectRejected(-4, 4, "grid_size = -4: must be a power of the degree's side 2 (degree 4)");
  ExpectRejected(1, 4, "grid_size = 1: must be at least the degree's side 2 (degree 4)");
  ExpectRejected(1, 256, "grid_size = 1: must be at least the degree's side 16 (degree 256)");
}

}  // namespace
}  // namespace grove::footslam
