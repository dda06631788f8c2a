// The `driftlab nav` demonstration (issue 14): a vehicle scenario, the simulated drive (yaw rate
// from the device simulator in the warming cabin, wheel-odometry speed, optional position fixes)
// and the navigation EKF run over it.
//
// Scenario file (YAML, format driftlab-nav-scenario/1; the bundled one is
// tools/mrpt/scenarios/cold_start_drive.yaml):
//   format: driftlab-nav-scenario/1
//   sample_rate_hz: 50            gyro and odometry rate, Hz
//   seed: 7                       drive seed (gyro noise, odometry noise, fixes); whole number, digits
//   calibration_seed: 1001        seed of the oven run `nav` calibrates on when given no model (same)
//   cabin:    {start_c: -10, segments: [...]}     cabin air around the gyro, degC, within
//                                                 [kMinTemperatureC, kMaxTemperatureC]
//   yaw_rate: {start_dps: 0, segments: [...]}     true yaw rate, deg/s
//   speed:    {start_mps: 0, segments: [...]}     true forward speed, m/s
//   odometry: {speed_sigma_mps: 0.05}             white noise of the odometry speed, per sample
//   fixes:    {period_s: 0, sigma_m: 3}           absolute position fixes (period 0: none)
// Segments as in driftlab-profile/1: {hold_s: S} or {to_<unit>: V, duration_s: S | rate_<unit>_per_min: R}.
// The duration is the longest of the three profiles. Errors: ConfigError with file, line and key.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "devices/device_file.hpp"
#include "devices/simulator.hpp"
#include "tools/mrpt/nav_ekf.hpp"

namespace driftlab::mrpt_bridge {

struct NavScenario {
  std::string source;
  double sample_rate_hz = 50.0;
  std::uint64_t seed = 7;
  std::uint64_t calibration_seed = 1001;
  devices::Profile cabin_c{25.0};        // degC
  devices::Profile yaw_rate_rad_s{0.0};  // rad/s
  devices::Profile speed_mps{0.0};       // m/s
  double odometry_speed_sigma_mps = 0.05;
  double fix_period_s = 0.0;
  double fix_sigma_m = 3.0;

  double duration_s() const;
};

// The bundled one-hour cold-start drive.
std::filesystem::path default_scenario_path();
NavScenario load_nav_scenario(const std::filesystem::path& path);
NavScenario parse_nav_scenario(const std::string& yaml_text, const std::string& file);

// The simulated drive. Truth: heading by the trapezoid rule on the true yaw rate (exact for the
// piecewise-linear profile), position by the midpoint rule the filter uses.
struct DriveRecord {
  devices::SimulationRecord gyro;         // time_s, rate_rad_s (measured), temp_c, true_rate_rad_s, ...
  Eigen::VectorXd speed_mps;              // true forward speed
  Eigen::VectorXd odometry_speed_mps;     // measured
  Eigen::VectorXd x_m, y_m, heading_rad;  // truth
  std::vector<Eigen::Index> fix_index;    // samples with a position fix
  std::vector<Eigen::Vector2d> fix_m;     // the fixes (truth + noise)
};
DriveRecord simulate_drive(const devices::DeviceDefinition& device, const NavScenario& scenario);

// Process noise from the device's noise terms and the scenario's odometry and fix noise.
NavNoise nav_noise(const devices::DeviceDefinition& device, const NavScenario& scenario);

// What the EKF runs over and what its errors are measured against: the simulated drive
// (nav_input below) or a user's record (nav_record.hpp).
struct NavInput {
  Eigen::VectorXd time_s;                 // s, increasing
  Eigen::VectorXd step_speed_mps;         // [k]: forward speed over (t[k-1], t[k]], m/s ([0] unused)
  Eigen::VectorXd x_m, y_m, heading_rad;  // the reference pose per sample (m, m, rad)
  std::vector<Eigen::Index> fix_index;    // samples with a position fix
  std::vector<Eigen::Vector2d> fix_m;     // the fixes, m
};
// The simulated drive: the truth as reference, the mean of consecutive odometry speeds per step.
NavInput nav_input(const DriveRecord& drive);

struct NavTrack {
  Eigen::VectorXd x_m, y_m, heading_rad, bias_rad_s, heading_sigma_rad, bias_sigma_rad_s;
  // estimate - reference; the heading error accumulated (unwrapped: a drift past 180 degrees keeps
  // counting), the position error as a distance
  Eigen::VectorXd heading_error_rad, position_error_m;
};
// Runs the EKF over the input with the given yaw rate (rad/s, one per sample); step k uses the
// mean of samples k-1 and k of the rate and step_speed_mps[k]. Starts at the reference pose with
// bias 0 and prior bias standard deviation `bias_prior_sigma_rad_s`. `progress(fraction)` is
// optional. DataError when the rate's length differs from the input's.
NavTrack run_nav(const NavInput& input, const Eigen::VectorXd& rate_rad_s, const NavNoise& noise, bool use_fixes,
                 double bias_prior_sigma_rad_s, const std::function<void(double)>& progress = {});

}  // namespace driftlab::mrpt_bridge
