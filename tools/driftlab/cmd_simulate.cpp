// `driftlab simulate`: run a device file through the oven simulator and write a CSV record:
// a single-axis gyro as t_s, rate_dps, temp_c, true_rate_dps, systematic_dps, die_temp_c,
// drive_freq_hz; a whole IMU (an `imu:` device file) as devices/imu_simulation_columns.hpp lists them; with
// --fleet, a fleet of such IMUs (simulate_fleet below).
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

#include <nlohmann/json.hpp>

#include "devices/device_file.hpp"
#include "devices/fleet_simulator.hpp"
#include "devices/imu_simulation_columns.hpp"
#include "devices/imu_simulator.hpp"
#include "devices/simulator.hpp"
#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/effect_catalogue.hpp"
#include "framework/imu.hpp"
#include "framework/output_set.hpp"
#include "framework/parallel.hpp"
#include "framework/resources.hpp"
#include "framework/units.hpp"
#include "tools/driftlab/cli.hpp"
#include "tools/driftlab/data_dirs.hpp"

namespace driftlab::cli {
namespace {

// Run time per sample and IMU instance (or single-axis gyro), rounded up from `driftlab simulate
// --device fmvmg --fs 100 --duration 36000`: 12.1 s for 3.6e6 samples (3.4e-6 s each) on the
// development machine (2 shared cores); checked against the time budget (framework/resources.hpp).
constexpr double kSimulateSecondsPerSample = 4e-6;

struct SimulateOptions {
  std::string device, profile = "oven", out, devices_dir;
  std::vector<std::string> effects;
  double fs = 100.0;
  double duration = 0.0;
  std::uint64_t seed = 1;
  std::size_t fleet = 0;                             // > 0: that many units into the directory --out (simulate_fleet)
  std::string spread = "0.1";                        // --spread (devices::parse_fleet_spread)
  std::string outliers = devices::kDefaultOutliers;  // --outliers (devices::parse_fault_plan)
};

// A column in `unit`, snapped to the output's resolution (devices::written_values); values are
// already converted, so they are written with unit "1".
CsvColumn output_column(const std::string& name, const Eigen::VectorXd& internal, const std::string& unit,
                        double resolution = 0.0) {
  return {name, devices::written_values(internal, unit, resolution), "1"};
}

double resolution_of(const devices::ChannelSpec* channel) { return channel ? channel->resolution : 0.0; }

std::vector<CsvColumn> single_axis_columns(const devices::DeviceDefinition& device,
                                           const devices::SimulationRecord& record) {
  std::vector<CsvColumn> columns{
      {"t_s", record.time_s, "s"},
      output_column("rate_dps", record.rate_rad_s, "deg/s", resolution_of(device.find_channel(role::kRate))),
      output_column("temp_c", record.temp_c, "degC", resolution_of(device.find_channel(role::kTemperature))),
      output_column("true_rate_dps", record.true_rate_rad_s, "deg/s"),
      output_column("systematic_dps", record.systematic_rate_rad_s, "deg/s"),
      output_column("die_temp_c", record.die_temp_c, "degC")};
  if (record.drive_frequency_hz.size() == record.time_s.size())
    columns.push_back(output_column("drive_freq_hz", record.drive_frequency_hz, "Hz",
                                    resolution_of(device.find_channel(role::kDriveFrequency))));
  return columns;
}

// The whole-IMU record (issue 20): devices::imu_simulation_columns in their written units.
std::vector<CsvColumn> imu_columns(const devices::ImuDefinition& imu, const devices::ImuSimulationRecord& record) {
  std::vector<CsvColumn> columns;
  for (const auto& c : devices::imu_simulation_columns(imu, record))
    columns.push_back(output_column(c.name, c.values, c.unit));
  return columns;
}

// `--fleet N`: N units of a whole-IMU device (devices/fleet_simulator.hpp: spread and planted
// faults) into DIR: <unit>.csv each, manifest.csv (unit,data) for `driftlab fleet`, and key.json,
// the answer key (per unit its seed, device ids, drawn parameters per channel under the fleet
// report's figure keys (truth), planted fault and the finding expected of it).
void simulate_fleet(const SimulateOptions& o, CommandEnv& env, const devices::DeviceDefinition& device,
                    const std::filesystem::path& device_path, const devices::SimulationProfile& profile) {
  if (!device.imu)
    throw ConfigError({device_path.string(), 0, "imu"},
                      "--fleet simulates a whole-IMU device file (an imu: section, e.g. devices/imu3.yaml)");
  const std::filesystem::path dir(o.out);
  const devices::FleetSpread spread = devices::parse_fleet_spread(o.spread);
  const auto plan = devices::parse_fault_plan(o.outliers);
  const auto fleet = devices::plan_fleet(*device.imu, o.fleet, o.seed, spread, plan);
  // One OutputSet for the whole fleet: the directory, every unit file, manifest.csv and key.json are
  // planned (and checked against the device file) before any simulation, and committed together.
  OutputSet outputs({device_path});
  outputs.make_directory(dir, "--out");
  for (const auto& unit : fleet) outputs.plan(dir / (unit.id + ".csv"), "--out");
  outputs.plan(dir / "manifest.csv", "--out");
  outputs.plan(dir / "key.json", "--out");
  devices::SimulationOptions options;
  options.sample_rate_hz = o.fs;
  if (o.duration > 0.0) options.duration_s = o.duration;
  const double samples = std::floor(options.duration_s.value_or(profile.duration_s()) * o.fs) + 1.0;
  char what[96];
  std::snprintf(what, sizeof what, "%.3g samples (--fs x --duration) at %.0f bytes each, %u at once", samples,
                800.0 * static_cast<double>(device.imu->instances.size()), env.threads);
  check_memory_estimate(samples * 800.0 * static_cast<double>(device.imu->instances.size()) * env.threads,
                        {"", 0, "--fs, --duration"}, what);
  const double per_unit = kSimulateSecondsPerSample * static_cast<double>(device.imu->instances.size());
  std::snprintf(what, sizeof what, "%.3g samples (--fs x --duration) for %zu units at %.2g s each", samples,
                fleet.size(), per_unit);
  check_time_estimate(samples * per_unit * static_cast<double>(fleet.size()), {"", 0, "--fs, --duration, --fleet"},
                      what);
  // Each unit is its own item (its own seed and file): the files do not depend on --threads.
  parallel_for(fleet.size(), env.threads, [&](std::size_t u) {
    const auto& unit = fleet[u];
    std::string text =
        format_csv(imu_columns(unit.imu, devices::simulate_unit(unit, profile, options)), unit.id + ".csv");
    if (unit.fault == devices::FaultKind::Truncated)
      text.resize(static_cast<std::size_t>(devices::kTruncatedFraction * static_cast<double>(text.size())));
    outputs.write(dir / (unit.id + ".csv"), text);  // each thread its own planned output
  });
  std::string manifest = "unit,data\n";
  nlohmann::json units = nlohmann::json::array();
  for (const auto& unit : fleet) {
    manifest += unit.id + "," + unit.id + ".csv\n";
    nlohmann::json ids = nlohmann::json::array();
    for (const auto& i : unit.imu.instances) ids.push_back(*i.device_id);
    // The unit's drawn parameters per channel, as the fleet report's figures (display units).
    nlohmann::json truth = nlohmann::json::object();
    for (std::size_t i = 0; i < unit.imu.instances.size(); ++i)
      for (const auto sensor : {imu::Sensor::Gyro, imu::Sensor::Accel})
        for (std::size_t a = 0; a < 3; ++a) {
          const auto& inst = unit.imu.instances[i];
          const auto& axis = (sensor == imu::Sensor::Gyro ? inst.gyro : inst.accel).axes[a];
          const double display = imu::display_unit(sensor).per_internal;
          const bool gyro = sensor == imu::Sensor::Gyro;
          const auto coefficient = [&](std::size_t k) {
            return axis.bias_polynomial.size() > k ? axis.bias_polynomial[k] * display : 0.0;
          };
          truth[imu::ChannelId{sensor, static_cast<char>('x' + a), static_cast<int>(i)}.role()] = {
              {gyro ? "a0_dph" : "a0_mg", coefficient(0)},
              {gyro ? "a1_dph_per_k" : "a1_mg_per_k", coefficient(1)},
              {gyro ? "N_dph_rthz" : "N_mg_rthz", axis.noise.arw_rad_sqrt_s * display}};
        }
    nlohmann::json entry = {{"unit", unit.id},   {"data", unit.id + ".csv"}, {"seed", unit.seed},
                            {"device_ids", ids}, {"truth", truth},           {"fault", nullptr}};
    if (unit.fault) {
      const auto expected = devices::expected_finding(*unit.fault);
      entry["fault"] = {{"kind", devices::to_string(*unit.fault)},
                        {"description", devices::describe(*unit.fault)},
                        {"expected", {{"channel", expected.channel}, {"figure", expected.figure}}}};
    }
    units.push_back(std::move(entry));
  }
  const nlohmann::json key = {
      {"format", "driftlab-fleet-key/1"},
      {"device", device_path.string()},
      {"profile", profile.source},
      {"sample_rate_hz", o.fs},
      {"seed", o.seed},
      {"spread",
       {{"distribution",
         "each parameter x (1 + sigma z), z ~ N(0, 1) per unit and parameter; noise terms and time "
         "constants at least 0"},
        {"bias_polynomial_sigma", spread.bias},
        {"scale_factor_polynomial_sigma", spread.scale_factor},
        {"noise_terms_sigma", spread.noise},
        {"time_constants_sigma", spread.time_constant}}},
      {"outliers", o.outliers},
      {"units", units}};
  outputs.write(dir / "manifest.csv", manifest);
  outputs.write(dir / "key.json", key.dump(2) + "\n");
  outputs.commit();
  std::cout << dir.string() << ": " << fleet.size() << " units of " << device.name << " (" << samples
            << " samples each at " << o.fs << " Hz, profile " << profile.source << ", seed " << o.seed
            << "), manifest.csv, key.json; planted:";
  for (const auto& unit : fleet)
    if (unit.fault) std::cout << " " << unit.id << " " << devices::to_string(*unit.fault);
  std::cout << "\n";
}

void simulate_command(const SimulateOptions& o, CommandEnv& env) {
  const auto device_path = resolve_device_file(o.device, o.devices_dir);
  auto device = devices::load_device_file(device_path);
  if (device.imu && !o.effects.empty())
    throw ConfigError({"", 0, "--effect"}, "effects apply to single-axis devices; " + device.name + " (" +
                                               device_path.string() + ") is a whole IMU");
  for (const auto& effect : o.effects) devices::apply_effect_option(effect, device.error_model.effects);
  const auto profile = o.profile == "oven" ? devices::default_oven_profile() : devices::load_profile_file(o.profile);
  if (o.fleet > 0) return simulate_fleet(o, env, device, device_path, profile);
  OutputSet outputs({device_path, o.profile == "oven" ? std::filesystem::path() : std::filesystem::path(o.profile)});
  outputs.plan(o.out, "--out");

  devices::SimulationOptions options;
  options.sample_rate_hz = o.fs;
  options.seed = o.seed;
  if (o.duration > 0.0) options.duration_s = o.duration;
  // The record and its CSV text: about 250 bytes per sample for a single axis (6 channels), 800
  // per IMU instance (20 series, 19 columns).
  const double samples = std::floor(options.duration_s.value_or(profile.duration_s()) * o.fs) + 1.0;
  const double bytes = device.imu ? 800.0 * static_cast<double>(device.imu->instances.size()) : 250.0;
  char what[96];
  std::snprintf(what, sizeof what, "%.3g samples (--fs x --duration) at %.0f bytes each", samples, bytes);
  check_memory_estimate(samples * bytes, {"", 0, "--fs, --duration"}, what);
  const double seconds =
      kSimulateSecondsPerSample * (device.imu ? static_cast<double>(device.imu->instances.size()) : 1.0);
  std::snprintf(what, sizeof what, "%.3g samples (--fs x --duration) at %.2g s each", samples, seconds);
  check_time_estimate(samples * seconds, {"", 0, "--fs, --duration"}, what);
  env.progress("simulate " + device.name, 0.0);
  const std::vector<CsvColumn> columns =
      device.imu ? imu_columns(*device.imu, devices::simulate_imu(*device.imu, profile, options))
                 : single_axis_columns(device, devices::simulate(device, profile, options));
  env.progress("simulate " + device.name, 0.5);
  outputs.write_csv(o.out, columns);
  outputs.commit();
  env.progress("simulate " + device.name, 1.0);

  const auto effects = devices::describe_effects(device.error_model.effects);
  const Eigen::VectorXd& time_s = columns.front().values;
  std::cout << o.out << ": " << time_s.size() << " samples, " << time_s[time_s.size() - 1] << " s at " << o.fs
            << " Hz, device " << device.name;
  if (device.imu)
    std::cout << " (whole IMU, " << device.imu->instances.size() << " instance"
              << (device.imu->instances.size() == 1 ? "" : "s") << ")";
  std::cout << ", profile " << profile.source << ", seed " << o.seed << ", effects:";
  if (effects.empty()) std::cout << " none";
  for (const auto& e : effects) std::cout << " " << e;
  std::cout << "\n";
}

std::string effect_help() {
  std::string text = "switch on an effect the device file leaves out, NAME:key=value,...; repeatable. Effects:";
  for (const auto& e : effect_catalogue()) {
    text += "\n  " + e.name + ":";
    for (std::size_t i = 0; i < e.keys.size(); ++i)
      text += (i ? "," : "") + e.keys[i].key + "=" + (e.keys[i].list ? "[..]" : "X");
    text += "  " + e.doc;
  }
  return text;
}

}  // namespace

void add_simulate_command(CLI::App& app, CommandEnv& env) {
  auto options = std::make_shared<SimulateOptions>();
  auto* cmd = app.add_subcommand("simulate", "simulate a device in a temperature chamber and write a CSV record");
  cmd->add_option("--device", options->device, "device file, or the name of one in the devices directory")->required();
  cmd->add_option("--profile", options->profile,
                  "chamber/rate profile: 'oven' (-30 -> +60 -> -30 degC, 4.5 h) or a driftlab-profile/1 YAML file")
      ->capture_default_str();
  cmd->add_option("--fs", options->fs, "sample rate, Hz")->check(finite_number(0.0, 1e9, true))->capture_default_str();
  cmd->add_option("--duration", options->duration, "duration, s (default: the profile's)")
      ->check(finite_number(0.0, 1e10, true));
  cmd->add_option("--seed", options->seed, "random seed; same seed, same record")
      ->check(whole_number(0, kMaxSeed))
      ->capture_default_str();
  cmd->add_option("--effect", options->effects, effect_help());
  cmd->add_option("--devices-dir", options->devices_dir, "directory of device files");
  auto* fleet = cmd->add_option("--fleet", options->fleet,
                                "simulate this many units of a whole-IMU device, spread unit to unit, with planted "
                                "faults (--outliers): --out is then a directory that receives <unit>.csv, "
                                "manifest.csv and key.json (the answer key)")
                    ->check(whole_number(1, 100000));
  cmd->add_option("--spread", options->spread,
                  "with --fleet, the unit-to-unit relative sigma of the device parameters: S for every group, or "
                  "group=S,... of bias, scale_factor, noise, time_constant (devices/fleet_simulator.hpp)")
      ->needs(fleet)
      ->capture_default_str();
  cmd->add_option("--outliers", options->outliers,
                  "with --fleet, the planted faults, kind:count,... of hysteresis, bias_step, noisy, truncated, lag, "
                  "dead_axis, lsb ('none': no fault)")
      ->needs(fleet)
      ->capture_default_str();
  cmd->add_option("--out", options->out, "output CSV (written atomically); with --fleet, a directory")->required();
  cmd->callback([options, &env] { simulate_command(*options, env); });
}

}  // namespace driftlab::cli
