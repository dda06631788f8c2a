// Gyro error model: the systematic rate error (bias and scale factor versus die temperature) plus
// the stochastic terms of IEEE Std 952-1997 Annex C, and the optional effects that the
// discrepancy workflow looks for. Pure kernel: std + Eigen, SI units (rad/s, s, degC, K).
//
// Measured rate (before range clipping and quantization, which the simulator applies):
//
//   w_meas(t) = s(T) * w_true(t) + b(T) + n(t) + e(t)
//
//   s(T) = s_dev(T) * (1 + P_s(T - T0))          scale factor, dimensionless (1 at T0)
//   b(T) = b_dev(T) + P_b(T - T0)                bias, rad/s
//
// where s_dev, b_dev come from the device physics (devices/device_model.hpp evaluates them and
// passes a DeviceResponse, so this kernel stays free of the device description), P_s and P_b are
// empirical polynomials in (T - T0), n(t) is the noise and e(t) the sum of the switched-on effects.
//
// Noise n(t), sampled at fs = 1/h (IEEE 952 Annex C, Allan-variance signatures):
//   N  angle random walk, rad/sqrt(s):   white rate, per-sample std N*sqrt(fs);  s2(tau) = N^2/tau
//   B  bias instability, rad/s:          flicker rate, two-sided PSD B^2/(2 pi f);
//                                        flat Allan floor s(tau) = B*sqrt(2 ln2/pi) = 0.664 B
//   K  rate random walk, rad/s/sqrt(s):  random-walk rate, step std K*sqrt(h);  s2(tau) = K^2 tau/3
//   GM Gauss-Markov bias noise (sigma rad/s, tau s), any number: the bump of a MEMS bias instability
//      that is no flicker floor; first-order, stationary std sigma, correlation time tau.
//   quantization: amplitude LSB of the rate output (rounding, applied by the simulator).
//
// Flicker approximation (B -> Gauss-Markov parameters): M first-order Gauss-Markov processes with
// correlation times log-spaced over [tau_min, tau_max], d = poles_per_decade per decade, all with
// the same variance sigma^2. A Lorentzian of variance sigma^2 and corner f_c = 1/(2 pi tau) has
// one-sided PSD 4 sigma^2 tau / (1 + (f/f_c)^2); a log-uniform density d/ln10 of equal-variance
// Lorentzians integrates to a one-sided PSD sigma^2 d / (ln10 f) between the corners. Equating the
// two-sided value sigma^2 d / (2 ln10 f) to B^2/(2 pi f) gives
//
//   sigma^2 = B^2 ln(10) / (pi d).
//
// The Allan floor is flat (within about +-5 % for d >= 2) for tau roughly in
// [2 tau_min, tau_max / 3]; outside that range the term rolls off like a Gauss-Markov process.
// Discretization is exact: x_{k+1} = a x_k + sigma sqrt(1 - a^2) w_k, a = exp(-h/tau).
//
// Every noise term draws from its own random stream derived from (seed, term index), so switching
// one term or effect on or off never changes the realization of another (the explicit Gauss-Markov
// terms follow the flicker components' streams).
// Cost: O(n (M + 2)) normal deviates for n samples; memory O(n) for the output only.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <vector>

namespace driftlab::error_model {

// Polynomial in x = T - T0: c[0] + c[1] x + c[2] x^2 + ...  (Horner evaluation).
double polynomial(const std::vector<double>& coefficients, double x);

// What the device physics contributes at one die temperature.
struct DeviceResponse {
  double scale_factor = 1.0;      // s_dev(T), dimensionless, 1 at the calibration temperature
  double bias_rad_s = 0.0;        // b_dev(T), rad/s
  double drive_frequency_hz = 0;  // resonance the drive loop tracks at T, Hz
};

struct GaussMarkovComponent {
  double tau_s;        // correlation time, s
  double sigma_rad_s;  // stationary standard deviation, rad/s
};

struct NoiseTerms {
  double arw_rad_sqrt_s = 0.0;                     // N, rad/sqrt(s)
  double bias_instability_rad_s = 0.0;             // B, rad/s
  double rate_random_walk_rad_s_sqrt_s = 0.0;      // K, rad/s/sqrt(s)
  double flicker_tau_min_s = 0.5;                  // shortest Gauss-Markov correlation time, s
  double flicker_tau_max_s = 5000.0;               // longest Gauss-Markov correlation time, s
  double flicker_poles_per_decade = 2.0;           // d, poles per decade of correlation time
  std::vector<GaussMarkovComponent> gauss_markov;  // explicit Gauss-Markov terms (GM above)
};

// The Gauss-Markov set that approximates flicker of bias instability B (mapping above).
// Empty when B = 0. Number of components M = ceil(d * log10(tau_max / tau_min)) + 1.
std::vector<GaussMarkovComponent> flicker_components(const NoiseTerms& terms);
// Every Gauss-Markov process of the noise: the flicker components, then the explicit terms.
std::vector<GaussMarkovComponent> gauss_markov_components(const NoiseTerms& terms);

// Optional effects (issue 6): each absent by default; the discrepancy workflow's fitted model
// leaves them out and names them when the data show them.
struct ThermalLag {  // the resonator (die) lags the temperature sensor
  double tau_s;      // extra first-order lag, s
};
struct TemperatureRate {             // bias proportional to the die's dT/dt
  double coefficient_rad_s_per_k_s;  // rad/s per K/s
};
struct Hysteresis {     // heating/cooling branch offset, rate independent
  double height_rad_s;  // full gap between the branches, rad/s (cooling branch is +height/2)
  double width_k;       // temperature travel after a reversal to reach 1 - 1/e of the switch, K
};
struct WarmupTransient {   // power-on exponential
  double amplitude_rad_s;  // at t = 0, rad/s
  double tau_s;            // decay time, s
};
struct PeriodicDisturbance {  // a sinusoid on the rate
  double amplitude_rad_s;
  double period_s;
  double phase_rad = 0.0;
};
struct ScaleFactorTemperature {            // extra scale-factor drift: s *= 1 + sum_i c_i (T - T0)^(i+1)
  std::vector<double> coefficients_per_k;  // 1/K, 1/K^2, ...
};

struct Effects {
  std::optional<ThermalLag> thermal_lag;
  std::optional<TemperatureRate> temperature_rate;
  std::optional<Hysteresis> hysteresis;
  std::optional<WarmupTransient> warmup_transient;
  std::optional<PeriodicDisturbance> periodic_disturbance;
  std::optional<ScaleFactorTemperature> scale_factor_temperature;
  bool any() const;
};

// The systematic part and its parameters.
struct Config {
  double reference_temp_c = 25.0;               // T0, degC
  std::vector<double> bias_polynomial_rad_s;    // P_b coefficients: rad/s, rad/s/K, rad/s/K^2 ...
  std::vector<double> scale_factor_polynomial;  // P_s coefficients: 1/K, 1/K^2, ... (no constant)
  NoiseTerms noise;
  Effects effects;
};

// Empirical scale-factor factor 1 + P_s(T - T0) (P_s has no constant term).
double empirical_scale_factor(const Config& config, double die_temp_c);

// Systematic rate (no noise, no effects): s(T) w + b(T).
double systematic_rate(const Config& config, const DeviceResponse& device, double die_temp_c, double true_rate_rad_s);

// ---- effects as the effect catalogue names them (framework/effect_catalogue.hpp) ------------

// Switches on catalogue effect `name` with its key values in SI, one entry per catalogue key in
// catalogue order (a list for list keys, one value otherwise). Throws std::logic_error for a name
// outside the catalogue or a wrong number of values (a programming error: callers check the catalogue).
void set_effect(Effects& effects, std::string_view name, const std::vector<std::vector<double>>& si_values);

struct EffectParameters {
  std::string name;                            // catalogue name
  std::vector<std::vector<double>> si_values;  // per catalogue key, SI
};
// The switched-on effects in catalogue order with their values in SI (the inverse of set_effect).
std::vector<EffectParameters> effect_parameters(const Effects& effects);

// ---- effect time series (vectors of equal length n, time stamps increasing) -------------------
// The time-series primitives (first-order lag, derivative, hysteresis branch state) are
// framework/signal.hpp, shared with the effect plugins that fit the same terms.

// Sum of the additive effect terms (temperature rate, hysteresis, warm-up, periodic), rad/s, for
// the die temperature series. Thermal lag and scale factor are not additive: the simulator applies
// them to the die temperature and the scale factor.
Eigen::VectorXd additive_effects(const Effects& effects, const Eigen::VectorXd& time_s,
                                 const Eigen::VectorXd& die_temp_c);

// Scale-factor multiplier of the ScaleFactorTemperature effect (1 when absent).
double effect_scale_factor(const Effects& effects, double reference_temp_c, double die_temp_c);

// ---- random numbers ---------------------------------------------------------------------------

// Portable standard normal deviates (Marsaglia polar method on a 53-bit uniform from
// std::mt19937_64), identical on every platform for the same seed.
class NormalStream {
 public:
  NormalStream(std::uint64_t seed, std::uint64_t stream);
  double next();

 private:
  double uniform_open();  // in (-1, 1)
  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

// Rate noise N + B + K at fs for n samples, from (seed): streams 0 (white), 1 (random walk),
// 2.. (Gauss-Markov components). Gauss-Markov states start in their stationary distribution; the
// random walk starts at 0. Result in rad/s. O(n (M + 2)).
Eigen::VectorXd rate_noise(const NoiseTerms& terms, double fs_hz, Eigen::Index n, std::uint64_t seed);

}  // namespace driftlab::error_model
