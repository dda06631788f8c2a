// libFuzzer harness: the MRPT rawlog reader (tools/mrpt/rawlog_io.hpp, import_rawlog_sensors), with
// MRPT's deserializer run first in its memory-limited child process as in every command. Each input
// is written to one scratch file and read. Property oracle on every accepted rawlog: its stats count
// one IMU label per table and as many IMU observations as the tables hold; each table's time starts at
// 0 and increases strictly, and every column has one finite value per time; each table, written back
// by export_rawlog and read again, gives the same IMU columns exactly and the same times to within
// one 100-ns tick plus the rounding of a double (times beyond ~1e9 s are spaced wider than a tick);
// odometry is re-derived by MRPT on export and not compared. Rejections must be
// DataError or ConfigError; anything else (another exception, a crash or sanitizer report in this
// process, a hang) is a finding.
//
// The child's memory limit is what turns a length field claiming gigabytes into a DataError. Under
// ASan that limit works differently: ASan serves small allocations from address space it reserved
// at start-up, which the child's RLIMIT_AS does not see, and its operator new reports a failed
// allocation and aborts instead of throwing std::bad_alloc. So in a forked child (pthread_atfork)
// this harness
//   - ends the process with SIGKILL (what the kernel's OOM killer does) once ASan's allocator holds
//     more than kChildBytes beyond what it held at the fork (inputs are at most 8 KiB: a real rawlog
//     of that size needs a few hundred KiB), and
//   - clears libFuzzer's death callback, so the child's abort after an out-of-memory report is not
//     saved as a finding of this process;
// the reader then reports the object as a DataError, as it does for a crash inside MRPT. A
// -malloc_limit_mb beyond any request keeps libFuzzer's own per-allocation check out of the child
// (tests/fuzz/run_fuzzers.sh). What the child runs of driftlab's own code (ObjectReader) runs here
// again, instrumented, on every rawlog the child accepts.
#include <pthread.h>
#include <sanitizer/allocator_interface.h>
#include <sanitizer/common_interface_defs.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <string>

#include "framework/error.hpp"
#include "tests/fuzz/fuzz_oracle.hpp"
#include "tools/mrpt/rawlog_io.hpp"

namespace {

using driftlab::mrpt_bridge::ImuTable;

constexpr std::size_t kChildBytes = std::size_t{64} << 20;
std::atomic<std::size_t> child_limit{0};  // 0 in this process, set in a forked child

void limit_child(const volatile void*, std::size_t) {
  const std::size_t limit = child_limit.load(std::memory_order_relaxed);
  if (limit != 0 && __sanitizer_get_current_allocated_bytes() > limit) ::raise(SIGKILL);
}
void on_free(const volatile void*) {}  // the hooks come in pairs (a null one is refused)

void check_table(const ImuTable& table, const std::string& label) {
  using driftlab::fuzz::require;
  const Eigen::VectorXd& t = table.time_s;
  require(t.size() > 0 && t[0] == 0.0, "a table's time starts at 0", label);
  for (Eigen::Index i = 1; i < t.size(); ++i)
    require(std::isfinite(t[i]) && t[i] > t[i - 1], "a table's time finite and strictly increasing", label);
  require(table.has("rate_rps"), "every table has the yaw rate", label);
  for (const auto& c : table.columns) {
    require(c.values.size() == t.size(), "one value per time in every column", label + " " + c.name);
    require(c.values.allFinite(), "finite values in every column", label + " " + c.name);
  }
}

void check_round_trip(const ImuTable& table, const std::string& scratch) {
  using driftlab::fuzz::require;
  const std::string path = scratch + ".again.rawlog";
  try {
    driftlab::mrpt_bridge::export_rawlog(table, path);
  } catch (const driftlab::ConfigError&) {
    return;  // time stamps beyond what export writes (after about year 14000): read, not written back
  }
  const ImuTable again = driftlab::mrpt_bridge::import_rawlog(path, table.sensor_label);
  require(again.time_s.size() == table.time_s.size(), "the same number of samples read back", table.sensor_label);
  const double tick = 1e-7;  // s, MRPT's clock step
  const double rounding = 4.0 * std::numeric_limits<double>::epsilon();
  for (Eigen::Index i = 0; i < table.time_s.size(); ++i)
    require(std::abs(again.time_s[i] - table.time_s[i]) <= tick + rounding * std::abs(table.time_s[i]),
            "the times read back to within a tick", table.sensor_label + " sample " + std::to_string(i));
  for (const auto& c : table.columns)
    if (!c.name.starts_with("odom_"))
      require(again.has(c.name) && again.values(c.name) == c.values, "the IMU columns read back exactly",
              table.sensor_label + " " + c.name);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  if (__sanitizer_install_malloc_and_free_hooks(limit_child, on_free) == 0) std::abort();
  ::pthread_atfork(nullptr, nullptr, [] {
    child_limit = __sanitizer_get_current_allocated_bytes() + kChildBytes;
    __sanitizer_set_death_callback(nullptr);
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace driftlab;
  using fuzz::require;
  static const std::string path = "/tmp/driftlab_fuzz_rawlog_" + std::to_string(::getpid()) + ".rawlog";
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    mrpt_bridge::RawlogStats stats;
    const auto tables = mrpt_bridge::import_rawlog_sensors(path, &stats);
    require(tables.size() == stats.imu_labels.size(), "one table per IMU label");
    std::size_t observations = 0;
    for (std::size_t i = 0; i < tables.size(); ++i) {
      require(tables[i].sensor_label == stats.imu_labels[i], "the tables in label order", tables[i].sensor_label);
      check_table(tables[i], tables[i].sensor_label);
      observations += static_cast<std::size_t>(tables[i].time_s.size());
    }
    require(observations == stats.imu_observations, "the stats count the tables' observations");
    for (const auto& table : tables) check_round_trip(table, path);
  } catch (const DataError&) {
  } catch (const ConfigError&) {
  }
  return 0;
}
