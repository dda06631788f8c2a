#include "framework/signal.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace driftlab::signal {

Eigen::VectorXd first_order_lag(const Eigen::VectorXd& time_s, const Eigen::VectorXd& x, double tau_s) {
  if (tau_s <= 0.0 || x.size() == 0) return x;
  Eigen::VectorXd y(x.size());
  y[0] = x[0];
  for (Eigen::Index k = 0; k + 1 < x.size(); ++k) {
    const double h = time_s[k + 1] - time_s[k];
    y[k + 1] = lag_step(y[k], x[k], x[k + 1], h, tau_s, std::exp(-h / tau_s));
  }
  return y;
}

Eigen::VectorXd time_derivative(const Eigen::VectorXd& time_s, const Eigen::VectorXd& x) {
  const Eigen::Index n = x.size();
  Eigen::VectorXd d = Eigen::VectorXd::Zero(n);
  if (n < 2) return d;
  d[0] = (x[1] - x[0]) / (time_s[1] - time_s[0]);
  d[n - 1] = (x[n - 1] - x[n - 2]) / (time_s[n - 1] - time_s[n - 2]);
  for (Eigen::Index k = 1; k + 1 < n; ++k) d[k] = (x[k + 1] - x[k - 1]) / (time_s[k + 1] - time_s[k - 1]);
  return d;
}

Eigen::VectorXd hysteresis_state(const Eigen::VectorXd& temp_c, double width_k) {
  Eigen::VectorXd s = Eigen::VectorXd::Zero(temp_c.size());
  double state = 0.0;
  for (Eigen::Index k = 1; k < temp_c.size(); ++k) {
    state = hysteresis_step(state, temp_c[k] - temp_c[k - 1], width_k);
    s[k] = state;
  }
  return s;
}

double hysteresis_step(double state, double step_k, double width_k) {
  if (step_k == 0.0) return state;
  const double target = step_k > 0.0 ? 1.0 : -1.0;
  return target + (state - target) * std::exp(-std::abs(step_k) / width_k);
}

double median_step(const Eigen::VectorXd& time_s) {
  const Eigen::Index n = time_s.size();
  if (n < 2) throw std::invalid_argument("the record has fewer than 2 samples");
  std::vector<double> steps(static_cast<std::size_t>(n - 1));
  for (Eigen::Index k = 0; k + 1 < n; ++k) steps[static_cast<std::size_t>(k)] = time_s[k + 1] - time_s[k];
  const auto middle = steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2);
  std::nth_element(steps.begin(), middle, steps.end());
  return *middle;
}

}  // namespace driftlab::signal
