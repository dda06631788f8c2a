#include "plugins/effects/effects.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "framework/signal.hpp"

namespace driftlab::effects {

Eigen::VectorXd lagged_temperature(const Eigen::VectorXd& time_s, const Eigen::VectorXd& temp_c, double tau_s) {
  return signal::first_order_lag(time_s, temp_c, tau_s);
}

Eigen::VectorXd temperature_rate(const Eigen::VectorXd& time_s, const Eigen::VectorXd& temp_c) {
  return signal::time_derivative(time_s, temp_c);
}

Eigen::VectorXd play(const Eigen::VectorXd& x, double half_width) {
  Eigen::VectorXd y = x;
  for (Eigen::Index k = 1; k < x.size(); ++k) y[k] = std::clamp(y[k - 1], x[k] - half_width, x[k] + half_width);
  return y;
}

Eigen::VectorXd hysteresis_basis(const Eigen::VectorXd& temp_c, double width_k, double deadband_k) {
  return -0.5 * signal::hysteresis_state(play(temp_c, deadband_k), width_k);
}

Eigen::VectorXd warmup_basis(const Eigen::VectorXd& time_s, double start_time_s, double tau_s) {
  return (-(time_s.array() - start_time_s) / tau_s).exp().matrix();
}

Eigen::MatrixXd periodic_basis(const Eigen::VectorXd& time_s, double period_s) {
  Eigen::MatrixXd basis(time_s.size(), 2);
  const Eigen::ArrayXd phase = (2.0 * std::numbers::pi / period_s) * time_s.array();
  basis.col(0) = phase.sin().matrix();
  basis.col(1) = phase.cos().matrix();
  return basis;
}

Sinusoid sinusoid_from_coefficients(double sin_coefficient, double cos_coefficient) {
  return {std::hypot(sin_coefficient, cos_coefficient), std::atan2(cos_coefficient, sin_coefficient)};
}

Eigen::MatrixXd scale_factor_basis(const Eigen::VectorXd& temp_c, const Eigen::VectorXd& true_rate_rad_s,
                                   double reference_temp_c, int degree) {
  Eigen::MatrixXd basis(temp_c.size(), degree);
  const Eigen::ArrayXd x = temp_c.array() - reference_temp_c;
  Eigen::ArrayXd column = true_rate_rad_s.array();
  for (int i = 0; i < degree; ++i) {
    column *= x;
    basis.col(i) = column.matrix();
  }
  return basis;
}

ResonatorThermometer resonator_temperature(const Eigen::VectorXd& temp_c, const Eigen::VectorXd& drive_frequency_hz,
                                           double reference_temp_c, double frequency_at_reference_hz,
                                           double slope_hz_per_k) {
  double slope = slope_hz_per_k, f_ref = frequency_at_reference_hz;
  if (slope == 0.0) {
    const Eigen::ArrayXd x = temp_c.array() - reference_temp_c;
    const double x_mean = x.mean(), f_mean = drive_frequency_hz.mean();
    const double sxx = (x - x_mean).square().sum();
    if (!(sxx > 0.0)) throw std::invalid_argument("the temperature does not vary");
    slope = ((x - x_mean) * (drive_frequency_hz.array() - f_mean)).sum() / sxx;
    if (slope == 0.0) throw std::invalid_argument("the drive frequency does not follow the temperature");
    f_ref = f_mean - slope * x_mean;
  }
  ResonatorThermometer t{f_ref, slope, {}};
  t.temperature_c = ((drive_frequency_hz.array() - f_ref) / slope + reference_temp_c).matrix();
  return t;
}

}  // namespace driftlab::effects
