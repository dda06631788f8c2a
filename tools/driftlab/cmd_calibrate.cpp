// `driftlab calibrate`: fits a causal temperature-calibration model (poly | physical | rbf) on one
// or more oven records and writes it as driftlab-calibration/1 JSON (models/calibration/).
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "models/calibration/fit.hpp"
#include "tools/driftlab/calibration_cli.hpp"
#include "tools/driftlab/cli.hpp"

namespace driftlab::cli {
namespace {

struct CalibrateOptions {
  CalibrationDataOptions data;
  std::string model = "poly";
  std::string out;
  std::string extrapolation = "clamp";
  std::string device;
  std::string axis = "z";
  double reference_temp_c = 25.0;
  int min_order = 1, max_order = 5;
  std::size_t blocks = 8;
  double bin_s = 1.0;
  double derivative_tau_s = 30.0;
  bool heating_only = false;
  std::size_t ga_population = 16, ga_generations = 10;
  std::uint64_t seed = 1;
};

void calibrate_command(const CalibrateOptions& o, const CommandEnv& env) {
  check_output(o.out, o.data.paths);
  calibration::FitOptions f;
  f.kind = parse_model_kind(o.model);
  f.extrapolation = parse_extrapolation(o.extrapolation);
  f.device = o.device;
  f.axis = o.axis;
  f.reference_temp_c = o.reference_temp_c;
  f.min_order = o.min_order;
  f.max_order = o.max_order;
  f.holdout_blocks = o.blocks;
  f.bin_s = o.bin_s;
  f.derivative_tau_s = o.derivative_tau_s;
  f.heating_only = o.heating_only;
  f.ga_population = o.ga_population;
  f.ga_generations = o.ga_generations;
  f.seed = o.seed;
  f.threads = env.threads;
  f.progress = [&env](const std::string& label, double fraction) { env.progress(label, fraction); };
  const auto records = load_calibration_records(o.data);
  const auto model = calibration::fit_calibration(records, f);
  calibration::write_calibration_model(model, o.out);
  print_model_summary(std::cout, model);
  std::cout << "wrote " << o.out << "\n";
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
  cmd->add_option("--reference-temp", o->reference_temp_c, "reference temperature T0 of the polynomial, degC")
      ->capture_default_str();
  cmd->add_option("--min-order", o->min_order, "lowest polynomial order scored")->check(CLI::Range(0, 12))->capture_default_str();
  cmd->add_option("--max-order", o->max_order, "highest polynomial order scored (= --min-order: fixed)")
      ->check(CLI::Range(0, 12))
      ->capture_default_str();
  cmd->add_option("--blocks", o->blocks, "held-out contiguous time blocks per record (model selection)")
      ->check(CLI::Range(2, 1000))
      ->capture_default_str();
  cmd->add_option("--bin", o->bin_s, "fitting bin length, s (features and target are averaged per bin)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--derivative-tau", o->derivative_tau_s, "smoothing time constant of the causal dT/dt estimate, s")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--heating-only", o->heating_only, "fit on heating samples only (PX4 practice; for comparison)");
  cmd->add_option("--device", o->device, "device name stored in the model");
  cmd->add_option("--axis", o->axis, "gyro axis the model applies to (for PX4 / ArduPilot exports)")
      ->check(CLI::IsMember({"x", "y", "z"}))
      ->capture_default_str();
  cmd->add_option("--ga-population", o->ga_population, "RBF tuning: GA population")->check(CLI::Range(2, 1000))->capture_default_str();
  cmd->add_option("--ga-generations", o->ga_generations, "RBF tuning: GA generations")->check(CLI::Range(1, 1000))->capture_default_str();
  cmd->add_option("--seed", o->seed, "seed of the RBF tuning (k-means, holdout, GA)")->capture_default_str();
  cmd->callback([o, &env] {
    if (o->min_order > o->max_order) throw ConfigError({"", 0, "--min-order"}, "--min-order exceeds --max-order");
    calibrate_command(*o, env);
  });
}

}  // namespace driftlab::cli
