// The channels of an inertial measurement unit: sensor (gyro, accelerometer) x axis (x, y, z) x
// instance (0, 1, 2, ... : several IMUs on one board, PX4 TC_G0..2, ArduPilot INS_TCAL1..3), and
// the temperature each instance reports.
//
// Every IMU channel is a channel of a TimeSeries whose role spells its identity:
//   gyro_x, gyro_y, gyro_z, accel_x, accel_y, accel_z        instance 0
//   gyro1_x, accel2_z, ...                                   instance 1, 2, ...
//   temperature, temperature1, temperature2, ...             the temperature of instance 0, 1, 2, ...
//   true_gyro_x, true_accel1_z, ...                          the reference input (rate table, gravity)
//   systematic_gyro_x, ...                                   a simulator's noise-free output (evidence)
// Internal units: gyro rad/s, accelerometer m/s^2, temperature degC.
//
// The single-axis role "rate" (a gyro of unknown axis) stays what it was: one gyro channel.
//
// Column headers people log are recognised by recognize_imu_column: gyro_x, gyr_x, gx, GyrX,
// gyro_x_rad_s, gyro_x_dps, accel_z, acc_z, ax, AccZ, accel_z_mps2, accel_z_g, an instance digit
// after the sensor (gyro1_x, GyrX1 / GyrX_1, accel_2_z), and temperatures temp, temp_c, temperature,
// T, temp1, imu1_temp_c, ... A header without a unit suffix is read in SI (rad/s, m/s^2, degC), the
// unit ROS, PX4 and ArduPilot log in; the unit the column was read in is kept with the channel and
// every output of that channel is written back in it.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace driftlab::imu {

enum class Sensor { Gyro, Accel };
std::string to_string(Sensor sensor);  // "gyro", "accel"

// The unit biases and residuals of a sensor are shown in (gyro deg/h, accelerometer mg) and the
// factor from its internal unit (rad/s, m/s^2) to it.
struct DisplayUnit {
  double per_internal;
  const char* name;
};
DisplayUnit display_unit(Sensor sensor);

inline constexpr int kMaxInstance = 99;  // the role names' last instance: gyro99_x, temperature99

struct ChannelId {
  Sensor sensor = Sensor::Gyro;
  char axis = 'z';  // 'x', 'y', 'z'
  int instance = 0;
  std::string role() const;  // "gyro_x", "accel1_z"
  auto operator<=>(const ChannelId&) const = default;
};

// Inverse of ChannelId::role (also accepts "true_"/"systematic_" prefixed roles when `prefix`
// names it); empty for any other role.
std::optional<ChannelId> parse_role(std::string_view role, std::string_view prefix = "");

std::string temperature_role(int instance);                        // "temperature", "temperature1"
std::optional<int> parse_temperature_role(std::string_view role);  // inverse (nullopt otherwise)
std::string truth_role(const ChannelId& id);                       // "true_gyro_x"
std::string systematic_role(const ChannelId& id);                  // "systematic_gyro_x"

// Internal unit of a sensor's channels ("rad/s", "m/s^2").
std::string internal_unit(Sensor sensor);

// A recognised header: the role and the unit spelling to read it in (units.hpp).
struct ColumnMatch {
  std::string role;
  std::string unit;
};
// The IMU role a column header names, or nullopt. Case-insensitive; see the header comment.
std::optional<ColumnMatch> recognize_imu_column(std::string_view header);

// Channels selected by text such as "gyro", "accel", "gyro_x,accel_z", "gyro1", "all"
// (comma-separated; each item a sensor, a sensor with instance, or a full role). Throws
// ConfigError naming `option` for an item that names no sensor or channel.
struct Selection {
  std::vector<std::string> items;
  bool selects(const ChannelId& id) const;
};
Selection parse_selection(const std::string& text, const std::string& option);

}  // namespace driftlab::imu
