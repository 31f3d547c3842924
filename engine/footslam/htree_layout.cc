#include "engine/footslam/htree_layout.h"

#include <string>

namespace grove::footslam {

StatusOr<HTreeLayout> HTreeLayout::Create(int grid_size, int degree) {
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
  return HTreeLayout(grid_size, side_bits, height);
}

HTreeLayout::HTreeLayout(int grid_size, int side_bits, int height)
    : grid_size_(grid_size),
      side_bits_(side_bits),
      height_(height),
      half_(grid_size / 2),
      rounds_(0) {
  while ((1 << rounds_) < height_) ++rounds_;
  const uint64_t digit = (uint64_t{1} << side_bits_) - 1;
  for (int j = 0; j <= rounds_; ++j) {
    const int64_t low = (int64_t{1} << j) - 1;
    for (int64_t i = 0; i < height_; ++i) {
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
  const int64_t r = row - half_;
  const int64_t q = col - half_ - (r >> 1);
  return Hex{static_cast<int32_t>(q), static_cast<int32_t>(r)};
}

}  // namespace grove::footslam
