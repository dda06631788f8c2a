#include "tools/mrpt/nav_scenario.hpp"

#include <cmath>

#include "devices/yaml_fields.hpp"
#include "framework/error.hpp"
#include "framework/regular_file.hpp"
#include "models/error_model/error_model.hpp"
#include "framework/units.hpp"

namespace driftlab::mrpt_bridge {

double NavScenario::duration_s() const {
  return std::max({cabin_c.duration_s(), yaw_rate_rad_s.duration_s(), speed_mps.duration_s()});
}

std::filesystem::path default_scenario_path() {
  return std::filesystem::path(DRIFTLAB_MRPT_SCENARIO_DIR) / "cold_start_drive.yaml";
}

NavScenario parse_nav_scenario(const std::string& yaml_text, const std::string& file) {
  using devices::Bounds;
  const YAML::Node root = load_yaml_checked(yaml_text, file);
  std::vector<Diagnostic> problems;
  devices::YamlFields y(file, problems);
  NavScenario s;
  s.source = file;
  if (y.map(root, "",
            {"format", "sample_rate_hz", "seed", "calibration_seed", "cabin", "yaw_rate", "speed", "odometry",
             "fixes"})) {
    if (auto format = y.text(root, "", "format", true); format && *format != "driftlab-nav-scenario/1")
      y.problem(y.child(root, "", "format", false), "format",
                "unsupported format '" + *format + "'; expected driftlab-nav-scenario/1");
    s.sample_rate_hz = y.number_or(root, "", "sample_rate_hz", s.sample_rate_hz, Bounds::positive());
    s.seed = y.whole_number_or(root, "", "seed", s.seed);
    s.calibration_seed = y.whole_number_or(root, "", "calibration_seed", s.calibration_seed);
    if (auto n = y.child(root, "", "cabin", true); n.IsDefined())
      s.cabin_c = devices::read_profile_section(y, n, "cabin", "c", 1.0, 25.0, Bounds::absolute_temperature_c());
    if (auto n = y.child(root, "", "yaw_rate", true); n.IsDefined())
      s.yaw_rate_rad_s = devices::read_profile_section(y, n, "yaw_rate", "dps", kRadPerDeg, 0.0, {});
    if (auto n = y.child(root, "", "speed", true); n.IsDefined())
      s.speed_mps = devices::read_profile_section(y, n, "speed", "mps", 1.0, 0.0, {});
    if (auto n = y.child(root, "", "odometry", false); n.IsDefined() && y.map(n, "odometry", {"speed_sigma_mps"}))
      s.odometry_speed_sigma_mps =
          y.number_or(n, "odometry", "speed_sigma_mps", s.odometry_speed_sigma_mps, Bounds::non_negative());
    if (auto n = y.child(root, "", "fixes", false); n.IsDefined() && y.map(n, "fixes", {"period_s", "sigma_m"})) {
      s.fix_period_s = y.number_or(n, "fixes", "period_s", 0.0, Bounds::non_negative());
      s.fix_sigma_m = y.number_or(n, "fixes", "sigma_m", s.fix_sigma_m, Bounds::positive());
    }
  }
  if (problems.empty() && !(s.duration_s() > 0.0))
    problems.push_back({{file, 0, "speed"}, "the scenario has no duration (every profile is a single value)"});
  if (!problems.empty()) throw ConfigError(std::move(problems));
  return s;
}

NavScenario load_nav_scenario(const std::filesystem::path& path) {
  return parse_nav_scenario(read_config_text(path, "scenario file"), input_name(path));
}

DriveRecord simulate_drive(const devices::DeviceDefinition& device, const NavScenario& scenario) {
  devices::SimulationProfile profile;
  profile.chamber_c = scenario.cabin_c;
  profile.true_rate = scenario.yaw_rate_rad_s;
  profile.source = scenario.source;
  devices::SimulationOptions options;
  options.sample_rate_hz = scenario.sample_rate_hz;
  options.duration_s = scenario.duration_s();
  options.seed = scenario.seed;

  DriveRecord d;
  d.gyro = devices::simulate(device, profile, options);
  const auto& t = d.gyro.time_s;
  const Eigen::Index n = t.size();
  d.speed_mps = scenario.speed_mps.sample(t);
  d.odometry_speed_mps.resize(n);
  // Streams of the drive seed beyond the gyro's (error_model::rate_noise uses 0, 1, 2, ...).
  constexpr std::uint64_t kOdometryStream = 0x6f646f6d, kFixStream = 0x66697865;  // "odom", "fixe"
  error_model::NormalStream odometry_noise(scenario.seed, kOdometryStream);
  for (Eigen::Index k = 0; k < n; ++k)
    d.odometry_speed_mps[k] = d.speed_mps[k] + scenario.odometry_speed_sigma_mps * odometry_noise.next();

  d.x_m = Eigen::VectorXd::Zero(n);
  d.y_m = Eigen::VectorXd::Zero(n);
  d.heading_rad = Eigen::VectorXd::Zero(n);
  const auto& w = d.gyro.true_rate_rad_s;
  double psi = 0.0;  // unwrapped
  for (Eigen::Index k = 1; k < n; ++k) {
    const double dt = t[k] - t[k - 1];
    const double dpsi = 0.5 * (w[k - 1] + w[k]) * dt;
    const double mid = psi + 0.5 * dpsi;
    const double v = 0.5 * (d.speed_mps[k - 1] + d.speed_mps[k]);
    d.x_m[k] = d.x_m[k - 1] + v * dt * std::cos(mid);
    d.y_m[k] = d.y_m[k - 1] + v * dt * std::sin(mid);
    psi += dpsi;
    d.heading_rad[k] = wrap_angle(psi);
  }

  if (scenario.fix_period_s > 0.0) {
    error_model::NormalStream fix_noise(scenario.seed, kFixStream);
    double next = scenario.fix_period_s;
    for (Eigen::Index k = 1; k < n; ++k) {
      if (t[k] + 1e-9 < next) continue;
      next += scenario.fix_period_s;
      d.fix_index.push_back(k);
      const double ex = scenario.fix_sigma_m * fix_noise.next(), ey = scenario.fix_sigma_m * fix_noise.next();
      d.fix_m.emplace_back(d.x_m[k] + ex, d.y_m[k] + ey);
    }
  }
  return d;
}

NavNoise nav_noise(const devices::DeviceDefinition& device, const NavScenario& scenario) {
  const auto& terms = device.error_model.noise;
  NavNoise noise;
  noise.arw_rad_sqrt_s = terms.arw_rad_sqrt_s;
  noise.bias_instability_rad_s = terms.bias_instability_rad_s;
  noise.rate_random_walk_rad_s_sqrt_s = terms.rate_random_walk_rad_s_sqrt_s;
  noise.bias_correlation_time_s = terms.flicker_tau_max_s;
  noise.speed_sigma_mps = scenario.odometry_speed_sigma_mps;
  noise.fix_sigma_m = scenario.fix_sigma_m;
  return noise;
}

NavInput nav_input(const DriveRecord& drive) {
  NavInput input;
  input.time_s = drive.gyro.time_s;
  const Eigen::Index n = input.time_s.size();
  input.step_speed_mps = Eigen::VectorXd::Zero(n);
  for (Eigen::Index k = 1; k < n; ++k)
    input.step_speed_mps[k] = 0.5 * (drive.odometry_speed_mps[k - 1] + drive.odometry_speed_mps[k]);
  input.x_m = drive.x_m;
  input.y_m = drive.y_m;
  input.heading_rad = drive.heading_rad;
  input.fix_index = drive.fix_index;
  input.fix_m = drive.fix_m;
  return input;
}

NavTrack run_nav(const NavInput& input, const Eigen::VectorXd& rate, const NavNoise& noise, bool use_fixes,
                 double bias_prior_sigma_rad_s, const std::function<void(double)>& progress) {
  const auto& t = input.time_s;
  const Eigen::Index n = t.size();
  if (rate.size() != n)
    throw DataError(Location{"", 0, "rate"},
                    "the yaw rate has " + std::to_string(rate.size()) + " samples, the record " + std::to_string(n));
  NavState start;
  start.heading_rad = input.heading_rad[0];
  start.x_m = input.x_m[0];
  start.y_m = input.y_m[0];
  start.covariance(3, 3) = bias_prior_sigma_rad_s * bias_prior_sigma_rad_s;
  NavEkf ekf(noise, start);

  NavTrack track;
  for (auto* v : {&track.x_m, &track.y_m, &track.heading_rad, &track.bias_rad_s, &track.heading_sigma_rad,
                  &track.bias_sigma_rad_s, &track.heading_error_rad, &track.position_error_m})
    v->resize(n);
  auto record = [&](Eigen::Index k) {
    const NavState s = ekf.state();
    track.x_m[k] = s.x_m;
    track.y_m[k] = s.y_m;
    track.heading_rad[k] = s.heading_rad;
    track.bias_rad_s[k] = s.bias_rad_s;
    track.heading_sigma_rad[k] = std::sqrt(s.covariance(2, 2));
    track.bias_sigma_rad_s[k] = std::sqrt(s.covariance(3, 3));
    // Accumulated (unwrapped) error: each step adds the wrapped change, so an error that grows past
    // 180 degrees keeps growing instead of folding back.
    const double wrapped = wrap_angle(s.heading_rad - input.heading_rad[k]);
    track.heading_error_rad[k] =
        k == 0 ? wrapped : track.heading_error_rad[k - 1] + wrap_angle(wrapped - track.heading_error_rad[k - 1]);
    track.position_error_m[k] = std::hypot(s.x_m - input.x_m[k], s.y_m - input.y_m[k]);
  };
  record(0);
  std::size_t next_fix = 0;
  const Eigen::Index report_every = std::max<Eigen::Index>(1, n / 100);
  for (Eigen::Index k = 1; k < n; ++k) {
    const double dt = t[k] - t[k - 1];
    std::optional<Eigen::Vector2d> fix;
    if (use_fixes && next_fix < input.fix_index.size() && input.fix_index[next_fix] == k) fix = input.fix_m[next_fix++];
    ekf.step(dt, 0.5 * (rate[k - 1] + rate[k]), input.step_speed_mps[k], fix);
    record(k);
    if (progress && k % report_every == 0) progress(static_cast<double>(k) / static_cast<double>(n));
  }
  return track;
}

}  // namespace driftlab::mrpt_bridge
