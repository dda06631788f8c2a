// `driftlab nav`: a simulated vehicle drive navigated by the MRPT-based EKF (tools/mrpt) on raw,
// compensated and perfect yaw rates; writes trajectories, errors over time, a rawlog, a plot and
// summary.json.
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "devices/device_file.hpp"
#include "devices/simulator.hpp"
#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/output_set.hpp"
#include "framework/units.hpp"
#include "tools/driftlab/cli.hpp"
#include "tools/driftlab/devices_dir.hpp"
#include "tools/driftlab/plot.hpp"
#include "tools/mrpt/nav_scenario.hpp"
#include "tools/mrpt/rawlog_io.hpp"
#include "tools/mrpt/nav_calibration.hpp"

namespace driftlab::cli {
namespace {

namespace fs = std::filesystem;
using mrpt_bridge::NavTrack;

struct NavOptions {
  std::string device, model, scenario, out, devices_dir;
  double every_s = 1.0;
  double bias_prior_dph = 100.0;
  std::string calibration_kind = "poly";
  bool fixes = false;
  bool no_rawlog = false;
};

double rms(const Eigen::VectorXd& v) { return std::sqrt(v.squaredNorm() / static_cast<double>(v.size())); }

// Every `step`-th sample (and the last).
std::vector<Eigen::Index> decimation(Eigen::Index n, Eigen::Index step) {
  std::vector<Eigen::Index> idx;
  for (Eigen::Index k = 0; k < n; k += step) idx.push_back(k);
  if (idx.back() != n - 1) idx.push_back(n - 1);
  return idx;
}

Eigen::VectorXd pick(const Eigen::VectorXd& v, const std::vector<Eigen::Index>& idx, double scale = 1.0) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(idx.size()));
  for (std::size_t i = 0; i < idx.size(); ++i) out[static_cast<Eigen::Index>(i)] = v[idx[i]] * scale;
  return out;
}

std::vector<double> as_std(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

void nav_command(const NavOptions& o, CommandEnv& env) {
  const auto device_path = resolve_device_file(o.device, o.devices_dir);
  const auto device = devices::load_device_file(device_path);
  const fs::path scenario_path = o.scenario.empty() ? mrpt_bridge::default_scenario_path() : fs::path(o.scenario);
  auto scenario = mrpt_bridge::load_nav_scenario(scenario_path);
  if (o.fixes && scenario.fix_period_s <= 0.0)
    throw ConfigError(Location{scenario_path.string(), 0, "fixes.period_s"},
                      "--fixes needs a scenario with position fixes (fixes.period_s > 0)");
  const fs::path out(o.out);
  make_output_directory(out, "--out");
  // Every output planned before the drive is simulated, committed together at the end.
  OutputSet outputs({device_path, scenario_path, o.model});
  for (const auto* name : {"summary.json", "trajectory.csv", "errors.csv", "nav.svg", "nav_info.json"})
    outputs.plan(out / name, name);
  if (!o.no_rawlog) outputs.plan(out / "drive.rawlog", "drive.rawlog");
  if (o.model.empty()) outputs.plan(out / "model.json", "model.json");

  std::cerr << "driftlab nav: device " << device.name << ", scenario " << scenario_path.string() << " ("
            << scenario.duration_s() << " s at " << scenario.sample_rate_hz << " Hz, seed " << scenario.seed << ")\n";
  env.progress("nav: simulate drive", 0.0);
  const auto drive = mrpt_bridge::simulate_drive(device, scenario);
  const Eigen::Index n = drive.gyro.time_s.size();

  // The compensated rate: the given model, or one calibrated on a simulated oven run.
  Eigen::VectorXd compensated;
  std::string model_source;
  calibration::CalibrationModel model;
  if (!o.model.empty()) {
    const auto imu_model = calibration::read_calibration(o.model);
    const auto* yaw = imu_model.find({imu::Sensor::Gyro, 'z', 0});
    if (!yaw) throw ConfigError({o.model, 0, "channels"}, "nav needs the model of the yaw gyro (gyro_z), which this model lacks");
    model = yaw->model;
    model_source = o.model;
  } else {
    mrpt_bridge::OvenCalibration oven;
    oven.kind = o.calibration_kind == "physical" ? calibration::ModelKind::Physical
                                                 : calibration::ModelKind::Polynomial;
    oven.seed = scenario.calibration_seed;
    oven.progress = [&env](const std::string& label, double f) { env.progress("nav: calibrate: " + label, f); };
    std::cerr << "driftlab nav: no --model given: calibrating a " << o.calibration_kind
              << " model on a simulated oven run of the same device (seed " << scenario.calibration_seed
              << "; the drive uses seed " << scenario.seed << ")\n";
    model = mrpt_bridge::calibrate_on_oven_run(device, oven);
    model.validate();
    outputs.write(out / "model.json", calibration::to_json_text(calibration::single_axis(model, 'z', device.name)));
    model_source = (out / "model.json").string() + " (" + o.calibration_kind + ", calibrated by nav on a " +
                   (model.fit.records.empty() ? std::string("simulated oven run") : model.fit.records.front()) + ")";
  }
  std::size_t extrapolated = 0;
  compensated = mrpt_bridge::compensate_drive(model, drive, &extrapolated);
  if (extrapolated > 0)
    std::cerr << "driftlab nav: warning: " << extrapolated
              << " drive samples had a temperature outside the model's calibrated range (extrapolated)\n";

  const auto noise = mrpt_bridge::nav_noise(device, scenario);
  const double bias_prior = o.bias_prior_dph * kRadPerDeg / 3600.0;
  struct Run {
    std::string name;
    const Eigen::VectorXd* rate;
    NavTrack track;
  };
  std::vector<Run> runs{{"raw", &drive.gyro.rate_rad_s, {}}};
  if (compensated.size() == n) runs.push_back({"compensated", &compensated, {}});
  runs.push_back({"perfect", &drive.gyro.true_rate_rad_s, {}});
  // The intrinsic floor (DESIGN.md §1): the true rate plus only the gyro's noise (measured minus
  // the simulator's systematic rate), i.e. what a perfect temperature model would leave.
  const Eigen::VectorXd floor_rate =
      drive.gyro.true_rate_rad_s + (drive.gyro.rate_rad_s - drive.gyro.systematic_rate_rad_s);
  runs.push_back({"noise_only", &floor_rate, {}});
  for (std::size_t r = 0; r < runs.size(); ++r) {
    const std::string label = "nav: EKF on " + runs[r].name + " rates";
    runs[r].track = mrpt_bridge::run_nav(drive, *runs[r].rate, noise, o.fixes, bias_prior,
                                         [&](double f) { env.progress(label, f); });
  }

  // summary.json: exactly the keys (degrees and metres; magnitudes).
  nlohmann::ordered_json summary, heading_final, position_final, heading_rms;
  for (const auto& run : runs) {
    if (run.name == "noise_only") continue;  // reported in nav_info.json and on stdout
    heading_final[run.name] = std::abs(run.track.heading_error_rad[n - 1]) * kDegPerRad;
    position_final[run.name] = run.track.position_error_m[n - 1];
    heading_rms[run.name] = rms(run.track.heading_error_rad) * kDegPerRad;
  }
  summary["heading_error_final_deg"] = heading_final;
  summary["position_error_final_m"] = position_final;
  summary["heading_error_rms_deg"] = heading_rms;
  outputs.write(out / "summary.json", summary.dump(2) + "\n");

  nlohmann::ordered_json info;
  info["device"] = device_path.string();
  info["scenario"] = scenario_path.string();
  info["duration_s"] = drive.gyro.time_s[n - 1];
  info["sample_rate_hz"] = scenario.sample_rate_hz;
  info["drive_seed"] = scenario.seed;
  info["model"] = model_source.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(model_source);
  info["position_fixes"] = o.fixes ? nlohmann::ordered_json(drive.fix_index.size()) : nlohmann::ordered_json(0);
  info["filter"] = "mrpt::bayes::CKalmanFilterCapable<4,2,0,3> EKF (kfEKFNaive): x, y, heading, gyro bias";
  info["process_noise"] = {{"arw_rad_sqrt_s", noise.arw_rad_sqrt_s},
                           {"bias_instability_rad_s", noise.bias_instability_rad_s},
                           {"rate_random_walk_rad_s_sqrt_s", noise.rate_random_walk_rad_s_sqrt_s},
                           {"bias_correlation_time_s", noise.bias_correlation_time_s},
                           {"odometry_speed_sigma_mps", noise.speed_sigma_mps},
                           {"fix_sigma_m", noise.fix_sigma_m}};
  info["bias_prior_sigma_dph"] = o.bias_prior_dph;
  for (const auto& run : runs)
    info["heading_error_max_abs_deg"][run.name] = run.track.heading_error_rad.cwiseAbs().maxCoeff() * kDegPerRad;
  const auto& floor_track = runs.back().track;
  info["noise_only"] = {
      {"what", "true rate + the gyro's noise only (measured - simulated systematic rate): the intrinsic floor"},
      {"heading_error_final_deg", std::abs(floor_track.heading_error_rad[n - 1]) * kDegPerRad},
      {"position_error_final_m", floor_track.position_error_m[n - 1]},
      {"heading_error_rms_deg", rms(floor_track.heading_error_rad) * kDegPerRad}};
  if (heading_final.contains("compensated") && heading_final["compensated"].get<double>() > 0)
    info["heading_error_final_raw_over_compensated"] =
        heading_final["raw"].get<double>() / heading_final["compensated"].get<double>();
  info["outputs"] = {{"summary.json", "final heading error (deg), final position error (m), heading error RMS (deg)"},
                     {"trajectory.csv", "t_s, truth and each run's x_m, y_m, heading_deg, every --every s"},
                     {"errors.csv", "t_s, temp_c, per run: heading error (deg, estimate - truth, accumulated: not wrapped), its EKF sigma (deg), position error (m), bias estimate (deg/h)"},
                     {"drive.rawlog", "the drive: CObservationIMU (raw IMU_WZ rad/s, IMU_TEMPERATURE degC) with odometry actions"},
                     {"nav.svg", "heading and position error over time"}};
  outputs.write(out / "nav_info.json", info.dump(2) + "\n");

  // trajectory.csv and errors.csv, decimated to --every seconds.
  const auto step = std::max<Eigen::Index>(1, static_cast<Eigen::Index>(std::llround(o.every_s * scenario.sample_rate_hz)));
  const auto idx = decimation(n, step);
  std::vector<CsvColumn> traj{{"t_s", pick(drive.gyro.time_s, idx), "s"},
                              {"true_x_m", pick(drive.x_m, idx), "1"},
                              {"true_y_m", pick(drive.y_m, idx), "1"},
                              {"true_heading_deg", pick(drive.heading_rad, idx, kDegPerRad), "1"}};
  std::vector<CsvColumn> errs{{"t_s", pick(drive.gyro.time_s, idx), "s"},
                              {"temp_c", pick(drive.gyro.temp_c, idx), "1"}};
  for (const auto& run : runs) {
    traj.push_back({run.name + "_x_m", pick(run.track.x_m, idx), "1"});
    traj.push_back({run.name + "_y_m", pick(run.track.y_m, idx), "1"});
    traj.push_back({run.name + "_heading_deg", pick(run.track.heading_rad, idx, kDegPerRad), "1"});
    errs.push_back({run.name + "_heading_error_deg", pick(run.track.heading_error_rad, idx, kDegPerRad), "1"});
    errs.push_back({run.name + "_heading_sigma_deg", pick(run.track.heading_sigma_rad, idx, kDegPerRad), "1"});
    errs.push_back({run.name + "_position_error_m", pick(run.track.position_error_m, idx), "1"});
    errs.push_back({run.name + "_bias_dph", pick(run.track.bias_rad_s, idx, kDegPerRad * 3600.0), "1"});
  }
  outputs.write_csv(out / "trajectory.csv", traj);
  outputs.write_csv(out / "errors.csv", errs);

  // The plot.
  Figure figure;
  PlotPanel heading{"Heading error, " + device.name + " on " + scenario_path.filename().string(), "time (min)",
                    "heading error (deg)"};
  PlotPanel position{"Position error", "time (min)", "position error (m)"};
  const auto minutes = as_std(pick(drive.gyro.time_s, idx, 1.0 / 60.0));
  for (const auto& run : runs) {
    heading.series.push_back({run.name, minutes, as_std(pick(run.track.heading_error_rad, idx, kDegPerRad))});
    position.series.push_back({run.name, minutes, as_std(pick(run.track.position_error_m, idx))});
  }
  figure.panels = {heading, position};
  try {
    outputs.write(out / "nav.svg", render_svg(figure));
  } catch (const PlotError& e) {  // the numbers stand without the figure
    outputs.drop(out / "nav.svg");
    std::cerr << "driftlab nav: warning: nav.svg not written: " << e.what() << "\n";
  }

  // The rawlog of the drive (raw rates), with odometry as action/observation pairs.
  if (!o.no_rawlog) {
    env.progress("nav: write drive.rawlog", 0.0);
    mrpt_bridge::ImuTable table;
    table.time_s = drive.gyro.time_s;
    table.sensor_label = "GYRO";
    Eigen::VectorXd dx = Eigen::VectorXd::Zero(n);
    for (Eigen::Index k = 1; k < n; ++k)
      dx[k] = 0.5 * (drive.odometry_speed_mps[k - 1] + drive.odometry_speed_mps[k]) *
              (drive.gyro.time_s[k] - drive.gyro.time_s[k - 1]);
    table.columns = {{"rate_rps", drive.gyro.rate_rad_s, "1"},
                     {"temp_c", drive.gyro.temp_c, "1"},
                     {"odom_dx_m", dx, "1"},
                     {"odom_dy_m", Eigen::VectorXd::Zero(n), "1"},
                     {"odom_dphi_rad", Eigen::VectorXd::Zero(n), "1"},
                     {"odom_speed_mps", drive.odometry_speed_mps, "1"}};
    mrpt_bridge::export_rawlog(table, outputs.stage_path(out / "drive.rawlog"));
  }
  outputs.commit();
  env.progress("nav", 1.0);

  std::cout << std::fixed << std::setprecision(3);
  std::cout << "driftlab nav: " << n << " samples, " << drive.gyro.time_s[n - 1] / 60.0 << " min, "
            << (o.fixes ? std::to_string(drive.fix_index.size()) + " position fixes" : std::string("no position fixes"))
            << (model_source.empty() ? "" : ", model " + model_source) << "\n";
  std::cout << "  run           heading final (deg)  heading RMS (deg)  position final (m)\n";
  for (const auto& run : runs)
    std::cout << "  " << std::left << std::setw(13) << run.name << std::right << std::setw(20)
              << std::abs(run.track.heading_error_rad[n - 1]) * kDegPerRad << std::setw(19)
              << rms(run.track.heading_error_rad) * kDegPerRad << std::setw(20) << run.track.position_error_m[n - 1]
              << "\n";
  if (info.contains("heading_error_final_raw_over_compensated"))
    std::cout << "  final heading error raw / compensated: " << std::setprecision(1)
              << info["heading_error_final_raw_over_compensated"].get<double>() << "x\n";
  std::cout << "  written to " << out.string() << ": summary.json, nav_info.json, trajectory.csv, errors.csv, nav.svg"
            << (o.no_rawlog ? "" : ", drive.rawlog") << (o.model.empty() && !model_source.empty() ? ", model.json" : "")
            << "\n";
}

}  // namespace

void add_nav_command(CLI::App& app, CommandEnv& env) {
  auto o = std::make_shared<NavOptions>();
  auto* cmd = app.add_subcommand(
      "nav", "simulate a vehicle drive and navigate it with an MRPT EKF on raw, compensated and perfect yaw rates");
  cmd->add_option("--device", o->device, "device file, or the name of one in the devices directory")->required();
  cmd->add_option("--model", o->model,
                  "calibration model JSON (driftlab calibrate); default: calibrate one on a simulated oven run of "
                  "the device (scenario calibration_seed) and write it to DIR/model.json")
      ->check(CLI::ExistingFile);
  cmd->add_option("--scenario", o->scenario,
                  "driftlab-nav-scenario/1 YAML (default: the bundled one-hour cold-start drive, cabin -10 -> +35 degC)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "output directory (created; files written atomically)")->required();
  cmd->add_flag("--fixes", o->fixes, "use the scenario's absolute position fixes as EKF observations");
  cmd->add_option("--every", o->every_s, "spacing of trajectory.csv / errors.csv rows, s")
      ->check(finite_number(0.0, 1e12, true))
      ->capture_default_str();
  cmd->add_option("--bias-prior", o->bias_prior_dph, "prior standard deviation of the gyro bias state, deg/h")
      ->check(finite_number(0.0, 1e12, true))
      ->capture_default_str();
  cmd->add_option("--calibration-kind", o->calibration_kind,
                  "model nav calibrates when given no --model: poly or physical (see driftlab calibrate)")
      ->check(CLI::IsMember({"poly", "physical"}))
      ->capture_default_str();
  cmd->add_flag("--no-rawlog", o->no_rawlog, "do not write DIR/drive.rawlog");
  cmd->add_option("--devices-dir", o->devices_dir, "directory of device files");
  cmd->callback([o, &env] { nav_command(*o, env); });
}

}  // namespace driftlab::cli
