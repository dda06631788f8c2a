// `driftlab mrpt import|export|compensate|info`: the MRPT rawlog bridge (tools/mrpt/rawlog_io.hpp).
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <vector>

#include "framework/error.hpp"
#include "framework/output_set.hpp"
#include "framework/units.hpp"
#include "models/calibration/calibration_model.hpp"
#include "tools/driftlab/cli.hpp"
#include "tools/mrpt/rawlog_io.hpp"

namespace driftlab::cli {
namespace {

struct MrptOptions {
  std::string input, out, model, sensor_label = "";
  std::string label = "GYRO";
  int instance = 0;
  double start_unix_s = mrpt_bridge::kDefaultStartUnixS;
};

// Each command plans its output before reading (framework/output_set.hpp: refused when it is an
// input or not a regular file; a hidden temporary file next to it) and commits it at the end.
void import_command(const MrptOptions& o, CommandEnv& env) {
  OutputSet outputs({o.input});
  outputs.plan(o.out, "--out");
  env.progress("mrpt import", 0.0);
  mrpt_bridge::RawlogStats stats;
  const auto table = mrpt_bridge::import_rawlog(o.input, o.sensor_label, &stats);
  mrpt_bridge::write_imu_csv(table, outputs, o.out);
  outputs.commit();
  env.progress("mrpt import", 1.0);
  std::cout << o.out << ": " << table.time_s.size() << " IMU samples of sensor '" << table.sensor_label << "' from "
            << o.input << " (" << stats.format << ", " << stats.objects << " objects, " << stats.odometry_actions
            << " odometry actions); columns t_s";
  for (const auto& c : table.columns) std::cout << "," << c.name;
  std::cout << std::setprecision(17) << "; t_s = 0 at Unix time " << table.start_unix_s << " s\n";
}

void export_command(const MrptOptions& o, CommandEnv& env) {
  OutputSet outputs({o.input});
  outputs.plan(o.out, "--out");
  env.progress("mrpt export", 0.0);
  auto table = mrpt_bridge::read_imu_csv(o.input);
  table.sensor_label = o.label;
  table.start_unix_s = o.start_unix_s;
  mrpt_bridge::export_rawlog(table, outputs, o.out);
  outputs.commit();
  env.progress("mrpt export", 1.0);
  std::cout << o.out << ": " << table.time_s.size() << " CObservationIMU '" << table.sensor_label << "' ("
            << (table.has_odometry() ? "action/observation pairs with CActionRobotMovement2D odometry"
                                     : "observations only")
            << ")\n";
  if (!table.ignored_columns.empty()) {
    std::cout << "  not exported (no CObservationIMU field):";
    for (const auto& c : table.ignored_columns) std::cout << " " << c;
    std::cout << "\n";
  }
}

// The largest correction of a field in the unit people read it in: deg/h for a rate, mg for an
// acceleration.
std::string correction_text(imu::Sensor sensor, double si) {
  std::ostringstream text;
  text << std::fixed << std::setprecision(3);
  if (sensor == imu::Sensor::Accel)
    text << difference_from_internal(si, *find_unit("mg")) << " mg";
  else
    text << si * kDphPerRadPerSec << " deg/h";
  return text.str();
}

// Every channel of the model's instance `o.instance` corrects its CObservationIMU field, each with
// its own causal compensator, on IMU_TEMPERATURE.
void compensate_command(const MrptOptions& o, CommandEnv& env) {
  OutputSet outputs({o.input, o.model});
  outputs.plan(o.out, "--out");
  const auto imu_model = calibration::read_calibration(o.model);
  std::vector<const calibration::ChannelCalibration*> applied;
  std::vector<std::string> other_instances;
  for (const auto& channel : imu_model.channels) {
    if (channel.id.instance == o.instance)
      applied.push_back(&channel);
    else
      other_instances.push_back(channel.id.role());
  }
  if (applied.empty()) {
    std::string roles;
    for (const auto& r : other_instances) roles += (roles.empty() ? "" : ", ") + r;
    throw ConfigError({o.model, 0, "channels"}, "the model has no channel of instance " + std::to_string(o.instance) +
                                                    " (--instance); its channels: " + roles);
  }
  std::vector<calibration::CausalCompensator> compensators;
  for (const auto* channel : applied) compensators.emplace_back(channel->model);
  std::vector<calibration::OutsideCount> outside(applied.size());
  std::vector<mrpt_bridge::FieldCorrection> corrections;
  for (std::size_t i = 0; i < applied.size(); ++i)
    corrections.push_back({mrpt_bridge::imu_field(applied[i]->id.sensor, applied[i]->id.axis),
                           applied[i]->id.role() + " of " + o.model,
                           [&compensators, &outside, i](double t, double value, double temp) {
                             const double out = compensators[i].step(t, value, temp);
                             outside[i].add(compensators[i].last_outside());
                             return out;
                           }});
  env.progress("mrpt compensate", 0.0);
  const auto stats = mrpt_bridge::compensate_rawlog(o.input, outputs, o.out, corrections, o.sensor_label);
  outputs.commit();
  env.progress("mrpt compensate", 1.0);
  std::cout << o.out << ": " << stats.compensated << " of " << stats.imu_observations << " IMU observations ('"
            << stats.sensor_label << "') compensated with instance " << o.instance << " of " << o.model << "; "
            << stats.objects << " objects copied in order\n";
  std::cout << "  corrected (largest correction):";
  for (std::size_t i = 0; i < stats.fields.size(); ++i)
    std::cout << (i ? "," : "") << " " << mrpt_bridge::imu_field_name(stats.fields[i].field) << " by "
              << applied[i]->id.role() << " "
              << correction_text(applied[i]->id.sensor, stats.fields[i].max_abs_correction);
  std::cout << "\n";
  if (!stats.passed_through.empty()) {
    std::cout << "  unchanged (not in the model):";
    for (const int field : stats.passed_through) std::cout << " " << mrpt_bridge::imu_field_name(field);
    std::cout << "\n";
  }
  if (!other_instances.empty()) {
    std::cout << "  model channels of other instances, not applied (--instance):";
    for (const auto& r : other_instances) std::cout << " " << r;
    std::cout << "\n";
  }
  for (std::size_t i = 0; i < applied.size(); ++i)
    if (outside[i].samples > 0)
      std::cerr << "driftlab: warning: " << applied[i]->id.role() << ": " << outside[i].text("observations") << "\n";
}

void info_command(const MrptOptions& o) {
  const auto stats = mrpt_bridge::rawlog_stats(o.input);
  std::cout << o.input << ": " << stats.format << ", " << stats.objects << " objects, " << stats.sensory_frames
            << " sensory frames, " << stats.odometry_actions << " odometry actions, " << stats.imu_observations
            << " IMU observations; IMU labels:";
  for (const auto& l : stats.imu_labels) std::cout << " '" << l << "'";
  std::cout << "\n";
}

}  // namespace

void add_mrpt_command(CLI::App& app, CommandEnv& env) {
  auto o = std::make_shared<MrptOptions>();
  auto* mrpt = app.add_subcommand("mrpt", "MRPT rawlog bridge: import, export, compensate, info");
  mrpt->require_subcommand(1);

  auto* imp = mrpt->add_subcommand("import",
                                   "IMU observations of a rawlog (either format) -> CSV (t_s, rate_rps, temp_c, ...)");
  imp->add_option("rawlog", o->input, "input rawlog (actions/sensory-frame or observations-only; gzip'ed or plain)")
      ->required()
      ->check(CLI::ExistingFile);
  imp->add_option("--out", o->out, "output CSV (written atomically); t_s is s since the first IMU observation")
      ->required();
  imp->add_option("--sensor-label", o->sensor_label, "IMU sensor label to import (needed when there are several)");
  imp->callback([o, &env] { import_command(*o, env); });

  auto* exp = mrpt->add_subcommand("export", "CSV -> rawlog of CObservationIMU (IMU_WZ rad/s, IMU_TEMPERATURE degC)");
  exp->add_option("csv", o->input,
                  "input CSV: t_s, rate_rps or rate_dps, temp_c, other IMU columns; odom_dx_m, odom_dy_m, "
                  "odom_dphi_rad [, odom_speed_mps] give action/observation pairs")
      ->required()
      ->check(CLI::ExistingFile);
  exp->add_option("--out", o->out, "output rawlog (gzip'ed, written atomically)")->required();
  exp->add_option("--label", o->label, "sensor label of the observations")->capture_default_str();
  exp->add_option("--start-unix", o->start_unix_s, "Unix time of t_s = 0, s (default 2026-01-01T00:00:00Z)")
      ->capture_default_str();
  exp->callback([o, &env] { export_command(*o, env); });

  auto* comp = mrpt->add_subcommand(
      "compensate",
      "apply a calibration model (driftlab calibrate) to the rates and accelerations of every IMU observation of one "
      "sensor label: IMU_WX/WY/WZ by gyro_x/y/z, IMU_X/Y/Z_ACC by accel_x/y/z, on IMU_TEMPERATURE; all else is kept");
  comp->add_option("rawlog", o->input, "input rawlog")->required()->check(CLI::ExistingFile);
  comp->add_option("--model", o->model, "calibration model JSON (driftlab-calibration/2, or /1: gyro_z only)")
      ->required()
      ->check(CLI::ExistingFile);
  comp->add_option("--out", o->out, "output rawlog (gzip'ed, written atomically; never the input)")->required();
  comp->add_option("--sensor-label", o->sensor_label, "IMU sensor label to compensate (needed when there are several)");
  comp->add_option("--instance", o->instance,
                   "model instance applied to that label's observations (one label is one IMU; gyro1_x is instance 1)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  comp->callback([o, &env] { compensate_command(*o, env); });

  auto* info = mrpt->add_subcommand("info", "counts of a rawlog: format, objects, IMU observations and labels");
  info->add_option("rawlog", o->input, "input rawlog")->required()->check(CLI::ExistingFile);
  info->callback([o] { info_command(*o); });
}

}  // namespace driftlab::cli
