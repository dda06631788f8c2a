#include "devices/simulator.hpp"

#include <cmath>

#include "devices/systematic_rate.hpp"
#include "devices/yaml_fields.hpp"
#include "framework/regular_file.hpp"
#include "framework/signal.hpp"
#include "framework/units.hpp"

namespace driftlab::devices {
namespace {

constexpr std::uint64_t kTemperatureNoiseStream = 1000;
constexpr std::uint64_t kDriveFrequencyNoiseStream = 1001;

double quantize(double value, double resolution) {
  return resolution > 0.0 ? std::round(value / resolution) * resolution : value;
}

OrientationSchedule read_orientation_section(YamlFields& y, const YAML::Node& node) {
  const std::string path = "orientation";
  OrientationSchedule o;
  if (!y.map(node, path, {"dwell_s", "up_directions"})) return o;
  o.dwell_s = y.number(node, path, "dwell_s", true, Bounds::positive()).value_or(0.0);
  const YAML::Node ups = y.child(node, path, "up_directions", true);
  if (!ups.IsDefined()) return o;
  const std::string expected = "expected a list of up directions [x, y, z] in the IMU's axes (not all zero)";
  if (!ups.IsSequence() || ups.size() == 0) {
    y.problem(ups, path + ".up_directions", expected);
    return o;
  }
  for (std::size_t i = 0; i < ups.size(); ++i) {
    const std::string p = path + ".up_directions[" + std::to_string(i) + "]";
    const YAML::Node u = ups[i];
    Eigen::Vector3d up = Eigen::Vector3d::Zero();
    bool valid = u.IsSequence() && u.size() == 3;
    for (std::size_t a = 0; valid && a < 3; ++a) {
      valid = u[a].IsScalar() && YAML::convert<double>::decode(u[a], up[static_cast<Eigen::Index>(a)]) &&
              std::isfinite(up[static_cast<Eigen::Index>(a)]);
    }
    if (!valid || up.norm() == 0.0) {
      y.problem(u, p, "expected [x, y, z], finite and not all zero (the direction pointing up, in the IMU's axes)");
      continue;
    }
    o.up_directions.push_back(up.normalized());
  }
  return o;
}

}  // namespace

const Eigen::Vector3d& OrientationSchedule::up_at(double t_s) const {
  const double position = std::floor(std::max(t_s, 0.0) / dwell_s);
  const auto n = static_cast<double>(up_directions.size());
  return up_directions[static_cast<std::size_t>(std::fmod(position, n))];
}

Profile read_profile_section(YamlFields& y, const YAML::Node& node, const std::string& path,
                             const std::string& unit_suffix, double scale, double fallback_start,
                             const Bounds& values) {
  const std::string start_key = "start_" + unit_suffix;
  const std::string to_key = "to_" + unit_suffix;
  const std::string rate_key = "rate_" + unit_suffix + "_per_min";
  if (!y.map(node, path, {start_key, "segments"})) return Profile(fallback_start);
  Profile profile(y.number_or(node, path, start_key, fallback_start / scale, values) * scale);
  const YAML::Node segments = y.child(node, path, "segments", false);
  if (!segments.IsDefined()) return profile;
  if (!segments.IsSequence()) {
    y.problem(segments, path + ".segments", "expected a list of segments");
    return profile;
  }
  for (std::size_t i = 0; i < segments.size(); ++i) {
    const YAML::Node s = segments[i];
    const std::string p = path + ".segments[" + std::to_string(i) + "]";
    if (!y.map(s, p, {"hold_s", to_key, "duration_s", rate_key})) continue;
    const bool holds = y.child(s, p, "hold_s", false).IsDefined();
    const bool moves = y.child(s, p, to_key, false).IsDefined();
    if (holds == moves) {
      y.problem(s, p, "a segment is either {hold_s: S} or {" + to_key + ": V, duration_s: S | " + rate_key + ": R}");
      continue;
    }
    if (holds) {
      if (auto d = y.number(s, p, "hold_s", true, Bounds::non_negative())) profile.hold(*d);
      continue;
    }
    const auto target = y.number(s, p, to_key, true, values);
    const bool has_duration = y.child(s, p, "duration_s", false).IsDefined();
    const bool has_rate = y.child(s, p, rate_key, false).IsDefined();
    if (has_duration == has_rate) {
      y.problem(s, p, "give exactly one of duration_s and " + rate_key);
      continue;
    }
    if (!target) continue;
    if (has_duration) {
      if (auto d = y.number(s, p, "duration_s", true, Bounds::non_negative())) profile.ramp_to(*target * scale, *d);
    } else if (auto r = y.number(s, p, rate_key, true, Bounds::positive())) {
      profile.ramp_at_rate(*target * scale, *r * scale / 60.0);
    }
  }
  return profile;
}

Profile::Profile(double start, std::vector<ProfileSegment> segments) : values_{start} {
  for (const auto& s : segments) {
    if (s.target)
      ramp_to(*s.target, s.duration_s);
    else
      hold(s.duration_s);
  }
}

Profile& Profile::hold(double duration_s) { return ramp_to(values_.back(), duration_s); }

Profile& Profile::ramp_to(double target, double duration_s) {
  times_.push_back(times_.back() + duration_s);
  values_.push_back(target);
  return *this;
}

Profile& Profile::ramp_at_rate(double target, double rate_per_s) {
  return ramp_to(target, std::abs(target - values_.back()) / rate_per_s);
}

double Profile::value_at(double t_s) const {
  if (t_s >= times_.back()) return values_.back();
  if (t_s <= times_.front()) return values_.front();
  const auto upper = std::upper_bound(times_.begin(), times_.end(), t_s);
  const auto i = static_cast<std::size_t>(upper - times_.begin());
  const double span = times_[i] - times_[i - 1];
  const double fraction = span > 0.0 ? (t_s - times_[i - 1]) / span : 1.0;
  return values_[i - 1] + fraction * (values_[i] - values_[i - 1]);
}

Eigen::VectorXd Profile::sample(const Eigen::VectorXd& time_s) const {
  Eigen::VectorXd out(time_s.size());
  std::size_t i = 1;
  for (Eigen::Index k = 0; k < time_s.size(); ++k) {
    const double t = time_s[k];
    while (i < times_.size() && times_[i] <= t) ++i;
    if (i >= times_.size() || t <= times_.front()) {
      out[k] = i >= times_.size() ? values_.back() : values_.front();
      continue;
    }
    const double span = times_[i] - times_[i - 1];
    out[k] = values_[i - 1] + (t - times_[i - 1]) / span * (values_[i] - values_[i - 1]);
  }
  return out;
}

SimulationProfile default_oven_profile() {
  SimulationProfile p;
  p.chamber_c = Profile(-30.0);
  p.chamber_c.hold(1800).ramp_at_rate(60.0, 1.0 / 60.0).hold(1800).ramp_at_rate(-30.0, 1.0 / 60.0).hold(1800);
  p.source = "oven: -30 degC soak 30 min, +1 degC/min to +60 degC, soak 30 min, -1 degC/min to -30 degC, soak 30 min";
  return p;
}

SimulationProfile parse_profile(const std::string& yaml_text, const std::string& file) {
  const YAML::Node root = load_yaml_checked(yaml_text, file);
  std::vector<Diagnostic> problems;
  YamlFields y(file, problems);
  SimulationProfile profile;
  profile.source = file;
  if (y.map(root, "", {"format", "chamber", "rate", "orientation"})) {
    if (auto format = y.text(root, "", "format", true); format && *format != "driftlab-profile/1")
      y.problem(y.child(root, "", "format", false), "format",
                "unsupported format '" + *format + "'; expected driftlab-profile/1");
    if (const auto chamber = y.child(root, "", "chamber", false); chamber.IsDefined())
      profile.chamber_c = read_profile_section(y, chamber, "chamber", "c", 1.0, 25.0, Bounds::absolute_temperature_c());
    if (const auto rate = y.child(root, "", "rate", false); rate.IsDefined())
      profile.true_rate = read_profile_section(y, rate, "rate", "dps", kRadPerDeg, 0.0, {});
    if (const auto orientation = y.child(root, "", "orientation", false); orientation.IsDefined())
      profile.orientation = read_orientation_section(y, orientation);
  }
  if (!problems.empty()) throw ConfigError(std::move(problems));
  return profile;
}

SimulationProfile load_profile_file(const std::filesystem::path& path) {
  return parse_profile(read_config_text(path, "profile file"), input_name(path));
}

TimeSeries SimulationRecord::to_time_series() const {
  TimeSeries series(time_s);
  series.set_channel({role::kRate, "rad/s", "simulated rate_dps", rate_rad_s});
  series.set_channel({role::kTemperature, "degC", "simulated temp_c", temp_c});
  series.set_channel({role::kTrueRate, "rad/s", "simulated true_rate_dps", true_rate_rad_s});
  series.set_channel({role::kDieTemperature, "degC", "simulated die_temp_c", die_temp_c});
  if (drive_frequency_hz.size() == time_s.size())
    series.set_channel({role::kDriveFrequency, "Hz", "simulated drive_freq_hz", drive_frequency_hz});
  return series;
}

Eigen::VectorXd sample_times(const SimulationProfile& profile, const SimulationOptions& options) {
  const double fs = options.sample_rate_hz;
  if (!(fs > 0.0) || !std::isfinite(fs))
    throw ConfigError({"", 0, "fs"}, "sample rate must be positive, got " + std::to_string(fs));
  const double duration = options.duration_s.value_or(profile.duration_s());
  if (!(duration > 0.0) || !std::isfinite(duration))
    throw ConfigError({profile.source, 0, "duration"},
                      "duration must be positive (the profile is static; give a duration)");
  const auto n = static_cast<Eigen::Index>(std::floor(duration * fs + 1e-9));
  if (n < 2) throw ConfigError({"", 0, "duration"}, "the run has fewer than 2 samples; raise fs or the duration");
  Eigen::VectorXd time_s(n);
  for (Eigen::Index k = 0; k < n; ++k) time_s[k] = static_cast<double>(k) / fs;
  return time_s;
}

SimulationRecord simulate(const DeviceDefinition& device, const SimulationProfile& profile,
                          const SimulationOptions& options) {
  require_single_axis(device);
  if (profile.orientation)
    throw ConfigError({profile.source, 0, "orientation"}, "an orientation schedule needs a whole-IMU device (imu:); '" +
                                                              device.name + "' is a single-axis gyro");
  const double fs = options.sample_rate_hz;
  const error_model::Config& config = device.error_model;

  SimulationRecord r;
  r.time_s = sample_times(profile, options);
  const Eigen::Index n = r.time_s.size();
  r.chamber_temp_c = profile.chamber_c.sample(r.time_s);
  r.true_rate_rad_s = profile.true_rate.sample(r.time_s);
  const Eigen::VectorXd die = signal::first_order_lag(r.time_s, r.chamber_temp_c, device.thermal.die_time_constant_s);
  const Eigen::VectorXd sensor = signal::first_order_lag(r.time_s, die, device.thermal.sensor_time_constant_s);
  SystematicRate systematic = systematic_rate(DeviceModel(device.physics), config, r.time_s, die, r.true_rate_rad_s);
  r.die_temp_c = std::move(systematic.resonator_temp_c);
  r.systematic_rate_rad_s = std::move(systematic.rate_rad_s);
  Eigen::VectorXd drive_hz = std::move(systematic.drive_frequency_hz);

  const ChannelSpec* rate_channel = device.find_channel(role::kRate);
  const ChannelSpec* temp_channel = device.find_channel(role::kTemperature);
  const ChannelSpec* drive_channel = device.find_channel(role::kDriveFrequency);
  r.rate_rad_s = r.systematic_rate_rad_s + error_model::rate_noise(config.noise, fs, n, options.seed);
  if (rate_channel)
    for (double& w : r.rate_rad_s)
      w = quantize(std::clamp(w, rate_channel->range_min, rate_channel->range_max), rate_channel->resolution);

  r.temp_c = sensor;
  if (temp_channel) {
    error_model::NormalStream noise(options.seed, kTemperatureNoiseStream);
    for (double& t : r.temp_c) {
      if (temp_channel->noise > 0.0) t += temp_channel->noise * noise.next();
      t = quantize(std::clamp(t, temp_channel->range_min, temp_channel->range_max), temp_channel->resolution);
    }
  }
  if (drive_channel) {
    error_model::NormalStream noise(options.seed, kDriveFrequencyNoiseStream);
    for (double& f : drive_hz) {
      if (drive_channel->noise > 0.0) f += drive_channel->noise * noise.next();
      f = quantize(f, drive_channel->resolution);
    }
    r.drive_frequency_hz = std::move(drive_hz);
  }
  return r;
}

}  // namespace driftlab::devices
