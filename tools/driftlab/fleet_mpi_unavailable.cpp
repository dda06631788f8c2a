// run_over_mpi in a build without MPI (fleet_mpi.hpp): the fleet runs on its thread pool.
#include "framework/error.hpp"
#include "tools/driftlab/fleet_mpi.hpp"

namespace driftlab::cli {

std::optional<bool> run_over_mpi(std::size_t, const std::function<std::string(std::size_t)>&) {
  if (launched_ranks() > 1)
    throw ConfigError({"", 0, "mpirun"}, "this driftlab was built without MPI (CMake DRIFTLAB_WITH_MPI; Debian "
                                         "libboost-mpi-dev, openmpi-bin): run the fleet in one process, or --shard");
  return std::nullopt;
}

}  // namespace driftlab::cli
