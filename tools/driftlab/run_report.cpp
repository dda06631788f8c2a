#include "tools/driftlab/run_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "framework/number_text.hpp"
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

// " (paper Fig. 10)" where the pipeline's reference names the publication's figure for `figure`
// (PipelineReference::figures), else nothing.
std::string paper_figure(const std::optional<PipelineReference>& reference, const std::string& figure) {
  if (!reference) return "";
  const auto it = reference->figures.find(figure);
  return it == reference->figures.end() ? "" : " (paper " + it->second + ")";
}

Figure raw_figure(const TimeSeries& record) {
  PlotPanel p;
  p.title = "Raw record";
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

// What a decomposed signal is, in words and with its display unit and factor.
struct Quantity {
  std::string name, unit;
  double factor = 1.0;
};
Quantity quantity_of(const Signal& s) {
  if (s.unit == "rad/s") return {"rate", "°/h", kDphPerRadPerSec};
  if (s.unit == "degC") return {"temperature", "°C", 1.0};
  return {"signal", s.unit, 1.0};
}

Figure imf_figure(const Signal& imfs, const Signal* residue, const Eigen::VectorXd& time) {
  const auto q = quantity_of(imfs);
  Figure f;
  f.columns = 3;
  f.width = 1100;
  f.panel_height = 190;
  f.shared_x = true;
  f.title = "IMFs of the " + q.name + " (" + q.unit + ") over time (h)";
  for (Eigen::Index k = 0; k <= imfs.columns.cols(); ++k) {
    if (k == imfs.columns.cols() && residue == nullptr) break;
    PlotPanel p;
    p.title = k < imfs.columns.cols() ? imfs.labels[static_cast<std::size_t>(k)] : "residue";
    p.x_label = "time (h)";
    p.y_label = q.name + " (" + q.unit + ")";
    p.legend = PlotPanel::Legend::None;
    const Eigen::VectorXd values =
        k < imfs.columns.cols() ? Eigen::VectorXd(imfs.columns.col(k)) : residue->columns.col(0);
    p.series.push_back(line("", time, values, kHoursPerSecond, q.factor));
    f.panels.push_back(std::move(p));
  }
  return f;
}

Figure entropy_figure(const std::string& of, const std::vector<ImfDecision>& decisions) {
  PlotPanel p;
  p.title = "Sample entropy of the " + of + "'s IMFs and their groups";
  p.x_label = "IMF (number, 1 = fastest)";
  p.y_label = "sample entropy (dimensionless)";
  p.legend = PlotPanel::Legend::TopRight;
  std::map<ImfGroup, PlotSeries> groups;
  for (const auto& d : decisions) {
    auto& s = groups[d.group];
    s.label = group_label(d.group, decisions);
    s.style = PlotSeries::Style::Markers;
    s.x.push_back(static_cast<double>(d.imf));
    s.y.push_back(d.score);
  }
  for (const auto g : kImfGroups)
    if (groups.count(g)) p.series.push_back(groups[g]);
  return {{p}, 700, 300, 1, ""};
}

Figure allan_figure(const RunScores& scores, const std::optional<PipelineReference>& reference) {
  PlotPanel p;
  p.title = "Allan deviation of every stage, 68.3 % intervals" + paper_figure(reference, "allan");
  p.x_label = "tau (s)";
  p.y_label = "Allan deviation (°/h)";
  p.log_x = p.log_y = true;
  const auto add = [&](const std::string& label, const allan::Analysis& a, PlotSeries::Style style) {
    p.series.push_back(allan_series(label, a.curve, kDphPerRadPerSec, style));
  };
  for (const auto& st : scores.stages) add(stage_label(st), st.analysis, PlotSeries::Style::Line);
  if (scores.intrinsic) add("intrinsic floor (measured - systematic)", *scores.intrinsic, PlotSeries::Style::Dashed);
  for (auto& g : allan_guides(scores.stages.front().analysis, kDphPerRadPerSec, "°/h")) p.series.push_back(g);
  return {{p}, 1000, 520, 1, ""};
}

// Block means (60 s) of the residual of a stage against temperature, heating and cooling apart.
Figure residual_figure(const TimeSeries& record, const std::vector<std::string>& stages,
                       const std::map<std::string, Eigen::VectorXd>& outputs,
                       const std::map<std::string, std::string>& labels) {
  const Eigen::VectorXd& time = record.time();
  const Eigen::VectorXd& temp = record.channel(role::kTemperature).values;
  const Eigen::VectorXd& truth = record.channel(role::kTrueRate).values;
  const Eigen::VectorXd temperature = evaluation::block_means(time, temp).means;
  Figure f;
  f.columns = static_cast<int>(std::min<std::size_t>(stages.size(), 2));
  f.width = 1100;
  f.panel_height = 320;
  f.shared_y = true;
  f.title = "Residual (output - true rate), 60-s block means, against the case temperature";
  for (const auto& stage : stages) {
    PlotPanel p;
    p.title = labels.at(stage);
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
      const auto& block = residual.blocks[static_cast<std::size_t>(b)];
      const double slope = temp[block.first + block.samples - 1] - temp[block.first];
      auto& series = slope >= 0 ? heat : cool;
      series.x.push_back(temperature[b]);
      series.y.push_back(residual.means[b] * kDphPerRadPerSec);
    }
    p.series = {heat, cool};
    f.panels.push_back(std::move(p));
  }
  return f;
}

const char* const kRunTable2Note =
    "B: flat floor of the overlapping Allan deviation / 0.664 (IEEE 952 Annex C), read at tau >= the output's "
    "correlation time (1 / noise bandwidth), with its 68.3 % chi-square interval, where the deviation has a floor "
    "(a minimum with rising or flat neighbours within the intervals); where it is still falling at the longest "
    "tau, only the bound '< x' (the upper end of the minimum's interval / 0.664). N: the -1/2 slope line at "
    "tau = 1 s; N is only comparable at equal noise bandwidth (one-sided equivalent bandwidth relative to the "
    "original record's white level). Residual drift: rms of 60-s block means of output - true rate. Systematic "
    "error (records with the true systematic rate): the same of output - true rate - intrinsic noise, the drift a "
    "stage left once the gyro's own noise, which dominates a good stage's residual drift, is taken out. Max error / "
    "floor: largest ratio over tau of the Allan deviation of (output - true rate) to that of the intrinsic "
    "noise (measured - true systematic rate); 'within 1.5x' when every tau is, allowing for both intervals. "
    "PX4-style polynomial (px4_polynomial): third-order polynomial in temperature fitted on the heating bins (on "
    "every bin when there are too few), the temperature clamped to their range. Cubic on the whole record "
    "(cubic_whole_record): the same on every bin, heating and cooling: the strongest simple model fitted in-sample "
    "like the pipeline.";

const char* const kCompareTable2Note =
    "B: flat floor of the overlapping Allan deviation / 0.664 beyond the output's correlation time, "
    "with the chi-square interval of that point (68.3 %), where the deviation has a floor; otherwise "
    "only the bound '< x' within the taus read; N: the -1/2 line at tau = 1 s, comparable "
    "only at equal noise bandwidth (one-sided, relative to the record's white level); residual "
    "drift: rms of 60-s block means of output - true rate (records with a truth column); systematic error: the "
    "same of output - true rate - intrinsic noise (records with the true systematic rate); run time: "
    "wall-clock seconds until the stage's step finished, on this machine.";

const HtmlCell kNone = std::string("–");

// The value cell of B: the number where resolved, otherwise the bound's text.
HtmlCell b_value_cell(const allan::FloorReading& reading, BStyle bound) {
  const auto b = b_deg_h(reading);
  return b.resolved ? HtmlCell(b.value) : HtmlCell(b_text(b, bound));
}

HtmlCell deg_h_cell(std::optional<double> rad_s) { return rad_s ? HtmlCell(*rad_s * kDphPerRadPerSec) : kNone; }

std::vector<HtmlCell> run_cells(const Table2Row& r, bool reference, bool systematic) {
  const auto& a = *r.analysis;
  std::vector<HtmlCell> row{r.stage};
  if (reference) {
    row.push_back(r.reference ? HtmlCell(r.reference->b_deg_h) : kNone);
    row.push_back(r.reference ? HtmlCell(r.reference->n_deg_h_rthz) : kNone);
  }
  row.insert(row.end(),
             {b_value_cell(a.bias_instability, BStyle::Bound), b_text(b_deg_h(a.bias_instability), BStyle::Interval),
              a.bias_instability.tau_s, a.arw_rad_sqrt_s * kDphPerRadPerSec, r.bandwidth_hz});
  row.push_back(deg_h_cell(r.residual_drift_rad_s));
  if (systematic) row.push_back(deg_h_cell(r.systematic_error_rad_s));
  row.push_back(r.against_floor
                    ? HtmlCell(number_text(r.against_floor->max_ratio, "%.2f") +
                               (r.against_floor->within ? " (within 1.5x given the intervals)" : " (above)"))
                    : kNone);
  return row;
}

std::vector<HtmlCell> compare_cells(const Table2Row& r, bool systematic) {
  const auto& a = *r.analysis;
  std::vector<HtmlCell> row{r.pipeline,
                            r.stage,
                            b_value_cell(a.bias_instability, BStyle::BoundFourDigits),
                            b_text(b_deg_h(a.bias_instability), BStyle::IntervalBracketed),
                            a.arw_rad_sqrt_s * kDphPerRadPerSec,
                            r.bandwidth_hz,
                            deg_h_cell(r.residual_drift_rad_s)};
  if (systematic) row.push_back(deg_h_cell(r.systematic_error_rad_s));
  row.push_back(r.seconds ? HtmlCell(*r.seconds) : kNone);
  return row;
}

// ---- the sections of report.html, in order ----

void add_table2(HtmlReport& html, const TimeSeries& record, const RunScores& scores,
                const std::optional<PipelineReference>& reference) {
  html.section("Allan figures per stage (the paper's Table 2)");
  std::vector<Table2Row> rows;
  for (const auto& st : scores.stages) {
    rows.push_back(table2_row(scores, st));
    if (st.label != st.stage) rows.back().stage = st.stage + " (" + st.label + ")";
  }
  if (scores.intrinsic) rows.push_back(intrinsic_floor_row(scores, record.sample_rate_hz()));
  // What stands beside the stages: the baselines need a temperature, the floor a systematic rate.
  std::vector<std::string> beside;
  if (!scores.baselines.empty()) beside.push_back("two simple baselines fitted on the same record");
  if (scores.intrinsic) beside.push_back("the intrinsic floor");
  std::string besides;
  for (std::size_t i = 0; i < beside.size(); ++i) besides += (i == 0 ? "" : " and ") + beside[i];
  HtmlTable table = table2_html(Table2Layout::Run, rows, scores.reference);
  if (!besides.empty()) table.caption += ", " + besides;
  html.table(table);
  if (!scores.reference_not_shown.empty())
    html.paragraph("The paper's columns are not shown: " + scores.reference_not_shown + ".");
  html.figure(
      allan_figure(scores, reference),
      "Allan deviation of the original record and every stage" + (besides.empty() ? "" : ", " + besides) +
          ", with 68.3 % intervals (bands). Grey dashed: the slopes the original record's figures are read from "
          "(-1/2: N; 0: the floor 0.664 B; +1/2: K where the term fit resolves it); black dots: where N (tau = 1 s) "
          "and B (the curve's minimum) are read. A stage lower at long tau has less drift left.");
}

void add_decomposition(HtmlReport& html, const PipelineStep& step, const TimeSeries& record,
                       const std::map<std::string, Signal>& step_signals,
                       const std::optional<PipelineReference>& reference) {
  const auto imfs = step_signals.find(step.name + ".imfs");
  const auto residue = step_signals.find(step.name + ".residue");
  if (imfs == step_signals.end()) return;
  const auto q = quantity_of(imfs->second);
  html.section("Decomposition of the " + q.name + ": step " + step.name + " (" + step.plugin + ")");
  html.figure(imf_figure(imfs->second, residue == step_signals.end() ? nullptr : &residue->second, record.time()),
              "IMFs of the " + q.name + ", fastest first, and the residue" +
                  (q.name == "rate" ? paper_figure(reference, "rate_imfs") +
                                          ": the first carry the noise, the last the thermal drift"
                                    : ": the first carry the sensor's noise, the last the oven cycle"));
}

void add_grouping(HtmlReport& html, const PipelineStep& step, const std::vector<StepRecord>& steps,
                  const std::map<std::string, Signal>& step_signals,
                  const std::optional<PipelineReference>& reference) {
  std::vector<ImfDecision> decisions;
  for (const auto& s : steps)
    if (s.name == step.name) decisions = imf_decisions(s.diagnostics);
  if (decisions.empty()) return;
  const auto imfs = step.inputs.find("imfs");
  const auto signal = imfs == step.inputs.end() || imfs->second.size() != 1 ? step_signals.end()
                                                                            : step_signals.find(imfs->second.front());
  const auto q = signal == step_signals.end() ? Quantity{"signal", "", 1.0} : quantity_of(signal->second);
  html.section("Grouping of the " + q.name + "'s IMFs: step " + step.name + " (" + step.plugin + ")");
  html.figure(entropy_figure(q.name, decisions),
              "Sample entropy of each IMF of the " + q.name + " and the group it falls in" +
                  (q.name == "rate" ? paper_figure(reference, "rate_grouping") : "") +
                  ": high entropy is noise, low entropy is drift, the middle is mixed");
  HtmlTable g;
  g.caption = "The group of each IMF of the " + q.name + " and why";
  g.header = {"IMF", "sample entropy", "group", "reason"};
  for (const auto& d : decisions) g.rows.push_back({static_cast<double>(d.imf), d.score, to_string(d.group), d.reason});
  html.table(g);
}

// Temperature trend: degC step outputs over the temperature.
void add_temperature_trend(HtmlReport& html, const TimeSeries& record,
                           const std::map<std::string, Signal>& step_signals,
                           const std::optional<PipelineReference>& reference) {
  const Eigen::VectorXd& temp = record.channel(role::kTemperature).values;
  PlotPanel p, removed;
  p.title = "Temperature and its trend" + paper_figure(reference, "temperature_trend");
  p.x_label = removed.x_label = "time (h)";
  p.y_label = "temperature (°C)";
  removed.title = "What each trend leaves out: case temperature - trend";
  removed.y_label = "temperature difference (K)";
  p.series.push_back(line("case temperature", record.time(), temp, kHoursPerSecond, 1.0));
  p.series.back().color = "#aaaaaa";
  for (const auto& [name, s] : step_signals)
    if (s.unit == "degC" && s.columns.cols() == 1 && name.ends_with(".signal")) {
      p.series.push_back(line(readable_name(name), record.time(), s.columns.col(0), kHoursPerSecond, 1.0));
      p.series.back().style = PlotSeries::Style::Dashed;
      p.series.back().color = palette_color(removed.series.size());
      removed.series.push_back(line(readable_name(name), record.time(), temp - s.columns.col(0), kHoursPerSecond, 1.0));
    }
  html.section("Temperature trend");
  Figure f{{p}, 900, 320, 1, ""};
  if (!removed.series.empty()) f.panels.push_back(removed), f.shared_x = true;
  html.figure(f,
              "The case temperature (grey) and the trend the drift is compensated with (dashed); they nearly "
              "coincide, so the lower panel shows their difference: the sensor noise the trend removes");
}

// The rate of every stage (the pipeline's, the baselines'), by name in Table 2's order.
struct StageOutputs {
  std::map<std::string, Eigen::VectorXd> rates;
  std::map<std::string, std::string> labels;  // stage_label of each
  std::vector<std::string> names;
  std::optional<std::string> final_stage;
};

StageOutputs stage_outputs(const RunScores& scores, const std::map<std::string, Signal>& outputs) {
  StageOutputs s;
  for (const auto& st : scores.stages) {
    if (st.source == StageScore::Source::Record) continue;
    if (st.source == StageScore::Source::Baseline) {
      for (const auto& b : scores.baselines)
        if (b.stage == st.stage) s.rates[st.stage] = b.compensated_rad_s;
    } else {
      s.final_stage = st.stage;
      s.rates[st.stage] = outputs.at(st.stage).columns.col(0);
    }
    s.names.push_back(st.stage);
    s.labels[st.stage] = stage_label(st);
  }
  return s;
}

void add_reconstruction(HtmlReport& html, const TimeSeries& record, const Pipeline& pipeline,
                        const std::map<std::string, Signal>& step_signals, const StageOutputs& stages) {
  // Minute means: the noise of a 10-Hz record hides the drift the stages remove.
  const Eigen::VectorXd& time = record.time();
  const Eigen::VectorXd minutes = evaluation::block_means(time, time).means;
  const auto minute_means = [&](const std::string& label, const Eigen::VectorXd& rate) {
    return line(label, minutes, evaluation::block_means(time, rate).means, kHoursPerSecond, kDphPerRadPerSec);
  };
  PlotPanel before_after, p;
  before_after.title = "Before and after: the record and the final stage, 60-s means";
  before_after.x_label = p.x_label = "time (h)";
  before_after.y_label = p.y_label = "rate (°/h)";
  before_after.series.push_back(minute_means("original record", record.channel(role::kRate).values));
  if (stages.final_stage)
    before_after.series.push_back(
        minute_means(stages.labels.at(*stages.final_stage), stages.rates.at(*stages.final_stage)));
  p.title = "After, every stage on its own scale, 60-s means" + paper_figure(pipeline.reference, "stages");
  // The final stage first and solid, the others dashed over it: a stage the next one barely changes
  // stays visible.
  for (const auto& name : stages.names) {
    auto s = minute_means(stages.labels.at(name), stages.rates.at(name));
    s.color = palette_color(1 + static_cast<std::size_t>(&name - stages.names.data()));
    if (name != stages.final_stage) s.style = PlotSeries::Style::Dashed;
    p.series.insert(name == stages.final_stage ? p.series.begin() : p.series.end(), std::move(s));
  }
  // Every filter step on a rate: its input and its output over the first 10 minutes.
  PlotPanel filtered;
  filtered.title = "Filter steps on a rate, before and after, first 10 minutes";
  filtered.x_label = "time (s)";
  filtered.y_label = "rate (°/h)";
  const auto first = std::min<Eigen::Index>(record.size(), static_cast<Eigen::Index>(600.0 * record.sample_rate_hz()));
  const auto add_rate = [&](const std::string& name, const std::string& label) {
    const auto it = step_signals.find(name);
    if (it != step_signals.end() && it->second.unit == "rad/s" && it->second.columns.cols() == 1)
      filtered.series.push_back(
          line(label, record.time().head(first), it->second.columns.col(0).head(first), 1.0, kDphPerRadPerSec));
  };
  for (const auto& step : pipeline.steps) {
    if (step.plugin.rfind("filter/", 0) != 0) continue;
    const auto in = step.inputs.find("signal");
    if (in == step.inputs.end() || in->second.size() != 1) continue;
    const auto before = filtered.series.size();
    const std::string filter = readable_name(step.plugin.substr(step.plugin.find('/') + 1)) + " filter";
    add_rate(in->second.front(), "before the " + filter);
    if (filtered.series.size() > before) add_rate(step.name + ".signal", "after the " + filter);
  }
  Figure f{{before_after, p}, 900, 300, 1, ""};  // not shared_x: the filter panel is in seconds
  if (!filtered.series.empty()) f.panels.push_back(filtered);
  html.section("Reconstruction");
  html.figure(f,
              "Top: the record's rate and the final stage's, 60-s means, on one scale: the thermal drift removed. "
              "Middle: every stage's output alone (the final stage solid, the others dashed), where what each "
              "stage adds is visible." +
                  std::string(filtered.series.empty()
                                  ? ""
                                  : " Bottom: each filter step on a rate, its input and output over the first 10 "
                                    "minutes (every sample)."));
}

void add_residual(HtmlReport& html, const TimeSeries& record, const StageOutputs& stages) {
  std::vector<std::string> shown;
  if (stages.final_stage) shown.push_back(*stages.final_stage);
  if (stages.rates.count(evaluation::kPx4BaselineStage)) shown.push_back(evaluation::kPx4BaselineStage);
  html.section("Residual against temperature");
  html.figure(residual_figure(record, shown, stages.rates, stages.labels),
              "Residual of the final stage and of the PX4-style baseline against temperature, heating (red) and "
              "cooling (blue) apart, on one y scale: what a temperature model left. Red and blue apart at one "
              "temperature: a heating/cooling difference (thermal lag or hysteresis) the model does not follow.");
}

void add_tuning(HtmlReport& html, const std::vector<StepRecord>& steps,
                const std::map<std::string, Signal>& step_signals) {
  HtmlTable t;
  t.caption = "Hyperparameters found by each tuned step on its blocked holdout";
  t.header = {"step", "plugin", "best hyperparameters", "held-out RMSE", "evaluations", "notes"};
  for (const auto& s : steps) {
    const auto it = s.diagnostics.find("tuning");
    if (it == s.diagnostics.end()) continue;
    const auto& tuning = *it;
    std::string best, notes;
    double rmse = 0.0;
    const nlohmann::json found = tuning.value("best", nlohmann::json::object());
    for (const auto& [key, value] : found.items()) {
      if (key == "holdout_rmse")
        rmse = value.get<double>();
      else if (value.is_number())
        best += (best.empty() ? "" : ", ") + key + " = " + format_number(value.get<double>());
    }
    for (const auto& note : tuning.value("notes", nlohmann::json::array()))
      notes += (notes.empty() ? "" : "; ") + note.get<std::string>();
    // In the unit of the step's fitted output: deg/h for a rate.
    const auto fitted = step_signals.find(s.name + ".fitted");
    const std::string unit = fitted == step_signals.end() ? "" : fitted->second.unit;
    const std::string rmse_text = unit == "rad/s" ? format_number(rmse * kDphPerRadPerSec) + " °/h"
                                                  : format_number(rmse) + (unit.empty() ? "" : " " + unit);
    t.rows.push_back({s.name, s.plugin, best, rmse_text, static_cast<double>(tuning.value("evaluations", 0)),
                      notes.empty() ? std::string("–") : notes});
  }
  if (t.rows.empty()) return;
  t.note =
      "A best value at a search bound means the optimum may lie outside the range (widen it with --set "
      "STEP.PARAM=[low,high]); a flat history means the search found nothing better than its first population.";
  html.section("Tuning");
  html.table(t);
}

}  // namespace

std::vector<std::string> tuning_notes(const std::vector<StepRecord>& steps) {
  std::vector<std::string> lines;
  for (const auto& s : steps) {
    const auto it = s.diagnostics.find("tuning");
    if (it == s.diagnostics.end()) continue;
    for (const auto& note : it->value("notes", nlohmann::json::array()))
      lines.push_back("step " + s.name + " (" + s.plugin + "): " + note.get<std::string>());
  }
  return lines;
}

std::string stage_label(const StageScore& st) {
  if (st.label != st.stage) return st.label;
  if (st.stage == evaluation::kOriginalStage) return "original record";
  if (st.stage == evaluation::kPx4BaselineStage) return "PX4-style polynomial";
  if (st.stage == evaluation::kCubicBaselineStage) return "cubic on the whole record";
  return readable_name(st.stage);
}

std::string group_label(ImfGroup group, const std::vector<ImfDecision>& decisions) {
  std::vector<int> imfs;
  for (const auto& d : decisions)
    if (d.group == group) imfs.push_back(static_cast<int>(d.imf));
  std::string text = to_string(group) + " group";
  if (imfs.empty()) return text;
  std::sort(imfs.begin(), imfs.end());
  const bool run = imfs.back() - imfs.front() + 1 == static_cast<int>(imfs.size());
  text += imfs.size() == 1 ? " (IMF " + std::to_string(imfs.front()) : " (IMFs ";
  if (imfs.size() > 1 && run) text += std::to_string(imfs.front()) + "–" + std::to_string(imfs.back());
  if (imfs.size() > 1 && !run)
    for (std::size_t i = 0; i < imfs.size(); ++i) text += (i ? ", " : "") + std::to_string(imfs[i]);
  return text + ")";
}

Table2Row intrinsic_floor_row(const RunScores& scores, double sample_rate_hz) {
  Table2Row floor;
  floor.stage = "intrinsic floor";
  floor.analysis = &*scores.intrinsic;
  floor.bandwidth_hz = sample_rate_hz / 2.0;
  return floor;
}

Table2Row table2_row(const RunScores& scores, const StageScore& st) {
  Table2Row r;
  r.stage = st.stage;
  r.analysis = &st.analysis;
  r.bandwidth_hz = st.bandwidth_hz;
  r.residual_drift_rad_s = st.residual_drift_rad_s;
  r.systematic_error_rad_s = st.systematic_error_rad_s;
  r.reference = evaluation::reference_row(scores, st.stage);
  if (const auto it = scores.against_floor.find(st.stage); it != scores.against_floor.end())
    r.against_floor = &it->second;
  return r;
}

HtmlTable table2_html(Table2Layout layout, const std::vector<Table2Row>& rows,
                      const std::optional<PipelineReference>& reference) {
  HtmlTable t;
  const bool systematic =
      std::any_of(rows.begin(), rows.end(), [](const Table2Row& r) { return r.systematic_error_rad_s.has_value(); });
  if (layout == Table2Layout::Compare) {
    t.caption = "B, N, bandwidth, residual drift and run time per pipeline and stage (the paper's Table 2 columns)";
    t.header = {
        "pipeline", "stage", "B (°/h)", "B interval (°/h)", "N (°/h/√Hz)", "bandwidth (Hz)", "residual drift (°/h)"};
    if (systematic) t.header.push_back("systematic error (°/h)");
    t.header.push_back("run time (s)");
    for (const auto& r : rows) t.rows.push_back(compare_cells(r, systematic));
    t.note = kCompareTable2Note;
    return t;
  }
  const bool ref = reference.has_value();
  t.caption =
      ref ? "The stages of the pipeline beside " + reference->source : std::string("The stages of the pipeline");
  t.header = {"stage"};
  if (ref) t.header.insert(t.header.end(), {"paper B (°/h)", "paper N (°/h/√Hz)"});
  t.header.insert(t.header.end(), {"B (°/h)", "B interval (°/h)", "minimum at tau (s)", "N (°/h/√Hz)",
                                   "noise bandwidth (Hz)", "residual drift (°/h)"});
  if (systematic) t.header.push_back("systematic error (°/h)");
  t.header.push_back("max error / floor");
  for (const auto& r : rows) t.rows.push_back(run_cells(r, ref, systematic));
  t.note = kRunTable2Note;
  return t;
}

std::string run_html(const std::string& title, const std::string& data, const TimeSeries& record,
                     const Pipeline& pipeline, const std::map<std::string, Signal>& outputs,
                     const std::map<std::string, Signal>& step_signals, const std::vector<StepRecord>& steps,
                     const RunScores& scores) {
  HtmlReport html(title);
  html.paragraph("Pipeline " + pipeline.file + " on " + data + ": " + std::to_string(record.size()) + " samples at " +
                 number_text(record.sample_rate_hz(), "%.3g") + " Hz (" +
                 number_text(record.size() / record.sample_rate_hz() * kHoursPerSecond, "%.3g") + " h), seed " +
                 std::to_string(pipeline.seed) + ".");
  add_table2(html, record, scores, pipeline.reference);

  html.section("The record");
  html.figure(raw_figure(record), "Rate and case temperature over time" + paper_figure(pipeline.reference, "record"));
  for (const auto& step : pipeline.steps) {
    if (step.plugin.empty()) continue;
    const auto kind = step.plugin.substr(0, step.plugin.find('/'));
    if (kind == "decomposition")
      add_decomposition(html, step, record, step_signals, pipeline.reference);
    else if (kind == "classifier")
      add_grouping(html, step, steps, step_signals, pipeline.reference);
  }
  if (record.has(role::kTemperature)) add_temperature_trend(html, record, step_signals, pipeline.reference);

  const auto stages = stage_outputs(scores, outputs);
  add_reconstruction(html, record, pipeline, step_signals, stages);
  if (record.has(role::kTrueRate) && record.has(role::kTemperature) && !stages.names.empty())
    add_residual(html, record, stages);
  add_tuning(html, steps, step_signals);
  return html.html();
}

}  // namespace driftlab::cli
