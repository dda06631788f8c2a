// The device's systematic rate: everything `driftlab simulate` puts into the rate output except
// noise, clipping and quantization. The one place this chain lives; the simulator
// (simulator.hpp) and the discrepancy workflow's device prior (discrepancy_options.hpp) both call it:
//
//   T_res = lag(T_die, effects.thermal_lag.tau_s) when that effect is on, else T_die
//   W_sys = s_dev(T_res) s_emp(T_res) s_eff(T_res) w + b_dev(T_res) + P_b(T_res - T0)
//           + additive effects(t, T_res)        (dT/dt, hysteresis, warm-up, periodic)
//
// s_dev, b_dev: device physics (device_model.hpp); s_emp, P_b: the error model's empirical
// polynomials; s_eff and the additive effects: the switched-on effects (error_model.hpp).
// Inputs: equal-length vectors, time increasing (s), die temperature (degC), true rate (rad/s).
// Cost: O(n) device-model evaluations plus the effects' O(n) series.
#pragma once

#include <Eigen/Core>

#include "devices/device_model.hpp"
#include "models/error_model/error_model.hpp"

namespace driftlab::devices {

struct SystematicRate {
  Eigen::VectorXd rate_rad_s;          // W_sys, rad/s
  Eigen::VectorXd resonator_temp_c;    // T_res, degC: the temperature that drives the physics
  Eigen::VectorXd drive_frequency_hz;  // f_x(T_res), Hz, noise-free
};

SystematicRate systematic_rate(const DeviceModel& model, const error_model::Config& config,
                               const Eigen::VectorXd& time_s, const Eigen::VectorXd& die_temp_c,
                               const Eigen::VectorXd& true_rate_rad_s);

}  // namespace driftlab::devices
