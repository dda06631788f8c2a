#include "framework/effect_catalogue.hpp"

#include <stdexcept>

#include "framework/units.hpp"

namespace driftlab {

const std::vector<EffectInfo>& effect_catalogue() {
  static const std::vector<EffectInfo> catalogue{
      {"thermal_lag",
       "the resonator lags the temperature sensor: the model's bias(T) follows lag(T, tau)",
       {{"tau_s", "s", 1.0, "extra first-order time constant of the resonator behind the sensor", false, true}}},
      {"temperature_rate",
       "bias proportional to the temperature rate dT/dt (thermal gradients across the die)",
       {{"coefficient_dph_per_c_per_min", "deg/h per degC/min", kRadPerSecPerDph * 60.0,
         "bias per unit heating rate"}}},
      {"hysteresis",
       "heating/cooling branch offset that saturates a few degC after each reversal",
       {{"height_dph", "deg/h", kRadPerSecPerDph, "gap between the branches (cooling branch above)"},
        {"width_c", "degC", 1.0, "temperature travel after a reversal to reach 1 - 1/e of the switch", false, true}}},
      {"warmup_transient",
       "power-on exponential from the start of the record: amplitude, time constant",
       {{"amplitude_dph", "deg/h", kRadPerSecPerDph, "value at the first sample"},
        {"tau_s", "s", 1.0, "decay time", false, true}}},
      {"periodic_disturbance",
       "a sinusoid on the rate (HVAC, chamber control cycling): amplitude, period, phase",
       {{"amplitude_dph", "deg/h", kRadPerSecPerDph, "amplitude"},
        {"period_s", "s", 1.0, "period", false, true},
        {"phase_deg", "deg", kRadPerDeg, "phase at t = 0: A sin(2 pi t / P + phase)"}}},
      {"scale_factor_temperature",
       "scale-factor drift with temperature beyond the model: s *= 1 + sum c_i (T - T0)^i "
       "(needs a true-rate channel)",
       {{"coefficients_ppm", "ppm/K^i", kPpm, "c_1, c_2, ... per K, K^2, ...", true}}},
  };
  return catalogue;
}

const EffectInfo* find_effect_info(std::string_view name) {
  for (const auto& e : effect_catalogue())
    if (e.name == name) return &e;
  return nullptr;
}

const EffectInfo& effect_info(std::string_view name) {
  if (const auto* e = find_effect_info(name)) return *e;
  throw std::logic_error("effect '" + std::string(name) + "' is not in the effect catalogue");
}

EffectValue effect_value(std::string_view effect, std::string_view key, std::vector<double> si_values) {
  for (const auto& k : effect_info(effect).keys) {
    if (k.key != key) continue;
    for (double& v : si_values) v /= k.to_si;
    return {k.key, k.unit, std::move(si_values)};
  }
  throw std::logic_error("effect '" + std::string(effect) + "' has no key '" + std::string(key) + "'");
}

}  // namespace driftlab
