// `driftlab discrepancy`: fit the device's model to a measured record, show where it misses and
// name the physical effects it lacks (models/discrepancy/discrepancy.hpp). Candidates are every
// effect/* plugin of the registry (built-in and external), or those given with --effects.
// Outputs: report.json (models/discrepancy/report.hpp), report.html (discrepancy_report.hpp), series.csv
// (t_s, measured_dps, model_initial_dps, model_final_dps).
#include <iostream>
#include <memory>

#include "devices/device_file.hpp"
#include "devices/device_file_update.hpp"
#include "devices/discrepancy_options.hpp"
#include "framework/effect_catalogue.hpp"
#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/regular_file.hpp"
#include "framework/output_set.hpp"
#include "framework/units.hpp"
#include "tools/driftlab/cli.hpp"
#include "tools/driftlab/data_dirs.hpp"
#include "tools/driftlab/discrepancy_report.hpp"

namespace driftlab::cli {
namespace {

struct DiscrepancyOptions {
  DataOptions data;
  std::string device, devices_dir, report, series, html, update_device, noise_gmwm;
  std::vector<std::string> effects, sets;
  bool max_gap_given = false;
  int bias_degree = -1;
  double block_s = 0.0;
  double significance = 10.0;
  int max_effects = 4;
};

void discrepancy_command(const DiscrepancyOptions& o, CommandEnv& env) {
  std::vector<std::string> inputs{o.data.path};
  discrepancy::Options options;
  std::string device_path;
  if (!o.device.empty()) {
    device_path = resolve_device_file(o.device, o.devices_dir).string();
    options = devices::discrepancy_options(devices::load_device_file(device_path));
    inputs.push_back(device_path);
  }
  if (o.bias_degree >= 0) options.bias_degree = o.bias_degree;
  if (!o.noise_gmwm.empty() && !o.device.empty())
    throw ConfigError({o.device, 0, "--noise-gmwm"},
                      "the device file gives the noise terms; --noise-gmwm estimates them from a record without one");
  options.noise_gmwm = o.noise_gmwm;
  options.block_s = o.block_s;
  options.significance = o.significance;
  options.max_effects = o.max_effects;
  if (!o.update_device.empty() && device_path.empty())
    throw ConfigError({"", 0, "--update-device"}, "needs --device: the named effects are added to a copy of that file");
  OutputSet outputs({inputs.begin(), inputs.end()});
  outputs.plan(o.report, "--report");
  outputs.plan(o.series, "--series");
  outputs.plan(o.html, "--html");
  outputs.plan(o.update_device, "--update-device");

  // With --update-device and no --effects, only effects a device file can hold are candidates
  // (effect/mode_split_drift would otherwise explain a lag that the file cannot record).
  const auto candidates = discrepancy::make_candidates(env.registry(), o.effects, o.sets, !o.update_device.empty());

  // Gaps: unless --max-gap is given, a record of regular bursts is accepted as it is (the block
  // means handle it); irregular gaps are refused with where the first one is (the shared policy,
  // cli.hpp load_even_or_bursts_record). A given --max-gap is the CSV reader's, as for any command.
  const std::vector<std::string> roles{role::kRate, role::kTemperature};
  const TimeSeries record = o.max_gap_given
                                ? load_record(o.data, roles)
                                : load_even_or_bursts_record(o.data, roles, "The discrepancy search (block means)",
                                                             "give --max-gap 0 to accept them as they are");
  env.progress("discrepancy", 0.0);
  const auto result = discrepancy::find_missing_effects(record, candidates.candidates, options);
  env.progress("discrepancy", 1.0);

  const discrepancy::ReportInfo info{o.data.path, device_path, &options};
  outputs.write(o.report, discrepancy::report_json(result, info).dump(2) + "\n");
  if (!o.series.empty())
    outputs.write_csv(o.series, {{"t_s", record.time(), "s"},
                                 {"measured_dps", record.channel(role::kRate).values, "deg/s"},
                                 {"model_initial_dps", result.model_initial_rad_s, "deg/s"},
                                 {"model_final_dps", result.model_final_rad_s, "deg/s"}});
  if (!o.html.empty()) outputs.write(o.html, discrepancy_html(result, info));
  std::vector<std::string> not_written;
  if (!o.update_device.empty()) {
    std::vector<devices::NamedEffect> named;
    for (const auto& step : result.steps) {
      if (!find_effect_info(step.effect)) {
        not_written.push_back(step.effect);
        continue;
      }
      devices::NamedEffect e{step.effect, {}};
      for (const auto& p : step.parameters) e.values.push_back({p.key, p.unit, p.values});
      named.push_back(std::move(e));
    }
    outputs.write(o.update_device, devices::add_effects_to_device_text(
                                       read_config_text(device_path, "device file"), o.update_device, named,
                                       "effects named by `driftlab discrepancy` on " + o.data.path));
  }
  outputs.commit();

  std::cout << "gap " << result.gap_initial_rad_s * kDphPerRadPerSec << " -> "
            << result.gap_final_rad_s * kDphPerRadPerSec << " deg/h (noise floor "
            << result.noise_floor_rad_s * kDphPerRadPerSec << " deg/h, " << result.blocks << " blocks of "
            << result.block_s << " s)\n";
  const auto& unexplained = result.unexplained;
  if (result.steps.empty() && !unexplained.found) std::cout << "nothing significant is missing\n";
  for (const auto& step : result.steps) {
    std::cout << "named " << step.effect << " (delta BIC " << step.delta_bic << "):";
    for (const auto& p : step.parameters)
      for (std::size_t i = 0; i < p.values.size(); ++i) std::cout << " " << p.key << "=" << p.values[i];
    std::cout << "; gap " << step.gap_before_rad_s * kDphPerRadPerSec << " -> "
              << step.gap_after_rad_s * kDphPerRadPerSec << " deg/h\n";
  }
  if (unexplained.found) {
    const auto& v = unexplained.views.front();
    std::cout << "unexplained: structure remains that no candidate explains, in the " << v.view << " view (delta BIC "
              << v.delta_bic << ", " << v.size_rad_s * kDphPerRadPerSec << " deg/h rms): " << v.where << "\n";
  }
  if (!o.update_device.empty()) {
    std::cout << "wrote " << o.update_device << " (" << device_path << " with the named effects under effects:)\n";
    for (const auto& name : not_written)
      std::cout << "not written: " << name << " (a device file has no such effect: it is the device's own physics "
                << "seen through another channel)\n";
  }
}

}  // namespace

void add_discrepancy_command(CLI::App& app, CommandEnv& env) {
  auto options = std::make_shared<DiscrepancyOptions>();
  auto* cmd = app.add_subcommand(
      "discrepancy", "fit the device's model to a measured record, show where it misses and name the missing effects");
  add_data_options(cmd, options->data,
                   "column mapping role=column:unit (roles rate, temperature; true_rate and drive_frequency used "
                   "when present)");
  cmd->add_option("--device", options->device,
                  "device file or name: its model is the prior, its noise terms the covariance (default: a bias "
                  "polynomial with noise terms estimated from the record)");
  cmd->add_option("--devices-dir", options->devices_dir, "directory of device files");
  cmd->add_option("--report", options->report, "report.json (named effects, gaps, evidence, residual views)")
      ->required();
  cmd->add_option("--series", options->series, "series.csv: t_s, measured_dps, model_initial_dps, model_final_dps");
  cmd->add_option("--html", options->html, "report.html with residual plots before and after");
  cmd->add_option("--update-device", options->update_device,
                  "new.yaml: a copy of the --device file with the named effects added under effects: (everything "
                  "else, comments included, kept); never the --device file itself");
  cmd->add_option("--effects", options->effects, "candidate effects (default: every effect/* plugin)");
  cmd->add_option("--set", options->sets,
                  "candidate parameter, effect/NAME.key=value (e.g. effect/thermal_lag.tau_max_s=8000); repeatable; "
                  "validated by the plugin's table (`driftlab plugins describe effect/NAME`)");
  cmd->add_option(
         "--bias-degree", options->bias_degree,
         "degree of the fitted bias correction polynomial (default: the device file's, at least 1; 2 without a device)")
      ->check(CLI::Range(0, 6));
  cmd->add_option("--block", options->block_s, "block length for the fit, s (default: duration / 400)")
      ->check(finite_number(0.0, 1e12));
  cmd->add_option("--noise-gmwm", options->noise_gmwm,
                  "without --device: estimate the noise terms by GMWM with this composite model of wn, rw and gm "
                  "terms (e.g. wn+rw+gm: a Gauss-Markov bias noise as itself) instead of the IEEE 952 slope fit (N, "
                  "B as flicker, K)");
  cmd->add_option("--significance", options->significance, "delta BIC needed to name an effect")
      ->check(finite_number(0.0, 1e12))
      ->capture_default_str();
  cmd->add_option("--max-effects", options->max_effects, "stop after naming this many effects")
      ->check(CLI::Range(0, 20))
      ->capture_default_str();
  cmd->callback([options, cmd, &env] {
    options->max_gap_given = cmd->get_option("--max-gap")->count() > 0;
    discrepancy_command(*options, env);
  });
}

}  // namespace driftlab::cli
