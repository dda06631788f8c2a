// Oven-run simulator: a device definition (device_file.hpp) in a temperature chamber on a rate
// table, sampled at fs. Per sample k (t_k = k / fs):
//
//   T_chamber(t)   piecewise-linear chamber profile (soak and ramp segments)
//   T_die          = lag(T_chamber, thermal.die_time_constant_s)          first-order lag
//   T_sensor       = lag(T_die, thermal.sensor_time_constant_s)           case sensor lags the die
//   W_true(t)      piecewise-linear rate-table profile (static 0 by default)
//   W_sys, T_res   = systematic_rate(T_die, W_true) (systematic_rate.hpp, the one home of the
//                    chain; T_res, the resonator temperature, is reported as die_temp_c)
//   rate           = quantize(clip(W_sys + N + B + K noise, rate range), rate resolution)
//   temp           = quantize(T_sensor + white noise, temperature resolution)
//   drive_freq     = quantize(f_x(T_res) + white noise, resolution)       when the device has it
//
// Lags are exact for inputs linear between samples (signal::first_order_lag) and start in
// equilibrium with the first chamber value (the part is soaked before the record starts). The
// rate output bandwidth is fs/2 (no sense low-pass filter is modelled). Random streams: rate noise
// from error_model::rate_noise(seed); temperature and drive-frequency noise from their own streams,
// so each term's realization is independent of which others are switched on.
// Cost: O(n (M + 8)) for n samples and M flicker components, single thread; about 2.5 s CPU per hour at
// 1 kHz on one core (driftlab-bench BM_Simulate/3600000). Memory: 9 vectors of n doubles.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "devices/device_file.hpp"
#include "framework/time_series.hpp"

namespace driftlab::devices {

// A piecewise-linear profile: a start value, then segments that hold or move linearly to a target.
struct ProfileSegment {
  double duration_s = 0.0;       // >= 0; 0 makes a step
  std::optional<double> target;  // end value; absent = hold the current value
};

class Profile {
 public:
  Profile() = default;
  explicit Profile(double start, std::vector<ProfileSegment> segments = {});
  Profile& hold(double duration_s);
  Profile& ramp_to(double target, double duration_s);
  Profile& ramp_at_rate(double target, double rate_per_s);  // duration = |target - end| / rate

  double duration_s() const { return times_.back(); }
  double end_value() const { return values_.back(); }
  // Value at time t (the last value after the end; the later value at a step). O(log segments).
  double value_at(double t_s) const;
  // Values at increasing time stamps, O(n + segments).
  Eigen::VectorXd sample(const Eigen::VectorXd& time_s) const;
  // The breakpoints: times (s, from 0, non-decreasing) and the values there.
  const std::vector<double>& breakpoint_times() const { return times_; }
  const std::vector<double>& breakpoint_values() const { return values_; }

 private:
  std::vector<double> times_{0.0};
  std::vector<double> values_{0.0};
};

// A multi-position test (e.g. the six-position tumble that makes an accelerometer's scale factor
// observable): the direction pointing up, in the IMU's axes, cycles through `up_directions`, each
// held for `dwell_s`, from the first at t = 0 to the end of the run. A change of position is a step:
// the rotation between positions (its rate, its settling) is not simulated.
struct OrientationSchedule {
  std::vector<Eigen::Vector3d> up_directions;  // unit vectors, at least one
  double dwell_s = 0.0;                        // > 0, s

  const Eigen::Vector3d& up_at(double t_s) const;
};

struct SimulationProfile {
  Profile chamber_c{25.0};  // degC
  Profile true_rate{0.0};   // rad/s
  // Whole-IMU devices only: replaces the device's fixed up direction (the table turns about 'up').
  std::optional<OrientationSchedule> orientation;
  std::string source = "static 25 degC";  // for messages and describe

  double duration_s() const { return std::max(chamber_c.duration_s(), true_rate.duration_s()); }
};

// The paper's oven experiment (Li et al. 2023, Section 4): static gyro, chamber soaked at -30 degC
// for 30 min, ramped at 1 degC/min to +60 degC, soaked 30 min, ramped back at 1 degC/min to -30 degC
// and soaked 30 min (4.5 h). The paper gives the range, not the timing: the ramps are assumptions.
SimulationProfile default_oven_profile();

// Profile file (YAML, format driftlab-profile/1):
//   format: driftlab-profile/1
//   chamber: {start_c: -30, segments: [{hold_s: 1800}, {to_c: 60, rate_c_per_min: 1}, {to_c: 20, duration_s: 600}]}
//   rate:    {start_dps: 0, segments: [{hold_s: 600}, {to_dps: 100, duration_s: 0}, {hold_s: 60}]}
//   orientation: {dwell_s: 300, up_directions: [[0, 0, 1], [0, 0, -1], [1, 0, 0], [-1, 0, 0], ...]}
// Every section is optional (chamber defaults to 25 degC, rate to 0, orientation to the device's
// up_direction; orientation needs a whole-IMU device; chamber temperatures within
// [kMinTemperatureC, kMaxTemperatureC], framework/units.hpp); a segment is either
// {hold_s} or {to_*, duration_s | rate_*_per_min}. Throws ConfigError with file, line and key.
SimulationProfile load_profile_file(const std::filesystem::path& path);
SimulationProfile parse_profile(const std::string& yaml_text, const std::string& file);

class YamlFields;
// One profile section {start_<suffix>, segments: [{hold_s} | {to_<suffix>, duration_s |
// rate_<suffix>_per_min}]}, values in the file unit times `scale` (e.g. suffix "dps", scale
// rad/deg); problems are reported through `y`. Also used by other formats (the nav scenario).
// `values` bounds the start and every to_<suffix> value in the file unit (an absolute temperature:
// Bounds::absolute_temperature_c()).
struct Bounds;
Profile read_profile_section(YamlFields& y, const YAML::Node& node, const std::string& path,
                             const std::string& unit_suffix, double scale, double fallback_start, const Bounds& values);

struct SimulationOptions {
  double sample_rate_hz = 100.0;
  std::optional<double> duration_s;  // default: the profile's duration
  std::uint64_t seed = 1;
};

// All series have n samples. Units: SI (rad/s, degC, Hz, s).
struct SimulationRecord {
  Eigen::VectorXd time_s;
  Eigen::VectorXd rate_rad_s;             // measured output
  Eigen::VectorXd temp_c;                 // case temperature sensor
  Eigen::VectorXd true_rate_rad_s;        // rate-table input
  Eigen::VectorXd die_temp_c;             // resonator temperature that drives the physics
  Eigen::VectorXd drive_frequency_hz;     // drive-loop frequency channel (empty without that channel)
  Eigen::VectorXd chamber_temp_c;         // chamber air
  Eigen::VectorXd systematic_rate_rad_s;  // W_sys: everything but noise, clipping and quantization

  // Channels rate, temperature, true_rate, die_temperature and (when present) drive_frequency.
  TimeSeries to_time_series() const;
};

// The run's sample times t_k = k / fs, k = 0 .. n-1, n = floor(duration fs) (duration: the
// options', else the profile's). Throws ConfigError when fs or the duration is not positive, or the
// run has fewer than 2 samples.
Eigen::VectorXd sample_times(const SimulationProfile& profile, const SimulationOptions& options);

// Throws ConfigError as sample_times does, and when the device is a whole IMU (imu_simulator.hpp).
SimulationRecord simulate(const DeviceDefinition& device, const SimulationProfile& profile,
                          const SimulationOptions& options);

}  // namespace driftlab::devices
