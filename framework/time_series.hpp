// A record: one time vector plus named channels, each with a role and an internal (SI) unit.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "framework/sampling.hpp"

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
  // The time stamps, s; their sampling facts are computed here, once (sampling::facts_of, O(n)): a
  // step longer than gap_factor x the median step is a gap.
  explicit TimeSeries(Eigen::VectorXd time_s, double gap_factor = sampling::kGapFactor);

  const Eigen::VectorXd& time() const { return time_; }
  Eigen::Index size() const { return time_.size(); }
  // Median step, mean rate, gaps, segments and layout (evenly sampled, regular bursts, irregular)
  // of the time stamps: what every analysis asks before it assumes even sampling.
  const sampling::Facts& sampling_facts() const { return facts_; }
  // Computes the sampling facts again with another gap factor (a reader's --max-gap).
  void set_gap_factor(double gap_factor);
  // Mean sample rate in Hz (0 for fewer than two samples or a zero span).
  double sample_rate_hz() const { return facts_.mean_rate_hz; }

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
  sampling::Facts facts_;
  std::vector<Channel> channels_;
  std::vector<std::string> device_ids_;
};

}  // namespace driftlab
