// MpiWorld: the grove command's place among MPI ranks. MPI is initialised only when the process
// was started by an MPI launcher (mpirun sets OMPI_COMM_WORLD_SIZE, other launchers PMI_SIZE or
// PMIX_RANK) and grove was built with MPI (CMake's FindMPI, GROVE_MPI); otherwise the world is
// one rank and nothing of MPI runs. Only the thread that made it may call its methods
// (MPI_THREAD_FUNNELED).
#ifndef GROVE_TOOLS_CLI_MPI_WORLD_H_
#define GROVE_TOOLS_CLI_MPI_WORLD_H_

#include <string>
#include <vector>

#include "grove/collective.h"

namespace grove::tools {

// Also the Collective of one filter across ranks (MPI_COMM_WORLD); alone, a world of one rank.
class MpiWorld : public Collective {
 public:
  MpiWorld();
  ~MpiWorld();  // MPI_Finalize, when it initialised MPI
  MpiWorld(const MpiWorld&) = delete;
  MpiWorld& operator=(const MpiWorld&) = delete;

  int rank() const override { return rank_; }
  int size() const override { return size_; }
  // Whether this build has MPI and the process was started by an MPI launcher.
  bool active() const { return active_; }

  // Every rank's string, in rank order, on every rank (collective: every rank must call it).
  std::vector<std::string> AllGather(const std::string& mine) const;

  // Collective: MPI_Allgatherv and MPI_Alltoallv of bytes (a part above 2 GiB is an error).
  Status AllGather(const std::string& mine, std::vector<std::string>* all) override;
  Status AllToAll(const std::vector<std::string>& to, std::vector<std::string>* from) override;

 private:
  int rank_ = 0;
  int size_ = 1;
  bool active_ = false;
};

}  // namespace grove::tools

#endif  // GROVE_TOOLS_CLI_MPI_WORLD_H_
