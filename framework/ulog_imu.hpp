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
// vehicle_imu (integrated delta angles) and sensor_gyro_fifo (packed int16 samples with a scale)
// are not read: they need integration / unpacking that these topics do not.
//
// Time base, repairs and the errors they share with the other log readers: framework/imu_streams.hpp
// (the lowest selected gyro instance is the time base, every other stream is interpolated onto it;
// out-of-order samples sorted, repeated time stamps dropped, each with a note). The device id is
// decimal, as PX4's CAL_GYROn_ID parameters show it.
// Errors of this adapter (DataError naming the file and topic): a requested topic or instance not in
// the log; the shared ones of imu_streams.hpp.
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
// sensor_accel when the log has them, else sensor_combined), "sensor_gyro" (gyros only),
// "sensor_accel" or "sensor_combined"; any other name is a ConfigError naming --topic.
// `selection.sensor` is parsed by imu::parse_selection (ConfigError naming --sensor).
TimeSeries imu_record(const Log& log, const LogSelection& selection, std::vector<std::string>* notes = nullptr);

// read() with imu_topics kept, then imu_record.
TimeSeries read_imu(const std::filesystem::path& path, const LogSelection& selection,
                    std::vector<std::string>* notes = nullptr);

}  // namespace driftlab::ulog
