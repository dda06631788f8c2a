// The cluster engine of `driftlab fleet` (issue 24): Boost.MPI over the system's MPI (Debian:
// libboost-mpi-dev, openmpi-bin), built when CMake finds both (DRIFTLAB_WITH_MPI), like MRPT.
//
// run_over_mpi(count, body, started, finished) (fleet_mpi_loader.cpp; the engine is the module
// fleet_mpi.cpp, loaded only then): when this process is one of several ranks of an MPI job
// (`mpirun -np N driftlab fleet ...`; detected by OpenMPI's OMPI_COMM_WORLD_SIZE or the PMI_SIZE
// of MPICH-style launchers, > 1), rank 0 calls started() once, then deals the items [0, count) one
// at a time to the ranks that ask (a master/worker queue: a slow item holds up only its rank) and
// calls finished(line) with the line body(i) returned for each as it arrives (the caller prints it
// and reports progress, as it does for its threads); ranks 1..N-1 run body(i) and call neither. Returns true on rank 0
// (which then writes the report) and false on the others, after every item has run. In a single process, or it runs
// nothing and returns std::nullopt: the caller uses its thread pool. A build without MPI started as several ranks
// throws ConfigError (each rank would run the whole fleet). body must not throw (an exception on a worker rank aborts
// the job).
#pragma once

#include <cstddef>
#include <cstdlib>
#include <functional>
#include <optional>
#include <string>

namespace driftlab::cli {

using MpiBody = std::function<std::string(std::size_t)>;
std::optional<bool> run_over_mpi(std::size_t count, const MpiBody& body, const std::function<void()>& started,
                                 const std::function<void(const std::string&)>& finished);

// The ranks the launcher started (1 when not started by one).
inline long launched_ranks() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
    if (const char* v = std::getenv(name)) return std::strtol(v, nullptr, 10);
  return 1;
}

}  // namespace driftlab::cli
