#include "tools/driftlab/calibration_cli.hpp"

#include <cmath>
#include <cstdio>

#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/time_series.hpp"
#include "tools/driftlab/cli.hpp"

namespace driftlab::cli {

void add_calibration_data_options(CLI::App* cmd, CalibrationDataOptions& data, bool repeatable) {
  auto* opt = cmd->add_option("--data", data.paths,
                              repeatable ? "input CSV record(s); repeat to combine several runs of one gyro "
                                           "(default columns t_s, rate_dps, temp_c, optional true_rate_dps)"
                                         : "input CSV (default columns t_s, rate_dps, temp_c)");
  opt->required();
  if (!repeatable) opt->expected(1);
  cmd->add_option("--column", data.columns,
                  "column mapping role=column:unit for rate, temperature, true_rate, time "
                  "(e.g. rate=gyro_x_rad_s:rad/s)");
  add_sampling_options(cmd, data.sample_rate_hz, data.max_gap_factor);
}

calibration::Record load_calibration_record(const std::string& path, const CalibrationDataOptions& data) {
  CsvReadOptions options;
  for (const auto& c : data.columns) options.columns.push_back(parse_column_mapping(c));
  options.required_roles = {role::kRate, role::kTemperature};
  options.sample_rate_hz = data.sample_rate_hz;
  options.max_gap_factor = data.max_gap_factor;
  const TimeSeries ts = read_csv(path, options);
  calibration::Record r;
  r.name = path;
  r.time_s = ts.time();
  r.rate_rad_s = ts.channel(role::kRate).values;
  r.temp_c = ts.channel(role::kTemperature).values;
  if (ts.has(role::kTrueRate)) r.true_rate_rad_s = ts.channel(role::kTrueRate).values;
  if (ts.has("systematic")) r.systematic_rad_s = ts.channel("systematic").values;
  return r;
}

std::vector<calibration::Record> load_calibration_records(const CalibrationDataOptions& data) {
  std::vector<calibration::Record> out;
  for (const auto& p : data.paths) out.push_back(load_calibration_record(p, data));
  return out;
}

calibration::ModelKind model_kind_option(const std::string& text) {
  if (const auto k = calibration::parse_model_kind(text)) return *k;
  throw ConfigError({"", 0, "--model"}, "expected poly, physical or rbf, got '" + text + "'");
}

calibration::Extrapolation extrapolation_option(const std::string& text) {
  if (const auto e = calibration::parse_extrapolation(text)) return *e;
  throw ConfigError({"", 0, "--extrapolation"}, "expected clamp, linear or evaluate, got '" + text + "'");
}

void print_model_summary(std::ostream& out, const calibration::CalibrationModel& m) {
  constexpr double kDegPerHour = 180.0 / M_PI * 3600.0;
  char line[256];
  out << "model: " << calibration::to_string(m.kind) << ", polynomial order " << m.order() << " in (T - "
      << m.reference_temp_c << " degC), valid " << m.valid_min_c << " .. " << m.valid_max_c
      << " degC, extrapolation " << calibration::to_string(m.extrapolation) << "\n";
  for (std::size_t i = 0; i < m.bias_rad_s.size(); ++i) {
    std::snprintf(line, sizeof line, "  a%zu = %.6e +- %.2e rad/s/K^%zu\n", i, m.bias_rad_s[i],
                  i < m.bias_sigma_rad_s.size() ? m.bias_sigma_rad_s[i] : 0.0, i);
    out << line;
  }
  if (m.kind != calibration::ModelKind::Polynomial) {
    std::snprintf(line, sizeof line,
                  "  lag_tau = %g s, dT/dt coefficient = %.4e +- %.1e rad/s per K/s (smoothing %g s), "
                  "hysteresis = %.4e +- %.1e rad/s (width %g K)\n",
                  m.lag_tau_s, m.temperature_rate_rad_s_per_k_s, m.temperature_rate_sigma, m.derivative_tau_s,
                  m.hysteresis_rad_s, m.hysteresis_sigma_rad_s, m.hysteresis_width_k);
    out << line;
  }
  if (m.rbf) out << "  RBF network: " << m.rbf->centres.rows() << " centres, sigma " << m.rbf->sigma << "\n";
  if (!m.scale_factor_per_k.empty()) {
    out << "  scale factor: 1 +";
    for (std::size_t j = 0; j < m.scale_factor_per_k.size(); ++j) out << " " << m.scale_factor_per_k[j] << " dT^" << j;
    out << "\n";
  }
  std::snprintf(line, sizeof line, "held-out residual (blocked CV, %g-s bins): %.4g deg/h; in-sample %.4g deg/h\n",
                m.fit.bin_s, m.fit.holdout_rms_rad_s * kDegPerHour, m.fit.train_rms_rad_s * kDegPerHour);
  out << line << "selection: " << m.fit.selection << "\n";
}

}  // namespace driftlab::cli
