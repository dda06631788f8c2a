#include "tools/driftlab/calibration_cli.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <optional>

#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/time_series.hpp"
#include "framework/units.hpp"
#include "models/calibration/oven_run.hpp"
#include "tools/driftlab/cli.hpp"

namespace driftlab::cli {

void add_calibration_data_options(CLI::App* cmd, CalibrationDataOptions& data, bool repeatable) {
  auto* opt = cmd->add_option("--data", data.paths,
                              repeatable ? "input record(s): CSV, PX4 ULog (.ulg), ArduPilot DataFlash (.bin) or ROS bag "
                                           "(.bag, .db3, .mcap, rosbag2 directory); repeat to combine several runs of one "
                                           "IMU (CSV columns: see --column)"
                                         : "input record: CSV, PX4 ULog (.ulg), ArduPilot DataFlash (.bin) or ROS bag (.bag, "
                                           ".db3, .mcap, rosbag2 directory)");
  opt->required();
  if (!repeatable) opt->expected(1);
  add_calibration_channel_options(cmd, data);
  if (repeatable)
    cmd->add_flag("--same-device", data.same_device,
                  "the --data records are one device even though their device ids or bias levels differ");
}

void add_calibration_channel_options(CLI::App* cmd, CalibrationDataOptions& data) {
  cmd->add_option("--column", data.columns,
                  "column mapping role=column:unit (repeatable). Roles: gyro_x..gyro_z, accel_x..accel_z (gyro1_x, "
                  "accel2_z for instances 1, 2), temperature (temperature1, ...), true_gyro_x (reference input), "
                  "time; rate for a single-axis gyro. Raw counts: gyro_x=gx:lsb*0.061:mdps. Without --column, "
                  "headers such as t_s, time_us, timestamp, gyro_x, gx, GyrX, gyro_x_dps, acc_z, accel_z_g, temp, "
                  "temp_c, T, rate_dps are recognised (no unit suffix: rad/s, m/s^2, degC)");
  cmd->add_option("--channels", data.channels,
                  "channels to calibrate, comma-separated: gyro, accel, gyro1, gyro_x, accel1_z, all (default: all)");
  cmd->add_option("--axis", data.axis, "axis of a single-axis 'rate' column (an IMU column names its own axis)")
      ->check(CLI::IsMember({"x", "y", "z"}))
      ->capture_default_str();
  add_sampling_options(cmd, data.sample_rate_hz, data.max_gap_factor);
  add_log_selection_options(cmd, data.log);
}

namespace {

struct FileChannels {
  TimeSeries series;
  std::string path;
};

const Channel* temperature_of(const TimeSeries& ts, int instance) {
  const std::string own = imu::temperature_role(instance);
  if (ts.has(own)) return &ts.channel(own);
  if (ts.has(role::kTemperature)) return &ts.channel(role::kTemperature);
  return nullptr;
}

}  // namespace

std::vector<ChannelRecords> load_channel_records(const std::vector<std::string>& paths, const CalibrationDataOptions& data) {
  CsvReadOptions options;
  for (const auto& c : data.columns) options.columns.push_back(parse_column_mapping(c));
  options.required_roles = {};
  options.sample_rate_hz = data.sample_rate_hz;
  options.max_gap_factor = data.max_gap_factor;
  const imu::Selection selection = data.channels.empty() ? imu::Selection{} : imu::parse_selection(data.channels, "--channels");

  std::vector<FileChannels> files;
  for (const auto& p : paths) {
    std::vector<std::string> notes;
    files.push_back({read_record(p, options, data.log, &notes), p});
    for (const auto& n : notes) std::cerr << "note: " << p << ": " << n << "\n";
  }
  if (files.empty()) throw ConfigError({"", 0, "--data"}, "no record given");

  // The channels of the first file, in model order: gyro before accel, then instance, then axis.
  std::map<std::tuple<int, int, char>, ChannelRecords> found;
  const TimeSeries& first = files.front().series;
  bool any_imu = false;
  for (const auto& c : first.channels()) {
    const auto id = imu::parse_role(c.role);
    if (!id) continue;
    any_imu = true;
    if (!selection.selects(*id)) continue;
    ChannelRecords cr;
    cr.id = *id;
    cr.role = c.role;
    cr.column = c.source;
    cr.read_unit = c.read_unit;
    found.emplace(std::make_tuple(id->sensor == imu::Sensor::Gyro ? 0 : 1, id->instance, id->axis), std::move(cr));
  }
  if (first.has(role::kRate)) {
    if (any_imu)
      throw ConfigError({files.front().path, 0, role::kRate},
                        "the record has both a single-axis 'rate' column and IMU columns (gyro_x, ...); map the rate "
                        "column to its axis with --column gyro_AXIS=COLUMN:UNIT");
    const imu::ChannelId id{imu::Sensor::Gyro, data.axis[0], 0};
    if (selection.selects(id)) {
      const auto& c = first.channel(role::kRate);
      found.emplace(std::make_tuple(0, 0, id.axis), ChannelRecords{id, role::kRate, c.source, c.read_unit, "", "", false, {}});
    }
  }
  if (found.empty())
    throw DataError({files.front().path, 1, ""},
                    data.channels.empty()
                        ? "no gyro or accelerometer column (expected e.g. gyro_x, gx, GyrX, acc_z, rate_dps; or map "
                          "them with --column gyro_x=COLUMN:UNIT)"
                        : "no column of the channels selected by --channels " + data.channels);

  std::vector<ChannelRecords> out;
  for (auto& [key, cr] : found) {
    const std::string truth = cr.role == role::kRate ? std::string(role::kTrueRate) : imu::truth_role(cr.id);
    const std::string systematic = cr.role == role::kRate ? std::string(role::kSystematic) : imu::systematic_role(cr.id);
    cr.has_truth = first.has(truth);
    cr.device_id = first.device_id(cr.id.instance);
    for (const auto& f : files) {
      const TimeSeries& ts = f.series;
      if (!ts.has(cr.role))
        throw DataError({f.path, 1, cr.role}, "this record has no '" + cr.role + "' channel, which " +
                                                  files.front().path + " has (column " + cr.column +
                                                  "); every --data record must hold the same channels");
      const Channel* temp = temperature_of(ts, cr.id.instance);
      if (!temp)
        throw DataError({f.path, 1, imu::temperature_role(cr.id.instance)},
                        "no temperature for " + cr.role + " (expected a column such as temp, temp_c, " +
                            (cr.id.instance ? "temp" + std::to_string(cr.id.instance) : std::string("temperature")) +
                            ", or --column " + imu::temperature_role(cr.id.instance) + "=COLUMN:UNIT)");
      if (cr.temperature_column.empty()) cr.temperature_column = temp->source;
      const std::string& id = ts.device_id(cr.id.instance);
      if (!data.same_device && !id.empty() && !cr.device_id.empty() && id != cr.device_id)
        throw ConfigError({f.path, 0, "device_id"},
                          "instance " + std::to_string(cr.id.instance) + " has device id " + id + " here but " +
                              cr.device_id + " in " + files.front().path +
                              ": two devices are not calibrated as one (give --same-device if they are one)");
      calibration::Record r;
      r.name = f.path;
      r.time_s = ts.time();
      r.rate_rad_s = ts.channel(cr.role).values;
      r.temp_c = temp->values;
      if (ts.has(truth)) r.true_rate_rad_s = ts.channel(truth).values;
      if (ts.has(systematic)) r.systematic_rad_s = ts.channel(systematic).values;
      cr.records.push_back(std::move(r));
    }
    if (!data.same_device && cr.records.size() > 1) {
      const auto d = calibration::largest_disagreement(cr.records);
      if (d.ratio > calibration::kSameDeviceRatio) {
        const auto shown = imu::display_unit(cr.id.sensor);
        char text[160];
        std::snprintf(text, sizeof text, "%.4g %s (%.3g times the noise of their 60-s means)",
                      d.difference_rms * shown.per_internal, shown.name, d.ratio);
        throw ConfigError({d.second, 0, cr.role},
                          "the " + cr.role + " bias of this record and of " + d.first + " differ by " + text +
                              ": they look like two devices, which are not calibrated as one (give --same-device "
                              "if they are one)");
      }
    }
    out.push_back(std::move(cr));
  }
  return out;
}

std::vector<calibration::Finding> run_quality_gate(const std::vector<ChannelRecords>& channels, double bin_s, bool strict,
                                                  std::ostream* print) {
  std::vector<calibration::Finding> all;
  std::vector<std::string> seen_temperatures;
  for (const auto& ch : channels) {
    if (std::find(seen_temperatures.begin(), seen_temperatures.end(), ch.temperature_column) != seen_temperatures.end())
      continue;
    seen_temperatures.push_back(ch.temperature_column);
    std::vector<calibration::OvenRun> runs;
    for (const auto& r : ch.records) runs.push_back(calibration::analyse_oven_run(r.name, r.time_s, r.temp_c, bin_s));
    for (auto f : calibration::quality_gate(runs)) {
      f.message = ch.temperature_column + ": " + f.message;
      if (print) *print << "quality gate " << calibration::to_string(f.severity) << " [" << f.code << "] " << f.message << "\n";
      all.push_back(std::move(f));
    }
  }
  for (const auto& f : all) {
    if (f.severity == calibration::Finding::Severity::Error ||
        (strict && f.severity == calibration::Finding::Severity::Warning))
      throw DataError({channels.front().records.front().name, 0, "temperature"},
                      "quality gate" + std::string(strict ? " (--strict)" : "") + ": " + f.message);
  }
  return all;
}

calibration::ChannelCalibration fit_channel(const ChannelRecords& ch, const std::vector<calibration::Record>& records,
                                            const calibration::FitOptions& f) {
  calibration::ChannelCalibration c;
  c.id = ch.id;
  c.role = ch.role;
  c.column = ch.column;
  c.read_unit = ch.read_unit;
  c.temperature_column = ch.temperature_column;
  c.device_id = ch.device_id;
  c.offset_observable = ch.id.sensor == imu::Sensor::Gyro || ch.has_truth;
  c.model = calibration::fit_calibration(records, f);
  if (!c.offset_observable) {
    c.model.bias_rad_s[0] = 0.0;
    if (!c.model.bias_sigma_rad_s.empty()) c.model.bias_sigma_rad_s[0] = 0.0;
  }
  return c;
}

void check_holdout_error(const calibration::ImuCalibration& model) {
  for (const auto& ch : model.channels) {
    const auto& fit = ch.model.fit;
    if (fit.holdout_rms_rad_s > fit.uncompensated_rms_rad_s)
      throw DataError({ch.model.fit.records.empty() ? "" : ch.model.fit.records.front(), 0, ch.column},
                      "the fitted model's held-out error (" + std::to_string(fit.holdout_rms_rad_s) + " " + ch.unit() +
                          ") exceeds the uncompensated error (" + std::to_string(fit.uncompensated_rms_rad_s) +
                          "): not written (--force writes it)");
  }
}

calibration::ModelKind model_kind_option(const std::string& text) {
  if (const auto k = calibration::parse_model_kind(text)) return *k;
  throw ConfigError({"", 0, "--model"}, "expected poly, physical or rbf, got '" + text + "'");
}

calibration::Extrapolation extrapolation_option(const std::string& text) {
  if (const auto e = calibration::parse_extrapolation(text)) return *e;
  throw ConfigError({"", 0, "--extrapolation"}, "expected clamp, linear or evaluate, got '" + text + "'");
}

void print_model_summary(std::ostream& out, const calibration::ChannelCalibration& channel) {
  const auto& m = channel.model;
  const auto [display, display_unit] = imu::display_unit(channel.id.sensor);
  const std::string unit = channel.unit();
  char line[256];
  out << channel.id.role() << " (column " << channel.column << ", temperature " << channel.temperature_column
      << (channel.device_id.empty() ? "" : ", device " + channel.device_id) << "): " << calibration::to_string(m.kind)
      << ", polynomial order " << m.order() << " in (T - " << m.reference_temp_c << " degC), valid " << m.valid_min_c
      << " .. " << m.valid_max_c << " degC, extrapolation " << calibration::to_string(m.extrapolation) << "\n";
  for (std::size_t i = 0; i < m.bias_rad_s.size(); ++i) {
    std::snprintf(line, sizeof line, "  a%zu = %.6e +- %.2e %s/K^%zu\n", i, m.bias_rad_s[i],
                  i < m.bias_sigma_rad_s.size() ? m.bias_sigma_rad_s[i] : 0.0, unit.c_str(), i);
    out << line;
  }
  if (!channel.offset_observable)
    out << "  a0 = 0: the constant offset is not observable without a reference (gravity along the axis); the model "
           "corrects bias(T) - bias(T0)\n";
  if (m.kind != calibration::ModelKind::Polynomial) {
    std::snprintf(line, sizeof line,
                  "  lag_tau = %g s, dT/dt coefficient = %.4e +- %.1e %s per K/s (smoothing %g s), "
                  "hysteresis = %.4e +- %.1e %s (width %g K)\n",
                  m.lag_tau_s, m.temperature_rate_rad_s_per_k_s, m.temperature_rate_sigma, unit.c_str(),
                  m.derivative_tau_s, m.hysteresis_rad_s, m.hysteresis_sigma_rad_s, unit.c_str(), m.hysteresis_width_k);
    out << line;
  }
  if (m.rbf) out << "  RBF network: " << m.rbf->centres.rows() << " centres, sigma " << m.rbf->sigma << "\n";
  if (!m.scale_factor_per_k.empty()) {
    out << "  scale factor: 1 +";
    for (std::size_t j = 0; j < m.scale_factor_per_k.size(); ++j) out << " " << m.scale_factor_per_k[j] << " dT^" << j;
    out << "\n";
  }
  std::snprintf(line, sizeof line, "  held-out residual (%g-s bins): %.4g %s; in-sample %.4g %s; uncompensated %.4g %s\n",
                m.fit.bin_s, m.fit.holdout_rms_rad_s * display, display_unit, m.fit.train_rms_rad_s * display,
                display_unit, m.fit.uncompensated_rms_rad_s * display, display_unit);
  out << line << "  held out: " << m.fit.holdout_design << "\n  selection: " << m.fit.selection << "\n";
}

}  // namespace driftlab::cli
