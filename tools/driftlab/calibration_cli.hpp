// Pieces shared by `driftlab calibrate`, `driftlab compensate` and the calibration exports: reading
// the whole-IMU records to calibrate (models/calibration/imu_channels.hpp), option parsing, summaries.
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
#include "models/calibration/imu_channels.hpp"
#include "models/calibration/oven_run.hpp"
#include "tools/driftlab/cli.hpp"

namespace driftlab::cli {

// The records of a calibration command, read alike (cli.hpp RecordReadOptions), and the channels taken.
struct CalibrationDataOptions : RecordReadOptions {
  std::vector<std::string> paths;  // --data (repeatable)
  std::string channels;            // --channels (empty: every channel)
  std::string axis = "z";          // --axis: the axis of a single-axis "rate" column
  bool same_device = false;        // --same-device: records of several devices are not refused
};

void add_calibration_data_options(CLI::App* cmd, CalibrationDataOptions& data, bool repeatable);
// The options of add_calibration_data_options but --data and --same-device (--column, --channels,
// --axis, --fs, --max-gap, --topic, --instance, --sensor), for a command whose records are listed
// elsewhere (`driftlab fleet`: in a manifest).
void add_calibration_channel_options(CLI::App* cmd, CalibrationDataOptions& data);

using calibration::ChannelRecords;
using calibration::check_holdout_error;
using calibration::fit_channel;
using calibration::run_quality_gate;

// Reads every file (CSV or a log, by content: framework/record_reader.hpp) and collects the selected
// channels (calibration::channel_records with --channels, --axis, --same-device).
std::vector<ChannelRecords> load_channel_records(const std::vector<std::string>& paths,
                                                 const CalibrationDataOptions& data);

calibration::ModelKind model_kind_option(const std::string& text);         // ConfigError naming --model
calibration::Extrapolation extrapolation_option(const std::string& text);  // ConfigError naming --extrapolation

// The model of one channel in words, in the channel's display unit (deg/h for a gyro, mg for an
// accelerometer).
void print_model_summary(std::ostream& out, const calibration::ChannelCalibration& channel);

}  // namespace driftlab::cli
