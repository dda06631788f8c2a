// driftlab compare: several pipelines on the same record, one report. Every pipeline is run as
// `driftlab run` runs it and scored by the same code (models/evaluation/run_scores.hpp: score_run, i.e.
// models/evaluation and the Allan entry point models/allan/analysis.hpp); this file only runs,
// times and lays the scores side by side:
//   report.json  per pipeline its Table 2 rows (scores_json), step seconds and total seconds;
//   report.html  one table (B with its interval, N with the output's noise bandwidth, residual drift
//                against the truth when the record has one, run time) per pipeline and per stage,
//                and the Allan curves of every output in one figure, with the reading guides (plot.hpp
//                allan_guides) of the original record and of the intrinsic floor.
// Both are planned before the record is read (an input, a directory or an unwritable --out is a
// usage error) and appear together at the end or not at all (framework/output_set.hpp).
// A stage's run time is the time until the step that produces it has finished (steps run in file
// order), so the last stage's time is the pipeline's.
#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>
#include <set>

#include "framework/error.hpp"
#include "framework/output_set.hpp"
#include "framework/pipeline.hpp"
#include "framework/units.hpp"
#include "tools/driftlab/cli.hpp"
#include "tools/driftlab/data_dirs.hpp"
#include "tools/driftlab/html_report.hpp"
#include "tools/driftlab/plot.hpp"
#include "tools/driftlab/run_report.hpp"
#include "tools/driftlab/version.hpp"

namespace driftlab::cli {
namespace {

struct CompareOptions {
  std::vector<std::string> pipelines;
  DataOptions data;
  std::string out;
  std::vector<std::string> sets;  // --set STEP.KEY=VALUE, applied to every pipeline with that step
};

struct PipelineResult {
  std::string file, label;
  Pipeline pipeline;
  std::vector<StepRecord> steps;
  double seconds = 0.0;
  RunScores scores;
};

// Seconds from the start of the run until the step producing `output` finished.
double stage_seconds(const PipelineResult& r, const std::string& output) {
  const auto it = r.pipeline.outputs.find(output);
  if (it == r.pipeline.outputs.end()) return r.seconds;
  const std::string step = it->second.substr(0, it->second.find('.'));
  double total = 0.0;
  for (const auto& s : r.steps) {
    total += s.seconds;
    if (s.name == step) return total;
  }
  return r.seconds;
}

std::string unique_label(const std::string& file, std::set<std::string>& taken) {
  std::string label = std::filesystem::path(file).stem().string();
  for (int k = 2; taken.count(label); ++k)
    label = std::filesystem::path(file).stem().string() + "_" + std::to_string(k);
  taken.insert(label);
  return label;
}

Table2Row row(const std::string& pipeline, const RunScores& scores, const evaluation::StageScore& s,
              std::optional<double> seconds) {
  Table2Row r = table2_row(scores, s);
  r.pipeline = pipeline;
  r.seconds = seconds;
  return r;
}

void compare(const CompareOptions& o, CommandEnv& env) {
  if (o.pipelines.size() < 1) throw ConfigError({"", 0, "--pipeline"}, "give at least one --pipeline");
  const auto& registry = env.registry();
  std::vector<PipelineResult> results;
  std::set<std::string> roles_needed{role::kRate}, labels;
  const auto overrides = pipeline_overrides(o.sets);
  std::vector<bool> override_used(overrides.size(), false);
  std::string steps_seen;                 // for the message of an override no pipeline can take
  for (const auto& file : o.pipelines) {  // every pipeline is validated before any data is read
    PipelineResult r;
    r.file = file;
    r.label = unique_label(file, labels);
    const auto path = resolve_pipeline_file(file, "--pipeline");
    r.pipeline = load_pipeline(path, registry);
    std::vector<PipelineOverride> mine;  // the overrides of the steps this pipeline has
    std::string steps;
    for (const auto& step : r.pipeline.steps) steps += (steps.empty() ? "" : ", ") + step.name;
    steps_seen += (steps_seen.empty() ? "" : "; ") + r.label + ": " + steps;
    for (std::size_t i = 0; i < overrides.size(); ++i)
      for (const auto& step : r.pipeline.steps)
        if (step.name == overrides[i].step) {
          mine.push_back(overrides[i]);
          override_used[i] = true;
          break;
        }
    if (!mine.empty()) {
      r.pipeline = load_pipeline(path, registry, mine);
      std::string applied;
      for (const auto& text : r.pipeline.overrides) applied += (applied.empty() ? "" : ", ") + text;
      r.label += " [" + applied + "]";
    }
    for (const auto& [name, role] : r.pipeline.inputs)
      if (role != "time") roles_needed.insert(role);
    results.push_back(std::move(r));
  }
  for (std::size_t i = 0; i < overrides.size(); ++i)
    if (!override_used[i])
      throw ConfigError({"--set " + overrides[i].text, 0, overrides[i].step},
                        "no pipeline has a step '" + overrides[i].step + "' (steps: " + steps_seen + ")");
  std::vector<std::filesystem::path> inputs{o.data.path};
  inputs.insert(inputs.end(), o.pipelines.begin(), o.pipelines.end());
  OutputSet files(inputs);  // planned before the data is read, committed together at the end
  const auto [report_json, report_html] = plan_report_files(files, o.out, "--out");
  const auto record =
      load_evenly_sampled_record(o.data, std::vector<std::string>(roles_needed.begin(), roles_needed.end()),
                                 "A pipeline (its decompositions, filters and Allan scores)");

  for (std::size_t i = 0; i < results.size(); ++i) {
    auto& r = results[i];
    PipelineRunOptions options;
    options.threads = env.threads;
    const std::string prefix =
        "[" + std::to_string(i + 1) + "/" + std::to_string(results.size()) + " " + r.label + "] ";
    options.progress = [&](std::size_t k, std::size_t n, const std::string& name, double f) {
      env.progress(prefix + "[" + std::to_string(k + 1) + "/" + std::to_string(n) + "] " + name, f);
    };
    const auto start = std::chrono::steady_clock::now();
    const auto outputs = run_pipeline(r.pipeline, registry, record, options, r.steps);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!env.quiet)
      for (const auto& note : tuning_notes(r.steps)) std::cerr << "note: " << r.label << ": " << note << "\n";
    env.progress(prefix + "scoring", 0.0);
    r.scores = score_run(record, r.pipeline, outputs);
    env.progress(prefix + "scoring", 1.0);
  }

  // The record-level rows (original, the baselines, intrinsic floor) are the same for every
  // pipeline: taken from the first.
  const RunScores& first = results.front().scores;
  std::vector<Table2Row> rows;
  for (const auto& s : first.stages)
    if (!is_pipeline_stage(s)) rows.push_back(row("(record)", first, s, std::nullopt));
  if (first.intrinsic) {
    rows.push_back(intrinsic_floor_row(first, record.sample_rate_hz()));
    rows.back().pipeline = "(record)";
  }
  for (const auto& r : results)
    for (const auto& s : r.scores.stages)
      if (is_pipeline_stage(s)) rows.push_back(row(r.label, r.scores, s, stage_seconds(r, s.stage)));
  const HtmlTable table = table2_html(Table2Layout::Compare, rows, std::nullopt);

  PlotPanel panel;
  panel.title = "Overlapping Allan deviation of every output, 68.3 % intervals";
  panel.x_label = "tau (s)";
  panel.y_label = "Allan deviation (°/h)";
  panel.log_x = panel.log_y = true;
  const auto curve = [](const std::string& label, const allan::Analysis& a, PlotSeries::Style style) {
    return allan_series(label, a.curve, kDphPerRadPerSec, style);
  };
  for (const auto& s : first.stages)
    if (!is_pipeline_stage(s)) panel.series.push_back(curve(stage_label(s), s.analysis, PlotSeries::Style::Dashed));
  if (first.intrinsic) panel.series.push_back(curve("intrinsic floor", *first.intrinsic, PlotSeries::Style::Dashed));
  for (const auto& r : results)
    for (const auto& s : r.scores.stages)
      if (is_pipeline_stage(s))
        panel.series.push_back(curve(r.label + ": " + stage_label(s), s.analysis, PlotSeries::Style::Line));
  // The reading guides of the original record (the first stage) and of the intrinsic floor.
  for (auto& g :
       allan_guides(first.stages.front().analysis, kDphPerRadPerSec, "°/h", stage_label(first.stages.front())))
    panel.series.push_back(std::move(g));
  if (first.intrinsic)
    for (auto& g : allan_guides(*first.intrinsic, kDphPerRadPerSec, "°/h", "intrinsic floor"))
      panel.series.push_back(std::move(g));
  Figure figure;
  figure.panels.push_back(panel);
  figure.width = 1000;
  figure.panel_height = 520;

  nlohmann::json report{{"format", "driftlab-compare-report/1"},
                        {"driftlab_version", kVersion},
                        {"data", o.data.path},
                        {"samples", record.size()},
                        {"threads", env.threads},
                        {"pipelines", nlohmann::json::array()}};
  for (const auto& st : first.stages)
    if (!is_pipeline_stage(st)) report[st.stage] = stage_json(first, st);
  if (first.intrinsic) report["intrinsic_floor"] = intrinsic_floor_json(*first.intrinsic);
  for (const auto& r : results) {
    nlohmann::json p = scores_json(r.scores);
    p["pipeline"] = r.file;
    p["label"] = r.label;
    p["seed"] = r.pipeline.seed;
    p["overrides"] = r.pipeline.overrides;
    p["seconds"] = r.seconds;
    p["steps"] = nlohmann::json::array();
    for (const auto& s : r.steps)
      p["steps"].push_back({{"name", s.name}, {"plugin", s.plugin}, {"seconds", s.seconds}});
    for (std::size_t i = 0; i < r.scores.stages.size(); ++i)  // table2 has one row per stage, in order
      if (is_pipeline_stage(r.scores.stages[i])) p["table2"][i]["seconds"] = stage_seconds(r, r.scores.stages[i].stage);
    report["pipelines"].push_back(p);
  }
  files.write(report_json, report.dump(2) + "\n");

  HtmlReport html("driftlab compare on " + o.data.path);
  html.paragraph("Pipelines: " +
                 [&] {
                   std::string s;
                   for (const auto& r : results) s += (s.empty() ? "" : ", ") + r.label + " (" + r.file + ")";
                   return s;
                 }() +
                 ". Record: " + std::to_string(record.size()) + " samples at " +
                 format_number(record.sample_rate_hz()) + " Hz.");
  html.table(table);
  html.figure(figure,
              "Allan deviation of the record, the two baselines (when the record has a temperature) and the "
              "intrinsic floor (when it has a systematic column), dashed, and every pipeline output (solid), each with "
              "its 68.3 % interval "
              "as a band. Lower at long tau: less drift left; a curve on the intrinsic floor has removed all of it. "
              "Grey dashed guides, of the original record" +
                  std::string(first.intrinsic ? " and of the intrinsic floor" : "") +
                  ": the -1/2 slope through N at tau = 1 s and the level of the floor where B is read (0.664 B), "
                  "with the points they are read at (black dots, their values in the legend).");
  files.write(report_html, html.html());
  files.commit();

  std::string header;
  for (const auto& h : table.header) header += (header.empty() ? "" : "  ") + h;
  std::cout << header << "\n";
  for (const auto& cells : table.rows) {
    std::string line;
    for (const auto& c : cells) {
      const std::string text =
          std::holds_alternative<double>(c) ? format_number(std::get<double>(c)) : std::get<std::string>(c);
      line += (line.empty() ? "" : "  ") + text;
    }
    std::cout << line << "\n";
  }
  if (!env.quiet) std::cerr << "wrote " << report_json.string() << ", " << report_html.string() << "\n";
}

}  // namespace

void add_compare_command(CLI::App& app, CommandEnv& env) {
  auto opts = std::make_shared<CompareOptions>();
  auto* cmd = app.add_subcommand("compare",
                                 "run several pipelines on the same record; writes one report (report.json, "
                                 "report.html: Table 2 columns per pipeline and stage, Allan curves)");
  cmd->add_option("--pipeline", opts->pipelines,
                  "pipeline description (YAML): a file, or the name of a bundled pipeline (li2023, ...); repeatable")
      ->required();
  add_data_options(cmd, opts->data, "column mapping role=column:unit (e.g. rate=gyro_z:rad/s); repeatable");
  cmd->add_option("--out", opts->out, "output directory (created if missing)")->required();
  add_set_option(cmd, opts->sets);
  cmd->callback([opts, &env] { compare(*opts, env); });
}

}  // namespace driftlab::cli
