// Signal helpers on sampled time series, shared by the error model (models/error_model, the
// simulator's effects) and the effect plugins (plugins/effects, the discrepancy workflow's
// candidates), so that a simulated effect and the fitted candidate of the same name are one
// function. Pure kernels: std + Eigen, no files, no registry. Inputs are equal-length vectors with
// increasing time stamps (s); values in any unit (the output keeps it). Every helper is O(n).
#pragma once

#include <Eigen/Core>

namespace driftlab::signal {

// First-order lag y' = (x - y)/tau with x linear between samples, exact per step; y(0) = x(0)
// (starts in equilibrium). tau <= 0 returns x.
Eigen::VectorXd first_order_lag(const Eigen::VectorXd& time_s, const Eigen::VectorXd& x, double tau_s);

// One exact step of first_order_lag, for streaming use: from y at the previous input x_prev to the
// next input x, h seconds later, with a = exp(-h / tau_s) (callers with a fixed step compute it once).
inline double lag_step(double y, double x_prev, double x, double h, double tau_s, double a) {
  return a * y + (1.0 - a) * x_prev + (x - x_prev) * (1.0 - tau_s * (1.0 - a) / h);
}

// Central-difference derivative dx/dt (one-sided at the ends), unit of x per second.
Eigen::VectorXd time_derivative(const Eigen::VectorXd& time_s, const Eigen::VectorXd& x);

// Hysteresis branch state s in [-1, 1], starting at 0: after each temperature step dT,
// s <- sgn(dT) + (s - sgn(dT)) exp(-|dT| / width). Heating drives s to +1, cooling to -1. Depends
// only on the temperature path (degC, width in K).
Eigen::VectorXd hysteresis_state(const Eigen::VectorXd& temp_c, double width_k);

// One step of hysteresis_state, for streaming use: the state after a temperature step (K).
double hysteresis_step(double state, double step_k, double width_k);

// Median of the time steps (s): the sampling interval of a record with gaps or jitter, and the
// yardstick a gap is measured against. Throws std::invalid_argument for fewer than 2 samples.
double median_step(const Eigen::VectorXd& time_s);

}  // namespace driftlab::signal
