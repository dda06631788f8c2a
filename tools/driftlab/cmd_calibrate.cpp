// `driftlab calibrate`: fits a causal temperature-calibration model (poly | physical | rbf) on one
// or more oven records and writes it as driftlab-calibration/1 JSON (models/calibration/).
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>

#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "models/calibration/fit.hpp"
#include "framework/pipeline.hpp"
#include "tools/driftlab/calibration_cli.hpp"
#include "tools/driftlab/calibration_report.hpp"
#include "tools/driftlab/cli.hpp"
#include "tools/driftlab/run_report.hpp"

namespace driftlab::cli {
namespace {

struct CalibrateOptions {
  CalibrationDataOptions data;
  std::string model = "poly";
  std::string out;
  std::string extrapolation = "clamp";
  calibration::FitOptions fit;        // the numeric options are bound to its fields directly
  std::vector<std::string> evaluate;  // held-out records
  double train_until_s = 0.0;         // > 0: calibrate on t < this of the --data record, test on the rest
  std::string report;                 // report directory
  std::string paper_pipeline;         // optional offline reference pipeline (e.g. models/pipelines/li2023.yaml)
  std::string command_line;
};

calibration::FitOptions fit_options(const CalibrateOptions& o, const CommandEnv& env) {
  calibration::FitOptions f = o.fit;
  f.kind = model_kind_option(o.model);
  f.extrapolation = extrapolation_option(o.extrapolation);
  f.progress = [&env](const std::string& label, double fraction) { env.progress(label, fraction); };
  return f;
}

TimeSeries as_time_series(const calibration::Record& r) {
  TimeSeries ts(r.time_s);
  ts.set_channel({role::kRate, "rad/s", r.name, r.rate_rad_s});
  ts.set_channel({role::kTemperature, "degC", r.name, r.temp_c});
  return ts;
}

void calibrate_command(const CalibrateOptions& o, CommandEnv& env) {
  std::vector<std::string> inputs = o.data.paths;
  inputs.insert(inputs.end(), o.evaluate.begin(), o.evaluate.end());
  if (!o.paper_pipeline.empty()) inputs.push_back(o.paper_pipeline);
  OutputSet files({inputs.begin(), inputs.end()});  // the model and the report appear together
  files.plan(o.out, "--out");
  std::optional<ReportFiles> report_files;
  if (!o.report.empty()) report_files = plan_report_files(files, o.report, "--report");
  if (o.train_until_s > 0 && o.data.paths.size() != 1) {
    throw ConfigError({"", 0, "--train-until"}, "--train-until splits a single --data record");
  }
  auto records = load_calibration_records(o.data);
  std::vector<calibration::Record> held_out;
  if (o.train_until_s > 0) {
    const auto whole = records.front();
    records = {calibration::slice(whole, -INFINITY, o.train_until_s)};
    held_out.push_back(calibration::slice(whole, o.train_until_s, INFINITY));
    held_out.back().name += " (t >= " + std::to_string(o.train_until_s) + " s)";
    records.front().name += " (t < " + std::to_string(o.train_until_s) + " s)";
    if (held_out.back().time_s.size() < 2) throw DataError({whole.name, 0, "t_s"}, "nothing left after --train-until");
  }
  for (const auto& p : o.evaluate) held_out.push_back(load_calibration_record(p, o.data));

  const calibration::FitOptions base = fit_options(o, env);
  const auto model = calibration::fit_calibration(records, base);
  model.validate();
  files.write(o.out, calibration::to_json_text(model));
  if (!report_files) {
    files.commit();
    print_model_summary(std::cout, model);
    std::cout << "wrote " << o.out << "\n";
    if (!held_out.empty()) std::cout << "note: held-out records are scored only with --report DIR\n";
    return;
  }

  ReportInput in;
  in.command = o.command_line;
  for (const auto& r : records) in.calibration_records.push_back(r.name);
  in.evaluations = held_out;
  bool any_truth = false;
  for (const auto& r : held_out) any_truth = any_truth || r.true_rate_rad_s.size();
  in.truth_note = any_truth ? "the true_rate column of each held-out record (the rate-table input)"
                            : "zero: the held-out records are static (no true-rate column); the residual is the "
                              "compensated output itself (Earth rate and any constant offset included)";
  in.models.push_back({"none", "raw output", std::nullopt});
  {
    auto px4 = calibration::fit_px4_style(records, base);
    if (px4.fit.heating_only) {
      in.models.push_back({"PX4-style poly", "order 3, heating samples only, clamped outside the range", std::move(px4)});
    } else {
      in.notes.push_back("PX4-style baseline fitted on all samples: too few heating bins (dT/dt > 0)");
      std::cerr << "note: " << in.notes.back() << "\n";
      in.models.push_back({"PX4-style poly", "order 3, all samples (no heating leg), clamped outside the range",
                           std::move(px4)});
    }
  }
  for (const auto kind : {calibration::ModelKind::Polynomial, calibration::ModelKind::Physical,
                          calibration::ModelKind::Rbf}) {
    calibration::FitOptions f = base;
    f.kind = kind;
    const std::string name = calibration::to_string(kind);
    in.models.push_back({name, "ours: heating and cooling, causal, " + o.extrapolation + " outside the range",
                         kind == model.kind && !o.fit.heating_only ? model : calibration::fit_calibration(records, f)});
  }
  if (!o.paper_pipeline.empty()) {
    const auto& registry = env.registry();
    const auto pipeline = load_pipeline(o.paper_pipeline, registry);
    for (std::size_t e = 0; e < held_out.size(); ++e) {
      nlohmann::json report;
      PipelineRunOptions po;
      po.threads = env.threads;
      po.progress = [&env](std::size_t i, std::size_t n, const std::string& step, double f) {
        env.progress("paper pipeline [" + std::to_string(i + 1) + "/" + std::to_string(n) + "] " + step, f);
      };
      const auto outputs = run_pipeline(pipeline, registry, as_time_series(held_out[e]), po, report);
      const auto stages = rate_stages(pipeline, outputs);
      if (stages.empty())
        throw ConfigError({o.paper_pipeline, 0, "outputs"}, "needs an output that is a compensated rate (rad/s)");
      in.external.push_back({"paper pipeline (offline, stage " + stages.back() + ")",
                             "fitted in-sample on this very record, non-causal",
                             "below fs/2: noise IMFs dropped, RBF + Kalman smoothing", e,
                             outputs.at(stages.back()).sum()});
    }
  }
  const auto j = write_calibration_report(in, *report_files, files);
  files.commit();
  print_model_summary(std::cout, model);
  std::cout << "wrote " << o.out << "\n";
  for (const auto& ev : j["evaluations"]) {
    std::cout << "held-out " << ev["record"].get<std::string>() << ":\n";
    for (const auto& m : ev["methods"]) {
      char line[200];
      std::snprintf(line, sizeof line, "  %-26s residual drift %9.3f deg/h   B %s deg/h   extrapolated %5.1f %%\n",
                    m["name"].get<std::string>().c_str(), m["residual_drift_dph"].get<double>(),
                    m["B_dph"].is_null() ? "-" : std::to_string(m["B_dph"].get<double>()).c_str(),
                    100.0 * m["extrapolated_fraction"].get<double>());
      std::cout << line;
    }
    if (ev.contains("intrinsic_floor_drift_dph")) {
      std::cout << "  intrinsic floor (measured - systematic): " << ev["intrinsic_floor_drift_dph"].get<double>()
                << " deg/h\n";
    }
  }
  std::cout << "wrote " << report_files->json.string() << " and " << report_files->html.string() << "\n";
}

}  // namespace

void add_calibrate_command(CLI::App& app, CommandEnv& env) {
  auto o = std::make_shared<CalibrateOptions>();
  auto* cmd = app.add_subcommand(
      "calibrate",
      "fit a causal temperature-calibration model (bias, and scale factor when a varying true rate exists) "
      "on oven records; write driftlab-calibration/1 JSON");
  add_calibration_data_options(cmd, o->data, true);
  cmd->add_option("--model", o->model, "poly: polynomial (order by held-out blocks); physical: + lag, dT/dt, "
                                       "hysteresis; rbf: physical + GA-tuned RBF network")
      ->check(CLI::IsMember({"poly", "physical", "rbf"}))
      ->capture_default_str();
  cmd->add_option("--out", o->out, "model JSON to write (atomically)")->required();
  cmd->add_option("--extrapolation", o->extrapolation,
                  "outside the calibrated range: clamp (hold the edge value), linear (edge tangent), evaluate")
      ->check(CLI::IsMember({"clamp", "linear", "evaluate"}))
      ->capture_default_str();
  cmd->add_option("--reference-temp", o->fit.reference_temp_c, "reference temperature T0 of the polynomial, degC")
      ->capture_default_str();
  cmd->add_option("--min-order", o->fit.min_order, "lowest polynomial order scored")->check(CLI::Range(0, 12))->capture_default_str();
  cmd->add_option("--max-order", o->fit.max_order, "highest polynomial order scored (= --min-order: fixed)")
      ->check(CLI::Range(0, 12))
      ->capture_default_str();
  cmd->add_option("--blocks", o->fit.holdout_blocks, "held-out contiguous time blocks per record (model selection)")
      ->check(CLI::Range(2, 1000))
      ->capture_default_str();
  cmd->add_option("--bin", o->fit.bin_s, "fitting bin length, s (features and target are averaged per bin)")
      ->check(finite_number(0.0, 1e12, true))
      ->capture_default_str();
  cmd->add_option("--derivative-tau", o->fit.derivative_tau_s, "smoothing time constant of the causal dT/dt estimate, s")
      ->check(finite_number(0.0, 1e12, true))
      ->capture_default_str();
  cmd->add_flag("--heating-only", o->fit.heating_only, "fit on heating samples only (PX4 practice; for comparison)");
  cmd->add_option("--device", o->fit.device, "device name stored in the model");
  cmd->add_option("--axis", o->fit.axis, "gyro axis the model applies to (for PX4 / ArduPilot exports)")
      ->check(CLI::IsMember({"x", "y", "z"}))
      ->capture_default_str();
  cmd->add_option("--ga-population", o->fit.ga_population, "RBF tuning: GA population")->check(CLI::Range(2, 1000))->capture_default_str();
  cmd->add_option("--ga-generations", o->fit.ga_generations, "RBF tuning: GA generations")->check(CLI::Range(1, 1000))->capture_default_str();
  cmd->add_option("--seed", o->fit.seed, "seed of the RBF tuning (k-means, holdout, GA)")->capture_default_str();
  cmd->add_option("--evaluate", o->evaluate, "held-out record(s) to score in the report (other seed / profile)");
  cmd->add_option("--train-until", o->train_until_s,
                  "calibrate on t < this (s) of the single --data record and score the rest in the report")
      ->check(finite_number(0.0, 1e12, true));
  cmd->add_option("--report", o->report,
                  "write DIR/report.json and DIR/report.html: no compensation, PX4-style polynomial, poly, "
                  "physical and rbf scored on the held-out records");
  cmd->add_option("--paper-pipeline", o->paper_pipeline,
                  "also run this pipeline offline on each held-out record as a reference (e.g. "
                  "models/pipelines/li2023.yaml; slow on long records)");
  cmd->callback([o, &env, cmd] {
    o->command_line = "driftlab calibrate";
    for (const auto* opt : cmd->get_options()) {
      for (const auto& v : opt->results()) o->command_line += " " + opt->get_name() + " " + v;
    }
    if (o->fit.min_order > o->fit.max_order) throw ConfigError({"", 0, "--min-order"}, "--min-order exceeds --max-order");
    calibrate_command(*o, env);
  });
}

}  // namespace driftlab::cli
