// Pieces shared by `driftlab calibrate`, `driftlab compensate` and the calibration exports: the
// whole-IMU records to calibrate (every gyro and accelerometer channel of every instance, or the
// single-axis "rate" column), option parsing, summaries.
#pragma once

#include <CLI/CLI.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "framework/imu.hpp"
#include "framework/record_reader.hpp"
#include "framework/time_series.hpp"
#include "models/calibration/calibration_model.hpp"
#include "models/calibration/fit.hpp"
#include "models/calibration/oven_run.hpp"

namespace driftlab::cli {

struct CalibrationDataOptions {
  std::vector<std::string> paths;     // --data (repeatable)
  std::vector<std::string> columns;   // --column role=column:unit
  double sample_rate_hz = 0.0;        // --fs
  double max_gap_factor = 3.0;        // --max-gap
  std::string channels;               // --channels (empty: every channel)
  std::string axis = "z";             // --axis: the axis of a single-axis "rate" column
  bool same_device = false;           // --same-device: records of several devices are not refused
  LogSelection log;                   // --topic, --instance, --sensor (logs only)
};

void add_calibration_data_options(CLI::App* cmd, CalibrationDataOptions& data, bool repeatable);
// The options of add_calibration_data_options but --data and --same-device (--column, --channels,
// --axis, --fs, --max-gap, --topic, --instance, --sensor), for a command whose records are listed
// elsewhere (`driftlab fleet`: in a manifest).
void add_calibration_channel_options(CLI::App* cmd, CalibrationDataOptions& data);

// One channel to calibrate: its identity, where it comes from, and one calibration::Record per file
// (signal in the channel's internal unit, its instance's temperature, the truth when the file has it).
struct ChannelRecords {
  imu::ChannelId id;
  std::string role;                 // record role: id.role(), or "rate" for a single-axis record
  std::string column, read_unit;    // as in the first file
  std::string temperature_column;
  std::string device_id;
  bool has_truth = false;
  std::vector<calibration::Record> records;
};

// Reads every file (CSV or a log, by content: framework/record_reader.hpp) and collects the selected channels (--channels; every gyro/accel channel, or the
// "rate" column, by default). Throws DataError when a file lacks a channel the first one has or an
// instance has no temperature, and ConfigError when the files come from different devices (their
// device ids differ, or a channel's bias disagrees beyond what one device's noise explains; see
// calibration::largest_disagreement) without --same-device.
std::vector<ChannelRecords> load_channel_records(const std::vector<std::string>& paths, const CalibrationDataOptions& data);

// The oven-run quality gate (models/calibration/oven_run.hpp) over each temperature the channels are
// fitted against (one per instance); each finding's message starts with its temperature column and
// is printed to `print` (when not null) as it is found. Throws DataError naming the first record on
// an error finding, and under `strict` on a warning.
std::vector<calibration::Finding> run_quality_gate(const std::vector<ChannelRecords>& channels, double bin_s, bool strict,
                                                  std::ostream* print);

// The model of one channel: the fit, with the constant term of an accelerometer without a
// reference set to 0 (a static record holds gravity along the axis, which is no bias).
calibration::ChannelCalibration fit_channel(const ChannelRecords& ch, const std::vector<calibration::Record>& records,
                                            const calibration::FitOptions& f);

// Throws DataError naming the first channel whose held-out error exceeds its uncompensated error:
// such a model is written only on request (calibrate --force).
void check_holdout_error(const calibration::ImuCalibration& model);

calibration::ModelKind model_kind_option(const std::string& text);  // ConfigError naming --model
calibration::Extrapolation extrapolation_option(const std::string& text);  // ConfigError naming --extrapolation

// The model of one channel in words, in the channel's display unit (deg/h for a gyro, mg for an
// accelerometer).
void print_model_summary(std::ostream& out, const calibration::ChannelCalibration& channel);

}  // namespace driftlab::cli
