#include "engine/ranks/collective.h"

#include <fmt/format.h>

#include <algorithm>
#include <barrier>

#include "engine/filter/resampler.h"
#include "engine/io/checkpoint_io.h"

namespace grove {

ParticleShare ShareOf(uint64_t total, const Collective* ranks) {
  return ShareOf(total, ranks, kSumBlock);
}

Status CheckRankShares(uint64_t total, int ranks, uint64_t block) {
  const uint64_t k = static_cast<uint64_t>(ranks);
  if (ranks < 1 || (total + block - 1) / block >= k) return Status::Ok();
  const uint64_t fit = std::max<uint64_t>(1, (total + block - 1) / block);
  return InvalidArgumentError(fmt::format(
      "particles = {}: across {} ranks every rank needs a block of {} particles, because the "
      "sums are taken block by block, as one process takes them, so that a seed gives the same "
      "result at any rank count; {} ranks need particles >= {} ({} particles run on at most {} "
      "rank{})",
      total, ranks, block, ranks, block * (k - 1) + 1, total, fit, fit == 1 ? "" : "s"));
}

Status CheckIslands(uint64_t total, int islands, int ranks, uint64_t block) {
  if (islands <= 1) return Status::Ok();
  const uint64_t blocks = (total + block - 1) / block;
  if (static_cast<uint64_t>(islands) > blocks) {
    return InvalidArgumentError(
        fmt::format("islands = {}: an island needs a block of {} particles, and particles = {} "
                    "make {}",
                    islands, block, total, blocks));
  }
  if (ranks > 1 && islands % ranks != 0) {
    return InvalidArgumentError(
        fmt::format("islands = {}: must be a multiple of the ranks ({}), each rank holding whole "
                    "islands",
                    islands, ranks));
  }
  return Status::Ok();
}

void WriteCheckpointRank(ByteWriter* w, const Collective* ranks) {
  w->Put<uint32_t>(ranks == nullptr ? 0 : static_cast<uint32_t>(ranks->rank()));
  w->Put<uint32_t>(ranks == nullptr ? 1 : static_cast<uint32_t>(ranks->size()));
}

Status ReadCheckpointRank(ByteReader* r, const Collective* ranks) {
  uint32_t rank = 0, count = 0;
  GROVE_RETURN_IF_ERROR(r->Get("rank", &rank));
  GROVE_RETURN_IF_ERROR(r->Get("rank count", &count));
  if (count == 0 || rank >= count) return r->Error("rank", "not one of the ranks");
  const uint32_t me = ranks == nullptr ? 0 : static_cast<uint32_t>(ranks->rank());
  const uint32_t size = ranks == nullptr ? 1 : static_cast<uint32_t>(ranks->size());
  if (rank != me || count != size) {
    return FailedPreconditionError(fmt::format(
        "{}: the checkpoint holds rank {} of {}'s particles, and this is rank {} of {}: resume on "
        "as many ranks as wrote it, each rank from its own file",
        r->name(), rank, count, me, size));
  }
  return Status::Ok();
}

Status CheckCheckpointSteps(Collective& c, int64_t steps) {
  std::vector<int64_t> all;
  GROVE_RETURN_IF_ERROR(AllGatherValues<int64_t>(c, std::span(&steps, 1), &all));
  for (size_t q = 1; q < all.size(); ++q) {
    if (all[q] != all[0]) {
      return FailedPreconditionError(fmt::format(
          "rank {}'s checkpoint was made after step {}, rank 0's after step {}: every rank must "
          "resume from the files of one checkpoint",
          q, all[q], all[0]));
    }
  }
  return Status::Ok();
}

Status AgreeStatus(Collective& c, const Status& mine) {
  ByteWriter w;
  w.Put<uint32_t>(static_cast<uint32_t>(mine.code()));
  w.PutString(mine.message());
  std::vector<std::string> all;
  GROVE_RETURN_IF_ERROR(c.AllGather(w.Take(), &all));
  for (size_t q = 0; q < all.size(); ++q) {
    ByteReader r(all[q], "rank " + std::to_string(q) + "'s status");
    uint32_t code = 0;
    std::string message;
    GROVE_RETURN_IF_ERROR(r.Get("code", &code));
    GROVE_RETURN_IF_ERROR(r.GetString("message", &message));
    if (code > static_cast<uint32_t>(StatusCode::kInternal)) {
      return r.Error("code", "not a status code");
    }
    if (code != 0) {
      if (static_cast<int>(q) == c.rank() || c.size() == 1) return mine;
      return Status(static_cast<StatusCode>(code), "rank " + std::to_string(q) + ": " + message);
    }
  }
  return Status::Ok();
}

struct InProcessCollective::Shared {
  explicit Shared(int ranks)
      : size(ranks),
        sync(ranks),
        gather(static_cast<size_t>(ranks)),
        exchange(static_cast<size_t>(ranks) * static_cast<size_t>(ranks)) {}
  int size;
  std::barrier<> sync;
  std::vector<const std::string*> gather;    // rank q's part
  std::vector<const std::string*> exchange;  // [from * size + to]
};

std::vector<std::unique_ptr<Collective>> InProcessCollective::Create(int ranks) {
  auto shared = std::make_shared<Shared>(ranks);
  std::vector<std::unique_ptr<Collective>> out;
  for (int r = 0; r < ranks; ++r) out.emplace_back(new InProcessCollective(shared, r));
  return out;
}

int InProcessCollective::size() const { return shared_->size; }

Status InProcessCollective::AllGather(const std::string& mine, std::vector<std::string>* all) {
  Shared& s = *shared_;
  s.gather[static_cast<size_t>(rank_)] = &mine;
  s.sync.arrive_and_wait();
  all->resize(static_cast<size_t>(s.size));
  for (size_t q = 0; q < all->size(); ++q) (*all)[q] = *s.gather[q];
  // Every rank has copied before any part is overwritten or goes away.
  s.sync.arrive_and_wait();
  return Status::Ok();
}

Status InProcessCollective::AllToAll(const std::vector<std::string>& to,
                                     std::vector<std::string>* from) {
  Shared& s = *shared_;
  const size_t k = static_cast<size_t>(s.size);
  if (to.size() != k) return InternalError("collective: one message per rank expected");
  for (size_t q = 0; q < k; ++q) s.exchange[static_cast<size_t>(rank_) * k + q] = &to[q];
  s.sync.arrive_and_wait();
  from->resize(k);
  for (size_t q = 0; q < k; ++q) (*from)[q] = *s.exchange[q * k + static_cast<size_t>(rank_)];
  s.sync.arrive_and_wait();
  return Status::Ok();
}

}  // namespace grove
