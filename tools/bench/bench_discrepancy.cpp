// BM_Discrepancy/<N>: the discrepancy workflow (models/discrepancy) with every built-in effect as a
// candidate on a 5-hour oven record of the shipped FMVMG (the worked example's profile,
// models/discrepancy/example_oven_profile.yaml, then a soak), N samples (N = 90 000 is 5 Hz,
// 18 000 is 1 Hz), with a hidden thermal lag (tau = 300 s) and hysteresis (200 deg/h, 2 degC) and
// no drive-frequency channel. Simulation, device loading and
// plugin creation are outside the timed region; timed: block means, noise covariance, the
// effect searches and refits (two named effects, three scoring rounds), uncertainties, the
// full-rate model and the residual views before and after.
#include <benchmark/benchmark.h>

#include <string>

#include "plugins/builtins.hpp"
#include "devices/simulator.hpp"
#include "framework/params_io.hpp"
#include "framework/registry.hpp"
#include "framework/units.hpp"
#include "models/discrepancy/discrepancy.hpp"
#include "devices/discrepancy_options.hpp"

namespace {

using namespace driftlab;

constexpr double kDuration = 5.0 * kSecondsPerHour;

void BM_Discrepancy(benchmark::State& state) {
  auto device = devices::load_device_file(std::string(DRIFTLAB_SOURCE_DIR) + "/devices/fmvmg.yaml");
  std::erase_if(device.channels, [](const auto& c) { return c.role == role::kDriveFrequency; });
  const auto options = devices::discrepancy_options(device);
  device.error_model.effects.thermal_lag = error_model::ThermalLag{300.0};
  device.error_model.effects.hysteresis = error_model::Hysteresis{200.0 * kRadPerSecPerDph, 2.0};
  devices::SimulationOptions sim;
  sim.sample_rate_hz = static_cast<double>(state.range(0)) / kDuration;
  sim.duration_s = kDuration;
  const auto profile =
      devices::load_profile_file(std::string(DRIFTLAB_SOURCE_DIR) + "/models/discrepancy/example_oven_profile.yaml");
  const auto record = devices::simulate(device, profile, sim).to_time_series();

  Registry registry;
  register_builtin_plugins(registry);
  std::vector<std::unique_ptr<Effect>> owned;
  std::vector<discrepancy::Candidate> candidates;
  for (const auto* info : registry.list("effect")) {
    owned.push_back(registry.create_as<Effect>({info->name, params_from_assignments(registry, info->name, {})}));
    candidates.push_back({info->name.substr(7), owned.back().get()});
  }
  std::size_t named = 0;
  for (auto _ : state) {
    const auto result = discrepancy::find_missing_effects(record, candidates, options);
    named = result.steps.size();
    benchmark::DoNotOptimize(result.model_final_rad_s.data());
  }
  state.counters["named_effects"] = static_cast<double>(named);
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_Discrepancy)->Arg(18000)->Arg(90000)->Unit(benchmark::kMillisecond);

}  // namespace
