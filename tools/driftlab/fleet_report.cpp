#include "tools/driftlab/fleet_report.hpp"

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <limits>
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

using signal::kMadToSigma;  // Phi^-1(3/4): MAD = 0.6745 sigma for normal data
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
                               "' is no figure of the channels selected (one sensor per column; figures:" + known +
                               ")");
}

nlohmann::json to_json(const UnitStatus& u) {
  nlohmann::json gate = nlohmann::json::array();
  for (const auto& f : u.quality_gate)
    gate.push_back({{"severity", f.severity}, {"code", f.code}, {"message", f.message}});
  nlohmann::json quantisation = nlohmann::json::object();
  for (const auto& [channel, q] : u.quantisation)
    quantisation[channel] = {
        {"lsb", q.lsb}, {"share", q.share}, {"sample_sigma", q.sample_sigma}, {"quantised", q.quantised}};
  nlohmann::json discrepancy = nlohmann::json::object();
  for (const auto& [channel, check] : u.discrepancy) {
    nlohmann::json named = nlohmann::json::array();
    for (const auto& n : check.named) named.push_back({{"effect", n.effect}, {"delta_bic", n.delta_bic}});
    discrepancy[channel] = {{"named", named},
                            {"unexplained", check.unexplained},
                            {"gap_initial_dph", check.gap_initial_dph},
                            {"gap_final_dph", check.gap_final_dph},
                            {"text", check.text}};
  }
  nlohmann::json figures = nlohmann::json::object(), curves = nlohmann::json::object();
  for (const auto& [channel, f] : u.figures) figures[channel] = f;
  for (const auto& [channel, c] : u.bias_curves) curves[channel] = c;
  return {{"format", kUnitStatusFormat},
          {"unit", u.unit},
          {"input_hash", u.input_hash},
          {"data", u.data},
          {"status", u.status},
          {"exit_class", u.exit_class},
          {"reason", u.reason},
          {"quality_gate", gate},
          {"figures", figures},
          {"quantisation", quantisation},
          {"bias_curves", curves},
          {"discrepancy", discrepancy},
          {"export_notes", u.export_notes}};
}

UnitStatus unit_status_from_json(const nlohmann::json& j) {
  UnitStatus u;
  u.unit = j.at("unit").get<std::string>();
  u.input_hash = j.at("input_hash").get<std::string>();
  u.data = j.at("data").get<std::vector<std::string>>();
  u.status = j.at("status").get<std::string>();
  u.exit_class = j.at("exit_class").get<int>();
  u.reason = j.at("reason").get<std::string>();
  for (const auto& f : j.at("quality_gate"))
    u.quality_gate.push_back(
        {f.at("severity").get<std::string>(), f.at("code").get<std::string>(), f.at("message").get<std::string>()});
  for (const auto& [channel, figures] : j.at("figures").items())
    for (const auto& [key, value] : figures.items()) u.figures[channel][key] = value.get<double>();
  for (const auto& [channel, q] : j.at("quantisation").items())
    u.quantisation[channel] = {q.at("lsb").get<double>(), q.at("share").get<double>(),
                               q.at("sample_sigma").get<double>(), q.at("quantised").get<bool>()};
  for (const auto& [channel, curve] : j.at("bias_curves").items())
    u.bias_curves[channel] = curve.get<std::vector<double>>();
  for (const auto& [channel, check] : j.at("discrepancy").items()) {
    DiscrepancyCheck c;
    for (const auto& n : check.at("named"))
      c.named.push_back({n.at("effect").get<std::string>(), n.at("delta_bic").get<double>()});
    c.unexplained = check.at("unexplained").get<bool>();
    c.gap_initial_dph = check.at("gap_initial_dph").get<double>();
    c.gap_final_dph = check.at("gap_final_dph").get<double>();
    c.text = check.at("text").get<std::string>();
    u.discrepancy[channel] = std::move(c);
  }
  u.export_notes = j.at("export_notes").get<std::vector<std::string>>();
  return u;
}

UnitStatus read_unit_status(const std::filesystem::path& status_json) {
  std::ifstream in(status_json);
  nlohmann::json j;
  try {
    in >> j;
    return unit_status_from_json(j);
  } catch (const nlohmann::json::exception& e) {
    throw ConfigError({status_json.string(), 0, ""}, std::string("not a fleet unit status file: ") + e.what());
  }
}

UnitSummary unit_summary(const UnitStatus& status) {
  UnitSummary u;
  u.unit = status.unit;
  u.status = status.status;
  u.exit_class = status.exit_class;
  u.reason = status.reason;
  u.figures = status.figures;
  u.quantisation = status.quantisation;
  u.bias_curves = status.bias_curves;
  for (const auto& [channel, check] : status.discrepancy) u.discrepancy.push_back(check.text);
  return u;
}

UnitSummary read_unit_summary(const std::filesystem::path& status_json) {
  return unit_summary(read_unit_status(status_json));
}

// The FigureDef::holdout_floor of `key` (0 for no figure).
double holdout_floor(const std::string& key) {
  for (const auto& f : kFigures)
    for (const auto sensor : {imu::Sensor::Gyro, imu::Sensor::Accel})
      if (figure_key(f, sensor) == key) return f.holdout_floor;
  return 0.0;
}

namespace {

// Median and robust scale of one (channel, figure) over the passed units (the rule in the header).
struct RobustScale {
  double median = 0.0, scale = 0.0;
};
std::map<std::pair<std::string, std::string>, RobustScale> robust_scales(
    const std::map<std::pair<std::string, std::string>, std::vector<std::pair<std::string, double>>>& all) {
  std::map<std::pair<std::string, std::string>, RobustScale> out;
  for (const auto& [where, values] : all) {
    const Distribution d = distribution(values);
    double scale = d.mad > 0 ? d.mad / kMadToSigma : kMeanAdToSigma * d.mean_ad;
    if (const double floor = holdout_floor(where.second); floor > 0) {
      const auto id = imu::parse_role(where.first);
      const auto holdout = id ? all.find({where.first, figure_key(kFigures[4], id->sensor)}) : all.end();
      if (holdout != all.end()) scale = std::max(scale, floor * distribution(holdout->second).median);
    }
    out[where] = {d.median, scale};
  }
  return out;
}

std::string quantisation_key(const std::string& channel) {
  const auto id = imu::parse_role(channel);
  return std::string("quantisation_") + (id && id->sensor == imu::Sensor::Accel ? "mg" : "dph");
}

}  // namespace

std::vector<Outlier> find_outliers(const std::vector<UnitSummary>& units) {
  std::vector<Outlier> out;
  const auto all = samples(units);
  const auto scales = robust_scales(all);
  for (const auto& [where, values] : all) {
    const RobustScale& r = scales.at(where);
    if (!(r.scale > 0)) continue;
    for (const auto& [unit, value] : values) {
      const double z = (value - r.median) / r.scale;
      if (std::abs(z) <= kOutlierZ) continue;
      Outlier o{unit, where.first, where.second, value, r.median, z, "", "robust_z"};
      o.text = o.channel + " " + o.figure_key + " " + number(value) + "; fleet median " + number(r.median) +
               " (robust z " + number(z) + ")";
      out.push_back(std::move(o));
    }
  }
  // The whole-model distance, made consistent (header): D^2 chi2_p(0.5) / median D^2.
  struct Distance {
    const UnitSummary* unit;
    double d2;
    std::vector<std::pair<double, std::string>> terms;
  };
  std::vector<Distance> distances;
  for (const auto& u : units) {
    if (u.status != "passed") continue;
    Distance d{&u, 0.0, {}};
    for (const auto& [channel, figures] : u.figures)
      for (const auto& [key, value] : figures) {
        const auto r = scales.find({channel, key});
        if (r == scales.end() || !(r->second.scale > 0)) continue;
        const double z = (value - r->second.median) / r->second.scale;
        d.d2 += z * z;
        d.terms.emplace_back(z * z, channel + " " + key + " (z " + number(z) + ")");
      }
    if (!d.terms.empty()) distances.push_back(std::move(d));
  }
  std::vector<double> d2s;
  for (const auto& d : distances) d2s.push_back(d.d2);
  const double median_d2 = d2s.empty() ? 0.0 : median(d2s);
  for (auto& d : distances) {
    const boost::math::chi_squared chi2(static_cast<double>(d.terms.size()));
    const double consistent = median_d2 > 0 ? d.d2 * boost::math::median(chi2) / median_d2 : 0.0;
    const double threshold = boost::math::quantile(chi2, kDistanceQuantile);
    if (consistent <= threshold) continue;
    std::stable_sort(d.terms.begin(), d.terms.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    std::string drivers;
    for (std::size_t i = 0; i < std::min(kDistanceDrivers, d.terms.size()); ++i)
      drivers += (i ? ", " : "") + d.terms[i].second;
    Outlier o{d.unit->unit,           "model", "distance", consistent, boost::math::median(chi2),
              consistent / threshold, "",      "distance"};
    o.text = "whole model: robust distance^2 " + number(consistent) + " > " + number(threshold) + " (chi-square, " +
             std::to_string(d.terms.size()) + " figures, " + number(kDistanceQuantile) + "; fleet median " +
             number(o.median) + "); driven by " + drivers;
    out.push_back(std::move(o));
  }
  // Quantised channels.
  std::map<std::string, std::vector<double>> lsbs;
  for (const auto& u : units)
    if (u.status == "passed")
      for (const auto& [channel, q] : u.quantisation) lsbs[channel].push_back(q.lsb);
  for (const auto& u : units) {
    if (u.status != "passed") continue;
    for (const auto& [channel, q] : u.quantisation) {
      if (!q.quantised) continue;
      const double fleet = median(lsbs[channel]);
      Outlier o{
          u.unit, channel,       quantisation_key(channel),
          q.lsb,  fleet,         q.sample_sigma > 0 ? q.lsb / q.sample_sigma : std::numeric_limits<double>::infinity(),
          "",     "quantisation"};
      o.text = channel + " quantised: " + number(100.0 * q.share) + " % of samples on multiples of one LSB " +
               number(q.lsb) + " (fleet median LSB " + number(fleet) + "), per-sample noise " + number(q.sample_sigma);
      out.push_back(std::move(o));
    }
  }
  std::stable_sort(out.begin(), out.end(), [](const Outlier& a, const Outlier& b) { return a.unit < b.unit; });
  return out;
}

Quantisation quantisation_check(const Eigen::VectorXd& x) {
  Quantisation q;
  if (x.size() < 2) return q;
  std::vector<double> sorted(x.data(), x.data() + x.size());
  std::sort(sorted.begin(), sorted.end());
  const double range = sorted.back() - sorted.front();
  if (!(range > 0)) return q;
  const double tolerance = kQuantisationTolerance * range;
  double step = range;
  for (std::size_t i = 1; i < sorted.size(); ++i)
    if (sorted[i] - sorted[i - 1] > tolerance) step = std::min(step, sorted[i] - sorted[i - 1]);
  q.lsb = step;
  std::size_t on = 0;
  for (double v : sorted) on += std::abs(v - step * std::round(v / step)) <= kQuantisationTolerance * step;
  q.share = static_cast<double>(on) / static_cast<double>(sorted.size());
  std::vector<double> d(static_cast<std::size_t>(x.size() - 1));
  for (Eigen::Index i = 1; i < x.size(); ++i) d[static_cast<std::size_t>(i - 1)] = x[i] - x[i - 1];
  const double m = median(d);
  for (double& v : d) v = std::abs(v - m);
  q.sample_sigma = median(d) / kMadToSigma / std::sqrt(2.0);
  q.quantised = q.share >= kQuantisedShare && q.lsb >= q.sample_sigma;
  return q;
}

std::vector<double> bias_curve(const calibration::ChannelCalibration& channel) {
  const double display = imu::display_unit(channel.id.sensor).per_internal;
  std::vector<double> out;
  for (double t : kFamilyGridC) out.push_back(channel.model.polynomial_bias_rad_s(t) * display);
  return out;
}

namespace {

// Total distance of every point to its nearest medoid, and each point's medoid index.
double assign(const Eigen::MatrixXd& d, const std::vector<std::size_t>& medoids, std::vector<std::size_t>* label) {
  double cost = 0.0;
  for (Eigen::Index i = 0; i < d.rows(); ++i) {
    std::size_t best = 0;
    for (std::size_t m = 1; m < medoids.size(); ++m)
      if (d(i, medoids[m]) < d(i, medoids[best])) best = m;
    cost += d(i, medoids[best]);
    if (label) (*label)[static_cast<std::size_t>(i)] = best;
  }
  return cost;
}

std::vector<std::size_t> pam(const Eigen::MatrixXd& d, std::size_t k) {
  const auto n = static_cast<std::size_t>(d.rows());
  std::vector<std::size_t> medoids;
  for (std::size_t c = 0; c < k; ++c) {  // BUILD: add the point that lowers the cost most
    double best = std::numeric_limits<double>::infinity();
    std::size_t pick = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (std::find(medoids.begin(), medoids.end(), i) != medoids.end()) continue;
      auto trial = medoids;
      trial.push_back(i);
      const double cost = assign(d, trial, nullptr);
      if (cost < best) best = cost, pick = i;
    }
    medoids.push_back(pick);
  }
  for (double cost = assign(d, medoids, nullptr);;) {  // SWAP: the best improving swap until none
    double best = cost;
    std::pair<std::size_t, std::size_t> swap{k, 0};
    for (std::size_t m = 0; m < k; ++m)
      for (std::size_t i = 0; i < n; ++i) {
        if (std::find(medoids.begin(), medoids.end(), i) != medoids.end()) continue;
        auto trial = medoids;
        trial[m] = i;
        const double c = assign(d, trial, nullptr);
        if (c < best - 1e-12 * std::abs(best)) best = c, swap = {m, i};
      }
    if (swap.first == k) return medoids;
    medoids[swap.first] = swap.second;
    cost = best;
  }
}

double mean_silhouette(const Eigen::MatrixXd& d, const std::vector<std::size_t>& label, std::size_t k) {
  const auto n = static_cast<std::size_t>(d.rows());
  double total = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    std::vector<double> sum(k, 0.0);
    std::vector<std::size_t> count(k, 0);
    for (std::size_t j = 0; j < n; ++j) {
      if (j == i) continue;
      sum[label[j]] += d(i, j);
      ++count[label[j]];
    }
    if (count[label[i]] == 0) continue;  // a family of one: s = 0
    const double a = sum[label[i]] / static_cast<double>(count[label[i]]);
    double b = std::numeric_limits<double>::infinity();
    for (std::size_t c = 0; c < k; ++c)
      if (c != label[i] && count[c] > 0) b = std::min(b, sum[c] / static_cast<double>(count[c]));
    if (std::max(a, b) > 0) total += (b - a) / std::max(a, b);
  }
  return total / static_cast<double>(n);
}

}  // namespace

Families find_families(const std::vector<UnitSummary>& units) {
  Families f;
  std::set<std::string> channels;
  for (const auto& u : units)
    for (const auto& [channel, curve] : u.bias_curves)
      if (const auto id = imu::parse_role(channel); id && id->sensor == imu::Sensor::Gyro) channels.insert(channel);
  f.channels.assign(channels.begin(), channels.end());
  std::vector<const UnitSummary*> members;
  for (const auto& u : units) {
    bool whole = u.status == "passed";
    for (const auto& c : f.channels) whole = whole && u.bias_curves.count(c);
    if (whole) members.push_back(&u);
  }
  const auto n = members.size();
  for (const auto* u : members) f.family[u->unit] = 0;
  if (n < 4 || f.channels.empty()) return f;
  Eigen::MatrixXd x(static_cast<Eigen::Index>(n),
                    static_cast<Eigen::Index>(f.channels.size() * std::size(kFamilyGridC)));
  for (std::size_t i = 0; i < n; ++i) {
    Eigen::Index c = 0;
    for (const auto& ch : f.channels)
      for (double v : members[i]->bias_curves.at(ch)) x(static_cast<Eigen::Index>(i), c++) = v;
  }
  Eigen::MatrixXd d(x.rows(), x.rows());
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    for (Eigen::Index j = 0; j < x.rows(); ++j) d(i, j) = (x.row(i) - x.row(j)).norm();
  const std::size_t min_size = std::max<std::size_t>(2, static_cast<std::size_t>(std::ceil(kMinFamilyShare * n)));
  std::vector<std::size_t> best_label(n, 0), best_medoids{0};
  for (std::size_t k = 2; k <= std::min(kMaxFamilies, n - 1); ++k) {
    const auto medoids = pam(d, k);
    std::vector<std::size_t> label(n);
    assign(d, medoids, &label);
    const double s = mean_silhouette(d, label, k);
    f.silhouette_by_k.push_back(s);
    std::vector<std::size_t> size(k, 0);
    for (auto l : label) ++size[l];
    if (*std::min_element(size.begin(), size.end()) < min_size) continue;
    if (s >= kFamilySilhouette && s > f.silhouette) {
      f.silhouette = s;
      f.k = k;
      best_label = label;
      best_medoids = medoids;
    }
  }
  f.medoids.clear();
  for (auto m : best_medoids) f.medoids.push_back(members[m]->unit);
  for (std::size_t i = 0; i < n; ++i) f.family[members[i]->unit] = best_label[i];
  return f;
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

namespace {

// Per channel the held-out residual of every passed unit (manifest order), units with a finding on
// that channel marked apart.
Figure holdout_figure(const std::vector<UnitSummary>& units, const std::vector<Outlier>& outliers) {
  std::set<std::pair<std::string, std::string>> flagged;  // (unit, channel)
  for (const auto& o : outliers) flagged.insert({o.unit, o.channel});
  std::map<std::string, PlotPanel> panels;
  for (std::size_t i = 0; i < units.size(); ++i) {
    if (units[i].status != "passed") continue;
    for (const auto& [channel, figures] : units[i].figures) {
      const auto id = imu::parse_role(channel);
      if (!id) continue;
      const std::string key = figure_key(kFigures[4], id->sensor);
      const auto v = figures.find(key);
      if (v == figures.end()) continue;
      PlotPanel& p = panels[channel];
      if (p.series.empty()) {
        p.title = channel;
        p.x_label = "unit (manifest order)";
        p.y_label = std::string(kFigures[4].doc) + (id->sensor == imu::Sensor::Gyro ? " (°/h)" : " (mg)");
        p.legend = PlotPanel::Legend::None;  // small panels: the caption says what the colours are
        p.series = {{"unit", {}, {}}, {"unit with a finding on " + channel, {}, {}}};
        for (auto& s : p.series) s.style = PlotSeries::Style::Markers;
        p.series[0].color = palette_color(0);
        p.series[1].color = palette_color(1);
      }
      PlotSeries& s = p.series[flagged.count({units[i].unit, channel}) ? 1 : 0];
      s.x.push_back(static_cast<double>(i + 1));
      s.y.push_back(v->second);
    }
  }
  Figure f;
  f.columns = 3;
  for (auto& [channel, p] : panels) f.panels.push_back(std::move(p));
  f.panel_height = 220;
  return f;
}

// Per gyro channel the fitted bias curve of every unit in the families, coloured by family.
Figure family_figure(const std::vector<UnitSummary>& units, const Families& families) {
  Figure f;
  f.columns = 3;
  f.panel_height = 220;
  for (const auto& channel : families.channels) {
    PlotPanel p;
    p.title = channel;
    p.x_label = "temperature (°C)";
    p.y_label = "bias (°/h)";
    p.legend = PlotPanel::Legend::None;
    for (const auto& u : units) {
      const auto fam = families.family.find(u.unit);
      if (fam == families.family.end()) continue;
      PlotSeries s;
      s.x.assign(std::begin(kFamilyGridC), std::end(kFamilyGridC));
      s.y = u.bias_curves.at(channel);
      s.color = palette_color(fam->second);
      p.series.push_back(std::move(s));
    }
    f.panels.push_back(std::move(p));
  }
  return f;
}

// "family 1: 12 units (medoid unit007), family 2: ..."
std::string family_sizes(const Families& families) {
  std::vector<std::size_t> size(families.k, 0);
  for (const auto& [unit, family] : families.family) ++size[family];
  std::string text;
  for (std::size_t f = 0; f < families.k; ++f)
    text += (f ? ", " : "") + std::string("family ") + std::to_string(f + 1) + " (" + palette_color(f) +
            "): " + std::to_string(size[f]) + " units, medoid " + families.medoids[f];
  return text;
}

// What every part of the report counts and lists per unit.
struct FleetTally {
  std::map<std::string, std::vector<std::string>> flags;  // unit -> its findings' texts
  std::vector<std::vector<std::string>> spec;             // per unit, the limits it does not meet
  std::size_t passed = 0, within = 0;
  double yield = 0.0;
};

FleetTally tally(const std::vector<UnitSummary>& units, const std::vector<Outlier>& outliers) {
  FleetTally t;
  for (const auto& o : outliers) t.flags[o.unit].push_back(o.text);
  for (const auto& u : units) t.flags[u.unit];  // every unit has an entry (perhaps empty)
  t.spec.resize(units.size());
  for (std::size_t i = 0; i < units.size(); ++i) {
    t.spec[i] = spec_violations(units[i]);
    const bool ok = units[i].status == "passed";
    t.passed += ok;
    t.within += ok && t.spec[i].empty();
  }
  t.yield = units.empty() ? 0.0 : static_cast<double>(t.within) / static_cast<double>(units.size());
  return t;
}

// report.json
nlohmann::json report_json(const std::vector<UnitSummary>& units, const std::vector<Outlier>& outliers,
                           const Families& families, const std::string& command, const FleetTally& t) {
  nlohmann::json unit_results = nlohmann::json::array(), failures = nlohmann::json::array();
  const auto& spec = t.spec;
  for (std::size_t i = 0; i < units.size(); ++i) {
    const auto& u = units[i];
    const bool ok = u.status == "passed";
    if (!ok) failures.push_back({{"unit", u.unit}, {"exit_class", u.exit_class}, {"reason", u.reason}});
    unit_results.push_back({{"unit", u.unit},
                            {"folder", "units/" + u.unit},
                            {"status", u.status},
                            {"exit_class", u.exit_class},
                            {"reason", u.reason},
                            {"within_spec", ok && spec[i].empty()},
                            {"spec_violations", spec[i]},
                            {"family", families.family.count(u.unit) ? nlohmann::json(families.family.at(u.unit))
                                                                     : nlohmann::json(nullptr)},
                            {"outliers", t.flags.at(u.unit)},
                            {"discrepancy", u.discrepancy}});
  }
  nlohmann::json dist = nlohmann::json::object();
  for (const auto& [where, values] : samples(units)) {
    const Distribution d = distribution(values);
    dist[where.first][where.second] = {
        {"n", d.n}, {"median", d.median}, {"mad", d.mad}, {"min", d.min}, {"max", d.max}};
  }
  nlohmann::json outlier_list = nlohmann::json::array();
  for (const auto& o : outliers)
    outlier_list.push_back({{"unit", o.unit},
                            {"rule", o.rule},
                            {"channel", o.channel},
                            {"figure", o.figure_key},
                            {"value", o.value},
                            {"fleet_median", o.median},
                            {"robust_z", o.z},
                            {"text", o.text}});
  return {{"format", "driftlab-fleet-report/1"},
          {"command", command},
          {"units", units.size()},
          {"passed", t.passed},
          {"failed", units.size() - t.passed},
          {"within_spec", t.within},
          {"yield", t.yield},
          {"figure_units",
           "gyro figures in deg/h (a1 deg/h/K, N deg/h/sqrt(Hz)), accelerometer figures in mg (a1 "
           "mg/K, N mg/sqrt(Hz)), as each key's suffix says"},
          {"outlier_rule",
           {{"statistic",
             "modified z-score 0.6745 (x - median) / MAD per channel and figure over the passed units "
             "(Iglewicz & Hoaglin 1993); MAD = 0: (x - median) / (1.2533 mean |x - median|); the scale is at "
             "least the channel's fleet-median held-out residual for a0 and hysteresis, half of it for "
             "holdout"},
            {"threshold", kOutlierZ},
            {"distance",
             "robust distance^2 = sum of the unit's squared robust z over its figures; flagged above the "
             "chi-square quantile " +
                 number(kDistanceQuantile) +
                 " with as many degrees of freedom as "
                 "figures; robust_z of a distance finding is D^2 / threshold"},
            {"quantisation", "raw output on multiples of its smallest step (share >= " + number(kQuantisedShare) +
                                 ") and that step >= the per-sample noise; robust_z of a quantisation finding is LSB / "
                                 "noise"}}},
          {"families",
           {{"k", families.k},
            {"silhouette", families.silhouette},
            {"silhouette_by_k", families.silhouette_by_k},
            {"medoids", families.medoids},
            {"channels", families.channels},
            {"rule", "k-medoids (PAM) of the gyro bias curves at " + std::to_string(std::size(kFamilyGridC)) +
                         " temperatures, k = 2.." + std::to_string(kMaxFamilies) + " by mean silhouette >= " +
                         number(kFamilySilhouette) + ", smallest family >= " + number(100 * kMinFamilyShare) +
                         " % of the units; else one family"}}},
          {"distributions", dist},
          {"outliers", outlier_list},
          {"failures", failures},
          {"unit_results", unit_results}};
}

// units.csv: one row per unit, every figure of every channel any passed unit has.
std::string units_csv(const std::vector<UnitSummary>& units, const FleetTally& t) {
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
    for (const auto& text : t.flags.at(u.unit)) f += (f.empty() ? "" : "; ") + text;
    csv << u.unit << "," << u.status << "," << u.exit_class << ","
        << (u.status == "passed" && t.spec[i].empty() ? 1 : 0) << "," << csv_cell(f) << "," << csv_cell(u.reason);
    for (const auto& c : columns) {
      csv << ",";
      const auto ch = u.figures.find(c.first);
      if (ch == u.figures.end()) continue;
      const auto v = ch->second.find(c.second);
      if (v != ch->second.end()) csv << v->second;
    }
    csv << "\n";
  }
  return csv.str();
}

HtmlCell unit_link(const std::string& unit) { return HtmlLink{unit, "units/" + unit + "/status.json"}; }

// The tables of report.html: failures, outliers, every unit, the figures' keys.
HtmlTable failed_table(const std::vector<UnitSummary>& units) {
  HtmlTable failed{"Units that failed",
                   {"unit", "exit class", "reason"},
                   {},
                   "exit class: 1 failure, 2 configuration, 3 bad input data"};
  for (const auto& u : units)
    if (u.status != "passed") failed.rows.push_back({unit_link(u.unit), static_cast<double>(u.exit_class), u.reason});
  return failed;
}

HtmlTable outlier_table(const std::vector<Outlier>& outliers) {
  HtmlTable flagged{"Outliers",
                    {"unit", "model", "rule", "channel", "figure", "value", "fleet median", "z"},
                    {},
                    "robust_z: modified z-score over the passed units, |z| > " + number(kOutlierZ) +
                        "; distance: the whole model's robust distance^2 above the chi-square " +
                        number(kDistanceQuantile) +
                        " quantile (z = D^2 / threshold); quantisation: output on "
                        "multiples of one LSB above the noise (z = LSB / noise); gyro figures in deg/h, "
                        "accelerometer figures in mg (see the key's suffix); each unit links to its status, "
                        "its model is beside it"};
  for (const auto& o : outliers)
    flagged.rows.push_back({unit_link(o.unit), HtmlLink{"model.json", "units/" + o.unit + "/model.json"}, o.rule,
                            o.channel, o.figure_key, o.value, o.median, o.z});
  return flagged;
}

HtmlTable units_table(const std::vector<UnitSummary>& units, const FleetTally& t) {
  HtmlTable all{"Every unit", {"unit", "status", "within spec", "outliers", "spec violations"}, {}, ""};
  for (std::size_t i = 0; i < units.size(); ++i) {
    std::string v, f;
    for (const auto& text : t.spec[i]) v += (v.empty() ? "" : "; ") + text;
    for (const auto& text : t.flags.at(units[i].unit)) f += (f.empty() ? "" : "; ") + text;
    all.rows.push_back({unit_link(units[i].unit), units[i].status,
                        std::string(units[i].status == "passed" && t.spec[i].empty() ? "yes" : "no"), f, v});
  }
  return all;
}

HtmlTable figures_table() {
  HtmlTable figures{"Figures of a channel",
                    {"figure", "gyro key", "accelerometer key"},
                    {},
                    "gyro figures in deg/h, accelerometer figures in mg, as each key's suffix says"};
  for (const auto& f : kFigures)
    figures.rows.push_back({std::string(f.doc), figure_key(f, imu::Sensor::Gyro), figure_key(f, imu::Sensor::Accel)});
  return figures;
}

// The families' paragraph: their count, silhouette and sizes, or why there is one.
std::string families_text(const Families& families) {
  return families.k == 1
             ? "One family: no split of the gyro bias-vs-temperature curves is supported (best mean silhouette " +
                   number(families.silhouette_by_k.empty()
                              ? 0.0
                              : *std::max_element(families.silhouette_by_k.begin(), families.silhouette_by_k.end())) +
                   " below " + number(kFamilySilhouette) + ", or a family smaller than " +
                   number(100 * kMinFamilyShare) + " % of the units)."
             : std::to_string(families.k) + " families of gyro bias-vs-temperature curves (mean silhouette " +
                   number(families.silhouette) + "); " + family_sizes(families) + ".";
}

// report.html
std::string report_html(const std::vector<UnitSummary>& units, const std::vector<Outlier>& outliers,
                        const Families& families, const std::string& command, const FleetTally& t) {
  HtmlReport html("driftlab fleet: " + std::to_string(units.size()) + " units");
  html.section("Summary").paragraph(std::to_string(t.passed) + " of " + std::to_string(units.size()) +
                                    " units calibrated; " + std::to_string(t.within) + " within spec (yield " +
                                    number(100.0 * t.yield) + " %); " + std::to_string(outliers.size()) +
                                    " outlier figures. Command: " + command);
  html.section("Failures").table(failed_table(units)).section("Outliers").table(outlier_table(outliers));
  if (const Figure f = holdout_figure(units, outliers); !f.panels.empty())
    html.figure_or_note(
        f,
        "Held-out residual of every calibrated unit per channel, units in manifest order; blue: a unit without "
        "findings on that channel, red: a unit with one (see the outlier table). A point far above the others "
        "is a unit whose calibration does not transfer to its held-out data.");
  html.section("Families").paragraph(families_text(families));
  if (const Figure f = family_figure(units, families); !f.panels.empty())
    html.figure_or_note(f, "Fitted gyro bias against temperature, one line per unit, coloured by family");
  HtmlTable checks{"Discrepancy check (--discrepancy)",
                   {"unit", "channel: named effects"},
                   {},
                   "driftlab discrepancy without a device file on each gyro channel's first record; an effect is named "
                   "when its delta BIC exceeds 10"};
  for (const auto& u : units)
    for (const auto& text : u.discrepancy) checks.rows.push_back({unit_link(u.unit), text});
  if (!checks.rows.empty()) html.section("Discrepancy check").table(checks);
  html.section("Units").table(units_table(units, t));
  html.section("Figures").table(figures_table());
  return html.html();
}

}  // namespace

void write_fleet_report(const std::vector<UnitSummary>& units, const std::vector<Outlier>& outliers,
                        const Families& families, const std::filesystem::path& out, const std::string& command,
                        OutputSet& files) {
  const FleetTally t = tally(units, outliers);
  files.write(out / "report.json", report_json(units, outliers, families, command, t).dump(2) + "\n");
  files.write(out / "units.csv", units_csv(units, t));
  files.write(out / "report.html", report_html(units, outliers, families, command, t));
}

}  // namespace driftlab::cli
