// From a PX4 ULog (framework/ulog.hpp) to the IMU record (framework/imu.hpp): the thin adapter
// between the pure parser and the record every command reads.
//
// Topics (PX4 uORB definitions; units as PX4 logs them, which are the record's internal units):
//   sensor_gyro   x, y, z (rad/s), temperature (degC), device_id, timestamp_sample (us; else
//                 timestamp): one gyro per multi_id -> instance (gyro_x, gyro1_x, ...).
//   sensor_accel  the same for the accelerometer (m/s^2): accel_x, accel1_x, ...
//   sensor_combined  the fallback when the log has neither: gyro_rad[3] at `timestamp`,
//                 accelerometer_m_s2[3] at timestamp + accelerometer_timestamp_relative (samples
//                 whose relative stamp is PX4's "invalid" 0x7fffffff are left out); instance 0 only;
//                 it carries no IMU temperature (baro_temp_celcius is the barometer's), so the
//                 record has none, and a note says so.
//   vehicle_imu   the next fallback (before sensor_combined), or chosen with --topic: PX4's
//                 integrated IMU per multi_id: delta_angle[3] (rad) over delta_angle_dt (us),
//                 delta_velocity[3] (m/s) over delta_velocity_dt (us); the record holds the mean
//                 rate delta / dt at the period's midpoint timestamp_sample - dt / 2 (timestamp_sample
//                 is the last raw sample of the period), rounded to 1 us; samples with dt = 0 are left
//                 out with a note; device ids from gyro_device_id / accel_device_id; no temperature
//                 (vehicle_imu has none), and a note says so. A mean over dt is a low-pass of the raw
//                 rate (a moving average of length dt): the noise density reads the same, the
//                 bandwidth is about 1 / (2 dt).
// sensor_gyro_fifo (packed int16 samples with a scale) is not read: no log with it was at hand to
// test against.
//
// Time base, interpolation, the temperature and device id of an instance, and the repairs of time
// order: framework/imu_streams.hpp (shared by every log reader); the time stamps are
// timestamp_sample (us; else timestamp). A temperature channel per instance comes from its gyro
// (the accel's when no gyro is selected); the device id likewise (decimal, as PX4's CAL_GYROn_ID
// parameters show it).
//
// Repairs, each with a note: samples out of time order are sorted and repeated time stamps dropped
// (imu_streams.hpp); a temperature that is NaN throughout leaves the channel out. Errors
// (DataError naming the file and topic): a requested topic or instance not in the log, a stream
// with fewer than 2 samples, streams that do not overlap in time, a non-finite value or one beyond
// kMaxMagnitude (csv.hpp), a temperature NaN only in part, an instance above 99 (the role names
// stop there), a time stamp beyond 2^53 us.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "framework/record_reader.hpp"
#include "framework/time_series.hpp"
#include "framework/ulog.hpp"

namespace driftlab::ulog {

// The topics imu_record reads: pass them as ReadOptions::keep_topics.
const std::vector<std::string>& imu_topics();

// The IMU record of a parsed log (its imu_topics kept). `selection.topic` is "" (sensor_gyro /
// sensor_accel when the log has them, else vehicle_imu, else sensor_combined), "sensor_gyro" (gyros
// only), "sensor_accel", "vehicle_imu" or "sensor_combined"; any other name is a ConfigError naming
// --topic.
// `selection.sensor` is parsed by imu::parse_selection (ConfigError naming --sensor).
TimeSeries imu_record(const Log& log, const LogSelection& selection, std::vector<std::string>* notes = nullptr);

// read() with imu_topics kept, then imu_record.
TimeSeries read_imu(const std::filesystem::path& path, const LogSelection& selection,
                    std::vector<std::string>* notes = nullptr);

}  // namespace driftlab::ulog
