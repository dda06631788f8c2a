// Oven-run simulator for a whole IMU (imu_definition.hpp): every instance in the same chamber on the
// same rate table, sampled at fs. Per instance, per sample k (t_k = k / fs):
//
//   T_die          = lag(T_chamber, die_time_constant_s)          the instance's own die
//   T_sensor       = lag(T_die, sensor_time_constant_s)
//   temp           = quantize(T_sensor + white noise, temperature resolution)
//   per axis a of each sensor (lags as in simulator.hpp, exact for piecewise-linear input):
//     T_a          = lag(T_die, lag_s)
//     truth        gyro: W_table(t) up_a(t) (the table turns about 'up'); accel: g up_a(t) (at rest
//                  the accelerometer reads the specific force, +g along up: z up gives +g on z);
//                  up(t) is the profile's orientation schedule, else the device's up_direction
//     systematic   = (1 + P_s(T_a - T0)) truth + P_b(T_a - T0)
//     measured     = systematic + noise          (no clipping, no quantization)
// Not modelled: Earth rotation, the centripetal acceleration of an off-centre mount, cross-axis
// sensitivity and misalignment, output range and resolution.
//
// Random streams: every noise source (instance i; gyro x, y, z, accel x, y, z, temperature) draws
// from a seed derived from (options.seed, i, source) alone, so its realization is the same whatever
// else the file describes (other instances, other axes' noise). Same seed, same record.
// Cost: O(n (7 + M)) per axis for n samples and M flicker components, single thread; memory 3
// vectors of n doubles per axis plus 2 per instance and 3 for the up direction.
#pragma once

#include <Eigen/Core>

#include <array>
#include <optional>
#include <vector>

#include "devices/imu_definition.hpp"
#include "devices/simulator.hpp"

namespace driftlab::devices {

struct ImuAxisRecord {
  Eigen::VectorXd measured;    // internal unit (gyro rad/s, accel m/s^2)
  Eigen::VectorXd truth;       // reference input
  Eigen::VectorXd systematic;  // measured without noise
};

struct ImuInstanceRecord {
  std::optional<double> device_id;           // the instance's, when the file gives one
  std::array<ImuAxisRecord, 3> gyro, accel;  // x, y, z
  Eigen::VectorXd temp_c;                    // the instance's temperature output, degC
  Eigen::VectorXd die_temp_c;                // its die, degC
};

struct ImuSimulationRecord {
  Eigen::VectorXd time_s;
  Eigen::VectorXd chamber_temp_c;
  std::vector<ImuInstanceRecord> instances;  // as in the definition
};

// Throws ConfigError as sample_times (simulator.hpp) does.
ImuSimulationRecord simulate_imu(const ImuDefinition& imu, const SimulationProfile& profile,
                                 const SimulationOptions& options);

}  // namespace driftlab::devices
