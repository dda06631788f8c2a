#include "tools/driftlab/calibration_cli.hpp"

#include <cstdio>
#include <iostream>

#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/time_series.hpp"
#include "framework/units.hpp"
#include "tools/driftlab/cli.hpp"

namespace driftlab::cli {

void add_calibration_data_options(CLI::App* cmd, CalibrationDataOptions& data, bool repeatable) {
  auto* opt =
      cmd->add_option("--data", data.paths,
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
  cmd->add_option("--channels", data.channels,
                  "channels to calibrate, comma-separated: gyro, accel, gyro1, gyro_x, accel1_z, all (default: all)");
  cmd->add_option("--axis", data.axis, "axis of a single-axis 'rate' column (an IMU column names its own axis)")
      ->check(CLI::IsMember({"x", "y", "z"}))
      ->capture_default_str();
  add_record_read_options(
      cmd, data,
      "column mapping role=column:unit (repeatable). Roles: gyro_x..gyro_z, accel_x..accel_z (gyro1_x, "
      "accel2_z for instances 1, 2), temperature (temperature1, ...), true_gyro_x (reference input), "
      "time; rate for a single-axis gyro. Raw counts: gyro_x=gx:lsb*0.061:mdps. Without --column, "
      "headers such as t_s, time_us, timestamp, gyro_x, gx, GyrX, gyro_x_dps, acc_z, accel_z_g, temp, "
      "temp_c, T, rate_dps are recognised (no unit suffix: rad/s, m/s^2, degC)");
}

std::vector<ChannelRecords> load_channel_records(const std::vector<std::string>& paths,
                                                 const CalibrationDataOptions& data) {
  const CsvReadOptions options = csv_read_options(data);
  std::vector<TimeSeries> series;
  for (const auto& p : paths) {
    std::vector<std::string> notes;
    series.push_back(read_record(p, options, data.log, &notes));
    for (const auto& n : notes) std::cerr << "note: " << p << ": " << n << "\n";
  }
  std::vector<calibration::NamedSeries> files;
  for (std::size_t i = 0; i < paths.size(); ++i) files.push_back({&series[i], paths[i]});
  return calibration::channel_records(
      files, {.channels = data.channels, .axis = data.axis[0], .same_device = data.same_device});
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
    std::snprintf(line, sizeof line, "  lag_tau = %g s, dT/dt coefficient = %.4e +- %.1e %s per K/s (smoothing %g s)\n",
                  m.lag_tau_s, m.temperature_rate_rad_s_per_k_s, m.temperature_rate_sigma, unit.c_str(),
                  m.derivative_tau_s);
    out << line;
    if (m.hysteresis_width_k > 0)
      std::snprintf(line, sizeof line,
                    "  hysteresis height (cooling minus heating branch) = %.4g +- %.2g %s (1 sigma), width %g K\n",
                    m.hysteresis_height() * display, m.hysteresis_height_sigma() * display, display_unit,
                    m.hysteresis_width_k);
    else
      std::snprintf(line, sizeof line, "  no hysteresis term\n");
    out << line;
  }
  if (m.rbf) out << "  RBF network: " << m.rbf->centres.rows() << " centres, sigma " << m.rbf->sigma << "\n";
  if (!m.scale_factor_per_k.empty()) {
    out << "  scale factor: 1 +";
    for (std::size_t j = 0; j < m.scale_factor_per_k.size(); ++j) out << " " << m.scale_factor_per_k[j] << " dT^" << j;
    out << "\n";
  }
  std::snprintf(line, sizeof line,
                "  held-out residual (%g-s bins): %.4g %s; in-sample %.4g %s; uncompensated %.4g %s\n", m.fit.bin_s,
                m.fit.holdout_rms_rad_s * display, display_unit, m.fit.train_rms_rad_s * display, display_unit,
                m.fit.uncompensated_rms_rad_s * display, display_unit);
  out << line << "  held out: " << m.fit.holdout_design << "\n  selection: " << m.fit.selection << "\n";
}

}  // namespace driftlab::cli
