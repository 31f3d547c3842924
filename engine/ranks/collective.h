// The engine's side of a filter across ranks (grove/collective.h): how the particles are split
// into shares, the rank records of a checkpoint, and gathers of values.
//
// Every rank holds a contiguous share of the particles, whole blocks of kSumBlock in rank order
// (RankShare), so the per-block sums a single process takes in block order are the same sums,
// gathered in rank order: the same seed gives the same bits at any rank count.
#ifndef GROVE_ENGINE_RANKS_COLLECTIVE_H_
#define GROVE_ENGINE_RANKS_COLLECTIVE_H_

#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "grove/collective.h"
#include "grove/status.h"

namespace grove {

// Rank `rank` of `ranks` holds blocks [rank * B / ranks, (rank + 1) * B / ranks) of the
// B = ceil(total / block) blocks of `block` particles.
inline ParticleShare RankShare(uint64_t total, int ranks, int rank, uint64_t block) {
  const uint64_t blocks = (total + block - 1) / block;
  const uint64_t b0 = blocks * static_cast<uint64_t>(rank) / static_cast<uint64_t>(ranks);
  const uint64_t b1 = blocks * static_cast<uint64_t>(rank + 1) / static_cast<uint64_t>(ranks);
  const uint64_t first = b0 * block < total ? b0 * block : total;
  const uint64_t end = b1 * block < total ? b1 * block : total;
  return ParticleShare{first, end - first};
}

// This rank's share of `total` particles in blocks of `block` (without ranks, null: all).
inline ParticleShare ShareOf(uint64_t total, const Collective* ranks, uint64_t block) {
  if (ranks == nullptr) return ParticleShare{0, total};
  return RankShare(total, ranks->size(), ranks->rank(), block);
}

// InvalidArgument unless each of `ranks` ranks gets at least one block of `block` particles of
// `total` (more than block * (ranks - 1) particles).
Status CheckRankShares(uint64_t total, int ranks, uint64_t block);

// InvalidArgument unless `islands` islands of whole blocks of `block` particles fit `total`
// particles and divide among `ranks` ranks (island mode, FilterOptions::islands; OK for 1).
Status CheckIslands(uint64_t total, int islands, int ranks, uint64_t block);

class ByteReader;
class ByteWriter;

// A checkpoint of one rank's share names its rank and rank count after the head (`ranks` null:
// rank 0 of 1). Reading refuses, FailedPrecondition naming both, another rank's file or one of
// another rank count (DataLoss for a rank that is not one of the count).
void WriteCheckpointRank(ByteWriter* w, const Collective* ranks);
Status ReadCheckpointRank(ByteReader* r, const Collective* ranks);
// Collective: FailedPrecondition on every rank unless every rank's checkpoint was made after the
// same step (the files of one checkpoint, not of two).
Status CheckCheckpointSteps(Collective& c, int64_t steps);

// Every rank's values of a trivially copyable type, concatenated in rank order.
template <typename T>
Status AllGatherValues(Collective& c, std::span<const T> mine, std::vector<T>* all) {
  static_assert(std::is_trivially_copyable_v<T>);
  std::vector<std::string> parts;
  GROVE_RETURN_IF_ERROR(c.AllGather(
      std::string(reinterpret_cast<const char*>(mine.data()), mine.size_bytes()), &parts));
  all->clear();
  for (const std::string& p : parts) {
    if (p.size() % sizeof(T) != 0) return InternalError("collective: a part is not whole values");
    const size_t at = all->size();
    all->resize(at + p.size() / sizeof(T));
    if (!p.empty()) std::memcpy(all->data() + at, p.data(), p.size());
  }
  return Status::Ok();
}

// Every rank's `mine` concatenated in rank order, or `mine` alone without ranks (null).
template <typename T>
StatusOr<std::vector<T>> GatherOverRanks(Collective* c, std::vector<T> mine) {
  if (c == nullptr) return mine;
  std::vector<T> all;
  GROVE_RETURN_IF_ERROR(AllGatherValues<T>(*c, mine, &all));
  return all;
}

}  // namespace grove

#endif  // GROVE_ENGINE_RANKS_COLLECTIVE_H_
