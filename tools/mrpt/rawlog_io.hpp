// MRPT rawlog I/O for the MRPT bridge (issue 14): IMU observations <-> the CSV contract, and the
// compensation of the IMU rates and accelerations of an existing rawlog (issue 20). MRPT is used only here
// (tools/mrpt).
//
// Rawlog formats (both read; https://docs.mrpt.org/reference/latest/rawlog_format.html):
//   - actions/sensory-frame: CActionCollection, CSensoryFrame, CActionCollection, ...
//   - observations-only:     CObservation, CObservation, ...
// Every top-level object is numbered from 0 in file order; errors name the file and that index
// ("object 12"), plus the observation's position inside a sensory frame where it applies. MRPT's
// deserializer trusts the file, so every reader below first reads the rawlog in a child process
// whose address space is limited (1 GiB beyond what it holds): a crash inside MRPT or a length
// field that would allocate gigabytes is a DataError naming the object, not a crash or a
// runaway allocation of this process (so each function below reads the file twice: once there,
// once here).
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
#include "framework/imu.hpp"
#include "framework/output_set.hpp"

namespace driftlab::mrpt_bridge {

// One CSV column of an IMU record and the CObservationIMU field (TIMUDataIndex) it carries;
// field < 0 (and an empty field_name) for the odometry columns.
struct ImuColumn {
  int field;
  std::string field_name;  // MRPT's name of the field ("IMU_WX")
  std::string column;      // CSV name, unit suffix included
  std::string unit;        // unit the CSV value is in ("rad/s", "degC", or "1" for SI values)
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
  Eigen::VectorXd time_s;  // s since start_unix_s
  double start_unix_s = kDefaultStartUnixS;
  std::string sensor_label = "GYRO";
  std::vector<CsvColumn> columns;            // each values.size() == time_s.size(), unit "1" (already SI)
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
  std::string format;  // "actions/sensory-frame", "observations-only" or "mixed"
  std::vector<std::string> imu_labels;
};

// Reads a CSV with t_s, rate_rps|rate_dps, temp_c and any of the other known columns; columns
// it does not know are listed in ignored_columns. Gaps are allowed. Throws DataError/ConfigError with file, line.
ImuTable read_imu_csv(const std::filesystem::path& path);
// Stages t_s and every column as the planned output `path` of `outputs` (committed by the caller).
void write_imu_csv(const ImuTable& table, OutputSet& outputs, const std::filesystem::path& path);

// IMU observations of a rawlog (of `sensor_label`, or of the only IMU label present; more than one
// label without a choice is a ConfigError listing them). Throws DataError naming file and object
// index on a malformed or truncated file (also: a presence or odometry flag byte other than 0/1, an
// IMU time stamp before MRPT's 1601 epoch), an IMU observation without IMU_WZ, or one lacking a
// field the first one has; a path that is not a regular file is refused before it is opened. `stats` (optional)
// receives counts of the whole file.
ImuTable import_rawlog(const std::filesystem::path& path, const std::string& sensor_label = "",
                       RawlogStats* stats = nullptr);
// The IMU observations of every sensor label, in label order (the rawlog's stats.imu_labels), from
// one read of the file (errors as import_rawlog; no label is no table).
std::vector<ImuTable> import_rawlog_sensors(const std::filesystem::path& path, RawlogStats* stats = nullptr);

// Writes CObservationIMU objects (IMU_WZ rad/s, IMU_TEMPERATURE degC, the other columns present,
// sensor label, time stamps); with odometry columns, as action/observation pairs (a
// CActionCollection holding a CActionRobotMovement2D, then a CSensoryFrame with the IMU
// observation), else observations-only, gzip'ed, into the staged temporary file of `path`, an
// output planned in `outputs` (framework/output_set.hpp, the one atomic output path; the caller
// commits). ConfigError when the time stamps (start_unix_s + t_s) fall outside MRPT's clock (before
// 1601 or not finite). The form without an OutputSet writes `path` alone, committed.
void export_rawlog(const ImuTable& table, OutputSet& outputs, const std::filesystem::path& path);
void export_rawlog(const ImuTable& table, const std::filesystem::path& path);

// Counts of a rawlog (reads the whole file; DataError as import_rawlog).
RawlogStats rawlog_stats(const std::filesystem::path& path);

// The CObservationIMU field (TIMUDataIndex) holding a sensor-frame gyro or accelerometer axis:
// gyro x, y, z -> IMU_WX, IMU_WY, IMU_WZ (rad/s); accel x, y, z -> IMU_X_ACC, IMU_Y_ACC, IMU_Z_ACC
// (m/s^2). Instances are not a field: one CObservationIMU sensor label is one IMU instance.
int imu_field(imu::Sensor sensor, char axis);
// MRPT's name of a field ("IMU_WX"), or its number for a field imu_columns() does not list.
std::string imu_field_name(int field);

// One field's correction, applied by compensate_rawlog sample by sample in file order:
// (t since the first selected IMU observation, s; the measured field in its SI unit, rad/s for a
// rate, m/s^2 for an acceleration; IMU_TEMPERATURE, degC) -> the corrected field, same unit.
// Each correction is called once per observation, so it may keep state (a causal model).
using FieldCorrector = std::function<double(double t_s, double value, double temp_c)>;
struct FieldCorrection {
  int field;           // TIMUDataIndex (imu_field())
  std::string source;  // what corrects it, named in errors and stats ("gyro_x")
  FieldCorrector correct;
};

struct FieldStats {
  int field = 0;
  std::string source;
  double max_abs_correction = 0.0;  // largest |measured - corrected|, the field's SI unit
};
struct CompensateStats {
  std::size_t objects = 0, imu_observations = 0, compensated = 0;
  std::string sensor_label;         // of the compensated observations
  std::vector<FieldStats> fields;   // one per correction, in the order given
  std::vector<int> passed_through;  // fields the compensated observations carry that no correction
                                    // touches (copied unchanged), imu_columns() order
};
// Copies `in` to `out` object by object, in order, replacing in every IMU observation of
// `sensor_label` (or of the only IMU label) each corrected field by its correction; nothing else
// changes. Errors (nothing is written): ConfigError for no correction, a field corrected twice, or
// `out` naming `in`; DataError naming the file, the object index and the field for an observation
// lacking a corrected field or IMU_TEMPERATURE (has() is checked before every get()). `out` is an
// output planned in `outputs` (the caller commits), or, in the form without an OutputSet, written
// alone and committed.
CompensateStats compensate_rawlog(const std::filesystem::path& in, OutputSet& outputs, const std::filesystem::path& out,
                                  const std::vector<FieldCorrection>& corrections,
                                  const std::string& sensor_label = "");
CompensateStats compensate_rawlog(const std::filesystem::path& in, const std::filesystem::path& out,
                                  const std::vector<FieldCorrection>& corrections,
                                  const std::string& sensor_label = "");

}  // namespace driftlab::mrpt_bridge
