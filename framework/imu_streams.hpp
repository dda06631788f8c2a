// From the sensor streams of a log to the IMU record (framework/imu.hpp): the part the log readers'
// IMU adapters share (PX4 ULog: framework/ulog_imu.hpp, ArduPilot DataFlash:
// framework/dataflash_imu.hpp). An adapter turns its messages into Streams -- one sensor of one
// instance, time stamps in us, three axes in the record's internal unit, optionally a temperature
// (degC) and a device id -- and `assemble` makes the record.
//
// Repairs, each with a note: samples out of time order are sorted (stable); repeated time stamps
// keep the first sample (repair_order); a temperature that is NaN throughout leaves the channel out
// (temperature). Errors (DataError naming the file and the stream): a non-finite value or one beyond
// kMaxMagnitude (csv.hpp), a temperature NaN only in part, a time stamp outside 0 to 2^53 us.
//
// Time base (assemble). One record has one time vector, but every sensor and instance samples at
// its own instants. Policy: the first selected stream -- gyro of the lowest selected instance
// (accel when no gyro is selected) -- is the time base; every other stream (other instances, the
// accelerometers, temperatures) is linearly interpolated onto it. Time stamps of the base outside
// the span that every selected stream covers are dropped (no extrapolation), and a note gives the
// count. Why: the gyro is what drift calibration models, so its samples stay exactly as logged;
// interpolating the slower-varying accelerometer and temperature costs least; one record keeps all
// instances side by side for a whole-IMU calibration. Picking one instance (LogSelection::instance)
// makes that instance's gyro the base. A temperature channel per instance comes from its first
// selected stream that has one (gyro before accel); the device id likewise.
// Errors of assemble (DataError naming the file): no stream matches the selection (the message
// lists the log's streams), a stream with fewer than 2 samples, streams that overlap at fewer than
// 2 samples of the base, an instance above 99 (the role names stop there).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "framework/imu.hpp"
#include "framework/record_reader.hpp"
#include "framework/time_series.hpp"

namespace driftlab::imu {

// One sensor of one instance, repaired: strictly increasing time stamps.
struct Stream {
  Sensor sensor = Sensor::Gyro;
  int instance = 0;
  std::string label;   // "sensor_gyro multi_id 1", "IMU I=1": for notes and errors
  std::string source;  // "sensor_gyro[1]", "IMU[1]": the channels' source
  std::vector<std::int64_t> time_us;
  std::array<std::vector<double>, 3> axes;  // x, y, z
  std::vector<double> temperature;          // degC; empty: none
  std::string device_id;                    // empty: none
};

// The samples of a stream in record order: their time stamps and the logged message each comes from.
struct SampleOrder {
  std::vector<std::int64_t> time_us;
  std::vector<std::size_t> message;
};

// A time stamp in us as int64: DataError beyond 0 to 2^53 us (285 years; the arithmetic stays exact).
std::int64_t time_stamp(const std::string& file, const std::string& source, double us);

// Sorts `order` by time (stable) and drops repeated time stamps, keeping the first; notes the counts.
void repair_order(SampleOrder& order, const std::string& label, std::vector<std::string>* notes);

// values[order.message[i]] for every i; DataError (naming `field`) for a non-finite or huge value.
std::vector<double> pick(const std::string& file, const Stream& s, const std::vector<double>& values,
                         const SampleOrder& order, const std::string& field);

// The temperature of a stream: all finite, or all NaN (empty, with a note); else DataError.
std::vector<double> temperature(const std::string& file, const Stream& s, const std::vector<double>& values,
                                const SampleOrder& order, std::vector<std::string>* notes);

// The record of the streams `selection` picks (instance, sensor: imu::parse_selection, ConfigError
// naming --sensor), per the time-base policy above.
TimeSeries assemble(const std::string& file, std::vector<Stream> all, const LogSelection& selection,
                    std::vector<std::string>* notes);

}  // namespace driftlab::imu
