#include "tools/driftlab/run_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "framework/units.hpp"
#include "tools/driftlab/html_report.hpp"
#include "tools/driftlab/plot.hpp"

namespace driftlab::cli {
namespace {

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
  p.series.push_back(
      line("rate", record.time(), record.channel(role::kRate).values, kHoursPerSecond, kDphPerRadPerSec));
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
    const Eigen::VectorXd values =
        k < imfs.columns.cols() ? Eigen::VectorXd(imfs.columns.col(k)) : residue->columns.col(0);
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
    p.series.push_back(allan_series(label, a.curve, kDphPerRadPerSec, style));
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
  const bool ref = scores.reference.has_value();
  t.caption = ref ? "The stages of the pipeline beside " + scores.reference->source +
                        ", the intrinsic floor and a PX4-style baseline"
                  : std::string("The stages of the pipeline, the intrinsic floor and a PX4-style baseline");
  t.header = {"stage"};
  if (ref) t.header.insert(t.header.end(), {"paper B (°/h)", "paper N (°/h/√Hz)"});
  t.header.insert(t.header.end(), {"B (°/h)", "B interval (°/h)", "minimum at tau (s)", "N (°/h/√Hz)",
                                   "noise bandwidth (Hz)", "residual drift (°/h)", "max error / floor"});
  // B: a value and its interval where the deviation has a floor, otherwise the bound.
  const auto b_cells = [](const allan::FloorReading& b) -> std::pair<HtmlCell, HtmlCell> {
    if (b.resolved)
      return {b.value * kDphPerRadPerSec, fmt(b.low * kDphPerRadPerSec) + " – " + fmt(b.high * kDphPerRadPerSec)};
    return {"< " + fmt(b.high * kDphPerRadPerSec), "not resolved within tau ≤ " + fmt(b.longest_tau_s, "%.0f") + " s"};
  };
  for (const auto& st : scores.stages) {
    const auto* p = evaluation::reference_row(scores, st.stage);
    const auto& a = st.analysis;
    const auto [b_value, b_interval] = b_cells(a.bias_instability);
    std::vector<HtmlCell> row{st.label == st.stage ? st.stage : st.stage + " (" + st.label + ")"};
    if (ref) {
      row.push_back(p ? HtmlCell(p->b_deg_h) : HtmlCell(std::string("–")));
      row.push_back(p ? HtmlCell(p->n_deg_h_rthz) : HtmlCell(std::string("–")));
    }
    row.insert(row.end(),
               {b_value, b_interval, a.bias_instability.tau_s, a.arw_rad_sqrt_s * kDphPerRadPerSec, st.bandwidth_hz});
    row.push_back(st.residual_drift_rad_s ? HtmlCell(*st.residual_drift_rad_s * kDphPerRadPerSec)
                                          : HtmlCell(std::string("–")));
    const auto it = scores.against_floor.find(st.stage);
    row.push_back(it != scores.against_floor.end() ? HtmlCell(fmt(it->second.max_ratio, "%.2f") +
                                                              (it->second.within ? " (within 1.5x)" : " (above)"))
                                                   : HtmlCell(std::string("–")));
    t.rows.push_back(row);
  }
  if (scores.intrinsic) {
    const auto& a = *scores.intrinsic;
    const auto [b_value, b_interval] = b_cells(a.bias_instability);
    std::vector<HtmlCell> row{std::string("intrinsic floor")};
    if (ref) row.insert(row.end(), {std::string("–"), std::string("–")});
    row.insert(row.end(), {b_value, b_interval, a.bias_instability.tau_s, a.arw_rad_sqrt_s * kDphPerRadPerSec,
                           record.sample_rate_hz() / 2.0, std::string("–"), std::string("–")});
    t.rows.push_back(row);
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
  html.figure(allan_figure(scores),
              "Allan deviation of the original record, every stage, the PX4-style baseline and "
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
        g.rows.push_back({e["imf"].get<double>(),
                          e["score"].is_number() ? HtmlCell(e["score"].get<double>()) : HtmlCell(std::string("Inf")),
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
    p.series.push_back(
        line("case temperature", record.time(), record.channel(role::kTemperature).values, kHoursPerSecond, 1.0));
    for (const auto& [name, s] : step_signals)
      if (s.unit == "degC" && s.columns.cols() == 1 && name.size() > 7 && name.substr(name.size() - 7) == ".signal")
        p.series.push_back(line(name, record.time(), s.columns.col(0), kHoursPerSecond, 1.0));
    html.section("Temperature trend");
    html.figure({{p}, 900, 320, 1, ""}, "The case temperature and the trend the drift is compensated with");
  }

  std::map<std::string, Eigen::VectorXd> stage_outputs;
  std::vector<std::string> stage_names;
  std::optional<std::string> final_stage, baseline_stage;
  for (const auto& st : scores.stages) {
    if (st.source == StageScore::Source::Record) continue;
    if (st.source == StageScore::Source::Baseline) {
      baseline_stage = st.stage;
      stage_outputs[st.stage] = scores.baseline->compensated_rad_s;
    } else {
      final_stage = st.stage;
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
    // Every filter step on a rate: its input and its output over the first 10 minutes.
    PlotPanel filtered;
    filtered.title = "Filter steps on a rate, input and output, first 10 minutes";
    filtered.x_label = "time (s)";
    filtered.y_label = "rate (°/h)";
    const auto first =
        std::min<Eigen::Index>(record.size(), static_cast<Eigen::Index>(600.0 * record.sample_rate_hz()));
    const auto add_rate = [&](const std::string& name) {
      const auto it = step_signals.find(name);
      if (it != step_signals.end() && it->second.unit == "rad/s" && it->second.columns.cols() == 1)
        filtered.series.push_back(
            line(name, record.time().head(first), it->second.columns.col(0).head(first), 1.0, kDphPerRadPerSec));
    };
    for (const auto& step : pipeline.steps) {
      if (step.plugin.rfind("filter/", 0) != 0) continue;
      const auto in = step.inputs.find("signal");
      if (in == step.inputs.end() || in->second.size() != 1) continue;
      const auto before = filtered.series.size();
      add_rate(in->second.front());
      if (filtered.series.size() > before) add_rate(step.name + ".signal");
    }
    Figure f{{p}, 900, 320, 1, ""};
    if (!filtered.series.empty()) f.panels.push_back(filtered);
    html.section("Reconstruction");
    html.figure(f, "The reconstructed rate of every stage (60-s means) and what each filter step on a rate does");
  }
  if (record.has(role::kTrueRate) && record.has(role::kTemperature) && !stage_names.empty()) {
    std::vector<std::string> shown;
    if (final_stage) shown.push_back(*final_stage);
    if (baseline_stage) shown.push_back(*baseline_stage);
    html.section("Residual against temperature");
    html.figure(residual_figure(record, shown, stage_outputs),
                "Residual of the final stage and of the PX4-style baseline against temperature, heating (red) and "
                "cooling (blue) apart: what a temperature model left");
  }
  html.write(path);
}

}  // namespace driftlab::cli
