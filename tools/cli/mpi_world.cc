#include "tools/cli/mpi_world.h"

#include <algorithm>
#include <climits>
#include <cstdlib>

#ifdef GROVE_HAVE_MPI
// The C API only: Open MPI's header otherwise pulls in its deprecated C++ bindings.
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace grove::tools {

#ifdef GROVE_HAVE_MPI
namespace {

bool StartedByMpiLauncher() {
  return std::getenv("OMPI_COMM_WORLD_SIZE") != nullptr || std::getenv("PMI_SIZE") != nullptr ||
         std::getenv("PMIX_RANK") != nullptr;
}

}  // namespace
#endif

MpiWorld::MpiWorld() {
#ifdef GROVE_HAVE_MPI
  if (!StartedByMpiLauncher()) return;
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  active_ = true;
#endif
}

MpiWorld::~MpiWorld() {
#ifdef GROVE_HAVE_MPI
  if (active_) MPI_Finalize();
#endif
}

std::vector<std::string> MpiWorld::AllGather(const std::string& mine) const {
#ifdef GROVE_HAVE_MPI
  if (active_) {
    const int length = static_cast<int>(mine.size());
    std::vector<int> lengths(static_cast<size_t>(size_));
    MPI_Allgather(&length, 1, MPI_INT, lengths.data(), 1, MPI_INT, MPI_COMM_WORLD);
    std::vector<int> offsets(static_cast<size_t>(size_));
    int total = 0;
    for (int r = 0; r < size_; ++r) {
      offsets[static_cast<size_t>(r)] = total;
      total += lengths[static_cast<size_t>(r)];
    }
    std::string all(static_cast<size_t>(total), '\0');
    MPI_Allgatherv(mine.data(), length, MPI_CHAR, all.data(), lengths.data(), offsets.data(),
                   MPI_CHAR, MPI_COMM_WORLD);
    std::vector<std::string> out;
    for (int r = 0; r < size_; ++r) {
      out.push_back(all.substr(static_cast<size_t>(offsets[static_cast<size_t>(r)]),
                               static_cast<size_t>(lengths[static_cast<size_t>(r)])));
    }
    return out;
  }
#endif
  return {mine};
}

Status MpiWorld::AllGather(const std::string& mine, std::vector<std::string>* all) {
  if (mine.size() > INT_MAX) return ResourceExhaustedError("MPI: a message above 2 GiB");
  *all = static_cast<const MpiWorld*>(this)->AllGather(mine);
  return Status::Ok();
}

Status MpiWorld::AllToAll(const std::vector<std::string>& to, std::vector<std::string>* from) {
  if (to.size() != static_cast<size_t>(size_)) {
    return InternalError("MPI: one message per rank expected");
  }
#ifdef GROVE_HAVE_MPI
  if (active_) {
    const size_t k = static_cast<size_t>(size_);
    // Every rank learns what each sends it, then the bytes go in one MPI_Alltoallv; a size
    // above what an int counts fails on every rank alike (the sizes are exchanged first).
    std::vector<long long> send_sizes(k), recv_sizes(k);
    for (size_t q = 0; q < k; ++q) send_sizes[q] = static_cast<long long>(to[q].size());
    MPI_Alltoall(send_sizes.data(), 1, MPI_LONG_LONG, recv_sizes.data(), 1, MPI_LONG_LONG,
                 MPI_COMM_WORLD);
    long long send_total = 0, recv_total = 0;
    for (size_t q = 0; q < k; ++q) {
      send_total += send_sizes[q];
      recv_total += recv_sizes[q];
    }
    long long largest = std::max(send_total, recv_total), any_largest = 0;
    MPI_Allreduce(&largest, &any_largest, 1, MPI_LONG_LONG, MPI_MAX, MPI_COMM_WORLD);
    if (any_largest > INT_MAX) {
      return ResourceExhaustedError("MPI: a rank's exchange is above 2 GiB");
    }
    std::vector<int> send_counts(k), send_offsets(k), recv_counts(k), recv_offsets(k);
    std::string send, recv(static_cast<size_t>(recv_total), '\0');
    send.reserve(static_cast<size_t>(send_total));
    int s_at = 0, r_at = 0;
    for (size_t q = 0; q < k; ++q) {
      send_counts[q] = static_cast<int>(send_sizes[q]);
      send_offsets[q] = s_at;
      s_at += send_counts[q];
      send += to[q];
      recv_counts[q] = static_cast<int>(recv_sizes[q]);
      recv_offsets[q] = r_at;
      r_at += recv_counts[q];
    }
    MPI_Alltoallv(send.data(), send_counts.data(), send_offsets.data(), MPI_CHAR, recv.data(),
                  recv_counts.data(), recv_offsets.data(), MPI_CHAR, MPI_COMM_WORLD);
    from->resize(k);
    for (size_t q = 0; q < k; ++q) {
      (*from)[q] =
          recv.substr(static_cast<size_t>(recv_offsets[q]), static_cast<size_t>(recv_counts[q]));
    }
    return Status::Ok();
  }
#endif
  *from = to;
  return Status::Ok();
}

}  // namespace grove::tools
