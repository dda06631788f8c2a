// Candidate physical terms of the discrepancy workflow (issue 6): pure kernels that turn a record's
// channels into basis columns. Each term is linear in its amplitude(s) c and, where it has one, a
// 1-D nonlinear parameter theta (time constant, width, period) that the workflow searches. The
// time-series primitives are framework/signal.hpp, which the simulator's effect terms
// (models/error_model/error_model.hpp, additive_effects) use too, so a fitted term and the
// simulated term of the same name are the same function:
//
//   thermal_lag        T_model = lag(T, tau)                          (signal::first_order_lag)
//   temperature_rate   basis dT/dt, coefficient rad/s per K/s         (signal::time_derivative)
//   hysteresis         basis -s(T)/2, s the branch state in [-1, 1]   (signal::hysteresis_state)
//                      with width w; coefficient = height, rad/s. The state is computed on the
//                      temperature after a play (backlash) operator of half-width `deadband`:
//                      sensor noise makes tiny reversals that would otherwise pull s towards 0
//                      (Visintin, "Differential Models of Hysteresis", 1994, ch. III: the play operator).
//   warmup_transient   basis exp(-(t - t_start)/tau), coefficient = amplitude at t_start, rad/s
//   periodic           basis [sin(2 pi t/P), cos(2 pi t/P)]; A = hypot(a, b), phase = atan2(b, a)
//                      (the simulator's A sin(2 pi t/P + phase), t from 0)
//   scale_factor_temp  basis x^i w, i = 1..degree, x = T - T0, w the true rate; coefficient 1/K^i
//   mode_split_drift   T_model = T0 + (f - f_ref)/k: the resonator temperature read from the drive
//                      frequency f (the drive loop tracks f_x(T_res), devices/device_model.hpp), with
//                      f_ref and k = df/dT from the device file, or, when the file gives none, fitted
//                      to the record by least squares f ~ f_ref + k (T - T0) (biased towards a smaller
//                      |k| when the resonator lags the sensor: the loop of a lag flattens the line).
//                      The FMVMG bias b = g W_q sin(theta) follows the mode split and Q through the
//                      sense phase, i.e. the resonator's own temperature; when that differs from the
//                      case sensor's (a lag, a gradient) the drive frequency shows it directly.
//
// All inputs are equal-length vectors in SI (s, degC, rad/s, Hz) with increasing time. Every kernel
// is O(n) (the lag O(n) exponentials).
#pragma once

#include <Eigen/Core>

namespace driftlab::effects {

// Temperature seen through an extra first-order lag tau_s (> 0), starting in equilibrium.
Eigen::VectorXd lagged_temperature(const Eigen::VectorXd& time_s, const Eigen::VectorXd& temp_c, double tau_s);

// dT/dt, K/s.
Eigen::VectorXd temperature_rate(const Eigen::VectorXd& time_s, const Eigen::VectorXd& temp_c);

// Play (backlash) operator: the output follows x only when x moves more than `half_width` away;
// y(0) = x(0). half_width = 0 returns x.
Eigen::VectorXd play(const Eigen::VectorXd& x, double half_width);

// Basis -s/2 of the hysteresis offset (coefficient = full branch gap, cooling branch above).
Eigen::VectorXd hysteresis_basis(const Eigen::VectorXd& temp_c, double width_k, double deadband_k);

// exp(-(t - start)/tau).
Eigen::VectorXd warmup_basis(const Eigen::VectorXd& time_s, double start_time_s, double tau_s);

// n x 2: sin(2 pi t / P), cos(2 pi t / P).
Eigen::MatrixXd periodic_basis(const Eigen::VectorXd& time_s, double period_s);

struct Sinusoid {
  double amplitude;  // same unit as the coefficients
  double phase_rad;  // A sin(2 pi t/P + phase)
};
Sinusoid sinusoid_from_coefficients(double sin_coefficient, double cos_coefficient);

// n x degree: x^i w for i = 1..degree, x = T - T0.
Eigen::MatrixXd scale_factor_basis(const Eigen::VectorXd& temp_c, const Eigen::VectorXd& true_rate_rad_s,
                                   double reference_temp_c, int degree);

struct ResonatorThermometer {
  double frequency_at_reference_hz;  // f_ref, drive frequency at T0
  double slope_hz_per_k;             // k = df/dT
  Eigen::VectorXd temperature_c;     // T0 + (f - f_ref)/k
};
// The inversion T0 + (f - f_ref)/k for a known line (slope_hz_per_k != 0), else the least-squares
// line f ~ f_ref + k (T - T0) of the record first. Throws std::invalid_argument when the line has
// to be fitted and the temperature does not vary or k comes out 0.
ResonatorThermometer resonator_temperature(const Eigen::VectorXd& temp_c, const Eigen::VectorXd& drive_frequency_hz,
                                           double reference_temp_c, double frequency_at_reference_hz = 0.0,
                                           double slope_hz_per_k = 0.0);

}  // namespace driftlab::effects
