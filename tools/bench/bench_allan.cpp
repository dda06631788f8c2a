// Allan-variance benchmarks on the standard records (rate in rad/s at 100 Hz), one core. Timed:
// integration of the rate to angle (in place) plus the deviations on the default octave grid.
// Not timed: file parsing (records are loaded before the loop) and the record-sized buffer each
// iteration integrates in place: copying the record into it and freeing it afterwards, which on
// the reference VM cost ~50 ms per 1e7 samples in page faults alone.
//   BM_Oadev/N    N = 1e5, 1e6, 1e7   overlapping Allan deviation, octave grid up to N/4
//   BM_Totdev/N   N = 1e5, 1e6, 1e7   total deviation (reflected record), octave grid up to N/2
//   BM_AllanAnalysis/N  N = 1e6, 1e7  what `driftlab allan` computes: OADEV, noise identification,
//                                     edf and 68.3 % intervals per tau, noise-term fit
#include <benchmark/benchmark.h>

#include "models/allan/confidence.hpp"
#include "models/allan/deviation.hpp"
#include "models/allan/analysis.hpp"
#include "models/allan/noise_fit.hpp"
#include "models/allan/tau_grid.hpp"
#include "tools/bench/bench_signals.hpp"

#include <utility>
#include <vector>

namespace driftlab {
namespace {

// Integrates a fresh copy of the record in place into `angle` (the copy and the release of the
// previous angle are not timed) and returns the default octave grid for `kind`.
std::vector<std::size_t> integrate_copy(benchmark::State& state, const bench::BenchSignal& signal, allan::Kind kind,
                                        Eigen::VectorXd& angle) {
  state.PauseTiming();
  angle = Eigen::VectorXd();
  angle = signal.rate_rad_s;
  state.ResumeTiming();
  const double tau0 = 1.0 / signal.sample_rate_hz;
  angle = allan::angle_from_rate(std::move(angle), tau0);
  return allan::averaging_factors(allan::TauGrid{}, kind, static_cast<std::size_t>(angle.size()), tau0);
}

void run_deviation(benchmark::State& state, allan::Kind kind) {
  const auto* signal = bench::signal_or_skip(state);
  if (signal == nullptr) return;
  Eigen::VectorXd angle;
  for (auto _ : state) {
    const auto factors = integrate_copy(state, *signal, kind, angle);
    const auto devs = allan::deviations(kind, angle, 1.0 / signal->sample_rate_hz, factors);
    benchmark::DoNotOptimize(devs.data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_Oadev(benchmark::State& state) { run_deviation(state, allan::Kind::Oadev); }
void BM_Totdev(benchmark::State& state) { run_deviation(state, allan::Kind::Totdev); }

void BM_AllanAnalysis(benchmark::State& state) {
  const auto* signal = bench::signal_or_skip(state);
  if (signal == nullptr) return;
  for (auto _ : state) {
    const auto analysis = allan::analyze_rate(signal->rate_rad_s, signal->sample_rate_hz);
    benchmark::DoNotOptimize(analysis.bias_instability.value);
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

BENCHMARK(BM_Oadev)->Arg(100000)->Arg(1000000)->Arg(10000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Totdev)->Arg(100000)->Arg(1000000)->Arg(10000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_AllanAnalysis)->Arg(1000000)->Arg(10000000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace driftlab
