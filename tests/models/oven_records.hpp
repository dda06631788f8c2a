// Seeded generator of simulated oven records with hidden effects, for the discrepancy workflow tests.
//
// Each record: the device in a chamber that soaks at -30 degC (20 min), heats to +60 degC, soaks
// (20 min), cools to -30 degC, soaks (20 min), heats to +15 degC and soaks (10 min). The three legs
// get one slow, one medium and one fast ramp rate, drawn log-uniformly from [0.6, 1], [1.2, 2] and
// [2.4, 3.6] degC/min, in a random order: every record has its own rates, and heating and cooling
// differ, so rate-dependent terms can be told from direction-dependent ones. A rate table cycles
// 0, +50, -50 deg/s (200 s each) so that scale-factor terms are visible. Sampled at 1 Hz
// (the FMVMG's noise terms, no effects in the device file). Hidden effects and their parameters are
// drawn from the ranges below: realistic for a MEMS gyro of this noise class, with the lower ends
// set at about twice the bias instability B = 34.7 deg/h of the signal each term puts into a
// record (hysteresis +-h/2, dT/dt term c x 0.6..3.6 degC/min, ...), the level at which a 4-h record
// can show a term above flicker and random-walk noise. Weaker terms are not named (by design: the
// criterion is set so that noise alone names nothing).
//
//   thermal_lag               tau_s                      log-uniform [150, 900] s
//   temperature_rate          coefficient                +-log-uniform [50, 150] deg/h per degC/min
//   hysteresis                height, width              +-log-uniform [150, 400] deg/h, [0.5, 4] degC
//   warmup_transient          amplitude, tau             +-log-uniform [300, 1000] deg/h, [300, 1800] s
//   periodic_disturbance      amplitude, period, phase   log-uniform [60, 180] deg/h, [300, 2400] s, U(-pi, pi)
//   scale_factor_temperature  c1                         +-log-uniform [30, 150] ppm/K
//
// Random numbers: std::mt19937_64 seeded from (seed, record index) through splitmix64, uniform
// doubles from the top 53 bits (portable); the simulator's noise seed is derived the same way.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "devices/device_file.hpp"
#include "devices/simulator.hpp"
#include "framework/seeded_random.hpp"
#include "framework/units.hpp"

namespace driftlab::testing_oven {

inline const std::array<std::string, 6> kEffectNames{"thermal_lag",          "temperature_rate",
                                                     "hysteresis",           "warmup_transient",
                                                     "periodic_disturbance", "scale_factor_temperature"};

class Draw {
 public:
  Draw(std::uint64_t seed, std::uint64_t index) : engine_(splitmix64(splitmix64(seed) ^ splitmix64(index + 1))) {}
  double uniform(double lo, double hi) { return lo + (hi - lo) * static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double log_uniform(double lo, double hi) { return std::exp(uniform(std::log(lo), std::log(hi))); }
  double signed_log_uniform(double lo, double hi) { return (uniform(0, 1) < 0.5 ? -1.0 : 1.0) * log_uniform(lo, hi); }
  std::size_t index(std::size_t n) {
    return std::min(n - 1, static_cast<std::size_t>(uniform(0, 1) * static_cast<double>(n)));
  }
  std::uint64_t bits() { return engine_(); }

 private:
  std::mt19937_64 engine_;
};

struct OvenRecord {
  TimeSeries series;
  Eigen::VectorXd truth_rad_s;  // the simulator's systematic rate
  std::vector<std::string> hidden;
  error_model::Effects effects;
  std::array<double, 3> ramp_c_per_min{};
};

inline void switch_on(const std::string& name, Draw& d, error_model::Effects& e) {
  if (name == "thermal_lag")
    e.thermal_lag = error_model::ThermalLag{d.log_uniform(150, 900)};
  else if (name == "temperature_rate")
    e.temperature_rate = error_model::TemperatureRate{d.signed_log_uniform(50, 150) * kRadPerSecPerDph * 60.0};
  else if (name == "hysteresis")
    e.hysteresis = error_model::Hysteresis{d.signed_log_uniform(150, 400) * kRadPerSecPerDph, d.log_uniform(0.5, 4)};
  else if (name == "warmup_transient")
    e.warmup_transient =
        error_model::WarmupTransient{d.signed_log_uniform(300, 1000) * kRadPerSecPerDph, d.log_uniform(300, 1800)};
  else if (name == "periodic_disturbance")
    e.periodic_disturbance =
        error_model::PeriodicDisturbance{d.log_uniform(60, 180) * kRadPerSecPerDph, d.log_uniform(300, 2400),
                                         d.uniform(-std::numbers::pi, std::numbers::pi)};
  else if (name == "scale_factor_temperature")
    e.scale_factor_temperature = error_model::ScaleFactorTemperature{{d.signed_log_uniform(30, 150) * 1e-6}};
}

inline devices::SimulationProfile oven_profile(Draw& d, std::array<double, 3>& rates) {
  rates = {d.log_uniform(0.6, 1.0), d.log_uniform(1.2, 2.0), d.log_uniform(2.4, 3.6)};
  for (std::size_t i = rates.size() - 1; i > 0; --i) std::swap(rates[i], rates[d.index(i + 1)]);
  devices::SimulationProfile p;
  p.chamber_c = devices::Profile(-30.0);
  p.chamber_c.hold(1200)
      .ramp_at_rate(60.0, rates[0] / 60.0)
      .hold(1200)
      .ramp_at_rate(-30.0, rates[1] / 60.0)
      .hold(1200)
      .ramp_at_rate(15.0, rates[2] / 60.0)
      .hold(600);
  p.true_rate = devices::Profile(0.0);
  const double w = 50.0 * kRadPerDeg;
  while (p.true_rate.duration_s() < p.chamber_c.duration_s())
    p.true_rate.hold(200).ramp_to(w, 0).hold(200).ramp_to(-w, 0).hold(200).ramp_to(0.0, 0);
  p.source = "test oven";
  return p;
}

// Record `index` of the sequence `seed` with `effect_names` switched on (their parameters drawn).
inline OvenRecord make_record(devices::DeviceDefinition device, std::uint64_t seed, std::uint64_t index,
                              const std::vector<std::string>& effect_names, double sample_rate_hz = 1.0) {
  Draw d(seed, index);
  OvenRecord r;
  const auto profile = oven_profile(d, r.ramp_c_per_min);
  for (const auto& name : effect_names) switch_on(name, d, r.effects);
  r.hidden = effect_names;
  device.error_model.effects = r.effects;
  devices::SimulationOptions options;
  options.sample_rate_hz = sample_rate_hz;
  options.seed = d.bits();
  const auto sim = devices::simulate(device, profile, options);
  r.series = sim.to_time_series();
  r.truth_rad_s = sim.systematic_rate_rad_s;
  return r;
}

// Draws distinct effect names for record `index`.
inline std::vector<std::string> draw_effects(std::uint64_t seed, std::uint64_t index, int count) {
  Draw d(seed ^ 0xA5A5A5A5ULL, index);
  std::vector<std::string> pool(kEffectNames.begin(), kEffectNames.end()), out;
  for (int i = 0; i < count; ++i) {
    const std::size_t k = d.index(pool.size());
    out.push_back(pool[k]);
    pool.erase(pool.begin() + static_cast<std::ptrdiff_t>(k));
  }
  return out;
}

}  // namespace driftlab::testing_oven
