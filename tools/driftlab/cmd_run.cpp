#include <chrono>
#include <iostream>
#include <memory>
#include <optional>

#include "framework/atomic_file.hpp"
#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/output_set.hpp"
#include "framework/pipeline.hpp"
#include "tools/driftlab/cli.hpp"
#include "tools/driftlab/data_dirs.hpp"
#include "tools/driftlab/run_report.hpp"
#include "tools/driftlab/version.hpp"

namespace driftlab::cli {
namespace {

// Output unit and column suffix for an internal unit.
std::pair<std::string, std::string> written_as(const std::string& internal_unit) {
  if (internal_unit == "rad/s") return {"deg/s", "_dps"};
  if (internal_unit == "degC") return {"degC", "_c"};
  if (internal_unit == "Hz") return {"Hz", "_hz"};
  if (internal_unit == "s") return {"s", "_s"};
  return {"1", ""};
}

struct RunOptions {
  std::string pipeline;
  DataOptions data;
  std::string out;
  bool validate_only = false;
  std::vector<std::string> sets;  // --set STEP.KEY=VALUE
};

void run(const RunOptions& o, CommandEnv& env) {
  const auto& registry = env.registry();
  const auto pipeline =
      load_pipeline(resolve_pipeline_file(o.pipeline, "--pipeline"), registry, pipeline_overrides(o.sets));
  if (o.validate_only) {
    std::cout << o.pipeline << ": valid (" << pipeline.steps.size() << " steps"
              << (pipeline.overrides.empty() ? ""
                                             : ", " + std::to_string(pipeline.overrides.size()) +
                                                   (pipeline.overrides.size() == 1 ? " override" : " overrides"))
              << ")\n";
    return;
  }
  const auto out_dir = std::filesystem::path(o.out);
  const auto outputs_csv = out_dir / "outputs.csv", effective = out_dir / "pipeline.effective.yaml";
  OutputSet files({o.data.path, o.pipeline});  // all planned before the data is read, committed together
  const auto [report_json, report_html] = plan_report_files(files, out_dir, "--out");
  files.plan(outputs_csv, "--out");
  files.plan(effective, "--out");

  std::vector<std::string> roles;
  for (const auto& [name, role] : pipeline.inputs)
    if (role != "time") roles.push_back(role);
  const auto record =
      load_evenly_sampled_record(o.data, roles, "A pipeline (its decompositions, filters and Allan scores)");

  nlohmann::json report{{"format", "driftlab-run-report/1"},
                        {"driftlab_version", kVersion},
                        {"pipeline", o.pipeline},
                        {"data", o.data.path},
                        {"samples", record.size()},
                        {"seed", pipeline.seed},
                        {"overrides", pipeline.overrides},
                        {"threads", env.threads}};
  PipelineRunOptions options;
  options.threads = env.threads;
  options.progress = [&env](std::size_t i, std::size_t n, const std::string& name, double f) {
    env.progress("[" + std::to_string(i + 1) + "/" + std::to_string(n) + "] " + name, f);
  };
  const auto start = std::chrono::steady_clock::now();
  std::map<std::string, Signal> outputs, step_signals;
  std::vector<StepRecord> steps;
  options.step_signals = &step_signals;
  try {
    outputs = run_pipeline(pipeline, registry, record, options, steps);
    report["steps"] = steps_json(steps);
  } catch (...) {
    report["steps"] = steps_json(steps);
    report["status"] = "failed";
    write_file_atomically(report_json, report.dump(2) + "\n");
    throw;
  }
  report["status"] = "ok";
  if (!env.quiet)
    for (const auto& note : tuning_notes(steps)) std::cerr << "note: " << note << "\n";
  report["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::vector<CsvColumn> columns{CsvColumn::view("t_s", record.time(), "s")};
  report["outputs"] = nlohmann::json::array();
  for (const auto& [name, signal] : outputs) {
    const auto [unit, suffix] = written_as(signal.unit);
    for (Eigen::Index c = 0; c < signal.columns.cols(); ++c) {
      const auto column = signal.columns.cols() == 1 ? name + suffix : name + "_" + signal.labels[c] + suffix;
      columns.push_back(CsvColumn::view(column, signal.columns.col(c), unit));
      report["outputs"].push_back({{"column", column}, {"unit", unit}});
    }
  }
  std::optional<RunScores> scores;
  if (record.has(role::kRate)) {
    env.progress("scoring (Allan analysis of every stage)", 0.0);
    try {
      scores = score_run(record, pipeline, outputs);
      report.update(scores_json(*scores));
    } catch (const DataError& e) {  // a record too short for Allan figures still gets its outputs
      report["table2_skipped"] = e.what();
      if (!env.quiet) std::cerr << "note: no Table 2: " << e.what() << "\n";
    }
    env.progress("scoring (Allan analysis of every stage)", 1.0);
  }
  files.write_csv(outputs_csv, columns);
  files.write(effective, effective_pipeline_yaml(pipeline, registry));
  files.write(report_json, report.dump(2) + "\n");
  if (scores) {
    env.progress("figures (gnuplot)", 0.0);
    std::string title = "driftlab run: " + pipeline.file;
    for (std::size_t i = 0; i < pipeline.overrides.size(); ++i)
      title += (i ? ", " : " with --set ") + pipeline.overrides[i];
    files.write(report_html, run_html(title, o.data.path, record, pipeline, outputs, step_signals, steps, *scores));
    env.progress("figures (gnuplot)", 1.0);
    std::cout << table2_text(*scores);
  } else {
    files.drop(report_html);
  }
  files.commit();
  if (!env.quiet)
    std::cerr << "wrote " << outputs_csv.string() << ", " << effective.string() << ", " << report_json.string()
              << (scores ? ", " + report_html.string() : std::string()) << "\n";
}

}  // namespace

void add_run_command(CLI::App& app, CommandEnv& env) {
  auto opts = std::make_shared<RunOptions>();
  auto* cmd = app.add_subcommand("run",
                                 "run a pipeline on a record; writes outputs.csv, pipeline.effective.yaml, "
                                 "report.json and report.html (Table 2, figures) into --out");
  cmd->add_option("--pipeline", opts->pipeline,
                  "pipeline description (YAML, driftlab-pipeline/1): a file, or the name of a bundled pipeline "
                  "(li2023, ...)")
      ->required();
  add_data_options(cmd, opts->data, "column mapping role=column:unit (e.g. rate=gyro_z:rad/s); repeatable");
  cmd->add_option("--out", opts->out, "output directory (created if missing)");
  add_set_option(cmd, opts->sets);
  cmd->add_flag("--validate-only", opts->validate_only, "check the pipeline and stop before reading data");
  cmd->callback([opts, &env] {
    if (!opts->validate_only && opts->out.empty()) throw ConfigError({"", 0, "--out"}, "--out is required");
    run(*opts, env);
  });
}

}  // namespace driftlab::cli
