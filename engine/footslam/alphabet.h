// Alphabet: one 16-bit symbol per combination of six small transition counters.
//
// Source: Garcia Puyol, Robertson, Heirich, "Complexity-reduced FootSLAM for indoor pedestrian
// navigation", Sec. V. With each counter in 0..T there are S = (T+1)^6 symbols; a leaf stores a
// symbol instead of six counters until a counter would pass T, and the symbol after a crossing
// of edge e is precomputed (Fig. 6).
//
// Symbol s is the mixed-radix number with digit e = counter e in base T+1, counter 0 least
// significant: symbol 0 is {0,0,0,0,0,0}, symbol S-1 is {T,...,T}, and Next(0, e) = (T+1)^e.
//
// Thread safety: immutable after Create; all methods may be called concurrently.
#ifndef GROVE_ENGINE_FOOTSLAM_ALPHABET_H_
#define GROVE_ENGINE_FOOTSLAM_ALPHABET_H_

#include <array>
#include <cstdint>
#include <vector>

#include "grove/status.h"

namespace grove::footslam {

class Alphabet {
 public:
  static constexpr int kEdges = 6;
  static constexpr int kMaxCount = 5;  // (5+1)^6 = 46656 symbols fit below kOverflow
  // Next() of a symbol whose counter is already T: the leaf must switch to full counters.
  static constexpr uint16_t kOverflow = 0xFFFF;

  // Builds the tables for counters in 0..max_count. InvalidArgument unless 1 <= max_count <= 5
  // (0 means "alphabet off" and is the caller's case, not a value of this class).
  static StatusOr<Alphabet> Create(int max_count);

  int max_count() const { return max_count_; }
  int symbol_count() const { return symbol_count_; }

  // REQUIRES: counts[e] <= max_count() for every e.
  uint16_t Encode(const uint32_t counts[kEdges]) const {
    uint32_t s = 0;
    for (int e = 0; e < kEdges; ++e) s += counts[e] * place_[e];
    return static_cast<uint16_t>(s);
  }
  // REQUIRES: s < symbol_count() for Decode, Next, Count and Total; 0 <= edge < 6.
  void Decode(uint16_t s, uint32_t counts[kEdges]) const {
    for (int e = 0; e < kEdges; ++e) counts[e] = counts_[s * kEdges + e];
  }
  // The symbol after one more crossing of `edge`, or kOverflow if that counter is at T.
  uint16_t Next(uint16_t s, int edge) const { return next_[s * kEdges + edge]; }
  uint32_t Count(uint16_t s, int edge) const { return counts_[s * kEdges + edge]; }
  uint32_t Total(uint16_t s) const { return total_[s]; }

 private:
  explicit Alphabet(int max_count);

  int max_count_;
  int symbol_count_;
  std::array<uint32_t, kEdges> place_;  // (T+1)^e
  std::vector<uint16_t> next_;          // [s * 6 + e]
  std::vector<uint8_t> counts_;         // [s * 6 + e]
  std::vector<uint16_t> total_;         // [s]
};

}  // namespace grove::footslam

#endif  // GROVE_ENGINE_FOOTSLAM_ALPHABET_H_
