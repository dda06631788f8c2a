#include "devices/imu_simulation_columns.hpp"

#include <cmath>

#include "framework/units.hpp"

namespace driftlab::devices {

Eigen::VectorXd written_values(const Eigen::VectorXd& internal, const std::string& unit, double resolution) {
  const auto u = find_unit(unit);
  Eigen::VectorXd values = internal.unaryExpr([&](double v) { return from_internal(v, *u); });
  if (resolution > 0.0) {
    const double steps = u->scale / resolution;
    if (std::abs(steps - std::round(steps)) < 1e-6 * steps) {
      const double whole = std::round(steps);
      for (double& v : values) v = std::round(v * whole) / whole;
    }
  }
  return values;
}

std::vector<ImuSimulationColumn> imu_simulation_columns(const ImuDefinition& imu, const ImuSimulationRecord& record) {
  std::vector<ImuSimulationColumn> columns{{"t_s", "time_s", "s", record.time_s}};
  for (std::size_t i = 0; i < record.instances.size(); ++i) {
    const auto& instance = record.instances[i];
    const std::string digit = i == 0 ? "" : std::to_string(i);
    auto add = [&](const std::string& prefix, auto member) {
      for (int a = 0; a < 3; ++a) {
        const std::string stem = prefix + "gyro" + digit + "_" + "xyz"[a];
        columns.push_back({stem + "_dps", stem + "_rad_s", "deg/s", instance.gyro[a].*member});
      }
      for (int a = 0; a < 3; ++a) {
        const std::string name = prefix + "accel" + digit + "_" + "xyz"[a] + "_mps2";
        columns.push_back({name, name, "m/s^2", instance.accel[a].*member});
      }
    };
    add("", &ImuAxisRecord::measured);
    // degC is the internal temperature unit: the snapped values are the written ones.
    const std::string temp = "temp" + digit + "_c";
    columns.push_back(
        {temp, temp, "degC", written_values(instance.temp_c, "degC", imu.instances[i].temperature_resolution_c)});
    if (instance.device_id)
      columns.push_back({"device_id" + digit, "device_id" + digit, "1",
                         Eigen::VectorXd::Constant(record.time_s.size(), *instance.device_id)});
    add("true_", &ImuAxisRecord::truth);
    add("systematic_", &ImuAxisRecord::systematic);
  }
  return columns;
}

}  // namespace driftlab::devices
