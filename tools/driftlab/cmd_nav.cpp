// `driftlab nav`: the MRPT-based EKF (tools/mrpt) navigating on raw and compensated yaw rates,
// either a simulated vehicle drive (the default; plus perfect and noise-only rates, against the
// truth) or the user's own record with odometry (--rawlog / --data, against the odometry pose);
// writes trajectories, errors over time, a plot and summary.json.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <optional>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "devices/device_file.hpp"
#include "devices/simulator.hpp"
#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/output_set.hpp"
#include "framework/regular_file.hpp"
#include "framework/resources.hpp"
#include "framework/units.hpp"
#include "models/evaluation/evaluation.hpp"
#include "tools/driftlab/cli.hpp"
#include "tools/driftlab/data_dirs.hpp"
#include "tools/driftlab/plot.hpp"
#include "tools/mrpt/nav_calibration.hpp"
#include "tools/mrpt/nav_record.hpp"
#include "tools/mrpt/nav_scenario.hpp"
#include "tools/mrpt/rawlog_io.hpp"

namespace driftlab::cli {
namespace {

namespace fs = std::filesystem;
using mrpt_bridge::NavInput;
using mrpt_bridge::NavTrack;

struct NavOptions {
  std::string device, model, scenario, out, devices_dir;
  std::string rawlog, data, sensor_label;
  int instance = 0;
  double every_s = 1.0;
  double bias_prior_dph = 100.0;
  std::string calibration_kind = "poly";
  bool fixes = false;
  bool no_rawlog = false;
};

struct Run {
  std::string name;
  Eigen::VectorXd rate_rad_s;
  NavTrack track;
};

// What the report shows, the same for the simulated drive and a user's record.
struct NavReport {
  NavInput input;
  Eigen::VectorXd temp_c;
  std::string reference;  // prefix of the reference columns: "true" or "odometry"
  std::string title;      // of the plot
  std::vector<Run> runs;  // a run named "noise_only" is left out of summary.json
};

double rms(const Eigen::VectorXd& v) { return std::sqrt(v.squaredNorm() / static_cast<double>(v.size())); }

// A run's error figures, as summary.json, nav_info.json and the terminal give them: the heading
// error's RMS, worst and final magnitude (deg) and the final position error (m).
struct RunErrors {
  double heading_rms_deg, heading_worst_deg, heading_final_deg, position_final_m;
};
RunErrors run_errors(const NavTrack& t) {
  const Eigen::VectorXd& h = t.heading_error_rad;
  return {rms(h) * kDegPerRad, h.cwiseAbs().maxCoeff() * kDegPerRad, std::abs(h[h.size() - 1]) * kDegPerRad,
          t.position_error_m[t.position_error_m.size() - 1]};
}

// The first sample, the first sample of every later `every_s` interval, and the last.
std::vector<Eigen::Index> decimation(const Eigen::VectorXd& t, double every_s) {
  constexpr double kSlack = 1e-9;  // of an interval: t = k / fs may land a rounding error short
  std::vector<Eigen::Index> idx{0};
  double taken = 0.0;
  for (Eigen::Index k = 1; k < t.size(); ++k) {
    const double bucket = std::floor((t[k] - t[0]) / every_s + kSlack);
    if (bucket > taken) {
      idx.push_back(k);
      taken = bucket;
    }
  }
  if (idx.back() != t.size() - 1) idx.push_back(t.size() - 1);
  return idx;
}

Eigen::VectorXd pick(const Eigen::VectorXd& v, const std::vector<Eigen::Index>& idx, double scale = 1.0) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(idx.size()));
  for (std::size_t i = 0; i < idx.size(); ++i) out[static_cast<Eigen::Index>(i)] = v[idx[i]] * scale;
  return out;
}

std::vector<double> as_std(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

double bias_prior_rad_s(const NavOptions& o) { return o.bias_prior_dph * kRadPerSecPerDph; }

void run_filters(NavReport& report, const mrpt_bridge::NavNoise& noise, const NavOptions& o, CommandEnv& env) {
  for (auto& run : report.runs) {
    const std::string label = "nav: EKF on " + run.name + " rates";
    run.track = mrpt_bridge::run_nav(report.input, run.rate_rad_s, noise, o.fixes, bias_prior_rad_s(o),
                                     [&](double f) { env.progress(label, f); });
  }
}

nlohmann::ordered_json process_noise_json(const mrpt_bridge::NavNoise& noise) {
  return {{"arw_rad_sqrt_s", noise.arw_rad_sqrt_s},
          {"bias_instability_rad_s", noise.bias_instability_rad_s},
          {"rate_random_walk_rad_s_sqrt_s", noise.rate_random_walk_rad_s_sqrt_s},
          {"bias_correlation_time_s", noise.bias_correlation_time_s},
          {"odometry_speed_sigma_mps", noise.speed_sigma_mps},
          {"fix_sigma_m", noise.fix_sigma_m}};
}

// summary.json, nav_info.json (`info` plus the errors), trajectory.csv, errors.csv and nav.svg.
void write_report(const NavReport& report, nlohmann::ordered_json info, OutputSet& outputs, const fs::path& out,
                  double every_s) {
  // summary.json (degrees and metres; magnitudes): the heading error's RMS and worst moment first (a
  // final value can be a lucky zero crossing), then the final values.
  nlohmann::ordered_json summary, heading_rms, heading_worst, heading_final, position_final;
  for (const auto& run : report.runs) {
    if (run.name == "noise_only") continue;  // reported in nav_info.json and on stdout
    const RunErrors e = run_errors(run.track);
    heading_rms[run.name] = e.heading_rms_deg;
    heading_worst[run.name] = e.heading_worst_deg;
    heading_final[run.name] = e.heading_final_deg;
    position_final[run.name] = e.position_final_m;
  }
  summary["heading_error_rms_deg"] = heading_rms;
  summary["heading_error_worst_deg"] = heading_worst;
  summary["heading_error_final_deg"] = heading_final;
  summary["position_error_final_m"] = position_final;
  outputs.write(out / "summary.json", summary.dump(2) + "\n");

  if (heading_rms.contains("raw") && heading_rms.contains("compensated") && heading_rms["compensated"] > 0) {
    info["heading_error_rms_raw_over_compensated"] =
        heading_rms["raw"].get<double>() / heading_rms["compensated"].get<double>();
    info["heading_error_worst_raw_over_compensated"] =
        heading_worst["raw"].get<double>() / heading_worst["compensated"].get<double>();
  }
  const std::string ref = report.reference;
  info["outputs"]["summary.json"] =
      "heading error RMS and worst (deg), final heading error (deg), final position error (m), per run";
  info["outputs"]["trajectory.csv"] = "t_s, " + ref + "_x_m, " + ref + "_y_m, " + ref +
                                      "_heading_deg and each run's x_m, y_m, heading_deg, every --every s";
  info["outputs"]["errors.csv"] =
      "t_s, temp_c, per run: heading error (deg, estimate - " + ref +
      ", accumulated: not wrapped), its EKF sigma (deg), position error (m), bias estimate (deg/h)";
  info["outputs"]["nav.svg"] = "heading and position error over time";
  outputs.write(out / "nav_info.json", info.dump(2) + "\n");

  const auto idx = decimation(report.input.time_s, every_s);
  const auto& in = report.input;
  std::vector<CsvColumn> traj{{"t_s", pick(in.time_s, idx), "s"},
                              {ref + "_x_m", pick(in.x_m, idx), "1"},
                              {ref + "_y_m", pick(in.y_m, idx), "1"},
                              {ref + "_heading_deg", pick(in.heading_rad, idx, kDegPerRad), "1"}};
  std::vector<CsvColumn> errs{{"t_s", pick(in.time_s, idx), "s"}, {"temp_c", pick(report.temp_c, idx), "1"}};
  for (const auto& run : report.runs) {
    traj.push_back({run.name + "_x_m", pick(run.track.x_m, idx), "1"});
    traj.push_back({run.name + "_y_m", pick(run.track.y_m, idx), "1"});
    traj.push_back({run.name + "_heading_deg", pick(run.track.heading_rad, idx, kDegPerRad), "1"});
    errs.push_back({run.name + "_heading_error_deg", pick(run.track.heading_error_rad, idx, kDegPerRad), "1"});
    errs.push_back({run.name + "_heading_sigma_deg", pick(run.track.heading_sigma_rad, idx, kDegPerRad), "1"});
    errs.push_back({run.name + "_position_error_m", pick(run.track.position_error_m, idx), "1"});
    errs.push_back({run.name + "_bias_dph", pick(run.track.bias_rad_s, idx, kDphPerRadPerSec), "1"});
  }
  outputs.write_csv(out / "trajectory.csv", traj);
  outputs.write_csv(out / "errors.csv", errs);

  // Log scales: the raw run's error is orders of magnitude above the others. Each run's EKF 1-sigma
  // heading bound is dashed in the run's colour: an error above its bound is one the filter did not expect.
  Figure figure;
  PlotPanel heading{report.title + " (dashed: each run's EKF 1σ)", "time (min)", "|heading error| (deg), log scale"};
  PlotPanel position{"Position error", "time (min)", "position error (m), log scale"};
  heading.log_y = position.log_y = true;
  const auto minutes = as_std(pick(in.time_s, idx, 1.0 / 60.0));
  for (std::size_t k = 0; k < report.runs.size(); ++k) {
    const auto& run = report.runs[k];
    const std::string name = readable_name(run.name);
    PlotSeries error{name, minutes, as_std(pick(run.track.heading_error_rad, idx, kDegPerRad).cwiseAbs())};
    // One legend entry for the bounds (the title says they are dashed): both panels' legends then
    // have the same width and their plots line up.
    PlotSeries sigma{k == 0 ? "EKF 1σ" : "", minutes, as_std(pick(run.track.heading_sigma_rad, idx, kDegPerRad))};
    PlotSeries metres{name, minutes, as_std(pick(run.track.position_error_m, idx))};
    error.color = sigma.color = metres.color = palette_color(k);
    sigma.style = PlotSeries::Style::Dashed;
    heading.series.insert(heading.series.end(), {error, sigma});
    position.series.push_back(metres);
  }
  figure.panels = {heading, position};
  figure.shared_x = true;
  try {
    outputs.write(out / "nav.svg", render_svg(figure));
  } catch (const PlotError& e) {  // the numbers stand without the figure
    outputs.drop(out / "nav.svg");
    std::cerr << "driftlab nav: warning: nav.svg not written: " << e.what() << "\n";
  }
}

// The table of errors on stdout: the heading error's RMS and worst moment first, then the final values.
void print_runs(const NavReport& report) {
  std::cout << "  run           heading RMS (deg)  heading worst (deg)  heading final (deg)  position final (m)\n";
  for (const auto& run : report.runs) {
    const RunErrors e = run_errors(run.track);
    std::cout << "  " << std::left << std::setw(13) << run.name << std::right << std::setw(18) << e.heading_rms_deg
              << std::setw(21) << e.heading_worst_deg << std::setw(21) << e.heading_final_deg << std::setw(20)
              << e.position_final_m << "\n";
  }
  const RunErrors raw = run_errors(report.runs.front().track), comp = run_errors(report.runs[1].track);
  if (comp.heading_rms_deg > 0)
    std::cout << "  heading error raw / compensated: " << std::setprecision(1)
              << raw.heading_rms_deg / comp.heading_rms_deg << "x on RMS, "
              << raw.heading_worst_deg / comp.heading_worst_deg << "x on the worst moment\n";
}

// The cost of a simulated drive per sample: the drive, the tracks and the output text held at once
// (a coarse upper bound), and the run time of `driftlab nav --device fmvmg` on the bundled scenario
// divided by its samples, rounded up: 8.4 s for 180 001 samples (4.7e-5 s each, the oven calibration
// included) on the development machine (2 shared cores).
constexpr double kNavBytesPerSample = 600.0;
constexpr double kNavSecondsPerSample = 5e-5;

// Refuses a scenario whose drive would not fit in memory or time, before it is simulated (a 1e6-Hz
// scenario or a 1e7-s segment must not end in bad_alloc hours later).
void check_drive_cost(const mrpt_bridge::NavScenario& scenario, const fs::path& scenario_path) {
  const double samples = std::floor(scenario.duration_s() * scenario.sample_rate_hz) + 1.0;
  char what[160];
  std::snprintf(what, sizeof what, "%.3g samples (scenario sample_rate_hz x duration %.3g s) at %.0f bytes each",
                samples, scenario.duration_s(), kNavBytesPerSample);
  const Location where{input_name(scenario_path), 0, "sample_rate_hz, duration"};
  check_memory_estimate(samples * kNavBytesPerSample, where, what);
  std::snprintf(what, sizeof what, "%.3g samples (scenario sample_rate_hz x duration %.3g s) at %.2g s each", samples,
                scenario.duration_s(), kNavSecondsPerSample);
  check_time_estimate(samples * kNavSecondsPerSample, where, what);
}

// The yaw gyro's temperature model and where it came from.
struct YawModel {
  calibration::CalibrationModel model;
  std::string source;
};

// The given model's yaw gyro, or one calibrated on a simulated oven run of the device (written to
// model.json).
YawModel yaw_model(const NavOptions& o, const devices::DeviceDefinition& device,
                   const mrpt_bridge::NavScenario& scenario, OutputSet& outputs, const fs::path& out, CommandEnv& env) {
  YawModel yaw;
  if (!o.model.empty()) {
    const auto imu_model = calibration::read_calibration(o.model);
    const auto* channel = imu_model.find({imu::Sensor::Gyro, 'z', o.instance});
    if (!channel)
      throw ConfigError({o.model, 0, "channels"}, "nav needs the model of the yaw gyro (" +
                                                      imu::ChannelId{imu::Sensor::Gyro, 'z', o.instance}.role() +
                                                      "), which this model lacks");
    yaw.model = channel->model;
    yaw.source = o.model;
    return yaw;
  }
  mrpt_bridge::OvenCalibration oven;
  oven.kind = o.calibration_kind == "physical" ? calibration::ModelKind::Physical : calibration::ModelKind::Polynomial;
  oven.seed = scenario.calibration_seed;
  oven.progress = [&env](const std::string& label, double f) { env.progress("nav: calibrate: " + label, f); };
  std::cerr << "driftlab nav: no --model given: calibrating a " << o.calibration_kind
            << " model on a simulated oven run of the same device (seed " << scenario.calibration_seed
            << "; the drive uses seed " << scenario.seed << ")\n";
  yaw.model = mrpt_bridge::calibrate_on_oven_run(device, oven);
  yaw.model.validate();
  outputs.write(out / "model.json", calibration::to_json_text(calibration::single_axis(yaw.model, 'z', device.name)));
  yaw.source = (out / "model.json").string() + " (" + o.calibration_kind + ", calibrated by nav on a " +
               (yaw.model.fit.records.empty() ? std::string("simulated oven run") : yaw.model.fit.records.front()) +
               ")";
  return yaw;
}

// nav_info.json's facts of a simulated drive (write_report adds the errors).
nlohmann::ordered_json simulated_info(const NavOptions& o, const fs::path& device_path, const fs::path& scenario_path,
                                      const mrpt_bridge::NavScenario& scenario, const mrpt_bridge::DriveRecord& drive,
                                      const std::string& model_source, const mrpt_bridge::NavNoise& noise,
                                      const NavReport& report) {
  const Eigen::Index n = drive.gyro.time_s.size();
  nlohmann::ordered_json info;
  info["device"] = device_path.string();
  info["scenario"] = scenario_path.string();
  info["reference"] = "the simulated truth";
  info["duration_s"] = drive.gyro.time_s[n - 1];
  info["sample_rate_hz"] = scenario.sample_rate_hz;
  info["drive_seed"] = scenario.seed;
  info["model"] = model_source;
  info["position_fixes"] = o.fixes ? nlohmann::ordered_json(drive.fix_index.size()) : nlohmann::ordered_json(0);
  info["filter"] = "mrpt::bayes::CKalmanFilterCapable<4,2,0,3> EKF (kfEKFNaive): x, y, heading, gyro bias";
  info["process_noise"] = process_noise_json(noise);
  info["bias_prior_sigma_dph"] = o.bias_prior_dph;
  const RunErrors floor = run_errors(report.runs.back().track);
  info["noise_only"] = {
      {"what", "true rate + the gyro's noise only (measured - simulated systematic rate): the intrinsic floor"},
      {"heading_error_rms_deg", floor.heading_rms_deg},
      {"heading_error_worst_deg", floor.heading_worst_deg},
      {"heading_error_final_deg", floor.heading_final_deg},
      {"position_error_final_m", floor.position_final_m}};
  if (!o.no_rawlog)
    info["outputs"]["drive.rawlog"] =
        "the drive for `nav --rawlog`: CObservationIMU (raw IMU_WZ rad/s, IMU_TEMPERATURE degC) with "
        "CActionRobotMovement2D odometry whose pose increments are the true motion (the reference) and whose "
        "velocity is the noisy odometry speed the EKF uses";
  return info;
}

// The rawlog of the drive (raw rates): odometry increments in the robot frame of the previous
// true pose, so that composing them gives the true track back.
void write_drive_rawlog(const mrpt_bridge::DriveRecord& drive, OutputSet& outputs, const fs::path& path,
                        CommandEnv& env) {
  env.progress("nav: write drive.rawlog", 0.0);
  const Eigen::Index n = drive.gyro.time_s.size();
  mrpt_bridge::ImuTable table;
  table.time_s = drive.gyro.time_s;
  table.sensor_label = "GYRO";
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(n), dy = Eigen::VectorXd::Zero(n), dphi = Eigen::VectorXd::Zero(n);
  for (Eigen::Index k = 1; k < n; ++k) {
    const double ex = drive.x_m[k] - drive.x_m[k - 1], ey = drive.y_m[k] - drive.y_m[k - 1];
    const double c = std::cos(drive.heading_rad[k - 1]), s = std::sin(drive.heading_rad[k - 1]);
    dx[k] = c * ex + s * ey;
    dy[k] = -s * ex + c * ey;
    dphi[k] = mrpt_bridge::wrap_angle(drive.heading_rad[k] - drive.heading_rad[k - 1]);
  }
  table.columns = {{"rate_rps", drive.gyro.rate_rad_s, "1"},
                   {"temp_c", drive.gyro.temp_c, "1"},
                   {"odom_dx_m", dx, "1"},
                   {"odom_dy_m", dy, "1"},
                   {"odom_dphi_rad", dphi, "1"},
                   {"odom_speed_mps", drive.odometry_speed_mps, "1"}};
  mrpt_bridge::export_rawlog(table, outputs, path);
}

// The simulated drive of a device in a scenario, against the truth.
void simulated_nav(const NavOptions& o, CommandEnv& env) {
  if (o.device.empty())
    throw ConfigError(Location{"", 0, "--device"},
                      "the simulated drive needs --device (or navigate a record with --rawlog / --data)");
  const auto device_path = resolve_device_file(o.device, o.devices_dir);
  const auto device = devices::load_device_file(device_path);
  const fs::path scenario_path = o.scenario.empty() ? mrpt_bridge::default_scenario_path() : fs::path(o.scenario);
  auto scenario = mrpt_bridge::load_nav_scenario(scenario_path);
  if (o.fixes && scenario.fix_period_s <= 0.0)
    throw ConfigError(Location{scenario_path.string(), 0, "fixes.period_s"},
                      "--fixes needs a scenario with position fixes (fixes.period_s > 0)");
  check_drive_cost(scenario, scenario_path);
  const fs::path out(o.out);
  // Every output planned before the drive is simulated, committed together at the end.
  OutputSet outputs({device_path, scenario_path, o.model});
  outputs.make_directory(out, "--out");
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
  const auto yaw = yaw_model(o, device, scenario, outputs, out, env);
  calibration::OutsideCount outside;
  const Eigen::VectorXd compensated = mrpt_bridge::compensate_drive(yaw.model, drive, &outside);
  if (outside.samples > 0) std::cerr << "driftlab nav: warning: " << outside.text("drive samples") << "\n";

  NavReport report;
  report.input = mrpt_bridge::nav_input(drive);
  report.temp_c = drive.gyro.temp_c;
  report.reference = "true";
  report.title = "Heading error, " + device.name + " on " + scenario_path.filename().string();
  // The intrinsic floor (DESIGN.md §1): the true rate plus only the gyro's noise (measured minus
  // the simulator's systematic rate), i.e. what a perfect temperature model would leave.
  report.runs = {{"raw", drive.gyro.rate_rad_s, {}},
                 {"compensated", compensated, {}},
                 {"perfect", drive.gyro.true_rate_rad_s, {}},
                 {"noise_only",
                  drive.gyro.true_rate_rad_s +
                      evaluation::intrinsic_noise(drive.gyro.rate_rad_s, drive.gyro.systematic_rate_rad_s),
                  {}}};
  const auto noise = mrpt_bridge::nav_noise(device, scenario);
  run_filters(report, noise, o, env);

  write_report(report, simulated_info(o, device_path, scenario_path, scenario, drive, yaw.source, noise, report),
               outputs, out, o.every_s);
  if (!o.no_rawlog) write_drive_rawlog(drive, outputs, out / "drive.rawlog", env);
  outputs.commit();
  env.progress("nav", 1.0);

  std::cout << std::fixed << std::setprecision(3);
  std::cout << "driftlab nav: " << n << " samples, " << drive.gyro.time_s[n - 1] / 60.0 << " min, "
            << (o.fixes ? std::to_string(drive.fix_index.size()) + " position fixes" : std::string("no position fixes"))
            << ", model " << yaw.source << "; errors against the simulated truth\n";
  print_runs(report);
  std::cout << "  written to " << out.string() << ": summary.json, nav_info.json, trajectory.csv, errors.csv, nav.svg"
            << (o.no_rawlog ? "" : ", drive.rawlog") << (o.model.empty() ? ", model.json" : "") << "\n";
}

// The user's record (--rawlog or --data) with odometry, against the odometry pose.
void record_nav(const NavOptions& o, CommandEnv& env) {
  const std::string source = o.rawlog.empty() ? o.data : o.rawlog;
  if (o.model.empty())
    throw ConfigError(Location{"", 0, "--model"},
                      "nav on a record needs --model (the comparison is the raw against the compensated yaw rate)");
  const auto imu_model = calibration::read_calibration(o.model);
  const imu::ChannelId yaw_id{imu::Sensor::Gyro, 'z', o.instance};
  const auto* yaw = imu_model.find(yaw_id);
  if (!yaw)
    throw ConfigError({o.model, 0, "channels"},
                      "nav needs the model of the yaw gyro (" + yaw_id.role() + "), which this model lacks");
  const fs::path out(o.out);
  OutputSet outputs({source, o.model});
  outputs.make_directory(out, "--out");
  for (const auto* name : {"summary.json", "trajectory.csv", "errors.csv", "nav.svg", "nav_info.json"})
    outputs.plan(out / name, name);

  env.progress("nav: read record", 0.0);
  mrpt_bridge::RawlogStats stats;
  const auto table = o.rawlog.empty() ? mrpt_bridge::read_imu_csv(o.data)
                                      : mrpt_bridge::import_rawlog(o.rawlog, o.sensor_label, &stats);
  if (!table.has("temp_c"))
    throw DataError(Location{source, 0, "temp_c"},
                    "the record has no temperature (temp_c; in a rawlog IMU_TEMPERATURE), which the model needs");
  auto record = mrpt_bridge::record_nav_input(table, source);
  const Eigen::Index n = table.time_s.size();
  const auto compensated =
      calibration::compensate(yaw->model, table.time_s, table.values("rate_rps"), table.values("temp_c"));
  calibration::OutsideCount outside;
  for (const unsigned char flags : compensated.outside) outside.add(flags);
  if (outside.samples > 0) std::cerr << "driftlab nav: warning: " << outside.text("samples") << "\n";

  NavReport report;
  report.input = std::move(record.input);
  report.temp_c = table.values("temp_c");
  report.reference = "odometry";
  report.title = "Heading error against odometry, " + fs::path(source).filename().string();
  report.runs = {{"raw", table.values("rate_rps"), {}}, {"compensated", compensated.rate_rad_s, {}}};
  // Process noise: the yaw channel's Allan terms (0 where the model has none). Without fixes the
  // EKF dead-reckons: the noise changes only the reported sigmas, not the track.
  mrpt_bridge::NavNoise noise;
  noise.arw_rad_sqrt_s = yaw->model.noise.arw_rad_sqrt_s;
  noise.bias_instability_rad_s = yaw->model.noise.bias_instability_rad_s;
  noise.rate_random_walk_rad_s_sqrt_s = yaw->model.noise.rate_random_walk_rad_s_sqrt_s;
  run_filters(report, noise, o, env);

  nlohmann::ordered_json info;
  info["record"] = source;
  if (!o.rawlog.empty()) {
    info["sensor_label"] = table.sensor_label;
    info["rawlog_format"] = stats.format;
  }
  info["reference"] =
      "the odometry pose, composed from the record's increments (odom_dx_m, odom_dy_m, odom_dphi_rad) from (0, 0, 0) "
      "at the first IMU sample: wheel odometry, not ground truth";
  info["odometry_speed"] = record.speed_source;
  info["samples"] = n;
  info["duration_s"] = table.time_s[n - 1];
  info["model"] = o.model;
  info["model_channel"] = yaw_id.role();
  info["extrapolated_samples"] = outside.samples;
  info["position_fixes"] = 0;
  info["filter"] = "mrpt::bayes::CKalmanFilterCapable<4,2,0,3> EKF (kfEKFNaive): x, y, heading, gyro bias";
  info["process_noise"] = process_noise_json(noise);
  info["bias_prior_sigma_dph"] = o.bias_prior_dph;
  write_report(report, info, outputs, out, o.every_s);
  outputs.commit();
  env.progress("nav", 1.0);

  std::cout << std::fixed << std::setprecision(3);
  std::cout << "driftlab nav: " << n << " samples, " << table.time_s[n - 1] / 60.0 << " min of " << source
            << (o.rawlog.empty() ? "" : " (sensor '" + table.sensor_label + "')") << ", model " << o.model << " ("
            << yaw_id.role() << "); errors against the odometry pose, speed from " << record.speed_source << "\n";
  print_runs(report);
  std::cout << "  written to " << out.string()
            << ": summary.json, nav_info.json, trajectory.csv, errors.csv, nav.svg\n";
}

void nav_command(const NavOptions& o, CommandEnv& env) {
  if (o.rawlog.empty() && o.data.empty())
    simulated_nav(o, env);
  else
    record_nav(o, env);
}

}  // namespace

void add_nav_command(CLI::App& app, CommandEnv& env) {
  auto o = std::make_shared<NavOptions>();
  auto* cmd = app.add_subcommand(
      "nav",
      "navigate with an MRPT EKF on raw and compensated yaw rates: a simulated vehicle drive (default; against the "
      "truth) or your record with odometry (--rawlog / --data; against the odometry pose)");
  auto* rawlog = cmd->add_option("--rawlog", o->rawlog,
                                 "navigate this rawlog: CObservationIMU (IMU_WZ, IMU_TEMPERATURE) with "
                                 "CActionRobotMovement2D odometry (actions/sensory-frame format)")
                     ->check(CLI::ExistingFile);
  auto* data = cmd->add_option("--data", o->data,
                               "navigate this CSV: t_s, rate_rps or rate_dps, temp_c, odom_dx_m, odom_dy_m, "
                               "odom_dphi_rad (increment since the previous row, robot frame) [, odom_speed_mps] "
                               "(what `driftlab mrpt import` writes)")
                   ->check(CLI::ExistingFile);
  rawlog->excludes(data);
  auto* device = cmd->add_option("--device", o->device,
                                 "simulated drive: device file, or the name of one in the devices directory");
  cmd->add_option("--model", o->model,
                  "calibration model JSON (driftlab calibrate); its gyro_z of --instance compensates the yaw rate. "
                  "Required with --rawlog/--data; for the simulated drive the default is to calibrate one on a "
                  "simulated oven run of the device (scenario calibration_seed) and write it to DIR/model.json")
      ->check(CLI::ExistingFile);
  cmd->add_option("--instance", o->instance, "IMU instance of the model's yaw gyro (gyro_z is 0, gyro1_z is 1)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--sensor-label", o->sensor_label, "--rawlog: IMU sensor label (needed when there are several)")
      ->needs(rawlog);
  auto* scenario = cmd->add_option("--scenario", o->scenario,
                                   "simulated drive: driftlab-nav-scenario/1 YAML (default: the bundled one-hour "
                                   "cold-start drive, cabin -10 -> "
                                   "+35 degC)")
                       ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "output directory (created; files written atomically)")->required();
  auto* fixes =
      cmd->add_flag("--fixes", o->fixes, "simulated drive: use the scenario's position fixes as EKF observations");
  cmd->add_option("--every", o->every_s, "spacing of trajectory.csv / errors.csv rows, s")
      ->check(finite_number(0.0, 1e12, true))
      ->capture_default_str();
  cmd->add_option("--bias-prior", o->bias_prior_dph, "prior standard deviation of the gyro bias state, deg/h")
      ->check(finite_number(0.0, 1e12, true))
      ->capture_default_str();
  auto* kind = cmd->add_option("--calibration-kind", o->calibration_kind,
                               "simulated drive: model nav calibrates when given no --model: poly or physical")
                   ->check(CLI::IsMember({"poly", "physical"}))
                   ->capture_default_str();
  auto* no_rawlog = cmd->add_flag("--no-rawlog", o->no_rawlog, "simulated drive: do not write DIR/drive.rawlog");
  auto* devices_dir = cmd->add_option("--devices-dir", o->devices_dir, "directory of device files");
  for (auto* record : {rawlog, data})
    for (auto* simulated_only : {device, scenario, fixes, kind, no_rawlog, devices_dir})
      record->excludes(simulated_only);
  cmd->callback([o, &env] { nav_command(*o, env); });
}

}  // namespace driftlab::cli
