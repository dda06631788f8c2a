// A whole IMU as a device file describes it (the `imu:` section, schema in device_file.hpp): one or
// more instances (IMUs on one board), each with three gyro axes, three accelerometer axes and a
// temperature sensor. Every axis is an empirical model of its own; there is no device physics:
//
//   y(t)   = s(T_a) u(t) + b(T_a) + n(t)        measured, internal units (gyro rad/s, accel m/s^2)
//   T_a    = lag(T_die, lag_s)                  the axis's sensing element lags the die
//   s(T)   = 1 + P_s(T - T0)                    scale factor, 1 at T0 (P_s has no constant term)
//   b(T)   = P_b(T - T0)                        bias
//   u(t)   reference input (imu_simulator.hpp: rate-table rate or gravity along the axis)
//   n(t)   N + B + K noise (error_model::rate_noise)
//
// Plain data in SI; device_file.cpp converts the file's units on load.
#pragma once

#include <Eigen/Core>

#include <array>
#include <optional>
#include <vector>

#include "framework/units.hpp"
#include "models/error_model/error_model.hpp"

namespace driftlab::devices {

struct ImuAxis {
  std::vector<double> bias_polynomial;          // P_b: c_i in internal unit per K^i (rad/s or m/s^2)
  std::vector<double> scale_factor_polynomial;  // P_s: 1/K, 1/K^2, ... (no constant term)
  // N, B, K. The gyro reads the fields as named (rad/sqrt(s), rad/s, rad/s/sqrt(s)); the same
  // kernel serves the accelerometer in m/s^2: N in m/s/sqrt(s), B in m/s^2, K in m/s^2/sqrt(s).
  error_model::NoiseTerms noise;
  double lag_s = 0.0;  // first-order lag of the sensing element behind the die, s (0: none)
};

struct ImuSensor {
  std::array<ImuAxis, 3> axes;  // x, y, z
};

struct ImuInstance {
  std::optional<double> device_id;        // numeric identity (PX4 device_id style), when the file gives one
  double die_time_constant_s = 0.0;       // die lags the chamber air, s
  double sensor_time_constant_s = 0.0;    // temperature sensor lags the die, s
  double temperature_noise_c = 0.0;       // white noise std per sample, K
  double temperature_resolution_c = 0.0;  // LSB of the temperature output, K (0: not quantized)
  ImuSensor gyro, accel;
};

struct ImuDefinition {
  double reference_temp_c = 25.0;  // T0 of every polynomial, degC (the file's reference_temp_c)
  // The board's orientation on the rate table: 'up' (against gravity, along the table's rotation
  // axis) in the IMU's axes, a unit vector. At rest the accelerometer reads +gravity along it.
  Eigen::Vector3d up{0.0, 0.0, 1.0};
  double gravity_mps2 = kStandardGravity;
  std::vector<ImuInstance> instances;  // at least one, at most kMaxImuInstances
};

// Instance numbers are one digit in the column names (framework/imu.hpp: gyro1_x .. gyro9_x).
inline constexpr int kMaxImuInstances = 10;

}  // namespace driftlab::devices
