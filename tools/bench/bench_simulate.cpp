// BM_Simulate/<N>: the oven simulator (devices/simulator.hpp) with the shipped FMVMG device for N
// samples at 1 kHz on the default oven profile (N = 3 600 000 is one hour). Loading the device file
// is outside the timed region.
#include <benchmark/benchmark.h>

#include <string>

#include "devices/simulator.hpp"

namespace {

void BM_Simulate(benchmark::State& state) {
  const auto device = driftlab::devices::load_device_file(std::string(DRIFTLAB_SOURCE_DIR) + "/devices/fmvmg.yaml");
  const auto profile = driftlab::devices::default_oven_profile();
  driftlab::devices::SimulationOptions options;
  options.sample_rate_hz = 1000.0;
  options.duration_s = static_cast<double>(state.range(0)) / options.sample_rate_hz;
  for (auto _ : state) {
    auto record = driftlab::devices::simulate(device, profile, options);
    benchmark::DoNotOptimize(record.rate_rad_s.data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_Simulate)->Arg(100000)->Arg(3600000)->Unit(benchmark::kMillisecond);

}  // namespace
