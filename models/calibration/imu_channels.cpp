#include "models/calibration/imu_channels.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <tuple>

#include "framework/error.hpp"
#include "models/calibration/oven_run.hpp"

namespace driftlab::calibration {

TimeSeries single_axis_record(const Record& r) {
  TimeSeries ts(r.time_s);
  ts.set_channel({role::kRate, "rad/s", r.name, r.rate_rad_s});
  ts.set_channel({role::kTemperature, "degC", r.name, r.temp_c});
  if (r.true_rate_rad_s.size()) ts.set_channel({role::kTrueRate, "rad/s", r.name, r.true_rate_rad_s});
  if (r.systematic_rad_s.size()) ts.set_channel({role::kSystematic, "rad/s", r.name, r.systematic_rad_s});
  return ts;
}

const Channel* temperature_of(const TimeSeries& ts, int instance) {
  const std::string own = imu::temperature_role(instance);
  if (ts.has(own)) return &ts.channel(own);
  if (ts.has(role::kTemperature)) return &ts.channel(role::kTemperature);
  return nullptr;
}

std::vector<ChannelRecords> channel_records(const std::vector<NamedSeries>& files, const ChannelSelection& s) {
  const imu::Selection selection =
      s.channels.empty() ? imu::Selection{} : imu::parse_selection(s.channels, s.channels_field);
  if (files.empty()) throw ConfigError({"", 0, s.records_field}, "no record given");

  // The channels of the first file, in model order: gyro before accel, then instance, then axis.
  std::map<std::tuple<int, int, char>, ChannelRecords> found;
  const TimeSeries& first = *files.front().series;
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
      throw ConfigError({files.front().name, 0, role::kRate},
                        "the record has both a single-axis 'rate' column and IMU columns (gyro_x, ...); map the rate "
                        "column to its axis with --column gyro_AXIS=COLUMN:UNIT");
    const imu::ChannelId id{imu::Sensor::Gyro, s.axis, 0};
    if (selection.selects(id)) {
      const auto& c = first.channel(role::kRate);
      found.emplace(std::make_tuple(0, 0, id.axis),
                    ChannelRecords{id, role::kRate, c.source, c.read_unit, "", "", false, {}});
    }
  }
  if (found.empty())
    throw DataError({files.front().name, 1, ""},
                    s.channels.empty()
                        ? "no gyro or accelerometer column (expected e.g. gyro_x, gx, GyrX, acc_z, rate_dps; or map "
                          "them with --column gyro_x=COLUMN:UNIT)"
                        : "no column of the channels selected by " + s.channels_field + " " + s.channels);

  std::vector<ChannelRecords> out;
  for (auto& [key, cr] : found) {
    const std::string truth = cr.role == role::kRate ? std::string(role::kTrueRate) : imu::truth_role(cr.id);
    const std::string systematic =
        cr.role == role::kRate ? std::string(role::kSystematic) : imu::systematic_role(cr.id);
    cr.has_truth = first.has(truth);
    cr.device_id = first.device_id(cr.id.instance);
    for (const auto& f : files) {
      const TimeSeries& ts = *f.series;
      if (!ts.has(cr.role))
        throw DataError({f.name, 1, cr.role}, "this record has no '" + cr.role + "' channel, which " +
                                                  files.front().name + " has (column " + cr.column +
                                                  "); every --data record must hold the same channels");
      const Channel* temp = temperature_of(ts, cr.id.instance);
      if (!temp)
        throw DataError({f.name, 1, imu::temperature_role(cr.id.instance)},
                        "no temperature for " + cr.role + " (expected a column such as temp, temp_c, " +
                            (cr.id.instance ? "temp" + std::to_string(cr.id.instance) : std::string("temperature")) +
                            ", or --column " + imu::temperature_role(cr.id.instance) + "=COLUMN:UNIT)");
      if (cr.temperature_column.empty()) cr.temperature_column = temp->source;
      const std::string& id = ts.device_id(cr.id.instance);
      if (!s.same_device && !id.empty() && !cr.device_id.empty() && id != cr.device_id)
        throw ConfigError({f.name, 0, "device_id"}, "instance " + std::to_string(cr.id.instance) + " has device id " +
                                                        id + " here but " + cr.device_id + " in " + files.front().name +
                                                        ": two devices are not calibrated as one (give " +
                                                        s.same_device_field + " if they are one)");
      Record r;
      r.name = f.name;
      r.time_s = ts.time();
      r.rate_rad_s = ts.channel(cr.role).values;
      r.temp_c = temp->values;
      if (ts.has(truth)) r.true_rate_rad_s = ts.channel(truth).values;
      if (ts.has(systematic)) r.systematic_rad_s = ts.channel(systematic).values;
      cr.records.push_back(std::move(r));
    }
    if (!s.same_device && cr.records.size() > 1) {
      const auto d = largest_disagreement(cr.records);
      if (d.ratio > kSameDeviceRatio) {
        const auto shown = imu::display_unit(cr.id.sensor);
        char text[160];
        std::snprintf(text, sizeof text, "%.4g %s (%.3g times the noise of their 60-s means)",
                      d.difference_rms * shown.per_internal, shown.name, d.ratio);
        throw ConfigError({d.second, 0, cr.role},
                          "the " + cr.role + " bias of this record and of " + d.first + " differ by " + text +
                              ": they look like two devices, which are not calibrated as one (give " +
                              s.same_device_field + " if they are one)");
      }
    }
    out.push_back(std::move(cr));
  }
  return out;
}

std::vector<Finding> run_quality_gate(const std::vector<ChannelRecords>& channels, double bin_s, bool strict,
                                      std::ostream* print) {
  std::vector<Finding> all;
  std::vector<std::string> seen_temperatures;
  for (const auto& ch : channels) {
    if (std::find(seen_temperatures.begin(), seen_temperatures.end(), ch.temperature_column) != seen_temperatures.end())
      continue;
    seen_temperatures.push_back(ch.temperature_column);
    std::vector<OvenRun> runs;
    for (const auto& r : ch.records) runs.push_back(analyse_oven_run(r.name, r.time_s, r.temp_c, bin_s));
    for (auto f : quality_gate(runs)) {
      f.message = ch.temperature_column + ": " + f.message;
      if (print) *print << "quality gate " << to_string(f.severity) << " [" << f.code << "] " << f.message << "\n";
      all.push_back(std::move(f));
    }
  }
  for (const auto& f : all) {
    if (f.severity == Finding::Severity::Error || (strict && f.severity == Finding::Severity::Warning))
      throw DataError({channels.front().records.front().name, 0, "temperature"},
                      "quality gate" + std::string(strict ? " (--strict)" : "") + ": " + f.message);
  }
  return all;
}

ChannelCalibration fit_channel(const ChannelRecords& ch, const std::vector<Record>& records, const FitOptions& f) {
  ChannelCalibration c;
  c.id = ch.id;
  c.role = ch.role;
  c.column = ch.column;
  c.read_unit = ch.read_unit;
  c.temperature_column = ch.temperature_column;
  c.device_id = ch.device_id;
  c.offset_observable = ch.id.sensor == imu::Sensor::Gyro || ch.has_truth;
  c.model = fit_calibration(records, f);
  if (!c.offset_observable) {
    c.model.bias_rad_s[0] = 0.0;
    if (!c.model.bias_sigma_rad_s.empty()) c.model.bias_sigma_rad_s[0] = 0.0;
  }
  return c;
}

void check_holdout_error(const ImuCalibration& model) {
  for (const auto& ch : model.channels) {
    const auto& fit = ch.model.fit;
    if (fit.holdout_rms_rad_s > fit.uncompensated_rms_rad_s)
      throw DataError({ch.model.fit.records.empty() ? "" : ch.model.fit.records.front(), 0, ch.column},
                      "the fitted model's held-out error (" + std::to_string(fit.holdout_rms_rad_s) + " " + ch.unit() +
                          ") exceeds the uncompensated error (" + std::to_string(fit.uncompensated_rms_rad_s) +
                          "): not written (--force writes it)");
  }
}

}  // namespace driftlab::calibration
