#include "engine/footslam/htree_layout.h"

#include <string>

namespace grove::footslam {

StatusOr<HTreeLayout> HTreeLayout::Create(int grid_size, int degree, FootSlamGrid grid) {
  int side_bits = 0;
  switch (degree) {
    case 4:
      side_bits = 1;
      break;
    case 16:
      side_bits = 2;
      break;
    case 64:
      side_bits = 3;
      break;
    case 256:
      side_bits = 4;
      break;
    default:
      return InvalidArgumentError("degree = " + std::to_string(degree) +
                                  ": must be one of 4, 16, 64, 256");
  }
  const int side = 1 << side_bits;
  const std::string rule_tail = std::to_string(side) + " (degree " + std::to_string(degree) + ")";
  int height = 0;
  int64_t n = 1;
  while (n < grid_size) {
    n <<= side_bits;
    ++height;
  }
  if (n != grid_size) {
    return InvalidArgumentError("grid_size = " + std::to_string(grid_size) +
                                ": must be a power of the degree's side " + rule_tail);
  }
  if (height < 1) {
    return InvalidArgumentError("grid_size = " + std::to_string(grid_size) +
                                ": must be at least the degree's side " + rule_tail);
  }
  int max_height = height;
  if (grid == FootSlamGrid::kGrowing) {
    while ((n << side_bits) <= kMaxGrowingSize) {
      n <<= side_bits;
      ++max_height;
    }
  }
  return HTreeLayout(grid_size, side_bits, height, max_height);
}

HTreeLayout::HTreeLayout(int grid_size, int side_bits, int height, int max_height)
    : grid_size_(grid_size),
      side_bits_(side_bits),
      height_(height),
      max_height_(max_height),
      max_size_(int64_t{1} << (side_bits * max_height)),
      offset_(grid_size / 2),
      rounds_(0) {
  // Each grid is block (g, g) of the next: g alternates below and above the middle.
  const int64_t side = int64_t{1} << side_bits_;
  for (int h = height_; h < max_height_; ++h) {
    const int64_t g = (h - height_) % 2 == 0 ? side / 2 - 1 : side / 2;
    offset_ += g << (side_bits_ * h);
  }
  while ((1 << rounds_) < max_height_) ++rounds_;
  const uint64_t digit = (uint64_t{1} << side_bits_) - 1;
  for (int j = 0; j <= rounds_; ++j) {
    const int64_t low = (int64_t{1} << j) - 1;
    for (int64_t i = 0; i < max_height_; ++i) {
      // After rounds j.. digit i has moved up by the digits' worth of its index bits >= j.
      masks_[j] |= digit << (side_bits_ * (i + (i & ~low)));
    }
  }
}

uint32_t HTreeLayout::Compact(uint64_t x) const {
  x &= masks_[0];
  for (int j = 0; j < rounds_; ++j) x = (x | (x >> (side_bits_ << j))) & masks_[j + 1];
  return static_cast<uint32_t>(x);
}

Hex HTreeLayout::HexOfKey(uint64_t key) const {
  const int64_t col = Compact(key >> side_bits_);
  const int64_t row = Compact(key);
  const int64_t r = row - offset_;
  const int64_t q = col - offset_ - (r >> 1);
  return Hex{static_cast<int32_t>(q), static_cast<int32_t>(r)};
}

}  // namespace grove::footslam
