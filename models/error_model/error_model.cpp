#include "models/error_model/error_model.hpp"

#include "framework/effect_catalogue.hpp"
#include "framework/seeded_random.hpp"
#include "framework/signal.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace driftlab::error_model {
double polynomial(const std::vector<double>& coefficients, double x) {
  double value = 0.0;
  for (auto it = coefficients.rbegin(); it != coefficients.rend(); ++it) value = value * x + *it;
  return value;
}

std::vector<GaussMarkovComponent> flicker_components(const NoiseTerms& terms) {
  std::vector<GaussMarkovComponent> components;
  if (terms.bias_instability_rad_s <= 0.0) return components;
  const double decades = std::log10(terms.flicker_tau_max_s / terms.flicker_tau_min_s);
  const int count = static_cast<int>(std::ceil(terms.flicker_poles_per_decade * decades)) + 1;
  const double sigma = terms.bias_instability_rad_s *
                       std::sqrt(std::numbers::ln10 / (std::numbers::pi * terms.flicker_poles_per_decade));
  for (int i = 0; i < count; ++i) {
    const double fraction = count == 1 ? 0.0 : static_cast<double>(i) / (count - 1);
    components.push_back({terms.flicker_tau_min_s * std::pow(10.0, fraction * decades), sigma});
  }
  return components;
}

std::vector<GaussMarkovComponent> gauss_markov_components(const NoiseTerms& terms) {
  auto components = flicker_components(terms);
  components.insert(components.end(), terms.gauss_markov.begin(), terms.gauss_markov.end());
  return components;
}

bool Effects::any() const {
  return thermal_lag || temperature_rate || hysteresis || warmup_transient || periodic_disturbance ||
         scale_factor_temperature;
}

double empirical_scale_factor(const Config& config, double die_temp_c) {
  const double x = die_temp_c - config.reference_temp_c;
  return 1.0 + x * polynomial(config.scale_factor_polynomial, x);
}

double systematic_rate(const Config& config, const DeviceResponse& device, double die_temp_c, double true_rate_rad_s) {
  const double x = die_temp_c - config.reference_temp_c;
  const double scale = device.scale_factor * empirical_scale_factor(config, die_temp_c);
  return scale * true_rate_rad_s + device.bias_rad_s + polynomial(config.bias_polynomial_rad_s, x);
}

void set_effect(Effects& effects, std::string_view name, const std::vector<std::vector<double>>& v) {
  const auto& info = effect_info(name);
  bool complete = v.size() == info.keys.size();
  for (std::size_t i = 0; complete && i < v.size(); ++i)
    complete = info.keys[i].list ? !v[i].empty() : v[i].size() == 1;
  if (!complete) throw std::logic_error("effect '" + std::string(name) + "': wrong number of values");
  if (name == "thermal_lag")
    effects.thermal_lag = ThermalLag{v[0][0]};
  else if (name == "temperature_rate")
    effects.temperature_rate = TemperatureRate{v[0][0]};
  else if (name == "hysteresis")
    effects.hysteresis = Hysteresis{v[0][0], v[1][0]};
  else if (name == "warmup_transient")
    effects.warmup_transient = WarmupTransient{v[0][0], v[1][0]};
  else if (name == "periodic_disturbance")
    effects.periodic_disturbance = PeriodicDisturbance{v[0][0], v[1][0], v[2][0]};
  else if (name == "scale_factor_temperature")
    effects.scale_factor_temperature = ScaleFactorTemperature{v[0]};
  else
    throw std::logic_error("effect '" + std::string(name) + "' has no error-model term");
}

std::vector<EffectParameters> effect_parameters(const Effects& e) {
  std::vector<EffectParameters> out;
  if (e.thermal_lag) out.push_back({"thermal_lag", {{e.thermal_lag->tau_s}}});
  if (e.temperature_rate) out.push_back({"temperature_rate", {{e.temperature_rate->coefficient_rad_s_per_k_s}}});
  if (e.hysteresis) out.push_back({"hysteresis", {{e.hysteresis->height_rad_s}, {e.hysteresis->width_k}}});
  if (e.warmup_transient)
    out.push_back({"warmup_transient", {{e.warmup_transient->amplitude_rad_s}, {e.warmup_transient->tau_s}}});
  if (const auto& p = e.periodic_disturbance)
    out.push_back({"periodic_disturbance", {{p->amplitude_rad_s}, {p->period_s}, {p->phase_rad}}});
  if (e.scale_factor_temperature)
    out.push_back({"scale_factor_temperature", {e.scale_factor_temperature->coefficients_per_k}});
  return out;
}

Eigen::VectorXd additive_effects(const Effects& effects, const Eigen::VectorXd& time_s,
                                 const Eigen::VectorXd& die_temp_c) {
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(time_s.size());
  if (effects.temperature_rate)
    sum += effects.temperature_rate->coefficient_rad_s_per_k_s * signal::time_derivative(time_s, die_temp_c);
  if (effects.hysteresis)
    sum -= 0.5 * effects.hysteresis->height_rad_s * signal::hysteresis_state(die_temp_c, effects.hysteresis->width_k);
  if (const auto& w = effects.warmup_transient) {
    const double t0 = time_s.size() > 0 ? time_s[0] : 0.0;
    sum += (w->amplitude_rad_s * (-(time_s.array() - t0) / w->tau_s).exp()).matrix();
  }
  if (const auto& p = effects.periodic_disturbance)
    sum += (p->amplitude_rad_s * (2.0 * std::numbers::pi * time_s.array() / p->period_s + p->phase_rad).sin()).matrix();
  return sum;
}

double effect_scale_factor(const Effects& effects, double reference_temp_c, double die_temp_c) {
  if (!effects.scale_factor_temperature) return 1.0;
  const double x = die_temp_c - reference_temp_c;
  return 1.0 + x * polynomial(effects.scale_factor_temperature->coefficients_per_k, x);
}

NormalStream::NormalStream(std::uint64_t seed, std::uint64_t stream)
    : engine_(splitmix64(splitmix64(seed) ^ splitmix64(stream + 0x632BE59BD9B4E019ULL))) {}

double NormalStream::uniform_open() {
  const double u = static_cast<double>(engine_() >> 11) * 0x1.0p-53;
  return 2.0 * u - 1.0;
}

double NormalStream::next() {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  double u, v, s;
  do {
    u = uniform_open();
    v = uniform_open();
    s = u * u + v * v;
  } while (s >= 1.0 || s == 0.0);
  const double factor = std::sqrt(-2.0 * std::log(s) / s);
  spare_ = v * factor;
  has_spare_ = true;
  return u * factor;
}

Eigen::VectorXd rate_noise(const NoiseTerms& terms, double fs_hz, Eigen::Index n, std::uint64_t seed) {
  Eigen::VectorXd noise = Eigen::VectorXd::Zero(n);
  const double h = 1.0 / fs_hz;
  if (terms.arw_rad_sqrt_s > 0.0) {
    NormalStream white(seed, 0);
    const double sigma = terms.arw_rad_sqrt_s * std::sqrt(fs_hz);
    for (Eigen::Index k = 0; k < n; ++k) noise[k] += sigma * white.next();
  }
  if (terms.rate_random_walk_rad_s_sqrt_s > 0.0) {
    NormalStream walk(seed, 1);
    const double step = terms.rate_random_walk_rad_s_sqrt_s * std::sqrt(h);
    double state = 0.0;
    for (Eigen::Index k = 0; k < n; ++k) {
      noise[k] += state;
      state += step * walk.next();
    }
  }
  const auto components = gauss_markov_components(terms);
  for (std::size_t i = 0; i < components.size(); ++i) {
    NormalStream stream(seed, 2 + i);
    const double a = std::exp(-h / components[i].tau_s);
    const double drive = components[i].sigma_rad_s * std::sqrt(1.0 - a * a);
    double state = components[i].sigma_rad_s * stream.next();
    for (Eigen::Index k = 0; k < n; ++k) {
      noise[k] += state;
      state = a * state + drive * stream.next();
    }
  }
  return noise;
}

}  // namespace driftlab::error_model
