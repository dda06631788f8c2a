// The paper's whole pipeline (models/pipelines/li2023.yaml: EMD of rate and temperature, sample
// entropy groups, untuned and GA-tuned RBF networks on both groups, Kalman filter) on the standard
// records, with the Table 2 scoring of `driftlab run` (Allan analysis and noise bandwidth of every
// stage and of the PX4-style baseline) included; two worker threads (the 2-core target machine);
// reading the CSV is not timed.
//   BM_Li2023Pipeline/N
#include <benchmark/benchmark.h>

#include "plugins/builtins.hpp"
#include "framework/pipeline.hpp"
#include "framework/registry.hpp"
#include "models/calibration/fit.hpp"
#include "models/evaluation/evaluation.hpp"
#include "tools/bench/bench_signals.hpp"

namespace driftlab {
namespace {

void BM_Li2023Pipeline(benchmark::State& state) {
  const auto* signal = bench::signal_or_skip(state);
  if (signal == nullptr) return;
  Registry registry;
  register_builtin_plugins(registry);
  const auto pipeline = load_pipeline(DRIFTLAB_SOURCE_DIR "/models/pipelines/li2023.yaml", registry);
  TimeSeries record(signal->time_s);
  record.set_channel({role::kRate, "rad/s", "rate_dps", signal->rate_rad_s});
  record.set_channel({role::kTemperature, "degC", "temp_c", signal->temp_c});
  PipelineRunOptions options;
  options.threads = 2;
  for (auto _ : state) {
    nlohmann::json report;
    const auto outputs = run_pipeline(pipeline, registry, record, options, report);
    const double fs = record.sample_rate_hz();
    const double n_ref = allan::analyze_rate(signal->rate_rad_s, fs, {.fit_terms = false}).arw_rad_sqrt_s;
    for (const auto& [name, out] : outputs)
      benchmark::DoNotOptimize(evaluation::score_stage(name, out.columns.col(0), signal->time_s, fs, n_ref, nullptr));
    const auto baseline =
        calibration::fit_px4_style({{"bench", signal->time_s, signal->rate_rad_s, signal->temp_c, {}, {}}}, {});
    benchmark::DoNotOptimize(calibration::compensate(baseline, signal->time_s, signal->rate_rad_s, signal->temp_c));
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_Li2023Pipeline)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
}  // namespace driftlab
