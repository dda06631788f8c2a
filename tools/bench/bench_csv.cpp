// BM_CsvRead/<N>: parse the bench record gyro_N<N>.csv (t_s, rate_dps, temp_c) from disk.
#include <benchmark/benchmark.h>

#include <filesystem>

#include "framework/csv.hpp"
#include "tools/bench/bench_signals.hpp"

namespace {

void BM_CsvRead(benchmark::State& state) {
  const auto path =
      std::filesystem::path(driftlab::bench::bench_signal_dir()) / ("gyro_N" + std::to_string(state.range(0)) + ".csv");
  if (!std::filesystem::exists(path)) {
    state.SkipWithError(("missing " + path.string()).c_str());
    return;
  }
  driftlab::CsvReadOptions options;
  options.required_roles = {"rate", "temperature"};
  for (auto _ : state) benchmark::DoNotOptimize(driftlab::read_csv(path, options));
  state.SetItemsProcessed(state.iterations() * state.range(0));
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(std::filesystem::file_size(path)));
}
BENCHMARK(BM_CsvRead)->Arg(1000000)->Unit(benchmark::kMillisecond);

}  // namespace
