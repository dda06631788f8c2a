// The channels of a whole IMU to calibrate, from one or more records of it (`driftlab calibrate`,
// `driftlab compensate`, `driftlab fleet` and the Python module's calibrate()): every gyro and
// accelerometer channel of every instance, or the single-axis "rate" channel; the quality gate over
// their temperatures; one fit per channel.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "framework/imu.hpp"
#include "framework/time_series.hpp"
#include "models/calibration/calibration_model.hpp"
#include "models/calibration/fit.hpp"
#include "models/calibration/oven_run.hpp"

namespace driftlab::calibration {

// One channel to calibrate: its identity, where it comes from, and one Record per input record
// (signal in the channel's internal unit, its instance's temperature, the truth when the record has it).
struct ChannelRecords {
  imu::ChannelId id;
  std::string role;               // record role: id.role(), or "rate" for a single-axis record
  std::string column, read_unit;  // as in the first record
  std::string temperature_column;
  std::string device_id;
  bool has_truth = false;
  std::vector<Record> records;
};

struct NamedSeries {
  const TimeSeries* series = nullptr;
  std::string name;  // the file it was read from, as messages name it
};

// Which channels, and the names of the options that set them (for messages).
struct ChannelSelection {
  std::string channels;      // comma-separated: gyro, accel, gyro1, gyro_x, accel1_z, all; empty: every channel
  char axis = 'z';           // the axis of a single-axis "rate" channel
  bool same_device = false;  // records of several devices are not refused
  std::string channels_field = "--channels", same_device_field = "--same-device", records_field = "--data";
};

// A channel's record as a single-axis record again: rate (rad/s, in the channel's internal unit),
// temperature, and true_rate / systematic when it has them (for a pipeline run on one channel).
TimeSeries single_axis_record(const Record& record);

// The temperature channel of an instance: its own (temperature1, ...), else "temperature"; null if none.
const Channel* temperature_of(const TimeSeries& ts, int instance);

// The selected channels of the first record (gyro before accel, then instance, then axis), each with
// one Record per input record. Throws DataError when a record lacks a channel the first one has or
// an instance has no temperature, and ConfigError when the records come from different devices (their
// device ids differ, or a channel's bias disagrees beyond what one device's noise explains; see
// largest_disagreement) without same_device.
std::vector<ChannelRecords> channel_records(const std::vector<NamedSeries>& records, const ChannelSelection& selection);

// The oven-run quality gate (oven_run.hpp) over each temperature the channels are fitted against
// (one per instance); each finding's message starts with its temperature column and is printed to
// `print` (when not null) as it is found. Throws DataError naming the first record on an error
// finding, and under `strict` on a warning.
std::vector<Finding> run_quality_gate(const std::vector<ChannelRecords>& channels, double bin_s, bool strict,
                                      std::ostream* print);

// The model of one channel: the fit, with the constant term of an accelerometer without a
// reference set to 0 (a static record holds gravity along the axis, which is no bias).
ChannelCalibration fit_channel(const ChannelRecords& ch, const std::vector<Record>& records, const FitOptions& f);

// Throws DataError naming the first channel whose held-out error exceeds its uncompensated error:
// such a model is written only on request (calibrate --force, force=True).
void check_holdout_error(const ImuCalibration& model);

}  // namespace driftlab::calibration
