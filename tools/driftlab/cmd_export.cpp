// `driftlab export`: writes a whole-IMU calibration model (or a single-axis /1 file, one gyro
// channel) in a firmware / navigation format (models/calibration/exports.hpp): c-header, px4,
// ardupilot, kalibr, json. Instances and axes come from the model.
#include <iostream>
#include <memory>
#include <vector>

#include "framework/error.hpp"
#include "framework/output_set.hpp"
#include "models/calibration/exports.hpp"
#include "tools/driftlab/cli.hpp"

namespace driftlab::cli {
namespace {

struct ExportCommandOptions {
  std::string model, format, out;
  calibration::ExportOptions e;
};

void export_command(const ExportCommandOptions& o) {
  OutputSet outputs({o.model});
  outputs.plan(o.out, "--out");
  const auto model = calibration::read_calibration(o.model);
  calibration::ExportResult r;
  try {
    if (o.format == "c-header") {
      r = calibration::export_c_header(model, o.e);
    } else if (o.format == "px4") {
      r = calibration::export_px4_params(model, o.e);
    } else if (o.format == "ardupilot") {
      r = calibration::export_ardupilot_params(model, o.e);
    } else if (o.format == "kalibr") {
      r = calibration::export_kalibr_imu_yaml(model, o.e);
    } else {
      r.text = calibration::to_json_text(model);
    }
  } catch (const ConfigError& e) {  // what the model cannot be exported as names the model's file
    std::vector<Diagnostic> named = e.problems();
    for (auto& d : named)
      if (d.where.file.empty() && d.where.field.rfind("--", 0) != 0) d.where.file = o.model;
    throw ConfigError(std::move(named));
  }
  outputs.write(o.out, r.text);
  outputs.commit();
  for (const auto& n : r.notes) std::cerr << "note: " << n << "\n";
  std::cout << "wrote " << o.out << " (" << o.format << ", " << model.channels.size() << " channel"
            << (model.channels.size() == 1 ? "" : "s") << ")\n";
}

}  // namespace

void add_export_command(CLI::App& app, CommandEnv&) {
  auto o = std::make_shared<ExportCommandOptions>();
  auto* cmd = app.add_subcommand(
      "export",
      "export a calibration model, every channel: C99 header, PX4 TC_G*/TC_A* .params, ArduPilot INS_TCAL*, Kalibr "
      "imu.yaml, JSON");
  cmd->add_option("--model", o->model, "driftlab-calibration/2 model JSON (or /1)")->required();
  cmd->add_option("--format", o->format,
                  "c-header (exact C99 evaluator), px4 (QGC .params, TC_G{i}/TC_A{i} per instance), ardupilot "
                  "(INS_TCAL{n}, 35 degC reference, 1e6 scaling), kalibr (imu.yaml noise terms of one instance), json")
      ->required()
      ->check(CLI::IsMember({"c-header", "px4", "ardupilot", "kalibr", "json"}));
  cmd->add_option("--out", o->out, "output file (written atomically)")->required();
  cmd->add_flag("--strict", o->e.strict,
                "refuse (exit 2) when PX4/ArduPilot cannot represent the model exactly, instead of exporting the best "
                "cubic with its stated error");
  cmd->add_option("--prefix", o->e.symbol_prefix, "C identifier prefix of the header")->capture_default_str();
  cmd->add_option("--instance", o->e.kalibr_instance, "Kalibr: the IMU instance of the imu.yaml (one per file)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--update-rate", o->e.kalibr_update_rate_hz, "Kalibr update_rate, Hz (default: the model's)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--allow-bounds", o->e.kalibr_allow_bounds,
                "Kalibr: write a noise term the calibration records did not resolve as its upper bound, marked as one "
                "in the file (otherwise refused, exit 2)");
  cmd->callback([o] { export_command(*o); });
}

}  // namespace driftlab::cli
