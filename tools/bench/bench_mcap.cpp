// BM_ReadMcap/<what>: read tests/data/logs/ros2-robot-localization/imu_zstd.mcap (325 kB: 61 s of
// a 50 Hz Jackal IMU and a 5 Hz temperature, zstd chunks, summary; page cache warm) from disk:
// what 0 parses the container (framework/mcap.hpp: every chunk decompressed and CRC-checked, every
// message counted, none decoded), 1 makes the IMU record (framework/ros_imu.hpp: the messages
// decoded from CDR, repaired, assembled), 2 the same on imu_uncompressed_chunks.mcap (189 kB).
// Throughput in MB/s of file (bytes_per_second). Measured on this project's 2-core AMD EPYC VM
// (Release, median of 5, CPU time): 178 MB/s, 134 MB/s, 709 MB/s. A 995-MB MCAP (zstd chunks, 41
// min of that IMU at 50 Hz and 4 920 messages of 200 kB of random bytes on another topic, written
// by @mcap/core) took 1.2 s and 77 MB of memory for `driftlab log info` and `log export`. Run:
//   DRIFTLAB_BENCH_SIGNALS=DIR build/tools/bench/driftlab-bench --benchmark_filter=BM_ReadMcap
#include <benchmark/benchmark.h>

#include <filesystem>

#include "framework/mcap.hpp"
#include "framework/ros_imu.hpp"

namespace {

void BM_ReadMcap(benchmark::State& state) {
  const auto dir = std::filesystem::path(DRIFTLAB_SOURCE_DIR) / "tests" / "data" / "logs" / "ros2-robot-localization";
  const auto path = dir / (state.range(0) == 2 ? "imu_uncompressed_chunks.mcap" : "imu_zstd.mcap");
  for (auto _ : state) {
    if (state.range(0) == 0)
      benchmark::DoNotOptimize(driftlab::mcap::read(path));
    else
      benchmark::DoNotOptimize(driftlab::ros::read_imu(path, {}));
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(std::filesystem::file_size(path)));
}
BENCHMARK(BM_ReadMcap)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

}  // namespace
