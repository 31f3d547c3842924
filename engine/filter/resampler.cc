#include "engine/filter/resampler.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "alloc/check.h"
#include "concurrency/random_stream.h"

namespace grove {
namespace {

// Stream keys for the resampler: one (step, particle) pair no particle uses.
constexpr uint32_t kResampleParticle = 0xFFFFFFFFu;

// Calls emit(i, k, k_end) for each particle i of block b (global block index, particles
// [begin, end) of `weights`, which starts at block first_block): the next generation's slots
// [k, k_end) copy particle i. Output slot k takes the particle whose cumulative interval holds
// (k + u) / n_out, so particle i gets slots [ceil(n_out * C_{i-1} - u), ceil(n_out * C_i - u)).
template <typename Emit>
void SystematicBlock(std::span<const double> weights, std::span<const double> prefix, size_t b,
                     size_t begin, size_t end, size_t n_out, double u, Emit&& emit) {
  const double scale = static_cast<double>(n_out) / prefix.back();
  auto first_slot = [&](double cumulative) {
    double x = std::ceil(cumulative * scale - u);
    return x <= 0 ? size_t{0} : std::min(n_out, static_cast<size_t>(x));
  };
  double c = prefix[b];
  size_t k = first_slot(c);
  for (size_t i = begin; i < end; ++i) {
    // The block's last particle ends exactly where the next block starts.
    c = i + 1 == end ? prefix[b + 1] : c + weights[i];
    size_t k_end = first_slot(c);
    emit(i, k, k_end);
    k = k_end;
  }
}

std::vector<double> BlockPrefix(std::span<const double> block_sum) {
  std::vector<double> prefix(block_sum.size() + 1, 0.0);
  for (size_t b = 0; b < block_sum.size(); ++b) prefix[b + 1] = prefix[b] + block_sum[b];
  return prefix;
}

}  // namespace

void SystematicResample(std::span<const double> weights, double u, WorkerPool& workers,
                        std::span<uint32_t> parents, std::span<const double> block_sums) {
  const size_t n_in = weights.size();
  const size_t n_out = parents.size();
  GROVE_DCHECK(block_sums.empty() || block_sums.size() == (n_in + kSumBlock - 1) / kSumBlock);
  std::vector<double> prefix =
      block_sums.empty() ? BlockPrefix(BlockSums(weights, workers)) : BlockPrefix(block_sums);
  workers.ParallelFor(prefix.size() - 1, 1, [&](int, size_t b0, size_t b1) {
    for (size_t b = b0; b < b1; ++b) {
      size_t begin = b * kSumBlock;
      size_t end = std::min(n_in, begin + kSumBlock);
      SystematicBlock(weights, prefix, b, begin, end, n_out, u, [&](size_t i, size_t k, size_t e) {
        for (; k < e; ++k) parents[k] = static_cast<uint32_t>(i);
      });
    }
  });
}

namespace {

// Expands offspring counts into a nondecreasing parent list.
void ExpandCounts(const std::vector<uint32_t>& counts, std::span<uint32_t> parents) {
  size_t k = 0;
  for (size_t i = 0; i < counts.size(); ++i) {
    for (uint32_t c = 0; c < counts[i]; ++c) parents[k++] = static_cast<uint32_t>(i);
  }
}

// Assigns sorted points in [0, total) to the particles whose cumulative interval holds them.
void AssignSorted(std::span<const double> weights, const std::vector<double>& sorted_points,
                  std::vector<uint32_t>* counts) {
  size_t i = 0;
  double c = weights.empty() ? 0 : weights[0];
  for (double point : sorted_points) {
    while (point >= c && i + 1 < weights.size()) c += weights[++i];
    ++(*counts)[i];
  }
}

}  // namespace

std::vector<double> BlockSums(std::span<const double> weights, WorkerPool& workers) {
  return workers.MapBlocks<double>(weights.size(), kSumBlock,
                                   [&](size_t, size_t begin, size_t end) {
                                     double s = 0;
                                     for (size_t i = begin; i < end; ++i) s += weights[i];
                                     return s;
                                   });
}

double SystematicUniform(uint64_t seed, uint64_t step) {
  return RandomStream(seed, step, kResampleParticle, StreamPurpose::kResample).NextUniform();
}

double IslandUniform(uint64_t seed, uint64_t step, uint32_t island, uint32_t draw) {
  return RandomStream(seed, step, 2 * island + draw, StreamPurpose::kIslandResample).NextUniform();
}

void SystematicSlots(std::span<const double> weights, size_t first_block,
                     std::span<const double> block_sums, size_t n_out, double u,
                     WorkerPool& workers, std::span<uint64_t> slots) {
  const size_t n = weights.size();
  std::vector<double> prefix = BlockPrefix(block_sums);
  if (n == 0) return;
  const size_t blocks = (n + kSumBlock - 1) / kSumBlock;
  workers.ParallelFor(blocks, 1, [&](int, size_t b0, size_t b1) {
    for (size_t b = b0; b < b1; ++b) {
      size_t begin = b * kSumBlock;
      size_t end = std::min(n, begin + kSumBlock);
      SystematicBlock(weights, prefix, first_block + b, begin, end, n_out, u,
                      [&](size_t i, size_t k, size_t e) {
                        slots[i] = k;
                        if (i + 1 == n) slots[n] = e;
                      });
    }
  });
}

const char* ResamplingSchemeName(ResamplingScheme scheme) {
  switch (scheme) {
    case ResamplingScheme::kSystematic:
      return "systematic";
    case ResamplingScheme::kStratified:
      return "stratified";
    case ResamplingScheme::kResidual:
      return "residual";
    case ResamplingScheme::kMultinomial:
      return "multinomial";
  }
  return "unknown";
}

bool ParseResamplingScheme(std::string_view name, ResamplingScheme* scheme) {
  for (ResamplingScheme s : {ResamplingScheme::kSystematic, ResamplingScheme::kStratified,
                             ResamplingScheme::kResidual, ResamplingScheme::kMultinomial}) {
    if (name == ResamplingSchemeName(s)) {
      *scheme = s;
      return true;
    }
  }
  return false;
}

void Resample(ResamplingScheme scheme, std::span<const double> weights, uint64_t seed,
              uint64_t step, WorkerPool& workers, std::span<uint32_t> parents,
              std::span<const double> block_sums) {
  if (scheme == ResamplingScheme::kSystematic) {
    SystematicResample(weights, SystematicUniform(seed, step), workers, parents, block_sums);
    return;
  }
  RandomStream stream(seed, step, kResampleParticle, StreamPurpose::kResample);
  const size_t n = parents.size();
  double total = 0;
  for (double w : weights) total += w;
  std::vector<uint32_t> counts(weights.size(), 0);
  std::vector<double> points;
  switch (scheme) {
    case ResamplingScheme::kStratified:
      points.resize(n);
      for (size_t k = 0; k < n; ++k) points[k] = (k + stream.NextUniform()) / n * total;
      AssignSorted(weights, points, &counts);
      break;
    case ResamplingScheme::kMultinomial:
      points.resize(n);
      for (size_t k = 0; k < n; ++k) points[k] = stream.NextUniform() * total;
      std::sort(points.begin(), points.end());
      AssignSorted(weights, points, &counts);
      break;
    case ResamplingScheme::kResidual: {
      std::vector<double> residual(weights.size());
      size_t assigned = 0;
      for (size_t i = 0; i < weights.size(); ++i) {
        double expected = weights[i] / total * n;
        double whole = std::floor(expected);
        counts[i] = static_cast<uint32_t>(whole);
        assigned += counts[i];
        residual[i] = expected - whole;
      }
      // Rounding can leave the floors summing past n by a hair: trim from the largest.
      while (assigned > n) {
        auto it = std::max_element(counts.begin(), counts.end());
        --*it;
        --assigned;
      }
      size_t rest = n - assigned;
      double residual_total = 0;
      for (double r : residual) residual_total += r;
      if (rest > 0 && residual_total > 0) {
        points.resize(rest);
        for (size_t k = 0; k < rest; ++k) points[k] = stream.NextUniform() * residual_total;
        std::sort(points.begin(), points.end());
        AssignSorted(residual, points, &counts);
      } else if (rest > 0) {
        counts[0] += static_cast<uint32_t>(rest);
      }
      break;
    }
    case ResamplingScheme::kSystematic:
      break;
  }
  ExpandCounts(counts, parents);
}

}  // namespace grove
