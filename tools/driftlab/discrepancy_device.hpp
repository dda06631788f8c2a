// What the discrepancy workflow (models/discrepancy/discrepancy.hpp) takes from a device file.
//
// device_prior: the device's systematic rate as the workflow's fixed prior, i.e. what
// `driftlab simulate` would produce without noise, for
// a given die temperature and true rate (the workflow turns the case sensor's reading into the die's
// with Options::sensor_time_constant_s = thermal.sensor_time_constant_s). The steps mirror
// devices/simulator.hpp:
//   T_res = lag(T_die, thermal_lag.tau_s) when the file lists that effect, else T_die
//   W_sys = s_dev(T_res) s_emp(T_res) s_eff(T_res) w + b_dev(T_res) + P_b(T_res - T0) + additive effects
// Effects already listed in the device file are part of the prior (fixed, not refitted).
// Cost: O(n) device-model evaluations.
//
// device_options: T0, the prior, the noise terms, the sensor's lag behind the die, the drive
// frequency line f0 (1 + a1 (T - T0)) for the drive-frequency thermometer, and the correction
// polynomial's degree (the file's bias polynomial degree, at least 1).
#pragma once

#include <algorithm>
#include <memory>

#include "devices/device_file.hpp"
#include "devices/device_model.hpp"
#include "models/discrepancy/discrepancy.hpp"
#include "models/error_model/error_model.hpp"

namespace driftlab::cli {

inline discrepancy::PriorFn device_prior(const devices::DeviceDefinition& device) {
  auto model = std::make_shared<const devices::DeviceModel>(device.physics);
  return [model, config = device.error_model](const Eigen::VectorXd& time_s, const Eigen::VectorXd& temp_c,
                                              const Eigen::VectorXd& true_rate) {
    const auto& effects = config.effects;
    const Eigen::VectorXd die =
        effects.thermal_lag ? error_model::first_order_lag(time_s, temp_c, effects.thermal_lag->tau_s) : temp_c;
    Eigen::VectorXd rate = error_model::additive_effects(effects, time_s, die);
    for (Eigen::Index k = 0; k < rate.size(); ++k) {
      error_model::DeviceResponse response = model->response(die[k]);
      response.scale_factor *= error_model::effect_scale_factor(effects, config.reference_temp_c, die[k]);
      rate[k] += error_model::systematic_rate(config, response, die[k], true_rate[k]);
    }
    return rate;
  };
}

inline discrepancy::Options device_options(const devices::DeviceDefinition& device) {
  discrepancy::Options o;
  o.reference_temp_c = device.error_model.reference_temp_c;
  o.prior = device_prior(device);
  o.noise = device.error_model.noise;
  o.sensor_time_constant_s = device.thermal.sensor_time_constant_s;
  o.drive_frequency_at_reference_hz = device.physics.drive.frequency_hz;
  o.drive_frequency_slope_hz_per_k = device.physics.drive.frequency_hz * device.physics.drive.frequency_tc_per_k;
  o.bias_degree = std::max(1, static_cast<int>(device.error_model.bias_polynomial_rad_s.size()) - 1);
  return o;
}

}  // namespace driftlab::cli
