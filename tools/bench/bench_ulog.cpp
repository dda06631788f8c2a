// BM_ReadUlog/<keep>: parse pyulog's sample.ulg (4 MB, 68 s of a PX4 flight, 43 topics) from disk
// (../shared/data/logs/px4-pyulog, page cache warm): keep 0 keeps the values of the IMU topics only,
// as `driftlab log info` and every record-reading command do; keep 1 keeps every topic's values.
// Throughput in MB/s of file (bytes_per_second).
#include <benchmark/benchmark.h>

#include <filesystem>

#include "framework/ulog.hpp"
#include "framework/ulog_imu.hpp"

namespace {

void BM_ReadUlog(benchmark::State& state) {
  const auto path = std::filesystem::path(DRIFTLAB_SHARED_DATA) / "logs" / "px4-pyulog" / "sample.ulg";
  if (!std::filesystem::exists(path)) {
    state.SkipWithError(("missing " + path.string()).c_str());
    return;
  }
  driftlab::ulog::ReadOptions options;
  options.keep_all = state.range(0) == 1;
  options.keep_topics = driftlab::ulog::imu_topics();
  for (auto _ : state) benchmark::DoNotOptimize(driftlab::ulog::read(path, options));
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(std::filesystem::file_size(path)));
}
BENCHMARK(BM_ReadUlog)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
