// The reader registry (DESIGN.md §8): one entry point that reads a record from any supported file,
// the reader chosen by content, not by file name.
//
//   first bytes "ULog" 0x01 0x12 0x35   PX4 ULog (framework/ulog.hpp, ulog_imu.hpp)
//   first bytes 0xA3 0x95 0x80          ArduPilot DataFlash (framework/dataflash.hpp, dataflash_imu.hpp)
//   a ROS bag (rosbag::sniff)           ROS 1 bag, ROS 2 sqlite3 bag, MCAP, or a rosbag2 directory
//                                       with metadata.yaml (framework/rosbag.hpp, ros_imu.hpp)
//   an MRPT archive's first object      MRPT rawlog, gzip'ed or plain (framework/rawlog.hpp; read by a
//   (rawlog::sniff)                     module that links MRPT, loaded only then)
//   anything else                       CSV (framework/csv.hpp), exactly as read_csv reads it
//
// For a log, the record is the IMU record (framework/imu.hpp roles, SI units, time in s), with
// LogSelection picking the topic, instances and sensors, and then the CsvReadOptions applied the
// way read_csv applies them, so commands treat both alike:
//   columns         empty: every IMU channel. Otherwise only the mapped channels: each mapping's
//                   column names an IMU channel of the log (gyro_z, gyro1_x, temp, temperature1,
//                   ...) and its role is the role it gets: `rate=gyro_z` analyses the z gyro as
//                   the single-axis "rate". A log's values are in SI already: a unit other than the
//                   channel's (rad/s, m/s^2, degC) is a ConfigError. A "time" mapping or
//                   sample_rate_hz > 0 is a ConfigError (a log carries its own time stamps).
//   required_roles  each must be present (DataError naming the channels the log has).
//   max_gap_factor  a time step of the record above factor x its median step is a DataError (0
//                   reads gaps as they are; flight logs with dropouts need it. The analyses that
//                   assume even sampling still find the gaps: framework/sampling.hpp).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "framework/csv.hpp"
#include "framework/time_series.hpp"

namespace driftlab {

// What to take from a log (ignored for CSV).
struct LogSelection {
  std::string topic;   // "" = the reader's default (ULog: ulog_imu.hpp's order, sensor_gyro/sensor_accel first;
                       // DataFlash: IMU; ROS: every Imu topic; rawlog: the only IMU sensor label),
                       // ROS: a comma-separated list (ros_imu.hpp); rawlog: a sensor label
  int instance = -1;   // -1 = every instance; else only this one (ULog multi_id, DataFlash IMU's I,
                       // ROS: Imu topic number)
  std::string sensor;  // imu::parse_selection text ("gyro", "accel", "gyro1", "gyro_z"); "" = all
};

enum class RecordFormat { Csv, Ulog, DataFlash, RosBag, Rawlog };
// The reader `path` gets: by its first bytes (DataError when the file cannot be opened).
RecordFormat sniff_record_format(const std::filesystem::path& path);

// Reads a record with the reader its content calls for. `notes`, when given, receives what a log
// reader repaired or left out (sorted samples, dropped duplicates, trimmed ends, missing
// temperature); CSV reading adds none.
TimeSeries read_record(const std::filesystem::path& path, const CsvReadOptions& options,
                       const LogSelection& selection = {}, std::vector<std::string>* notes = nullptr);

}  // namespace driftlab
