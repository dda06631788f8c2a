// Pieces shared by `driftlab calibrate`, `driftlab compensate` and the calibration exports:
// loading calibration records (rate, temperature, optional true rate), option parsing, summaries.
#pragma once

#include <CLI/CLI.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "models/calibration/calibration_model.hpp"
#include "models/calibration/fit.hpp"

namespace driftlab::cli {

struct CalibrationDataOptions {
  std::vector<std::string> paths;     // --data (repeatable)
  std::vector<std::string> columns;   // --column role=column:unit
  double sample_rate_hz = 0.0;        // --fs
  double max_gap_factor = 3.0;        // --max-gap
};

void add_calibration_data_options(CLI::App* cmd, CalibrationDataOptions& data, bool repeatable);
// Reads every --data file; rate and temperature are required, true_rate is used when present.
std::vector<calibration::Record> load_calibration_records(const CalibrationDataOptions& data);
calibration::Record load_calibration_record(const std::string& path, const CalibrationDataOptions& data);

calibration::ModelKind model_kind_option(const std::string& text);  // ConfigError naming --model
calibration::Extrapolation extrapolation_option(const std::string& text);  // ConfigError naming --extrapolation

void print_model_summary(std::ostream& out, const calibration::CalibrationModel& model);

}  // namespace driftlab::cli
