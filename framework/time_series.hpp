// A record: one time vector plus named channels, each with a role and an internal (SI) unit.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace driftlab {

// Well-known channel roles. Any other string is allowed too (it is the column's name stem).
namespace role {
inline constexpr const char* kRate = "rate";                // angular rate, rad/s
inline constexpr const char* kTemperature = "temperature";  // case / sensor temperature, degC
inline constexpr const char* kTrueRate = "true_rate";       // reference input rate, rad/s
// The true systematic rate of a simulated record (everything but noise), rad/s: measured minus
// this is the intrinsic noise, whose Allan deviation is the floor no compensation can go below.
inline constexpr const char* kSystematic = "systematic";
inline constexpr const char* kDieTemperature = "die_temperature";  // degC
inline constexpr const char* kDriveFrequency = "drive_frequency";  // Hz
}  // namespace role

struct Channel {
  std::string role;    // "rate", "temperature", "gyro_x", ... (IMU roles: framework/imu.hpp)
  std::string unit;    // internal unit symbol ("rad/s", "m/s^2", "degC", "Hz", "s", "1")
  std::string source;  // where it came from (CSV column name), for messages
  Eigen::VectorXd values;
  std::string read_unit = {};  // the unit spelling the source holds it in (outputs are written back in it)
};

class TimeSeries {
 public:
  TimeSeries() = default;
  explicit TimeSeries(Eigen::VectorXd time_s) : time_(std::move(time_s)) {}

  const Eigen::VectorXd& time() const { return time_; }
  Eigen::Index size() const { return time_.size(); }
  // Mean sample rate in Hz (sampling::mean_rate_hz: 0 for fewer than two samples or a zero span).
  double sample_rate_hz() const;

  // Adds or replaces the channel with this role. Throws DataError when the length differs.
  void set_channel(Channel channel);
  bool has(const std::string& role) const;
  // Throws DataError naming the role and the roles that exist.
  const Channel& channel(const std::string& role) const;
  const std::vector<Channel>& channels() const { return channels_; }

  // Identity of the unit that recorded instance `instance` (device id / serial), when the source
  // states it; empty otherwise.
  const std::string& device_id(int instance) const;
  void set_device_id(int instance, std::string id);

 private:
  Eigen::VectorXd time_;
  std::vector<Channel> channels_;
  std::vector<std::string> device_ids_;
};

}  // namespace driftlab
