#include "tools/driftlab/run_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "framework/units.hpp"
#include "models/calibration/fit.hpp"
#include "models/calibration/oven_run.hpp"
#include "tools/driftlab/html_report.hpp"
#include "tools/driftlab/plot.hpp"

namespace driftlab::cli {
namespace {


struct PaperRow {
  const char* stage;
  double b_deg_h, n_deg_h_rthz;
};
// Li et al. 2023, Table 2.
constexpr PaperRow kPaperTable2[] = {
    {"original", 34.66, 99.608}, {"rbf", 28.42, 99.6037}, {"rbf_ga", 23.65, 99.6011}, {"rbf_ga_kf", 3.589, 0.967814}};

const PaperRow* paper_row(const std::string& stage) {
  for (const auto& r : kPaperTable2)
    if (stage == r.stage) return &r;
  return nullptr;
}

nlohmann::json curve_json(const allan::Analysis& a) {
  nlohmann::json c = nlohmann::json::array();
  for (const auto& e : a.curve)
    c.push_back({{"tau_s", e.tau}, {"dev_deg_h", e.dev * kDphPerRadPerSec}, {"lo_deg_h", e.dev_lo * kDphPerRadPerSec},
                 {"hi_deg_h", e.dev_hi * kDphPerRadPerSec}});
  return c;
}

nlohmann::json fit_json(const allan::Analysis& a) {
  if (!a.fit) return nullptr;
  nlohmann::json j{{"label", "least-squares fit of the five IEEE 952 terms (not the paper's reading)"},
                   {"chi2_per_dof", a.fit->reduced_chi2()},
                   {"dof", a.fit->dof}};
  for (const auto& c : allan::kIeee952Units) {
    const auto& t = (*a.fit)[c.term];
    nlohmann::json term{{"resolved", t.resolved}, {"unit", std::string(c.unit)}};
    if (t.resolved) {
      term["value"] = t.value * c.factor;
      term["sigma"] = t.sigma * c.factor;
      term["interval"] = {t.low * c.factor, t.high * c.factor};
    } else {
      term["value"] = nullptr;
      term["upper"] = t.high * c.factor;
    }
    j[std::string(c.key)] = term;
  }
  return j;
}

std::string number_text(double v, const char* format) {
  char b[32];
  std::snprintf(b, sizeof b, format, v);
  return b;
}

}  // namespace

std::vector<std::string> rate_stages(const Pipeline& pipeline, const std::map<std::string, Signal>& outputs) {
  std::vector<std::string> names;
  for (const auto& name : pipeline.output_order) {
    const auto it = outputs.find(name);
    if (it == outputs.end() || it->second.unit != "rad/s" || it->second.columns.cols() != 1) continue;
    if (name != "drift_model") names.push_back(name);
  }
  return names;
}

RunScores score_run(const TimeSeries& record, const Pipeline& pipeline, const std::map<std::string, Signal>& outputs) {
  RunScores s;
  const double fs = record.sample_rate_hz();
  const Eigen::VectorXd& rate = record.channel(role::kRate).values;
  std::optional<evaluation::Truth> truth;
  if (record.has(role::kTrueRate)) {
    truth = evaluation::Truth{record.channel(role::kTrueRate).values, std::nullopt};
    if (record.has(role::kSystematic)) truth->systematic_rad_s = record.channel(role::kSystematic).values;
  }
  const evaluation::Truth* t = truth ? &*truth : nullptr;
  const double reference_n = allan::analyze_rate(rate, fs, {.fit_terms = false}).arw_rad_sqrt_s;

  const Eigen::VectorXd& time = record.time();
  s.stages.push_back(evaluation::score_stage("original", rate, time, fs, reference_n, t));
  for (const auto& name : rate_stages(pipeline, outputs))
    s.stages.push_back(evaluation::score_stage(name, outputs.at(name).columns.col(0), time, fs, reference_n, t));
  // The PX4-style row needs an oven run the calibration quality gate does not refuse.
  const auto fittable = [&](const Eigen::VectorXd& temp) {
    const auto gate = calibration::quality_gate({calibration::analyse_oven_run("the record", time, temp, calibration::FitOptions{}.bin_s)});
    return std::none_of(gate.begin(), gate.end(), [](const auto& f) { return f.severity == calibration::Finding::Severity::Error; });
  };
  if (record.has(role::kTemperature) && fittable(record.channel(role::kTemperature).values)) {
    const Eigen::VectorXd& temp = record.channel(role::kTemperature).values;
    auto model = calibration::fit_px4_style({{"the record", time, rate, temp, {}, {}}}, {});
    Eigen::VectorXd compensated = calibration::compensate(model, time, rate, temp).rate_rad_s;
    s.baseline = Px4Baseline{std::move(model), std::move(compensated)};
    s.stages.push_back(evaluation::score_stage("px4_polynomial", s.baseline->compensated_rad_s, time, fs, reference_n, t));
  }
  if (truth && truth->systematic_rad_s) {
    s.intrinsic = evaluation::intrinsic_floor(rate, *truth->systematic_rad_s, fs);
    for (const auto& stage : s.stages)
      if (stage.error) s.against_floor[stage.stage] = evaluation::compare_to_floor(*stage.error, *s.intrinsic, kFloorFactor);
  }
  return s;
}

nlohmann::json b_json(const allan::FloorReading& b) {
  const double f = kDphPerRadPerSec;
  nlohmann::json j{{"B_resolved", b.resolved}, {"B_deg_h", nullptr}, {"B_upper_deg_h", b.high * f},
                   {"B_tau_s", b.tau_s}, {"B_within_tau_s", b.longest_tau_s}};
  if (b.resolved) {
    j["B_deg_h"] = b.value * f;
    j["B_ci"] = {b.low * f, b.high * f};
  }
  return j;
}

std::string b_text(const allan::FloorReading& b) {
  const double f = kDphPerRadPerSec;
  if (b.resolved)
    return number_text(b.value * f, "%.3g") + " [" + number_text(b.low * f, "%.2g") + "," + number_text(b.high * f, "%.2g") + "]";
  return "< " + number_text(b.high * f, "%.3g") + " (tau<=" + number_text(b.longest_tau_s, "%.0f") + "s)";
}

nlohmann::json scores_json(const RunScores& s) {
  nlohmann::json j;
  auto& rows = j["table2"] = nlohmann::json::array();
  auto& curves = j["allan"] = nlohmann::json::object();
  for (const auto& st : s.stages) {
    const auto& a = st.analysis;
    nlohmann::json row{{"stage", st.stage},
                       {"N_deg_h_rtHz", a.arw_rad_sqrt_s * kDphPerRadPerSec},
                       {"bandwidth_hz", st.bandwidth_hz},
                       {"correlation_time_s", st.correlation_time_s},
                       {"fit", fit_json(a)}};
    row.update(b_json(a.bias_instability));
    if (st.residual_drift_rad_s) row["residual_drift_deg_h"] = *st.residual_drift_rad_s * kDphPerRadPerSec;
    if (const auto it = s.against_floor.find(st.stage); it != s.against_floor.end()) {
      row["error_vs_floor"] = {{"max_ratio", it->second.max_ratio}, {"tau_of_max_s", it->second.tau_of_max_s},
                               {"within_1_5x", it->second.within}};
    }
    if (const auto* p = paper_row(st.stage)) row["paper"] = {{"B_deg_h", p->b_deg_h}, {"N_deg_h_rtHz", p->n_deg_h_rthz}};
    rows.push_back(row);
    curves[st.stage] = curve_json(a);
    if (st.error) curves[st.stage + "_minus_truth"] = curve_json(*st.error);
  }
  if (s.intrinsic) {
    const auto& a = *s.intrinsic;
    j["intrinsic_floor"] = {
        {"what", "Allan analysis of measured - true systematic rate: the gyro's own noise"},
        {"N_deg_h_rtHz", a.arw_rad_sqrt_s * kDphPerRadPerSec}};
    j["intrinsic_floor"].update(b_json(a.bias_instability));
    curves["intrinsic_floor"] = curve_json(a);
  }
  if (s.baseline) {
    const auto& m = s.baseline->model;
    nlohmann::json c = nlohmann::json::array();
    for (double v : m.bias_rad_s) c.push_back(v * kDphPerRadPerSec);
    j["baseline"] = {{"what", std::string("PX4-style (driftlab calibrate's PX4-style poly, fitted on this record): "
                                          "third-order polynomial in T - T0 fitted on ") +
                                  (m.fit.heating_only ? "the heating bins" : "all bins (too few heating bins)") +
                                  ", T clamped to their range"},
                     {"coefficients_deg_h_per_c_pow_i", c},
                     {"reference_temp_c", m.reference_temp_c},
                     {"fit_range_c", {m.valid_min_c, m.valid_max_c}},
                     {"heating_only", m.fit.heating_only},
                     {"bin_s", m.fit.bin_s}};
  }
  j["units"] = {{"B", "deg/h"}, {"N", "deg/h/sqrt(Hz)"}, {"bandwidth", "Hz (one-sided equivalent noise bandwidth)"},
                {"residual_drift", "deg/h, rms of 60-s block means of output - true rate"}, {"allan", "deg/h"}};
  j["readings"] = {{"B", "flat floor of the overlapping Allan deviation / 0.664 (IEEE 952 Annex C), at tau >= the "
                         "output's correlation time (1 / bandwidth); a value only where the deviation has a floor (a "
                         "minimum with rising or flat neighbours within the intervals), otherwise B_deg_h is null and "
                         "B_upper_deg_h bounds B within tau <= B_within_tau_s"},
                   {"N", "-1/2 slope line at tau = 1 s"}};
  return j;
}

std::string table2_text(const RunScores& s) {
  std::string out;
  char line[256];
  out += "Table 2 (B in deg/h, N in deg/h/sqrt(Hz), noise bandwidth in Hz, residual drift in deg/h; B is a value "
         "[68% CI] only where the Allan deviation has a floor, otherwise a bound '< x' within the taus read)\n";
  std::snprintf(line, sizeof line, "%-16s %10s %10s  %20s %12s %10s %14s\n", "stage", "paper B", "paper N", "B",
                "N", "bandwidth", "resid. drift");
  out += line;
  const auto cell = [](std::optional<double> v, const char* fmt) {
    char b[32];
    if (!v) return std::string("-");
    std::snprintf(b, sizeof b, fmt, *v);
    return std::string(b);
  };
  for (const auto& st : s.stages) {
    const auto* p = paper_row(st.stage);
    const auto& a = st.analysis;
    const std::string b = b_text(a.bias_instability);
    std::snprintf(line, sizeof line, "%-16s %10s %10s  %20s %12s %10s %14s\n", st.stage.c_str(),
                  p ? cell(p->b_deg_h, "%.4g").c_str() : "-", p ? cell(p->n_deg_h_rthz, "%.4g").c_str() : "-", b.c_str(),
                  cell(a.arw_rad_sqrt_s * kDphPerRadPerSec, "%.4g").c_str(), cell(st.bandwidth_hz, "%.3g").c_str(),
                  st.residual_drift_rad_s ? cell(*st.residual_drift_rad_s * kDphPerRadPerSec, "%.3g").c_str() : "-");
    out += line;
  }
  if (s.intrinsic) {
    const auto& a = *s.intrinsic;
    std::snprintf(line, sizeof line, "%-16s %10s %10s  %20s %12s %10s %14s\n", "intrinsic floor", "-", "-",
                  b_text(a.bias_instability).c_str(),
                  cell(a.arw_rad_sqrt_s * kDphPerRadPerSec, "%.4g").c_str(), "-", "-");
    out += line;
  }
  return out;
}

}  // namespace driftlab::cli

namespace driftlab::cli {
namespace {

constexpr double kHoursPerSecond = 1.0 / 3600.0;

std::vector<double> to_vector(const Eigen::VectorXd& v, double scale = 1.0) {
  std::vector<double> out(static_cast<std::size_t>(v.size()));
  for (Eigen::Index i = 0; i < v.size(); ++i) out[static_cast<std::size_t>(i)] = v[i] * scale;
  return out;
}

PlotSeries line(std::string label, const Eigen::VectorXd& x, const Eigen::VectorXd& y, double xs, double ys) {
  PlotSeries s;
  s.label = std::move(label);
  s.x = to_vector(x, xs);
  s.y = to_vector(y, ys);
  return s;
}

Figure raw_figure(const TimeSeries& record) {
  PlotPanel p;
  p.title = "Raw record (paper Fig. 10)";
  p.x_label = "time (h)";
  p.y_label = "rate (°/h)";
  p.y2_label = "temperature (°C)";
  p.series.push_back(line("rate", record.time(), record.channel(role::kRate).values, kHoursPerSecond, kDphPerRadPerSec));
  if (record.has(role::kSystematic))
    p.series.push_back(line("true systematic rate", record.time(), record.channel(role::kSystematic).values,
                            kHoursPerSecond, kDphPerRadPerSec));
  if (record.has(role::kTemperature)) {
    auto t = line("case temperature", record.time(), record.channel(role::kTemperature).values, kHoursPerSecond, 1.0);
    t.right_axis = true;
    p.series.push_back(t);
  }
  return {{p}, 900, 320, 1, ""};
}

Figure imf_figure(const std::string& step, const Signal& imfs, const Signal* residue, const Eigen::VectorXd& time) {
  const bool rate = imfs.unit == "rad/s";
  const double ys = rate ? kDphPerRadPerSec : 1.0;
  const std::string unit = rate ? "°/h" : imfs.unit == "degC" ? "°C" : imfs.unit;
  Figure f;
  f.columns = 3;
  f.width = 1100;
  f.panel_height = 170;
  f.title = step + ": IMFs (" + unit + ") over time (h)";
  for (Eigen::Index k = 0; k <= imfs.columns.cols(); ++k) {
    if (k == imfs.columns.cols() && residue == nullptr) break;
    PlotPanel p;
    p.title = k < imfs.columns.cols() ? imfs.labels[static_cast<std::size_t>(k)] : "residue";
    p.legend = PlotPanel::Legend::None;
    const Eigen::VectorXd values = k < imfs.columns.cols() ? Eigen::VectorXd(imfs.columns.col(k)) : residue->columns.col(0);
    p.series.push_back(line("", time, values, kHoursPerSecond, ys));
    f.panels.push_back(p);
  }
  return f;
}

Figure entropy_figure(const std::string& step, const nlohmann::json& imfs) {
  PlotPanel p;
  p.title = step + ": sample entropy per IMF and the groups (paper Fig. 12)";
  p.x_label = "IMF";
  p.y_label = "SampEn";
  p.legend = PlotPanel::Legend::TopRight;
  std::map<std::string, PlotSeries> groups;
  for (const auto& e : imfs) {
    if (!e["score"].is_number()) continue;
    auto& s = groups[e["group"].get<std::string>()];
    s.label = e["group"].get<std::string>();
    s.style = PlotSeries::Style::Markers;
    s.x.push_back(e["imf"].get<double>());
    s.y.push_back(e["score"].get<double>());
  }
  for (const char* g : {"noise", "mixed", "drift"})
    if (groups.count(g)) p.series.push_back(groups[g]);
  return {{p}, 700, 300, 1, ""};
}

Figure allan_figure(const RunScores& scores) {
  PlotPanel p;
  p.title = "Allan deviation of every stage, 68.3 % intervals (paper Fig. 15)";
  p.x_label = "tau (s)";
  p.y_label = "Allan deviation (°/h)";
  p.log_x = p.log_y = true;
  const auto add = [&](const std::string& label, const allan::Analysis& a, PlotSeries::Style style) {
    PlotSeries s;
    s.label = label;
    s.style = style;
    s.interval = PlotSeries::Interval::Band;
    for (const auto& e : a.curve) {
      s.x.push_back(e.tau);
      s.y.push_back(e.dev * kDphPerRadPerSec);
      s.y_low.push_back(e.dev_lo * kDphPerRadPerSec);
      s.y_high.push_back(e.dev_hi * kDphPerRadPerSec);
    }
    p.series.push_back(s);
  };
  for (const auto& st : scores.stages) add(st.stage, st.analysis, PlotSeries::Style::Line);
  if (scores.intrinsic) add("intrinsic floor (measured - systematic)", *scores.intrinsic, PlotSeries::Style::Dashed);
  return {{p}, 900, 520, 1, ""};
}

// Block means (60 s) of the residual of a stage against temperature, heating and cooling apart.
Figure residual_figure(const TimeSeries& record, const std::vector<std::string>& stages,
                       const std::map<std::string, Eigen::VectorXd>& outputs) {
  const Eigen::VectorXd& time = record.time();
  const Eigen::VectorXd& temp = record.channel(role::kTemperature).values;
  const Eigen::VectorXd& truth = record.channel(role::kTrueRate).values;
  const Eigen::VectorXd temperature = evaluation::block_means(time, temp).means;
  Figure f;
  f.columns = static_cast<int>(std::min<std::size_t>(stages.size(), 2));
  f.width = 1100;
  f.panel_height = 320;
  f.title = "Residual (output - true rate), 60-s block means, against the case temperature";
  for (const auto& stage : stages) {
    PlotPanel p;
    p.title = stage;
    p.x_label = "temperature (°C)";
    p.y_label = "residual (°/h)";
    PlotSeries heat, cool;
    heat.label = "heating";
    cool.label = "cooling";
    heat.style = cool.style = PlotSeries::Style::Markers;
    heat.color = "#d62728";
    cool.color = "#1f77b4";
    const auto residual = evaluation::block_means(time, outputs.at(stage) - truth);
    for (Eigen::Index b = 0; b < residual.means.size(); ++b) {
      const auto first = residual.first[static_cast<std::size_t>(b)];
      const double slope = temp[first + residual.samples[static_cast<std::size_t>(b)] - 1] - temp[first];
      auto& series = slope >= 0 ? heat : cool;
      series.x.push_back(temperature[b]);
      series.y.push_back(residual.means[b] * kDphPerRadPerSec);
    }
    p.series = {heat, cool};
    f.panels.push_back(p);
  }
  return f;
}

std::string fmt(double v, const char* format = "%.3g") {
  char b[64];
  std::snprintf(b, sizeof b, format, v);
  return b;
}

}  // namespace

void write_run_html(const std::filesystem::path& path, const std::string& title, const TimeSeries& record,
                    const Pipeline& pipeline, const std::map<std::string, Signal>& outputs,
                    const std::map<std::string, Signal>& step_signals, const nlohmann::json& report,
                    const RunScores& scores) {
  HtmlReport html(title);
  html.paragraph("Pipeline " + pipeline.file + " on " + report.value("data", std::string()) + ": " +
                 std::to_string(record.size()) + " samples at " + fmt(record.sample_rate_hz()) + " Hz (" +
                 fmt(record.size() / record.sample_rate_hz() * kHoursPerSecond) + " h), seed " +
                 std::to_string(pipeline.seed) + ".");

  html.section("Table 2: Allan figures per stage");
  HtmlTable t;
  t.caption = "The stages of the pipeline beside the paper's Table 2, the intrinsic floor and a PX4-style baseline";
  t.header = {"stage", "paper B (°/h)", "paper N (°/h/√Hz)", "B (°/h)", "B interval (°/h)", "minimum at tau (s)",
              "N (°/h/√Hz)", "noise bandwidth (Hz)", "residual drift (°/h)", "max error / floor"};
  // B: a value and its interval where the deviation has a floor, otherwise the bound.
  const auto b_cells = [](const allan::FloorReading& b) -> std::pair<HtmlCell, HtmlCell> {
    if (b.resolved)
      return {b.value * kDphPerRadPerSec, fmt(b.low * kDphPerRadPerSec) + " – " + fmt(b.high * kDphPerRadPerSec)};
    return {"< " + fmt(b.high * kDphPerRadPerSec), "not resolved within tau ≤ " + fmt(b.longest_tau_s, "%.0f") + " s"};
  };
  for (const auto& st : scores.stages) {
    const auto* p = paper_row(st.stage);
    const auto& a = st.analysis;
    const auto [b_value, b_interval] = b_cells(a.bias_instability);
    std::vector<HtmlCell> row{st.stage,
                              p ? HtmlCell(p->b_deg_h) : HtmlCell(std::string("–")),
                              p ? HtmlCell(p->n_deg_h_rthz) : HtmlCell(std::string("–")),
                              b_value,
                              b_interval,
                              a.bias_instability.tau_s,
                              a.arw_rad_sqrt_s * kDphPerRadPerSec,
                              st.bandwidth_hz};
    row.push_back(st.residual_drift_rad_s ? HtmlCell(*st.residual_drift_rad_s * kDphPerRadPerSec)
                                          : HtmlCell(std::string("–")));
    const auto it = scores.against_floor.find(st.stage);
    row.push_back(it != scores.against_floor.end()
                      ? HtmlCell(fmt(it->second.max_ratio, "%.2f") + (it->second.within ? " (within 1.5x)" : " (above)"))
                      : HtmlCell(std::string("–")));
    t.rows.push_back(row);
  }
  if (scores.intrinsic) {
    const auto& a = *scores.intrinsic;
    const auto [b_value, b_interval] = b_cells(a.bias_instability);
    t.rows.push_back({std::string("intrinsic floor"), std::string("–"), std::string("–"), b_value, b_interval,
                      a.bias_instability.tau_s, a.arw_rad_sqrt_s * kDphPerRadPerSec, record.sample_rate_hz() / 2.0,
                      std::string("–"), std::string("–")});
  }
  t.note =
      "B: flat floor of the overlapping Allan deviation / 0.664 (IEEE 952 Annex C), read at tau >= the output's "
      "correlation time (1 / noise bandwidth), with its 68.3 % chi-square interval, where the deviation has a floor "
      "(a minimum with rising or flat neighbours within the intervals); where it is still falling at the longest "
      "tau, only the bound '< x' (the upper end of the minimum's interval / 0.664). N: the -1/2 slope line at "
      "tau = 1 s; N is only comparable at equal noise bandwidth (one-sided equivalent bandwidth relative to the "
      "original record's white level). Residual drift: rms of 60-s block means of output - true rate. Max error / "
      "floor: largest ratio over tau of the Allan deviation of (output - true rate) to that of the intrinsic "
      "noise (measured - true systematic rate); 'within 1.5x' when every tau is, allowing for both intervals. "
      "px4_polynomial: third-order polynomial in temperature fitted on the first heating leg, clipped to it.";
  html.table(t);
  html.figure(allan_figure(scores), "Allan deviation of the original record, every stage, the PX4-style baseline and "
                                    "the intrinsic floor, with 68.3 % intervals (bands)");

  html.section("The record");
  html.figure(raw_figure(record), "Rate and case temperature over time (paper Fig. 10)");

  for (const auto& step : pipeline.steps) {
    if (step.plugin.empty()) continue;
    const auto kind = step.plugin.substr(0, step.plugin.find('/'));
    if (kind == "decomposition") {
      const auto imfs = step_signals.find(step.name + ".imfs");
      const auto residue = step_signals.find(step.name + ".residue");
      if (imfs == step_signals.end()) continue;
      html.section("Decomposition: " + step.name + " (" + step.plugin + ")");
      html.figure(imf_figure(step.name, imfs->second, residue == step_signals.end() ? nullptr : &residue->second,
                             record.time()),
                  imfs->second.unit == "rad/s" ? "IMFs of the rate (paper Fig. 11)"
                                               : "IMFs of the temperature (paper Fig. 13)");
    } else if (kind == "classifier") {
      nlohmann::json imfs;
      for (const auto& s : report["steps"])
        if (s["name"] == step.name) imfs = s["diagnostics"].value("imfs", nlohmann::json::array());
      if (imfs.empty()) continue;
      html.section("Grouping: " + step.name + " (" + step.plugin + ")");
      html.figure(entropy_figure(step.name, imfs), "Sample entropy per IMF and the groups (paper Fig. 12)");
      HtmlTable g;
      g.caption = step.name + ": the group of each IMF and why";
      g.header = {"IMF", "sample entropy", "group", "reason"};
      for (const auto& e : imfs)
        g.rows.push_back({e["imf"].get<double>(), e["score"].is_number() ? HtmlCell(e["score"].get<double>())
                                                                          : HtmlCell(std::string("Inf")),
                          e["group"].get<std::string>(), e["reason"].get<std::string>()});
      html.table(g);
    }
  }

  // Temperature trend (degC step outputs over the temperature) and the mixed group before/after.
  if (record.has(role::kTemperature)) {
    PlotPanel p;
    p.title = "Temperature and its trend (paper Fig. 13)";
    p.x_label = "time (h)";
    p.y_label = "temperature (°C)";
    p.series.push_back(line("case temperature", record.time(), record.channel(role::kTemperature).values, kHoursPerSecond, 1.0));
    for (const auto& [name, s] : step_signals)
      if (s.unit == "degC" && s.columns.cols() == 1 && name.size() > 7 && name.substr(name.size() - 7) == ".signal")
        p.series.push_back(line(name, record.time(), s.columns.col(0), kHoursPerSecond, 1.0));
    html.section("Temperature trend");
    html.figure({{p}, 900, 320, 1, ""}, "The case temperature and the trend the drift is compensated with");
  }

  std::map<std::string, Eigen::VectorXd> stage_outputs;
  std::vector<std::string> stage_names;
  for (const auto& st : scores.stages) {
    if (st.stage == "original") continue;
    if (st.stage == "px4_polynomial") {
      stage_outputs[st.stage] = scores.baseline->compensated_rad_s;
    } else {
      stage_outputs[st.stage] = outputs.at(st.stage).columns.col(0);
    }
    stage_names.push_back(st.stage);
  }
  {
    // Minute means: the noise of a 10-Hz record hides the drift the stages remove.
    const Eigen::VectorXd& time = record.time();
    const Eigen::VectorXd minutes = evaluation::block_means(time, time).means;
    PlotPanel p;
    p.title = "Reconstructed rate per stage, 60-s means (paper Fig. 14)";
    p.x_label = "time (h)";
    p.y_label = "rate (°/h)";
    for (const auto& name : stage_names) {
      p.series.push_back(line(name, minutes, evaluation::block_means(time, stage_outputs[name]).means, kHoursPerSecond,
                              kDphPerRadPerSec));
    }
    PlotPanel mixed;
    mixed.title = "Mixed group before and after the Kalman filter, first 10 minutes";
    mixed.x_label = "time (s)";
    mixed.y_label = "rate (°/h)";
    const auto first = std::min<Eigen::Index>(record.size(), static_cast<Eigen::Index>(600.0 * record.sample_rate_hz()));
    for (const auto& [name, sig] : step_signals) {
      const bool is_mixed = name.size() > 6 && name.substr(name.size() - 6) == ".mixed";
      const bool is_filtered = name.find("kf") != std::string::npos && name.substr(name.size() - 7) == ".signal";
      if ((is_mixed || is_filtered) && sig.unit == "rad/s")
        mixed.series.push_back(line(name, record.time().head(first), sig.columns.col(0).head(first), 1.0, kDphPerRadPerSec));
    }
    Figure f{{p}, 900, 320, 1, ""};
    if (!mixed.series.empty()) f.panels.push_back(mixed);
    html.section("Reconstruction");
    html.figure(f, "The reconstructed rate of every stage (60-s means) and the denoising of the mixed group");
  }
  if (record.has(role::kTrueRate) && record.has(role::kTemperature) && !stage_names.empty()) {
    std::vector<std::string> shown;
    for (const auto& name : stage_names)
      if (name != "px4_polynomial") shown = {name};
    if (stage_outputs.count("px4_polynomial")) shown.push_back("px4_polynomial");
    html.section("Residual against temperature");
    html.figure(residual_figure(record, shown, stage_outputs),
                "Residual of the final stage and of the PX4-style baseline against temperature, heating (red) and "
                "cooling (blue) apart: what a temperature model left");
  }
  html.write(path);
}

}  // namespace driftlab::cli
