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
//   sensor_gyro_fifo / sensor_accel_fifo  the next fallback (before vehicle_imu), or chosen with
//                 --topic: the driver's raw FIFO batches, one stream per multi_id. A message holds
//                 `samples` (N) samples x[i], y[i], z[i] (int16 counts, FRD) at `dt` us apart; the
//                 value is count * `scale` (rad/s or m/s^2 per count). timestamp_sample (else
//                 timestamp) is the time of the LAST sample of the batch, so sample i (0-based) is
//                 at timestamp_sample - (N - 1 - i) * dt, rounded to 1 us. PX4's source:
//                 src/drivers/imu/invensense/icm42688p/ICM42688P.cpp, RunImpl (FIFO_READ):
//                 timestamp_sample is the data-ready interrupt's time, when the FIFO reached its
//                 watermark (the newest sample), and when the FIFO holds one sample more than the
//                 watermark the newest is left for the next read and timestamp_sample moved back by
//                 one FIFO_SAMPLE_DT; src/lib/drivers/gyroscope/PX4Gyroscope.cpp, updateFIFO:
//                 sensor_gyro is published with the FIFO's timestamp_sample and device_id, its
//                 value the trapezoidal mean ending at sample N - 1. PX4's Flight Review expands
//                 the topics the same way (github.com/PX4/flight_review, app/plot_app/plotting.py,
//                 add_virtual_fifo_topic_data; it truncates to whole us). Fields are read by name
//                 from the log's format (is_external, present only in newer PX4, is not needed);
//                 the array length is the format's (32 today, 20 in early versions). Older formats
//                 with a `rotation` field hold samples in the sensor's own frame: a rotation other
//                 than 0 (none) is a DataError. The FIFO topics carry no temperature: an instance's
//                 temperature is sensor_gyro's of the instance of its gyro's device id (else
//                 sensor_accel's of its accelerometer's), as a temperature stream interpolated onto
//                 the time base (the record spans only the time it covers, imu_streams.hpp);
//                 without one, no temperature channel for the instance and a note says so (the
//                 `temperature` field of early sensor_accel_fifo formats is not read). Device ids
//                 from device_id. A format without dt, scale or samples (one revision of
//                 SensorAccelFifo.msg has no scale) is a DataError naming the field. Errors
//                 (DataError naming the file, topic, multi_id and the message index, 0-based in log
//                 order): dt not finite or <= 0, scale not finite or <= 0, a sample count that is
//                 not a whole number up to the arrays' length, sample times of one message not
//                 increasing after rounding (dt below 1 us); messages with 0 samples add none.
//
// Time base, interpolation, the temperature and device id of an instance, and the repairs of time
// order: framework/imu_streams.hpp (shared by every log reader); the time stamps are
// timestamp_sample (us; else timestamp). A temperature channel per instance comes from its gyro
// (the accel's when no gyro is selected; FIFO topics: see above); the device id likewise (decimal,
// as PX4's CAL_GYROn_ID parameters show it).
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

// The topics imu_record reads: pass them as ReadOptions::keep_topics. The FIFO topics are kept even
// when sensor_gyro is read: about 100 columns of 8 bytes per message.
const std::vector<std::string>& imu_topics();

// The IMU record of a parsed log (its imu_topics kept). `selection.topic` is "" (sensor_gyro /
// sensor_accel when the log has them, else sensor_gyro_fifo / sensor_accel_fifo, else vehicle_imu,
// else sensor_combined), "sensor_gyro" (gyros only), "sensor_accel", "sensor_gyro_fifo",
// "sensor_accel_fifo", "vehicle_imu" or "sensor_combined"; any other name is a ConfigError naming
// --topic.
// `selection.sensor` is parsed by imu::parse_selection (ConfigError naming --sensor).
TimeSeries imu_record(const Log& log, const LogSelection& selection, std::vector<std::string>* notes = nullptr);

// read() with imu_topics kept, then imu_record.
TimeSeries read_imu(const std::filesystem::path& path, const LogSelection& selection,
                    std::vector<std::string>* notes = nullptr);

}  // namespace driftlab::ulog
