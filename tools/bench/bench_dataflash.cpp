// BM_ReadDataflash/<keep>: parse spark404/dataflashlog's 0.7-MB log.bin (51 s of an ArduCopter
// flight, 43 message types, tests/data/logs/spark404-dataflashlog) from disk (page cache warm):
// keep 0 keeps the values of the IMU types only, as `driftlab log export` and every record-reading
// command do; keep 1 keeps every type's values. Throughput in MB/s of file (bytes_per_second).
#include <benchmark/benchmark.h>

#include <filesystem>

#include "framework/dataflash.hpp"
#include "framework/dataflash_imu.hpp"

namespace {

void BM_ReadDataflash(benchmark::State& state) {
  const auto path =
      std::filesystem::path(DRIFTLAB_SOURCE_DIR) / "tests" / "data" / "logs" / "spark404-dataflashlog" / "log.bin";
  driftlab::dataflash::ReadOptions options;
  options.keep_all = state.range(0) == 1;
  options.keep_types = driftlab::dataflash::imu_types();
  for (auto _ : state) benchmark::DoNotOptimize(driftlab::dataflash::read(path, options));
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(std::filesystem::file_size(path)));
}
BENCHMARK(BM_ReadDataflash)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
