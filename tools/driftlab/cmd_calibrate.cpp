// `driftlab calibrate`: fits a causal temperature-calibration model (poly | physical | rbf) for every
// gyro and accelerometer channel of one or more oven records of one IMU and writes it as
// driftlab-calibration/2 JSON (models/calibration/).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/parallel.hpp"
#include "framework/resources.hpp"
#include "models/allan/gmwm.hpp"
#include "models/calibration/fit.hpp"
#include "models/calibration/oven_run.hpp"
#include "framework/pipeline.hpp"
#include "tools/driftlab/calibration_cli.hpp"
#include "tools/driftlab/calibration_report.hpp"
#include "tools/driftlab/cli.hpp"
#include "tools/driftlab/data_dirs.hpp"
#include "tools/driftlab/noise_report.hpp"
#include "tools/driftlab/run_report.hpp"

namespace driftlab::cli {
namespace {

struct CalibrateOptions {
  CalibrationDataOptions data;
  std::string model = "physical";
  bool strict = false;  // quality-gate warnings are errors
  bool force = false;   // write a model even when its held-out error exceeds the raw one
  std::string out;
  std::string extrapolation = "clamp";
  calibration::FitOptions fit;        // the numeric options are bound to its fields directly
  std::vector<std::string> evaluate;  // held-out records
  double train_until_s = 0.0;         // > 0: calibrate on t < this of the --data record, test on the rest
  std::string report;                 // report directory
  std::string paper_pipeline;         // optional offline reference pipeline (e.g. models/pipelines/li2023.yaml)
  std::string gmwm;                   // --gmwm: composite noise model of the residuals, e.g. "wn+rw"; empty: none
  std::size_t gmwm_bootstrap = 50;    // replicates of its parametric bootstrap; 0: asymptotic intervals
  std::string command_line;
  std::string device;  // free text stored in the model
};

calibration::FitOptions fit_options(const CalibrateOptions& o, CommandEnv& env, const std::string& channel) {
  calibration::FitOptions f = o.fit;
  f.kind = model_kind_option(o.model);
  f.extrapolation = extrapolation_option(o.extrapolation);
  f.progress = [&env, channel](const std::string& label, double fraction) {
    env.progress(channel + ": " + label, fraction);
  };
  return f;
}

// The GA's run time (issue 28): population x (generations + 1) evaluations per channel, each an RBF
// fit and a held-out prediction over the records' bins. Cost of one evaluation per bin, rounded up
// from `calibrate --model rbf --bin 10` on a simulated oven run of 1620 bins: 240 more evaluations
// took 0.33 s (8.6e-7 s per bin each) on the development machine (2 shared cores).
constexpr double kGaSecondsPerBinEvaluation = 1e-6;

void check_ga_cost(const CalibrateOptions& o, const std::vector<ChannelRecords>& channels) {
  double bins = 0.0;
  for (const auto& ch : channels)
    for (const auto& r : ch.records) {
      if (r.time_s.size() < 2) continue;
      const double span = r.time_s[r.time_s.size() - 1] - r.time_s[0];
      bins += std::min(static_cast<double>(r.time_s.size()), std::ceil(span / o.fit.bin_s) + 1.0);
    }
  const double evaluations = static_cast<double>(o.fit.ga_population) * static_cast<double>(o.fit.ga_generations + 1);
  char what[200];
  std::snprintf(what, sizeof what, "%.3g GA evaluations per channel over %.3g bins in all at %.2g s per bin each",
                evaluations, bins, kGaSecondsPerBinEvaluation);
  check_time_estimate(evaluations * bins * kGaSecondsPerBinEvaluation, {"", 0, "--ga-population, --ga-generations"},
                      what);
}

// The records of `channels` that match `ch` (by role), for held-out scoring.
std::vector<calibration::Record> matching(const std::vector<ChannelRecords>& channels, const ChannelRecords& ch) {
  for (const auto& c : channels)
    if (c.role == ch.role) return c.records;
  throw DataError(
      {channels.empty() || channels.front().records.empty() ? "" : channels.front().records.front().name, 1, ch.role},
      "the held-out record has no '" + ch.role + "' channel (column " + ch.column + ")");
}

void report_channel(const CalibrateOptions& o, CommandEnv& env, const ChannelRecords& ch,
                    const std::vector<calibration::Record>& records, const std::vector<calibration::Record>& held_out,
                    const calibration::ChannelCalibration& chosen, const std::vector<calibration::Finding>& gate,
                    const GmwmRequest& gmwm, const ReportFiles& report_files, OutputSet& files) {
  const calibration::FitOptions base = fit_options(o, env, ch.role);
  ReportInput in;
  in.gate = gate;
  in.chosen = ch.role + ": " + calibration::to_string(chosen.model.kind) + " (" + chosen.model.fit.selection +
              "; held out: " + chosen.model.fit.holdout_design + ")";
  in.command = o.command_line;
  in.calibration = records;
  in.evaluations = held_out;
  bool any_truth = false;
  for (const auto& r : held_out) any_truth = any_truth || r.true_rate_rad_s.size();
  in.gmwm = gmwm;
  in.truth_note = any_truth ? "the true_rate column of each held-out record (the rate-table input)"
                            : "zero: the held-out records are static (no true-rate column); the residual is the "
                              "compensated output itself (Earth rate and any constant offset included)";
  in.models.push_back({"none", "raw output", std::nullopt});
  {
    auto px4 = calibration::fit_px4_style(records, base);
    if (px4.fit.heating_only) {
      in.models.push_back(
          {"PX4-style poly", "order 3, heating samples only, clamped outside the range", std::move(px4)});
    } else {
      in.notes.push_back("PX4-style baseline fitted on all samples: too few heating bins (dT/dt > 0)");
      std::cerr << "note: " << ch.role << ": " << in.notes.back() << "\n";
      in.models.push_back(
          {"PX4-style poly", "order 3, all samples (no heating leg), clamped outside the range", std::move(px4)});
    }
  }
  for (const auto kind :
       {calibration::ModelKind::Polynomial, calibration::ModelKind::Physical, calibration::ModelKind::Rbf}) {
    calibration::FitOptions f = base;
    f.kind = kind;
    const std::string name = calibration::to_string(kind);
    in.models.push_back(
        {name, "ours: heating and cooling, causal, " + o.extrapolation + " outside the range",
         kind == chosen.model.kind && !o.fit.heating_only ? chosen.model : calibration::fit_calibration(records, f)});
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
      const auto outputs = run_pipeline(pipeline, registry, calibration::single_axis_record(held_out[e]), po, report);
      const auto stages = rate_stages(pipeline, outputs);
      if (stages.empty())
        throw ConfigError({o.paper_pipeline, 0, "outputs"}, "needs an output that is a compensated rate (rad/s)");
      in.external.push_back({"paper pipeline (offline, stage " + stages.back().output + ")",
                             "fitted in-sample on this very record, non-causal",
                             "below fs/2: noise IMFs dropped, RBF + Kalman smoothing", e,
                             outputs.at(stages.back().output).sum()});
    }
  }
  for (const auto& held : write_calibration_report(in, report_files, files)) {
    std::cout << ch.role << ": held-out " << held.record << ":\n";
    for (const auto& m : held.methods) {
      char line[200];
      std::snprintf(line, sizeof line, "  %-26s residual drift %9.3f deg/h   B %s deg/h   extrapolated %5.1f %%\n",
                    m.name.c_str(), m.drift_dph,
                    m.b_resolved && std::isfinite(m.b_dph) ? std::to_string(m.b_dph).c_str() : "-",
                    100.0 * m.extrapolated);
      std::cout << line;
      if (m.gmwm) print_gmwm(std::cout, *m.gmwm, true, "rad/s", "    ");
      if (!m.gmwm_failure.empty()) std::cout << "    GMWM not fitted: " << m.gmwm_failure << "\n";
    }
    if (held.intrinsic_floor_drift_dph)
      std::cout << "  intrinsic floor (measured - systematic): " << *held.intrinsic_floor_drift_dph << " deg/h\n";
  }
}

void calibrate_command(const CalibrateOptions& o, CommandEnv& env) {
  std::vector<std::string> inputs = o.data.paths;
  inputs.insert(inputs.end(), o.evaluate.begin(), o.evaluate.end());
  if (!o.paper_pipeline.empty()) inputs.push_back(o.paper_pipeline);
  OutputSet files({inputs.begin(), inputs.end()});  // the model and the reports appear together
  files.plan(o.out, "--out");
  GmwmRequest gmwm;  // refused before any fit when bad
  if (!o.gmwm.empty()) {
    if (o.report.empty())
      throw ConfigError({"", 0, "--gmwm"}, "--gmwm fits the residuals the report scores; give --report DIR");
    gmwm = {allan::gmwm::parse_model(o.gmwm, "--gmwm"), o.gmwm_bootstrap, o.fit.seed, env.threads};
  }
  if (o.train_until_s > 0 && o.data.paths.size() != 1) {
    throw ConfigError({"", 0, "--train-until"}, "--train-until splits a single --data record");
  }
  for (const auto& held : o.evaluate)  // a record scored against itself is no held-out figure
    for (const auto& data : o.data.paths) {
      std::error_code error;
      if (std::filesystem::equivalent(held, data, error))
        throw ConfigError({held, 0, "--evaluate"},
                          "is also a --data record: the model is fitted on it, so its "
                          "score would not be held out; give a record not used for the fit");
    }
  auto channels = load_channel_records(o.data.paths, o.data);
  if (o.model == "rbf") check_ga_cost(o, channels);
  const auto gate = run_quality_gate(channels, o.fit.bin_s, o.strict, &std::cout);
  // --report scores the gyro channels (its figures are in deg/h): one gyro channel writes
  // DIR/report.{json,html}, several write DIR/<channel>/report.{json,html}.
  std::vector<std::optional<ReportFiles>> report_files(channels.size());
  std::size_t gyros = 0;
  for (const auto& ch : channels) gyros += ch.id.sensor == imu::Sensor::Gyro ? 1 : 0;
  if (!o.report.empty()) {
    if (gyros == 0) throw ConfigError({"", 0, "--report"}, "--report scores gyro channels, and none is selected");
    for (std::size_t c = 0; c < channels.size(); ++c) {
      if (channels[c].id.sensor != imu::Sensor::Gyro) continue;
      const std::filesystem::path dir =
          gyros == 1 ? std::filesystem::path(o.report) : std::filesystem::path(o.report) / channels[c].role;
      report_files[c] = plan_report_files(files, dir, "--report");
    }
  }
  std::vector<ChannelRecords> evaluate;
  if (!o.evaluate.empty()) {
    CalibrationDataOptions same = o.data;
    same.same_device = true;  // held-out records are scored, not fitted together
    evaluate = load_channel_records(o.evaluate, same);
  }

  calibration::ImuCalibration model;
  model.device = o.device;
  std::vector<std::vector<calibration::Record>> fitted(channels.size()), held_out(channels.size());
  for (std::size_t c = 0; c < channels.size(); ++c) {
    auto& ch = channels[c];
    fitted[c] = ch.records;
    if (o.train_until_s > 0) {
      const auto whole = ch.records.front();
      fitted[c] = {calibration::slice(whole, -INFINITY, o.train_until_s)};
      held_out[c].push_back(calibration::slice(whole, o.train_until_s, INFINITY));
      held_out[c].back().name += " (t >= " + std::to_string(o.train_until_s) + " s)";
      fitted[c].front().name += " (t < " + std::to_string(o.train_until_s) + " s)";
      if (held_out[c].back().time_s.size() < 2)
        throw DataError({whole.name, 0, "t_s"}, "nothing left after --train-until");
    }
    if (!evaluate.empty()) {
      const auto more = matching(evaluate, ch);
      held_out[c].insert(held_out[c].end(), more.begin(), more.end());
    }
  }
  // The channels are independent fits, one per item (results in channel order, whatever --threads).
  model.channels.resize(channels.size());
  parallel_for(channels.size(), env.threads, [&](std::size_t c) {
    model.channels[c] = fit_channel(channels[c], fitted[c], fit_options(o, env, channels[c].role));
  });
  model.validate();
  if (!o.force) check_holdout_error(model);
  files.write(o.out, calibration::to_json_text(model));
  for (std::size_t c = 0; c < channels.size(); ++c)
    if (report_files[c])
      report_channel(o, env, channels[c], fitted[c], held_out[c], model.channels[c], gate, gmwm, *report_files[c],
                     files);
  files.commit();
  for (const auto& ch : model.channels) print_model_summary(std::cout, ch);
  std::cout << "wrote " << o.out << " (" << model.channels.size() << " channel"
            << (model.channels.size() == 1 ? "" : "s") << ")\n";
  if (o.report.empty() && (!o.evaluate.empty() || o.train_until_s > 0))
    std::cout << "note: held-out records are scored only with --report DIR\n";
  for (const auto& r : report_files)
    if (r) std::cout << "wrote " << r->json.string() << " and " << r->html.string() << "\n";
  if (!o.report.empty() && gyros < channels.size())
    std::cout
        << "note: --report scores the gyro channels; the accelerometer channels' held-out figures are in the model\n";
}

}  // namespace

void add_calibrate_command(CLI::App& app, CommandEnv& env) {
  auto o = std::make_shared<CalibrateOptions>();
  auto* cmd = app.add_subcommand(
      "calibrate",
      "fit a causal temperature-calibration model for every gyro and accelerometer channel of an IMU's oven "
      "records (bias, and scale factor when a varying true rate exists); write driftlab-calibration/2 JSON");
  add_calibration_data_options(cmd, o->data, true);
  cmd->add_option("--model", o->model,
                  "the richest model considered: poly (polynomial, order by held-out blocks); "
                  "physical (+ lag, dT/dt, hysteresis, each kept only when determinable, "
                  "significant, plausible and transferring); rbf (+ a GA-tuned RBF network)")
      ->check(CLI::IsMember({"poly", "physical", "rbf"}))
      ->capture_default_str();
  cmd->add_option("--out", o->out, "model JSON to write (atomically)")->required();
  cmd->add_option("--extrapolation", o->extrapolation,
                  "outside the calibrated range: clamp (hold the edge value), linear (edge tangent), evaluate")
      ->check(CLI::IsMember({"clamp", "linear", "evaluate"}))
      ->capture_default_str();
  cmd->add_option("--reference-temp", o->fit.reference_temp_c, "reference temperature T0 of the polynomial, degC")
      ->capture_default_str();
  cmd->add_option("--min-order", o->fit.min_order, "lowest polynomial order scored")
      ->check(CLI::Range(0, 12))
      ->capture_default_str();
  cmd->add_option("--max-order", o->fit.max_order, "highest polynomial order scored (= --min-order: fixed)")
      ->check(CLI::Range(0, 12))
      ->capture_default_str();
  cmd->add_option("--blocks", o->fit.holdout_blocks, "held-out contiguous time blocks per record (model selection)")
      ->check(CLI::Range(2, 1000))
      ->capture_default_str();
  cmd->add_option("--bin", o->fit.bin_s, "fitting bin length, s (features and target are averaged per bin)")
      ->check(finite_number(0.0, 1e12, true))
      ->capture_default_str();
  cmd->add_option("--derivative-tau", o->fit.derivative_tau_s,
                  "smoothing time constant of the causal dT/dt estimate, s")
      ->check(finite_number(0.0, 1e12, true))
      ->capture_default_str();
  cmd->add_flag("--strict", o->strict,
                "treat quality-gate warnings (span, one direction, no soak, fast ramp, short "
                "leg, dropouts) as errors");
  cmd->add_flag("--force", o->force, "write the model even when its held-out error exceeds the uncompensated error");
  cmd->add_flag("--heating-only", o->fit.heating_only, "fit on heating samples only (PX4 practice; for comparison)");
  cmd->add_option("--device", o->device, "device name stored in the model");
  cmd->add_option("--ga-population", o->fit.ga_population, "RBF tuning: GA population")
      ->check(CLI::Range(2, 1000))
      ->capture_default_str();
  cmd->add_option("--ga-generations", o->fit.ga_generations, "RBF tuning: GA generations")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--seed", o->fit.seed, "seed of the RBF tuning (k-means, holdout, GA) and of the GMWM bootstrap")
      ->capture_default_str();
  cmd->add_option("--evaluate", o->evaluate,
                  "held-out record(s) to score in the report (other seed / profile; not a --data record)");
  cmd->add_option("--train-until", o->train_until_s,
                  "calibrate on t < this (s) of the single --data record and score the rest in the report")
      ->check(finite_number(0.0, 1e12, true));
  cmd->add_option("--report", o->report,
                  "write DIR/report.json and DIR/report.html: no compensation, PX4-style polynomial, poly, "
                  "physical and rbf scored on the held-out records");
  cmd->add_option("--gmwm", o->gmwm,
                  "with --report: also fit a composite noise model by GMWM to every method's residual, beside B and "
                  "N (as driftlab allan --gmwm): processes joined by '+' of wn, qn, rw, dr, gm; e.g. wn+rw");
  add_gmwm_bootstrap_option(cmd, o->gmwm_bootstrap);
  cmd->add_option("--paper-pipeline", o->paper_pipeline,
                  "also run this pipeline offline on each held-out record as a reference (a file or the name of "
                  "a bundled pipeline, e.g. li2023; slow on long records)");
  cmd->callback([o, &env, cmd] {
    o->command_line = "driftlab calibrate";
    for (const auto* opt : cmd->get_options()) {
      for (const auto& v : opt->results()) o->command_line += " " + opt->get_name() + " " + v;
    }
    if (o->fit.min_order > o->fit.max_order)
      throw ConfigError({"", 0, "--min-order"}, "--min-order exceeds --max-order");
    if (!o->paper_pipeline.empty())  // before the records are read and fitted
      o->paper_pipeline = resolve_pipeline_file(o->paper_pipeline, "--paper-pipeline").string();
    calibrate_command(*o, env);
  });
}

}  // namespace driftlab::cli
