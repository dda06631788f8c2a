// MRPT rawlog I/O for the MRPT bridge (issue 14): IMU observations <-> the CSV contract, and the
// compensation of the IMU rate of an existing rawlog. MRPT is used only here (tools/mrpt).
//
// Rawlog formats (both read; https://docs.mrpt.org/reference/latest/rawlog_format.html):
//   - actions/sensory-frame: CActionCollection, CSensoryFrame, CActionCollection, ...
//   - observations-only:     CObservation, CObservation, ...
// Every top-level object is numbered from 0 in file order; errors name the file and that index
// ("object 12"), plus the observation's position inside a sensory frame where it applies.
// Files are read through CFileGZInputStream (gzip'ed or plain) and written gzip'ed.
//
// CSV columns (SI, unit in the name; DESIGN.md §5): t_s (s since the first IMU observation),
// rate_rps (IMU_WZ, rad/s), temp_c (IMU_TEMPERATURE, degC), the other CObservationIMU fields that
// the observations carry (imu_columns(): wx_rps, acc_x_mps2, ...) and, when the rawlog has
// odometry, odom_dx_m, odom_dy_m, odom_dphi_rad (robot-frame pose increment since the previous IMU
// sample) and odom_speed_mps (when the action has velocities). Export reads rate_rps or rate_dps.
//
// Time: MRPT time stamps are 100 ns ticks. Export stores start_unix_s + round(t_s * 1e7) ticks;
// import gives t_s = ticks since the first IMU observation / 1e7. A time with at most 7 decimals
// therefore survives CSV -> rawlog -> CSV exactly; rates and temperatures are doubles in both.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "framework/csv.hpp"

namespace driftlab::mrpt_bridge {

// One CSV column of an IMU record and the CObservationIMU field (TIMUDataIndex) it carries;
// field < 0 for the odometry columns.
struct ImuColumn {
  int field;
  std::string column;  // CSV name, unit suffix included
  std::string unit;    // unit the CSV value is in ("rad/s", "degC", or "1" for SI values)
  std::string doc;
};
// The IMU fields in CSV order: rate_rps, temp_c, then the others.
const std::vector<ImuColumn>& imu_columns();
// odom_dx_m, odom_dy_m, odom_dphi_rad, odom_speed_mps.
const std::vector<ImuColumn>& odometry_columns();

// Default start time of exported rawlogs: 2026-01-01T00:00:00Z, s since the Unix epoch.
inline constexpr double kDefaultStartUnixS = 1767225600.0;

// An IMU record: time plus named columns (names from imu_columns()/odometry_columns()), SI values.
struct ImuTable {
  Eigen::VectorXd time_s;         // s since start_unix_s
  double start_unix_s = kDefaultStartUnixS;
  std::string sensor_label = "GYRO";
  std::vector<CsvColumn> columns;  // each values.size() == time_s.size(), unit "1" (already SI)
  std::vector<std::string> ignored_columns;  // read_imu_csv: CSV columns the bridge does not know

  bool has(const std::string& column) const;
  const Eigen::VectorXd& values(const std::string& column) const;  // DataError when absent
  bool has_odometry() const { return has("odom_dx_m"); }
};

struct RawlogStats {
  std::size_t objects = 0;           // top-level objects
  std::size_t imu_observations = 0;  // all IMU observations (any label)
  std::size_t odometry_actions = 0;  // CActionRobotMovement2D
  std::size_t sensory_frames = 0;
  std::string format;                // "actions/sensory-frame", "observations-only" or "mixed"
  std::vector<std::string> imu_labels;
};

// Reads a CSV with t_s, rate_rps|rate_dps, temp_c and any of the other known columns; columns
// it does not know are listed in ignored_columns. Gaps are allowed. Throws DataError/ConfigError with file, line.
ImuTable read_imu_csv(const std::filesystem::path& path);
// Writes t_s and every column, atomically.
void write_imu_csv(const ImuTable& table, const std::filesystem::path& path);

// IMU observations of a rawlog (of `sensor_label`, or of the only IMU label present; more than one
// label without a choice is a ConfigError listing them). Throws DataError naming file and object
// index on a malformed or truncated file, an IMU observation without IMU_WZ, or one lacking a field
// the first one has. `stats` (optional) receives counts of the whole file.
ImuTable import_rawlog(const std::filesystem::path& path, const std::string& sensor_label = "",
                       RawlogStats* stats = nullptr);

// Writes CObservationIMU objects (IMU_WZ rad/s, IMU_TEMPERATURE degC, the other columns present,
// sensor label, time stamps); with odometry columns, as action/observation pairs (a
// CActionCollection holding a CActionRobotMovement2D, then a CSensoryFrame with the IMU
// observation), else observations-only. Written to a temporary file and renamed into place.
void export_rawlog(const ImuTable& table, const std::filesystem::path& path);

// Counts of a rawlog (reads the whole file; DataError as import_rawlog).
RawlogStats rawlog_stats(const std::filesystem::path& path);

// Rate correction applied by compensate_rawlog: (t since the first selected IMU observation, s;
// measured IMU_WZ, rad/s; IMU_TEMPERATURE, degC) -> compensated IMU_WZ, rad/s.
using RateCorrector = std::function<double(double t_s, double rate_rad_s, double temp_c)>;

struct CompensateStats {
  std::size_t objects = 0, imu_observations = 0, compensated = 0;
  double max_abs_correction_rad_s = 0.0;
};
// Copies `in` to `out` object by object, in order, replacing IMU_WZ of every IMU observation of
// `sensor_label` (or the only IMU label) by corrector(...); nothing else changes. Observations need
// IMU_TEMPERATURE (DataError naming the object otherwise). `out` is written atomically.
CompensateStats compensate_rawlog(const std::filesystem::path& in, const std::filesystem::path& out,
                                  const RateCorrector& corrector, const std::string& sensor_label = "");

}  // namespace driftlab::mrpt_bridge
