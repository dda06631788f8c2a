#include "tools/driftlab/fleet_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>

#include "framework/error.hpp"
#include "framework/units.hpp"
#include "plugins/signal/robust.hpp"
#include "tools/driftlab/html_report.hpp"

namespace driftlab::cli {
namespace {

using signal::kMadToSigma;                    // Phi^-1(3/4): MAD = 0.6745 sigma for normal data
using signal::median;
constexpr double kMeanAdToSigma = 1.253314;  // sqrt(pi/2): mean|x - median| = sigma / 1.2533

std::string number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", v);
  return text;
}

std::string csv_cell(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

struct Distribution {
  double median = 0.0, mad = 0.0, mean_ad = 0.0, min = 0.0, max = 0.0;
  std::size_t n = 0;
};

// Every (channel, key) of the passed units with its values, in role and key order.
std::map<std::pair<std::string, std::string>, std::vector<std::pair<std::string, double>>> samples(
    const std::vector<UnitSummary>& units) {
  std::map<std::pair<std::string, std::string>, std::vector<std::pair<std::string, double>>> out;
  for (const auto& u : units) {
    if (u.status != "passed") continue;
    for (const auto& [channel, figures] : u.figures)
      for (const auto& [key, value] : figures) out[{channel, key}].emplace_back(u.unit, value);
  }
  return out;
}

Distribution distribution(const std::vector<std::pair<std::string, double>>& values) {
  std::vector<double> x;
  for (const auto& v : values) x.push_back(v.second);
  Distribution d;
  d.n = x.size();
  d.median = median(x);
  std::vector<double> dev;
  for (double v : x) dev.push_back(std::abs(v - d.median));
  d.mad = median(dev);
  for (double v : dev) d.mean_ad += v / static_cast<double>(dev.size());
  d.min = *std::min_element(x.begin(), x.end());
  d.max = *std::max_element(x.begin(), x.end());
  return d;
}

}  // namespace

std::string figure_key(const FigureDef& figure, imu::Sensor sensor) {
  return std::string(figure.name) + "_" + (sensor == imu::Sensor::Gyro ? figure.gyro_suffix : figure.accel_suffix);
}

std::map<std::string, double> channel_figures(const calibration::ChannelCalibration& channel) {
  const auto& m = channel.model;
  const double display = imu::display_unit(channel.id.sensor).per_internal;
  const imu::Sensor s = channel.id.sensor;
  return {
      {figure_key(kFigures[0], s), m.bias_rad_s.empty() ? 0.0 : m.bias_rad_s[0] * display},
      {figure_key(kFigures[1], s), m.bias_rad_s.size() < 2 ? 0.0 : m.bias_rad_s[1] * display},
      {figure_key(kFigures[2], s), m.hysteresis_width_k > 0 ? m.hysteresis_rad_s * display : 0.0},
      {figure_key(kFigures[3], s), m.noise.arw_rad_sqrt_s * display},
      {figure_key(kFigures[4], s), m.fit.holdout_rms_rad_s * display},
  };
}

SpecLimit parse_spec_column(const std::string& header, const Location& where) {
  const auto dot = header.find('.');
  const std::string suffix = "_max";
  if (dot == std::string::npos || header.size() <= suffix.size() ||
      header.compare(header.size() - suffix.size(), suffix.size(), suffix) != 0)
    throw ConfigError(where, "column '" + header +
                                 "' is neither unit, data nor a spec limit '<channels>.<figure>_max' (e.g. "
                                 "gyro.holdout_dph_max)");
  SpecLimit limit;
  limit.column = header;
  limit.channels = imu::parse_selection(header.substr(0, dot), "manifest column " + header);
  limit.figure_key = header.substr(dot + 1, header.size() - suffix.size() - dot - 1);
  std::set<imu::Sensor> selected;
  for (const auto sensor : {imu::Sensor::Gyro, imu::Sensor::Accel})
    for (int instance = 0; instance <= imu::kMaxInstance; ++instance)
      for (char axis : {'x', 'y', 'z'})
        if (limit.channels.selects({sensor, axis, instance})) selected.insert(sensor);
  std::string known;
  for (const auto& f : kFigures)
    for (const auto sensor : selected) {
      if (figure_key(f, sensor) == limit.figure_key && selected.size() == 1) return limit;
      known += " " + figure_key(f, sensor);
    }
  throw ConfigError(where, "spec limit '" + header + "': '" + limit.figure_key +
                               "' is no figure of the channels selected (one sensor per column; figures:" + known + ")");
}

UnitSummary read_unit_summary(const std::filesystem::path& status_json) {
  std::ifstream in(status_json);
  nlohmann::json j;
  try {
    in >> j;
    UnitSummary u;
    u.unit = j.at("unit").get<std::string>();
    u.status = j.at("status").get<std::string>();
    u.exit_class = j.at("exit_class").get<int>();
    u.reason = j.at("reason").get<std::string>();
    for (const auto& [channel, figures] : j.at("figures").items())
      for (const auto& [key, value] : figures.items()) u.figures[channel][key] = value.get<double>();
    return u;
  } catch (const nlohmann::json::exception& e) {
    throw ConfigError({status_json.string(), 0, ""}, std::string("not a fleet unit status file: ") + e.what());
  }
}

// Is `key` a figure whose outlier scale is floored (FigureDef::floored)?
bool floored(const std::string& key) {
  for (const auto& f : kFigures)
    for (const auto sensor : {imu::Sensor::Gyro, imu::Sensor::Accel})
      if (figure_key(f, sensor) == key) return f.floored;
  return false;
}

std::vector<Outlier> find_outliers(const std::vector<UnitSummary>& units) {
  std::vector<Outlier> out;
  const auto all = samples(units);
  for (const auto& [where, values] : all) {
    const Distribution d = distribution(values);
    double scale = d.mad > 0 ? d.mad / kMadToSigma : kMeanAdToSigma * d.mean_ad;
    if (floored(where.second)) {
      const auto id = imu::parse_role(where.first);
      const auto holdout = id ? all.find({where.first, figure_key(kFigures[4], id->sensor)}) : all.end();
      if (holdout != all.end()) scale = std::max(scale, distribution(holdout->second).median);
    }
    if (!(scale > 0)) continue;
    for (const auto& [unit, value] : values) {
      const double z = (value - d.median) / scale;
      if (std::abs(z) <= kOutlierZ) continue;
      Outlier o{unit, where.first, where.second, value, d.median, z, ""};
      o.text = o.channel + " " + o.figure_key + " " + number(value) + "; fleet median " + number(d.median) +
               " (robust z " + number(z) + ")";
      out.push_back(std::move(o));
    }
  }
  std::stable_sort(out.begin(), out.end(), [](const Outlier& a, const Outlier& b) { return a.unit < b.unit; });
  return out;
}

std::vector<std::string> spec_violations(const UnitSummary& unit) {
  std::vector<std::string> out;
  for (const auto& limit : unit.limits)
    for (const auto& [channel, figures] : unit.figures) {
      const auto id = imu::parse_role(channel);
      const auto f = figures.find(limit.figure_key);
      if (!id || !limit.channels.selects(*id) || f == figures.end()) continue;
      if (std::abs(f->second) > limit.max)
        out.push_back(channel + " |" + limit.figure_key + "| " + number(std::abs(f->second)) + " > " +
                      number(limit.max) + " (" + limit.column + ")");
    }
  return out;
}

void write_fleet_report(const std::vector<UnitSummary>& units, const std::vector<Outlier>& outliers,
                        const std::filesystem::path& out, const std::string& command, OutputSet& files) {
  std::map<std::string, std::vector<std::string>> flags;
  for (const auto& o : outliers) flags[o.unit].push_back(o.text);
  std::size_t passed = 0, within = 0;
  nlohmann::json unit_results = nlohmann::json::array(), failures = nlohmann::json::array();
  std::vector<std::vector<std::string>> spec(units.size());
  for (std::size_t i = 0; i < units.size(); ++i) {
    const auto& u = units[i];
    spec[i] = spec_violations(u);
    const bool ok = u.status == "passed";
    passed += ok;
    within += ok && spec[i].empty();
    if (!ok) failures.push_back({{"unit", u.unit}, {"exit_class", u.exit_class}, {"reason", u.reason}});
    unit_results.push_back({{"unit", u.unit},
                            {"folder", "units/" + u.unit},
                            {"status", u.status},
                            {"exit_class", u.exit_class},
                            {"reason", u.reason},
                            {"within_spec", ok && spec[i].empty()},
                            {"spec_violations", spec[i]},
                            {"outliers", flags[u.unit]}});
  }
  nlohmann::json dist = nlohmann::json::object();
  for (const auto& [where, values] : samples(units)) {
    const Distribution d = distribution(values);
    dist[where.first][where.second] = {{"n", d.n}, {"median", d.median}, {"mad", d.mad}, {"min", d.min}, {"max", d.max}};
  }
  nlohmann::json outlier_list = nlohmann::json::array();
  for (const auto& o : outliers)
    outlier_list.push_back({{"unit", o.unit}, {"channel", o.channel}, {"figure", o.figure_key}, {"value", o.value},
                            {"fleet_median", o.median}, {"robust_z", o.z}, {"text", o.text}});
  const double yield = units.empty() ? 0.0 : static_cast<double>(within) / static_cast<double>(units.size());
  const nlohmann::json report = {
      {"format", "driftlab-fleet-report/1"},
      {"command", command},
      {"units", units.size()},
      {"passed", passed},
      {"failed", units.size() - passed},
      {"within_spec", within},
      {"yield", yield},
      {"figure_units", "gyro figures in deg/h (a1 deg/h/K, N deg/h/sqrt(Hz)), accelerometer figures in mg (a1 "
                       "mg/K, N mg/sqrt(Hz)), as each key's suffix says"},
      {"outlier_rule",
       {{"statistic", "modified z-score 0.6745 (x - median) / MAD per channel and figure over the passed units "
                      "(Iglewicz & Hoaglin 1993); MAD = 0: (x - median) / (1.2533 mean |x - median|); for a0 and "
                      "hysteresis the scale is at least the channel's fleet-median held-out residual"},
        {"threshold", kOutlierZ}}},
      {"distributions", dist},
      {"outliers", outlier_list},
      {"failures", failures},
      {"unit_results", unit_results}};
  files.write(out / "report.json", report.dump(2) + "\n");

  // units.csv: one row per unit, every figure of every channel any passed unit has.
  std::set<std::pair<std::string, std::string>> columns;
  for (const auto& u : units)
    for (const auto& [channel, figures] : u.figures)
      for (const auto& [key, value] : figures) columns.insert({channel, key});
  std::ostringstream csv;
  csv.precision(17);
  csv << "unit,status,exit_class,within_spec,outliers,reason";
  for (const auto& c : columns) csv << "," << c.first << "." << c.second;
  csv << "\n";
  for (std::size_t i = 0; i < units.size(); ++i) {
    const auto& u = units[i];
    std::string f;
    for (const auto& t : flags[u.unit]) f += (f.empty() ? "" : "; ") + t;
    csv << u.unit << "," << u.status << "," << u.exit_class << "," << (u.status == "passed" && spec[i].empty() ? 1 : 0)
        << "," << csv_cell(f) << "," << csv_cell(u.reason);
    for (const auto& c : columns) {
      csv << ",";
      const auto ch = u.figures.find(c.first);
      if (ch == u.figures.end()) continue;
      const auto v = ch->second.find(c.second);
      if (v != ch->second.end()) csv << v->second;
    }
    csv << "\n";
  }
  files.write(out / "units.csv", csv.str());

  HtmlReport html("driftlab fleet: " + std::to_string(units.size()) + " units");
  html.section("Summary").paragraph(std::to_string(passed) + " of " + std::to_string(units.size()) +
                                    " units calibrated; " + std::to_string(within) + " within spec (yield " +
                                    number(100.0 * yield) + " %); " + std::to_string(outliers.size()) +
                                    " outlier figures. Command: " + command);
  HtmlTable failed{"Units that failed", {"unit", "exit class", "reason"}, {}, "exit class: 1 failure, 2 configuration, 3 bad input data"};
  for (const auto& u : units)
    if (u.status != "passed") failed.rows.push_back({u.unit, static_cast<double>(u.exit_class), u.reason});
  HtmlTable flagged{"Outliers", {"unit", "channel", "figure", "value", "fleet median", "robust z"}, {},
                    "modified z-score over the passed units, |z| > " + number(kOutlierZ) +
                        "; gyro figures in deg/h, accelerometer figures in mg (see the key's suffix); each unit's "
                        "model and status are in units/<unit>/"};
  for (const auto& o : outliers) flagged.rows.push_back({o.unit, o.channel, o.figure_key, o.value, o.median, o.z});
  HtmlTable all{"Every unit", {"unit", "status", "within spec", "outliers", "spec violations"}, {}, ""};
  for (std::size_t i = 0; i < units.size(); ++i) {
    std::string v, f;
    for (const auto& t : spec[i]) v += (v.empty() ? "" : "; ") + t;
    for (const auto& t : flags[units[i].unit]) f += (f.empty() ? "" : "; ") + t;
    all.rows.push_back({units[i].unit, units[i].status,
                        std::string(units[i].status == "passed" && spec[i].empty() ? "yes" : "no"), f, v});
  }
  HtmlTable figures{"Figures of a channel", {"figure", "gyro key", "accelerometer key"}, {},
                    "gyro figures in deg/h, accelerometer figures in mg, as each key's suffix says"};
  for (const auto& f : kFigures)
    figures.rows.push_back({std::string(f.doc), figure_key(f, imu::Sensor::Gyro), figure_key(f, imu::Sensor::Accel)});
  html.section("Failures").table(failed).section("Outliers").table(flagged).section("Units").table(all);
  html.section("Figures").table(figures);
  files.write(out / "report.html", html.html());
}

}  // namespace driftlab::cli
