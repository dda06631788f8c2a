// driftlab compare: several pipelines on the same record, one report. Every pipeline is run as
// `driftlab run` runs it (framework/pipeline.hpp), every rate output scored, and the scores laid
// side by side:
//   report.json  per pipeline its Table 2 rows (scores_json), step seconds and total seconds;
//   report.html  one table (B with its interval, N with the output's noise bandwidth, residual drift
//                against the truth when the record has one, run time) per pipeline and per stage,
//                and the Allan curves of every output in one figure.
// A stage's run time is the time until the step that produces it has finished (steps run in file
// order), so the last stage's time is the pipeline's.
//
// Scoring: issue 12's Table 2 scoring (models/evaluation, with the one-stop Allan analysis and the
// noise bandwidth) was not on main when this command was written; score() below reads the same
// figures from models/allan's OADEV curve and models/calibration's residual drift, without the
// noise bandwidth. It is the one place to switch to evaluation::score_stage when that lands.
#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>
#include <set>

#include "framework/atomic_file.hpp"
#include "framework/error.hpp"
#include "framework/pipeline.hpp"
#include "framework/units.hpp"
#include "tools/driftlab/cli.hpp"
#include "tools/driftlab/html_report.hpp"
#include "tools/driftlab/plot.hpp"
#include "models/allan/confidence.hpp"
#include "models/allan/deviation.hpp"
#include "models/allan/tau_grid.hpp"
#include "models/calibration/evidence.hpp"
#include "tools/driftlab/version.hpp"

namespace driftlab::cli {
namespace {

constexpr double kDegPerHour = kDegPerRad * 3600.0;  // rad/s -> deg/h; rad/sqrt(s) -> deg/h/sqrt(Hz)
constexpr double kFlickerFloor = 0.6642824702679600;  // sqrt(2 ln 2 / pi): OADEV floor of flicker B
constexpr double kMinTauForB = 10.0;                   // s: below it a low-passed output looks stable
constexpr double kResidualBlockS = 60.0;

struct Score {
  std::string stage;
  std::vector<allan::Estimate> curve;  // OADEV, octave taus, rad/s
  double b = NAN, b_low = NAN, b_high = NAN, b_tau = NAN;  // rad/s, s
  double n = NAN;                                            // rad/sqrt(s)
  std::optional<double> residual_drift;                      // rad/s
};

// B: min OADEV / 0.664 at tau >= 10 s with that point's interval; N: OADEV at tau = 1 s (log-log
// interpolation) times sqrt(1 s); residual drift: rms of 60-s block means of output - true rate.
Score score(const std::string& stage, const Eigen::VectorXd& rate, const TimeSeries& record) {
  Score s;
  s.stage = stage;
  const double fs = record.sample_rate_hz(), tau0 = 1.0 / fs;
  const Eigen::VectorXd angle = allan::angle_from_rate(rate, tau0);
  const auto factors = allan::averaging_factors(allan::TauGrid{}, allan::Kind::Oadev, static_cast<std::size_t>(angle.size()), tau0);
  s.curve = allan::estimate(allan::Kind::Oadev, angle, tau0, allan::InputType::Rate, factors);
  for (std::size_t i = 0; i < s.curve.size(); ++i) {
    const auto& e = s.curve[i];
    if (e.tau >= kMinTauForB && !(e.dev / kFlickerFloor >= s.b)) {
      s.b = e.dev / kFlickerFloor;
      s.b_low = e.dev_lo / kFlickerFloor;
      s.b_high = e.dev_hi / kFlickerFloor;
      s.b_tau = e.tau;
    }
    if (i > 0 && s.curve[i - 1].tau <= 1.0 && e.tau >= 1.0) {
      const auto& p = s.curve[i - 1];
      const double w = e.tau == p.tau ? 0.0 : std::log(1.0 / p.tau) / std::log(e.tau / p.tau);
      s.n = std::exp(std::log(p.dev) + w * (std::log(e.dev) - std::log(p.dev)));
    }
  }
  if (record.has(role::kTrueRate)) {
    s.residual_drift = calibration::residual_drift_rad_s(record.time(), rate, record.channel(role::kTrueRate).values,
                                                         kResidualBlockS);
  }
  return s;
}

struct CompareOptions {
  std::vector<std::string> pipelines;
  DataOptions data;
  std::string out;
};

struct PipelineResult {
  std::string file, label;
  Pipeline pipeline;
  nlohmann::json report;
  double seconds = 0.0;
  std::vector<Score> stages;  // every single-column rate output but drift_model, in output order
};

// Seconds from the start of the run until the step producing `output` finished.
double stage_seconds(const PipelineResult& r, const std::string& output) {
  const auto it = r.pipeline.outputs.find(output);
  if (it == r.pipeline.outputs.end()) return r.seconds;
  const std::string step = it->second.substr(0, it->second.find('.'));
  double total = 0.0;
  for (const auto& s : r.report.value("steps", nlohmann::json::array())) {
    total += s.value("seconds", 0.0);
    if (s.value("name", std::string()) == step) return total;
  }
  return r.seconds;
}

// Output names: the map's order (issue 12 adds the file's order to Pipeline).
std::vector<std::string> output_order(const Pipeline& p) {
  std::vector<std::string> names;
  for (const auto& [name, reference] : p.outputs) names.push_back(name);
  return names;
}

std::string unique_label(const std::string& file, std::set<std::string>& taken) {
  std::string label = std::filesystem::path(file).stem().string();
  for (int k = 2; taken.count(label); ++k) label = std::filesystem::path(file).stem().string() + "_" + std::to_string(k);
  taken.insert(label);
  return label;
}

std::vector<HtmlCell> row(const std::string& pipeline, const Score& s, std::optional<double> seconds) {
  const auto dash = [](std::optional<double> v) { return v ? HtmlCell(*v) : HtmlCell(std::string("–")); };
  return {pipeline,
          s.stage,
          s.b * kDegPerHour,
          "[" + format_number(s.b_low * kDegPerHour) + ", " + format_number(s.b_high * kDegPerHour) + "]",
          s.n * kDegPerHour,
          std::string("–"),
          dash(s.residual_drift ? std::optional<double>(*s.residual_drift * kDegPerHour) : std::nullopt),
          dash(seconds)};
}

nlohmann::json score_json(const Score& s) {
  nlohmann::json j{{"stage", s.stage},
                   {"B_deg_h", s.b * kDegPerHour},
                   {"B_ci", {s.b_low * kDegPerHour, s.b_high * kDegPerHour}},
                   {"B_tau_s", s.b_tau},
                   {"N_deg_h_rtHz", s.n * kDegPerHour}};
  if (s.residual_drift) j["residual_drift_deg_h"] = *s.residual_drift * kDegPerHour;
  nlohmann::json curve = nlohmann::json::array();
  for (const auto& e : s.curve) curve.push_back({{"tau_s", e.tau}, {"dev_deg_h", e.dev * kDegPerHour}});
  j["allan"] = curve;
  return j;
}

PlotSeries curve_series(const std::string& label, const Score& a, PlotSeries::Style style) {
  PlotSeries s;
  s.label = label;
  s.style = style;
  for (const auto& e : a.curve) {
    s.x.push_back(e.tau);
    s.y.push_back(e.dev * kDegPerHour);
  }
  return s;
}

void compare(const CompareOptions& o, CommandEnv& env) {
  if (o.pipelines.size() < 1) throw ConfigError({"", 0, "--pipeline"}, "give at least one --pipeline");
  const auto& registry = env.registry();
  std::vector<PipelineResult> results;
  std::set<std::string> roles_needed{role::kRate}, labels;
  for (const auto& file : o.pipelines) {  // every pipeline is validated before any data is read
    PipelineResult r;
    r.file = file;
    r.label = unique_label(file, labels);
    r.pipeline = load_pipeline(file, registry);
    for (const auto& [name, role] : r.pipeline.inputs)
      if (role != "time") roles_needed.insert(role);
    results.push_back(std::move(r));
  }
  const auto record = load_record(o.data, std::vector<std::string>(roles_needed.begin(), roles_needed.end()));

  std::error_code ec;
  std::filesystem::create_directories(o.out, ec);
  if (!std::filesystem::is_directory(o.out))
    throw ConfigError({o.out, 0, "--out"}, "cannot create the output directory");
  const auto out_dir = std::filesystem::path(o.out);
  const auto report_json = out_dir / "report.json", report_html = out_dir / "report.html";
  std::vector<std::string> inputs{o.data.path};
  inputs.insert(inputs.end(), o.pipelines.begin(), o.pipelines.end());
  for (const auto& f : {report_json, report_html}) check_output(f.string(), inputs);

  for (std::size_t i = 0; i < results.size(); ++i) {
    auto& r = results[i];
    PipelineRunOptions options;
    options.threads = env.threads;
    const std::string prefix = "[" + std::to_string(i + 1) + "/" + std::to_string(results.size()) + " " + r.label + "] ";
    options.progress = [&](std::size_t k, std::size_t n, const std::string& name, double f) {
      env.progress(prefix + "[" + std::to_string(k + 1) + "/" + std::to_string(n) + "] " + name, f);
    };
    r.report = nlohmann::json::object();
    const auto start = std::chrono::steady_clock::now();
    const auto outputs = run_pipeline(r.pipeline, registry, record, options, r.report);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    env.progress(prefix + "scoring", 0.0);
    for (const auto& name : output_order(r.pipeline)) {
      const auto& signal = outputs.at(name);
      if (signal.unit != "rad/s" || signal.columns.cols() != 1 || name == "drift_model") continue;
      r.stages.push_back(score(name, signal.columns.col(0), record));
    }
  }
  const Score original = score("original", record.channel(role::kRate).values, record);

  HtmlTable table{"Table 2 columns per pipeline and stage",
                  {"pipeline", "stage", "B (°/h)", "B interval (°/h)", "N (°/h/√Hz)", "bandwidth (Hz)",
                   "residual drift (°/h)", "run time (s)"},
                  {},
                  "B: min of the overlapping Allan deviation at tau >= 10 s / 0.664 (IEEE 952 flicker floor), with "
                  "the chi-square interval of that point (68.3 %); N: the deviation at tau = 1 s; bandwidth: not "
                  "computed here yet (issue 12's noise bandwidth is not on main), so compare N only between "
                  "outputs of equal bandwidth; residual drift: rms of 60-s block means of output - true rate "
                  "(records with a truth column); run time: wall-clock seconds until the stage's step finished."};
  table.rows.push_back(row("(record)", original, std::nullopt));
  for (const auto& r : results)
    for (const auto& s : r.stages) table.rows.push_back(row(r.label, s, stage_seconds(r, s.stage)));

  PlotPanel panel;
  panel.title = "Overlapping Allan deviation of every output";
  panel.x_label = "tau (s)";
  panel.y_label = "OADEV (°/h)";
  panel.log_x = panel.log_y = true;
  panel.series.push_back(curve_series("original", original, PlotSeries::Style::Dashed));
  for (const auto& r : results)
    for (const auto& s : r.stages) panel.series.push_back(curve_series(r.label + ": " + s.stage, s, PlotSeries::Style::Line));
  Figure figure;
  figure.panels.push_back(panel);
  figure.panel_height = 520;

  nlohmann::json report{{"format", "driftlab-compare-report/1"}, {"driftlab_version", kVersion},
                        {"data", o.data.path},                  {"samples", record.size()},
                        {"threads", env.threads},               {"pipelines", nlohmann::json::array()}};
  report["original"] = score_json(original);
  for (const auto& r : results) {
    nlohmann::json p{{"pipeline", r.file}, {"label", r.label}, {"seed", r.pipeline.seed}, {"seconds", r.seconds}};
    p["steps"] = nlohmann::json::array();
    for (const auto& s : r.report.value("steps", nlohmann::json::array()))
      p["steps"].push_back({{"name", s.value("name", "")}, {"plugin", s.value("plugin", "")}, {"seconds", s.value("seconds", 0.0)}});
    p["table2"] = nlohmann::json::array();
    for (const auto& s : r.stages) {
      p["table2"].push_back(score_json(s));
      p["table2"].back()["seconds"] = stage_seconds(r, s.stage);
    }
    report["pipelines"].push_back(p);
  }
  report["units"] = {{"B", "deg/h"}, {"N", "deg/h/sqrt(Hz)"}, {"residual_drift", "deg/h"}, {"seconds", "s"}};
  write_file_atomically(report_json, report.dump(2) + "\n");

  HtmlReport html("driftlab compare on " + o.data.path);
  html.paragraph("Pipelines: " + [&] {
    std::string s;
    for (const auto& r : results) s += (s.empty() ? "" : ", ") + r.label + " (" + r.file + ")";
    return s;
  }() + ". Record: " + std::to_string(record.size()) + " samples at " + format_number(record.sample_rate_hz()) + " Hz.");
  html.table(table);
  html.figure(figure, "Overlapping Allan deviation of the record and of every pipeline output");
  html.write(report_html);

  for (const auto& cells : table.rows) {
    std::string line;
    for (const auto& c : cells) {
      const std::string text = std::holds_alternative<double>(c) ? format_number(std::get<double>(c)) : std::get<std::string>(c);
      line += (line.empty() ? "" : "  ") + text;
    }
    std::cout << line << "\n";
  }
  if (!env.quiet) std::cerr << "wrote " << report_json.string() << ", " << report_html.string() << "\n";
}

}  // namespace

void add_compare_command(CLI::App& app, CommandEnv& env) {
  auto opts = std::make_shared<CompareOptions>();
  auto* cmd = app.add_subcommand("compare", "run several pipelines on the same record; writes one report (report.json, "
                                            "report.html: Table 2 columns per pipeline and stage, Allan curves)");
  cmd->add_option("--pipeline", opts->pipelines, "pipeline description (YAML); repeatable")->required();
  add_data_options(cmd, opts->data, "column mapping role=column:unit (e.g. rate=gyro_z:rad/s); repeatable");
  cmd->add_option("--out", opts->out, "output directory (created if missing)")->required();
  cmd->callback([opts, &env] { compare(*opts, env); });
}

}  // namespace driftlab::cli
