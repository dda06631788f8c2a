// run_over_mpi (fleet_mpi.hpp): in a single process, std::nullopt; started as several ranks, the
// MPI engine, the module libdriftlab_fleet_mpi.so (fleet_mpi.cpp) next to the driftlab executable
// (the build tree) or in an installed driftlab's library directory (cli.hpp installed_lib_dir),
// loaded then and only then, so that no other run of driftlab loads the MPI libraries. Loaded with
// RTLD_GLOBAL: Open MPI's own components resolve their symbols against libmpi.
#include <dlfcn.h>

#include <filesystem>

#include "framework/error.hpp"
#include "tools/driftlab/cli.hpp"
#include "tools/driftlab/fleet_mpi.hpp"

namespace driftlab::cli {
namespace {

using RunOverMpi = int (*)(std::size_t, const MpiBody&, const std::function<void()>&,
                           const std::function<void(const std::string&)>&);

RunOverMpi load_engine() {
  if (!DRIFTLAB_HAVE_MPI)
    throw ConfigError({"", 0, "mpirun"},
                      "this driftlab was built without MPI (CMake DRIFTLAB_WITH_MPI; Debian "
                      "libboost-mpi-dev, openmpi-bin): run the fleet in one process, or --shard");
  const std::string name = "libdriftlab_fleet_mpi.so";
  const auto beside = executable_dir() / name;
  const auto module = std::filesystem::exists(beside) ? beside : installed_lib_dir() / name;
  void* handle = dlopen(module.c_str(), RTLD_NOW | RTLD_GLOBAL);
  const char* error = handle ? nullptr : dlerror();
  const auto run = handle ? reinterpret_cast<RunOverMpi>(dlsym(handle, "driftlab_run_over_mpi")) : nullptr;
  if (!run)
    throw ConfigError({module.string(), 0, "mpirun"}, std::string("cannot load the fleet's MPI engine (") +
                                                          (error ? error : "no driftlab_run_over_mpi") +
                                                          "; Debian: libboost-mpi1.74.0, openmpi-bin)");
  return run;
}

}  // namespace

std::optional<bool> run_over_mpi(std::size_t count, const MpiBody& body, const std::function<void()>& started,
                                 const std::function<void(const std::string&)>& finished) {
  if (launched_ranks() <= 1) return std::nullopt;
  const int result = load_engine()(count, body, started, finished);
  if (result < 0) return std::nullopt;
  return result == 1;
}

}  // namespace driftlab::cli
