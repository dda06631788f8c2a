// Example calibration models shared by the calibration tests.
#pragma once

#include <vector>

#include "models/calibration/calibration_model.hpp"

namespace driftlab::calibration::testing {

// A temperature-only polynomial model (kind poly, clamp), coefficients in rad/s/K^i about 25 degC.
inline CalibrationModel example_polynomial_model(std::vector<double> coefficients = {1e-3, 2e-5, -3e-7},
                                                 double min_c = -10.0, double max_c = 50.0) {
  CalibrationModel m;
  m.reference_temp_c = 25.0;
  m.valid_min_c = min_c;
  m.valid_max_c = max_c;
  m.bias_sigma_rad_s.assign(coefficients.size(), 1e-9);
  m.bias_rad_s = std::move(coefficients);
  return m;
}

// Every term switched on: lag, dT/dt, hysteresis, an RBF network, a scale factor, noise terms.
inline CalibrationModel example_full_model() {
  CalibrationModel m = example_polynomial_model();
  m.kind = ModelKind::Rbf;
  m.extrapolation = Extrapolation::Linear;
  m.lag_tau_s = 100.0;
  m.derivative_tau_s = 20.0;
  m.temperature_rate_rad_s_per_k_s = 3e-3;
  m.hysteresis_rad_s = -2e-5;
  m.hysteresis_width_k = 1.5;
  m.temperature_rate_range_k_s = InputRange{-0.1, 0.1};  // the test records leave both ranges
  m.hysteresis_state_range = InputRange{-0.8, 1.0};
  RbfTerm r;
  r.mean = {20, 0, 0};
  r.scale = {15, 0.01, 0.5};
  r.input_min = {-20, -0.02, -1};  // dT/dt within +-1.2 degC/min: the test records leave it
  r.input_max = {55, 0.02, 1};
  r.centres = Eigen::MatrixXd(3, 3);
  r.centres << 0.1, -0.2, 0.3, -1.0, 0.5, 0.0, 0.7, 0.0, -0.9;
  r.sigma = 0.8;
  r.weights_rad_s = {1e-5, -2e-5, 3e-6};
  r.bias_rad_s = 1e-6;
  m.rbf = r;
  m.scale_factor_per_k = {1e-4, 2e-6};
  m.noise = {1e-4, 2e-5, 3e-7, 100.0};
  m.fit.records = {"a.csv", "b.csv"};
  m.fit.samples = 1234;
  m.fit.selection = "test";
  m.fit.holdout_rms_rad_s = 1e-5;
  return m;
}

// A whole-IMU model of one channel (for the tests of single-channel behaviour).
inline ImuCalibration one_channel(CalibrationModel m, imu::ChannelId id = {imu::Sensor::Gyro, 'z', 0}) {
  ImuCalibration out;
  out.device = "fmvmg";
  out.channels.push_back({id, id.role(), id.role(), "rad/s", "temperature", "", true, std::move(m)});
  if (id.sensor == imu::Sensor::Accel) out.channels.back().read_unit = "m/s^2";
  return out;
}

}  // namespace driftlab::calibration::testing
