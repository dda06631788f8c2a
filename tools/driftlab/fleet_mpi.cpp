// The MPI engine of `driftlab fleet` as the module libdriftlab_fleet_mpi.so, loaded by
// run_over_mpi (fleet_mpi_loader.cpp) only when the process is one of several MPI ranks: every other
// run of driftlab starts without the MPI libraries. Contract of driftlab_run_over_mpi: that of
// run_over_mpi (fleet_mpi.hpp), its result coded -1 (std::nullopt), 1 (true), 0 (false).
#include "tools/driftlab/fleet_mpi.hpp"

#include <boost/mpi/communicator.hpp>
#include <boost/mpi/environment.hpp>
#include <boost/serialization/string.hpp>

namespace driftlab::cli {
namespace {

constexpr int kTagResult = 1;  // worker -> master: the last item's line ("" for the first request)
constexpr int kTagWork = 2;    // master -> worker: the next item, or -1 when there is none

int run_ranks(std::size_t count, const MpiBody& body, const std::function<void()>& started,
              const std::function<void(const std::string&)>& finished) {
  boost::mpi::environment environment;
  boost::mpi::communicator world;
  if (world.size() <= 1) return -1;
  if (world.rank() == 0) {
    started();
    std::size_t next = 0;
    for (int active = world.size() - 1; active > 0;) {
      std::string line;
      const auto status = world.recv(boost::mpi::any_source, kTagResult, line);
      if (!line.empty()) finished(line);
      const long item = next < count ? static_cast<long>(next++) : -1L;
      world.send(status.source(), kTagWork, item);
      active -= item < 0;
    }
    return 1;
  }
  world.send(0, kTagResult, std::string());
  for (;;) {
    long item = -1;
    world.recv(0, kTagWork, item);
    if (item < 0) break;
    world.send(0, kTagResult, body(static_cast<std::size_t>(item)));
  }
  return 0;
}

}  // namespace
}  // namespace driftlab::cli

extern "C" int driftlab_run_over_mpi(std::size_t count, const driftlab::cli::MpiBody& body,
                                     const std::function<void()>& started,
                                     const std::function<void(const std::string&)>& finished) {
  return driftlab::cli::run_ranks(count, body, started, finished);
}
