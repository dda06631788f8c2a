// The columns of a whole-IMU simulation record (imu_simulator.hpp), one list for every writer:
// `driftlab simulate --device imu3` writes them as CSV in display units, the Python module returns
// them in SI. Order and names (issue 20, the names framework/imu.hpp and the CSV reader know): t,
// then per instance i (the digit omitted for i = 0) the measured gyro{i}_{x,y,z} and
// accel{i}_{x,y,z}, temp{i}, device_id{i} when the file gives one, the reference input
// true_gyro{i}_*, true_accel{i}_*, and the noise-free systematic_gyro{i}_*, systematic_accel{i}_*.
// Written units: gyro deg/s (suffix _dps), accel m/s^2 (_mps2), temperature degC (_c), time s (_s),
// device id none. SI names: time_s, gyro _rad_s, the others as written.
#pragma once

#include <Eigen/Core>

#include <string>
#include <vector>

#include "devices/imu_definition.hpp"
#include "devices/imu_simulator.hpp"

namespace driftlab::devices {

struct ImuSimulationColumn {
  std::string name;        // as written: "gyro1_x_dps", "temp_c", "device_id"
  std::string si_name;     // in SI: "gyro1_x_rad_s", "temp_c", "device_id"
  std::string unit;        // the written unit's symbol (framework/units.hpp), "1" for the device id
  Eigen::VectorXd values;  // SI (internal unit); temperatures snapped to the instance's resolution
};

std::vector<ImuSimulationColumn> imu_simulation_columns(const ImuDefinition& imu, const ImuSimulationRecord& record);

// `internal` in `unit` (a framework/units.hpp symbol), snapped to `resolution` (internal units;
// 0 = none) as k / steps, steps = 1 / resolution in that unit when it is a whole number, so that the
// shortest round-trip text of each value is the clean decimal the device would print.
Eigen::VectorXd written_values(const Eigen::VectorXd& internal, const std::string& unit, double resolution = 0.0);

}  // namespace driftlab::devices
