// From the streams a log holds to the IMU record (framework/imu.hpp): the part every log reader
// shares (PX4 ULog, ArduPilot DataFlash, ROS bags). A reader turns its topics into streams -- one sensor (gyro or
// accelerometer, three axes) of one instance, or one temperature of one instance, each at its own
// time stamps -- and assemble() makes the one record every command reads.
//
// Time stamps are integer ticks of the reader's clock (ULog: us since boot, ROS: ns since the
// epoch); `ticks_per_second` converts them. The record's time in s is correctly rounded (a stamp
// beyond 2^53 ticks is split into whole seconds and the rest first): ROS epoch stamps near 1.7e9 s
// keep a resolution of 2.4e-7 s, the spacing of doubles there.
//
// Repairs (repaired_order), each with a note naming the stream: samples out of time order are
// sorted (stable); of repeated time stamps the first sample is kept.
//
// Time base. One record has one time vector, but every sensor and instance samples at its own
// instants. Policy: the first selected stream -- gyro of the lowest selected instance (accel when
// no gyro is selected) -- is the time base; every other stream (other instances, the accelerometers,
// temperatures) is linearly interpolated onto it. Time stamps of the base outside the span that
// every selected stream covers are dropped (no extrapolation), and a note gives the count. Why: the
// gyro is what drift calibration models, so its samples stay exactly as logged; interpolating the
// slower-varying accelerometer and temperature costs least; one record keeps all instances side by
// side for a whole-IMU calibration. Pick one instance (LogSelection::instance) to make that
// instance's gyro the base.
// Temperature of an instance: the one its gyro stream carries (the accel's when no gyro is
// selected); else a separate temperature stream of the instance (ROS sensor_msgs/Temperature), also
// interpolated. The device id of an instance likewise comes from its gyro, else its accelerometer.
//
// Errors (DataError naming the file): a selection that matches no stream, a selected stream with
// fewer than 2 samples, streams that do not overlap at 2 or more base samples, an instance above 99
// (the role names stop there).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "framework/imu.hpp"
#include "framework/record_reader.hpp"
#include "framework/time_series.hpp"

namespace driftlab::imu {

inline constexpr std::int64_t kMicrosecondsPerSecond = 1000000;  // ticks_per_second of logs stamped in us

// One sensor of one instance: repaired (strictly increasing time), values validated by the reader.
struct SensorStream {
  Sensor sensor = Sensor::Gyro;
  int instance = 0;
  std::string label;                        // "sensor_gyro multi_id 1", "/imu/data": notes and errors
  std::string source;                       // the channels' source: "sensor_gyro[1]", "/imu/data"
  std::vector<std::int64_t> time;           // ticks
  std::array<std::vector<double>, 3> axes;  // x, y, z in the sensor's internal unit
  std::vector<double> temperature;          // degC at `time`; empty: none
  std::string device_id;                    // empty: none
};

// A temperature of one instance at its own time stamps (repaired), degC.
struct TemperatureStream {
  int instance = 0;
  std::string label;
  std::string source;
  std::vector<std::int64_t> time;
  std::vector<double> values;
};

// Indices into `time` in repaired order: sorted by time (stable), the first sample of each repeated
// time stamp kept. Notes (when given) count the samples sorted and dropped, naming `label`.
std::vector<std::size_t> repaired_order(const std::vector<std::int64_t>& time, const std::string& label,
                                        std::vector<std::string>* notes);

// The samples of a message-based log's stream (ULog, DataFlash) in record order: their time stamps
// (us) and the logged message each comes from.
struct SampleOrder {
  std::vector<std::int64_t> time_us;
  std::vector<std::size_t> message;
};

// A time stamp in us as int64: DataError naming `source` outside 0 to 2^53 us (285 years; the
// arithmetic stays exact).
std::int64_t time_stamp_us(const std::string& file, const std::string& source, double us);

// `order` put into repaired order (repaired_order), the message indices following their stamps.
void repair_order(SampleOrder& order, const std::string& label, std::vector<std::string>* notes);

// values[order.message[i]] for every i; DataError at `<s.source>.<field>` for a value that is not
// usable_value, naming its time stamp.
std::vector<double> pick(const std::string& file, const SensorStream& s, const std::vector<double>& values,
                         const SampleOrder& order, const std::string& field);

// The temperature column of a stream in `order`, checked by check_temperature (empty: none).
std::vector<double> pick_temperature(const std::string& file, const SensorStream& s, const std::vector<double>& values,
                                     const SampleOrder& order, std::vector<std::string>* notes);

// A value a log holds is usable when finite and within kMaxMagnitude (csv.hpp); else
// unusable_value says why ("non-finite value", "value beyond 1e100") for the reader's DataError.
bool usable_value(double v);
std::string unusable_value(double v);

// A temperature series as logged: every value usable keeps it; NaN
// throughout (a sensor without a thermometer) empties it, with a note naming `label`; NaN only in
// part is a DataError at `field`.
void check_temperature(std::vector<double>& values, const std::string& file, const std::string& field,
                       const std::string& label, std::vector<std::string>* notes);

// The record of the streams `selection` picks (instance and sensor; its topic is the reader's).
// `selection.sensor` is parsed by imu::parse_selection (ConfigError naming --sensor). See above.
TimeSeries assemble(std::vector<SensorStream> sensors, std::vector<TemperatureStream> temperatures,
                    const LogSelection& selection, std::int64_t ticks_per_second, const std::string& file,
                    std::vector<std::string>* notes);

}  // namespace driftlab::imu
