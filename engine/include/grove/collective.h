// Collective: the few operations a filter needs to run across ranks (processes, or engines in one
// process), whatever carries the bytes: MPI in the grove command, threads of one process in
// InProcessCollective (for tests and embedders), anything else an embedder derives.
//
// One filter across K ranks: every rank creates its engine with FootSlam::Create(config, ranks)
// (or FastSlam's) and holds a contiguous share of the particles (ShareOf); the same seed gives
// the same bits at any rank count. Every rank must make the same calls in the same order (as
// with MPI's collectives); a call on one rank waits for the others.
//
//   grove::FootSlamConfig config;
//   config.particles = 8192;  // at least one block of 4,096 particles per rank
//   std::vector<std::unique_ptr<grove::Collective>> ranks = grove::InProcessCollective::Create(2);
//   std::vector<grove::Status> results(ranks.size());
//   std::vector<std::thread> threads;
//   for (size_t r = 0; r < ranks.size(); ++r) {
//     threads.emplace_back([&, r] {
//       auto slam = grove::FootSlam::Create(config, ranks[r].get());
//       results[r] = slam.ok() ? (*slam)->Step(0.5, 0.7, 0.0) : slam.status();
//     });
//   }
//   for (std::thread& t : threads) t.join();
//   return results[0];
#ifndef GROVE_COLLECTIVE_H_
#define GROVE_COLLECTIVE_H_

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "grove/export.h"
#include "grove/status.h"

namespace grove {

// Thread safety: each rank's endpoint is driven by one thread at a time.
class GROVE_EXPORT Collective {
 public:
  virtual ~Collective() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  // Every rank's `mine`, in rank order, to every rank.
  virtual Status AllGather(const std::string& mine, std::vector<std::string>* all) = 0;
  // to[q] goes to rank q (to.size() == size()); (*from)[q] is what rank q sent to this rank.
  virtual Status AllToAll(const std::vector<std::string>& to, std::vector<std::string>* from) = 0;
};

// The particles a rank holds: [first, first + count) of the filter's total.
struct ParticleShare {
  uint64_t first = 0;
  uint64_t count = 0;
};

// This rank's share of a filter of `total` particles as the engines split it over `ranks` (null:
// one process, all of them).
GROVE_EXPORT ParticleShare ShareOf(uint64_t total, const Collective* ranks);

// Collective: the same status on every rank, the lowest failing rank's (OK when none failed). A
// rank whose own work failed calls it too, so no rank is left waiting in a later collective.
GROVE_EXPORT Status AgreeStatus(Collective& c, const Status& mine);

// K ranks as threads of one process: Create(K) gives the K endpoints, each to be driven by its
// own thread. The operations meet at a barrier; a thread that stops calling blocks the others.
class GROVE_EXPORT InProcessCollective : public Collective {
 public:
  static std::vector<std::unique_ptr<Collective>> Create(int ranks);

  int rank() const override { return rank_; }
  int size() const override;
  Status AllGather(const std::string& mine, std::vector<std::string>* all) override;
  Status AllToAll(const std::vector<std::string>& to, std::vector<std::string>* from) override;

 private:
  struct Shared;
  InProcessCollective(std::shared_ptr<Shared> shared, int rank)
      : shared_(std::move(shared)), rank_(rank) {}
  std::shared_ptr<Shared> shared_;
  int rank_;
};

}  // namespace grove

#endif  // GROVE_COLLECTIVE_H_
