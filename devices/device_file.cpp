#include "devices/device_file.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "devices/yaml_fields.hpp"
#include "framework/effect_catalogue.hpp"
#include "framework/units.hpp"

namespace driftlab::devices {
namespace {

const std::vector<std::string> kRoles{"rate", "temperature", "drive_frequency"};

Quantity quantity_of_role(const std::string& role) {
  if (role == "rate") return Quantity::AngularRate;
  if (role == "temperature") return Quantity::Temperature;
  return Quantity::Frequency;
}

std::string quantity_name(Quantity q) {
  switch (q) {
    case Quantity::AngularRate:
      return "an angular-rate unit (deg/s, rad/s, deg/h)";
    case Quantity::Temperature:
      return "a temperature unit (degC, K)";
    case Quantity::Frequency:
      return "a frequency unit (Hz, kHz)";
    default:
      return "a unit";
  }
}

// The keys of the three noise terms (N, B, K) of one sensor kind and their scales to SI; the
// flicker keys are common to both kinds.
struct NoiseKeys {
  const char* white;
  const char* instability;
  const char* random_walk;
  const char* gauss_markov_sigma;  // key of a Gauss-Markov term's std, in the instability's unit
  double white_scale, instability_scale, random_walk_scale;
};
const NoiseKeys kGyroNoise{"arw_dph_rthz",   "bias_instability_dph", "rate_random_walk_dph_rth", "sigma_dph",
                           kRadPerSecPerDph, kRadPerSecPerDph,       kRadPerSecPerDph / 60.0};
constexpr double kMicroG = 1e-6 * kStandardGravity;  // m/s^2
const NoiseKeys kAccelNoise{
    "vrw_ug_rthz", "bias_instability_ug", "acceleration_random_walk_ug_rth", "sigma_ug", kMicroG,
    kMicroG,       kMicroG / 60.0};

// The single-axis sections a whole-IMU file leaves out (its instances describe themselves).
const std::vector<std::string> kSingleAxisSections{"structure", "modes",       "electronics", "thermal",
                                                   "channels",  "error_model", "effects"};

class DeviceReader {
 public:
  DeviceReader(const std::string& file, std::vector<Diagnostic>& problems) : y_(file, problems), problems_(problems) {}

  DeviceDefinition read(const YAML::Node& root) {
    DeviceDefinition d;
    d.source = y_.file();
    if (!y_.map(root, "",
                {"format", "identity", "reference_temp_c", "structure", "modes", "electronics", "thermal", "channels",
                 "error_model", "effects", "imu"}))
      return d;
    if (auto format = y_.text(root, "", "format", true); format && *format != kDeviceFormat)
      y_.problem(y_.child(root, "", "format", false), "format",
                 "unsupported format '" + *format + "'; expected " + kDeviceFormat);
    read_identity(y_.child(root, "", "identity", true), d);
    // Above absolute zero: Q(T) scales with the absolute temperature ratio.
    d.physics.reference_temp_c = y_.number_or(root, "", "reference_temp_c", 25.0, Bounds{-273.15, 500.0, true});
    d.error_model.reference_temp_c = d.physics.reference_temp_c;
    if (const YAML::Node imu = y_.child(root, "", "imu", false); imu.IsDefined()) {
      for (const auto& kv : root)
        if (const std::string key = kv.first.Scalar();
            std::find(kSingleAxisSections.begin(), kSingleAxisSections.end(), key) != kSingleAxisSections.end())
          y_.problem(kv.first, key,
                     "not used by a whole-IMU device (imu:): each instance declares its thermal, gyro and accel");
      d.imu = read_imu(imu, d.physics.reference_temp_c);
      return d;
    }
    read_structure(y_.child(root, "", "structure", true), d.physics.structure);
    read_modes(y_.child(root, "", "modes", true), d.physics);
    read_electronics(y_.child(root, "", "electronics", true), d.physics.electronics);
    read_thermal(y_.child(root, "", "thermal", false), "thermal", d.thermal);
    read_channels(y_.child(root, "", "channels", true), d.channels);
    read_error_model(y_.child(root, "", "error_model", false), d.error_model);
    if (const auto effects = y_.child(root, "", "effects", false); effects.IsDefined() && !effects.IsNull())
      parse_effects(effects, y_.file(), "effects", d.error_model.effects, problems_);
    if (problems_.empty()) check_consistency(root, d);
    return d;
  }

 private:
  void read_identity(const YAML::Node& node, DeviceDefinition& d) {
    if (!node.IsDefined() || !y_.map(node, "identity", {"name", "title", "manufacturer", "reference", "notes"})) return;
    d.name = y_.text(node, "identity", "name", true).value_or("");
    d.title = y_.text(node, "identity", "title", false).value_or(d.name);
    d.manufacturer = y_.text(node, "identity", "manufacturer", false).value_or("");
    d.reference = y_.text(node, "identity", "reference", false).value_or("");
    d.notes = y_.text(node, "identity", "notes", false).value_or("");
  }

  void read_structure(const YAML::Node& node, Structure& s) {
    const std::string p = "structure";
    if (!node.IsDefined() ||
        !y_.map(node, p,
                {"material", "youngs_modulus_gpa", "youngs_modulus_tc_ppm_per_k", "poisson_ratio", "density_kg_m3",
                 "length_um", "width_um", "thickness_um", "proof_mass_area_fraction", "suspension"}))
      return;
    y_.text(node, p, "material", false);
    s.youngs_modulus_pa = y_.number(node, p, "youngs_modulus_gpa", true, Bounds::positive()).value_or(1.0) * 1e9;
    s.youngs_modulus_tc_per_k = y_.number_or(node, p, "youngs_modulus_tc_ppm_per_k", -60.0) * kPpm;
    s.poisson_ratio = y_.number(node, p, "poisson_ratio", true, Bounds::between(0.0, 0.5)).value_or(0.0);
    s.density_kg_m3 = y_.number(node, p, "density_kg_m3", true, Bounds::positive()).value_or(1.0);
    s.length_m = y_.number(node, p, "length_um", true, Bounds::positive()).value_or(1.0) * 1e-6;
    s.width_m = y_.number(node, p, "width_um", true, Bounds::positive()).value_or(1.0) * 1e-6;
    s.thickness_m = y_.number(node, p, "thickness_um", true, Bounds::positive()).value_or(1.0) * 1e-6;
    s.proof_mass_area_fraction = y_.number(node, p, "proof_mass_area_fraction", true, {0.0, 1.0, true}).value_or(0.5);
    const YAML::Node suspension = y_.child(node, p, "suspension", false);
    if (suspension.IsDefined() && y_.map(suspension, p + ".suspension", {"beams_per_mode", "beam_width_um"})) {
      const std::string sp = p + ".suspension";
      if (auto beams = y_.number(suspension, sp, "beams_per_mode", false, Bounds::between(1, 1024))) {
        if (*beams != static_cast<int>(*beams))
          y_.problem(y_.child(suspension, sp, "beams_per_mode", false), sp + ".beams_per_mode",
                     "expected a whole number of beams");
        s.beams_per_mode = static_cast<int>(*beams);
      }
      s.beam_width_m = y_.number_or(suspension, sp, "beam_width_um", s.beam_width_m * 1e6, Bounds::positive()) * 1e-6;
    }
  }

  void read_mode(const YAML::Node& node, const std::string& p, double tce, Mode& m) {
    if (!node.IsDefined() || !y_.map(node, p,
                                     {"frequency_hz", "quality_factor", "frequency_tc_ppm_per_k",
                                      "frequency_tc2_ppb_per_k2", "quality_factor_exponent"}))
      return;
    m.frequency_hz = y_.number(node, p, "frequency_hz", true, Bounds::positive()).value_or(1.0);
    m.quality_factor = y_.number(node, p, "quality_factor", true, Bounds::positive()).value_or(1.0);
    m.frequency_tc_per_k = y_.number_or(node, p, "frequency_tc_ppm_per_k", tce / kPpm / 2.0) * kPpm;
    m.frequency_tc2_per_k2 = y_.number_or(node, p, "frequency_tc2_ppb_per_k2", 0.0) * 1e-9;
    m.quality_factor_exponent = y_.number_or(node, p, "quality_factor_exponent", 1.0, Bounds::between(-10, 10));
  }

  void read_modes(const YAML::Node& node, PhysicsConfig& physics) {
    if (!node.IsDefined() || !y_.map(node, "modes", {"drive", "sense"})) return;
    const double tce = physics.structure.youngs_modulus_tc_per_k;
    read_mode(y_.child(node, "modes", "drive", true), "modes.drive", tce, physics.drive);
    const YAML::Node sense = y_.child(node, "modes", "sense", true);
    read_mode(sense, "modes.sense", tce, physics.sense);
    if (sense.IsMap() && physics.sense.frequency_hz == physics.drive.frequency_hz)
      y_.problem(y_.child(sense, "modes.sense", "frequency_hz", false), "modes.sense.frequency_hz",
                 "equals the drive frequency; the open-loop sense model needs a mode split");
  }

  void read_electronics(const YAML::Node& node, Electronics& e) {
    const std::string p = "electronics";
    if (!node.IsDefined() ||
        !y_.map(node, p,
                {"drive_amplitude_um", "quadrature_dps", "quadrature_tc_ppm_per_k", "demodulation_phase_error_mrad"}))
      return;
    e.drive_amplitude_m = y_.number(node, p, "drive_amplitude_um", true, Bounds::positive()).value_or(1.0) * 1e-6;
    e.quadrature_rad_s = y_.number_or(node, p, "quadrature_dps", 0.0) * kRadPerDeg;
    e.quadrature_tc_per_k = y_.number_or(node, p, "quadrature_tc_ppm_per_k", 0.0) * kPpm;
    e.demodulation_phase_error_rad =
        y_.number_or(node, p, "demodulation_phase_error_mrad", 0.0, Bounds::between(-1500, 1500)) * 1e-3;
  }

  void read_thermal(const YAML::Node& node, const std::string& p, Thermal& t) {
    if (!node.IsDefined() || !y_.map(node, p, {"die_time_constant_s", "sensor_time_constant_s"})) return;
    t.die_time_constant_s = y_.number_or(node, p, "die_time_constant_s", 0.0, Bounds::non_negative());
    t.sensor_time_constant_s = y_.number_or(node, p, "sensor_time_constant_s", 0.0, Bounds::non_negative());
  }

  void read_channels(const YAML::Node& node, std::vector<ChannelSpec>& channels) {
    if (!node.IsDefined()) return;
    if (!node.IsSequence()) {
      y_.problem(node, "channels", "expected a list of channels ({name, role, unit, ...})");
      return;
    }
    std::map<std::string, int> role_lines;
    for (std::size_t i = 0; i < node.size(); ++i) {
      const YAML::Node c = node[i];
      const std::string p = "channels[" + std::to_string(i) + "]";
      if (!y_.map(c, p, {"name", "role", "unit", "range", "resolution", "noise", "scale_factor_mv_per_dps"})) continue;
      ChannelSpec spec;
      spec.name = y_.text(c, p, "name", true).value_or("");
      spec.role = y_.text(c, p, "role", true).value_or("");
      spec.unit = y_.text(c, p, "unit", true).value_or("");
      if (spec.role.empty() || spec.unit.empty()) continue;
      if (std::find(kRoles.begin(), kRoles.end(), spec.role) == kRoles.end()) {
        y_.problem(y_.child(c, p, "role", false), p + ".role",
                   "unknown role '" + spec.role + "'; expected one of: rate, temperature, drive_frequency");
        continue;
      }
      if (const auto [it, inserted] = role_lines.emplace(spec.role, YamlFields::line_of(c)); !inserted) {
        y_.problem(y_.child(c, p, "role", false), p + ".role",
                   "role '" + spec.role + "' already used by the channel on line " + std::to_string(it->second));
        continue;
      }
      const auto unit = find_unit(spec.unit);
      const Quantity quantity = quantity_of_role(spec.role);
      if (!unit || unit->quantity != quantity) {
        y_.problem(
            y_.child(c, p, "unit", false), p + ".unit",
            "unit '" + spec.unit + "' does not fit role '" + spec.role + "'; expected " + quantity_name(quantity));
        continue;
      }
      if (auto range = y_.numbers(c, p, "range", false)) {
        if (range->size() != 2 || !((*range)[0] < (*range)[1])) {
          y_.problem(y_.child(c, p, "range", false), p + ".range", "expected [min, max] with min < max");
        } else {
          spec.range_min = to_internal((*range)[0], *unit);
          spec.range_max = to_internal((*range)[1], *unit);
        }
      }
      spec.resolution = y_.number_or(c, p, "resolution", 0.0, Bounds::non_negative()) * unit->scale;
      spec.noise = y_.number_or(c, p, "noise", 0.0, Bounds::non_negative()) * unit->scale;
      spec.scale_factor_mv_per_dps = y_.number_or(c, p, "scale_factor_mv_per_dps", 0.0, Bounds::non_negative());
      if (spec.role == "rate" && !(spec.range_min < 0.0 && spec.range_max > 0.0))
        y_.problem(y_.child(c, p, "range", false), p + ".range", "the rate range must contain 0");
      channels.push_back(spec);
    }
    for (const char* required : {"rate", "temperature"})
      if (!role_lines.count(required))
        y_.problem(node, "channels", std::string("no channel with role '") + required + "' (required)");
  }

  void read_error_model(const YAML::Node& node, error_model::Config& config) {
    const std::string p = "error_model";
    if (!node.IsDefined() || !y_.map(node, p, {"bias_polynomial", "scale_factor_polynomial_ppm", "noise"})) return;
    const YAML::Node bias = y_.child(node, p, "bias_polynomial", false);
    if (bias.IsDefined() && y_.map(bias, p + ".bias_polynomial", {"unit", "coefficients"})) {
      const std::string bp = p + ".bias_polynomial";
      const auto unit_text = y_.text(bias, bp, "unit", true);
      const auto coefficients = y_.numbers(bias, bp, "coefficients", true);
      const auto unit = unit_text ? find_unit(*unit_text) : std::nullopt;
      if (unit_text && (!unit || unit->quantity != Quantity::AngularRate))
        y_.problem(y_.child(bias, bp, "unit", false), bp + ".unit",
                   "unit '" + *unit_text + "' is not " + quantity_name(Quantity::AngularRate));
      else if (unit && coefficients)
        for (double c : *coefficients) config.bias_polynomial_rad_s.push_back(c * unit->scale);
    }
    if (auto sf = y_.numbers(node, p, "scale_factor_polynomial_ppm", false))
      for (double c : *sf) config.scale_factor_polynomial.push_back(c * kPpm);
    if (const YAML::Node noise = y_.child(node, p, "noise", false); noise.IsDefined())
      read_noise(noise, p + ".noise", kGyroNoise, config.noise);
  }

  void read_noise(const YAML::Node& noise, const std::string& np, const NoiseKeys& keys, error_model::NoiseTerms& n) {
    if (!y_.map(noise, np,
                {keys.white, keys.instability, keys.random_walk, "flicker_correlation_times_s",
                 "flicker_poles_per_decade", "gauss_markov"}))
      return;
    if (const YAML::Node gm = y_.child(noise, np, "gauss_markov", false); gm.IsDefined()) {
      const std::string expected = std::string("expected a list of {") + keys.gauss_markov_sigma + ": S, tau_s: T}";
      if (!gm.IsSequence()) y_.problem(gm, np + ".gauss_markov", expected);
      for (std::size_t i = 0; gm.IsSequence() && i < gm.size(); ++i) {
        const std::string gp = np + ".gauss_markov[" + std::to_string(i) + "]";
        if (!y_.map(gm[i], gp, {keys.gauss_markov_sigma, "tau_s"})) continue;
        const auto sigma = y_.number(gm[i], gp, keys.gauss_markov_sigma, true, Bounds::positive());
        const auto tau = y_.number(gm[i], gp, "tau_s", true, Bounds::positive());
        if (sigma && tau) n.gauss_markov.push_back({*tau, *sigma * keys.instability_scale});
      }
    }
    n.arw_rad_sqrt_s = y_.number_or(noise, np, keys.white, 0.0, Bounds::non_negative()) * keys.white_scale;
    n.bias_instability_rad_s =
        y_.number_or(noise, np, keys.instability, 0.0, Bounds::non_negative()) * keys.instability_scale;
    n.rate_random_walk_rad_s_sqrt_s =
        y_.number_or(noise, np, keys.random_walk, 0.0, Bounds::non_negative()) * keys.random_walk_scale;
    n.flicker_poles_per_decade =
        y_.number_or(noise, np, "flicker_poles_per_decade", n.flicker_poles_per_decade, Bounds::between(0.5, 20));
    if (auto taus = y_.numbers(noise, np, "flicker_correlation_times_s", false)) {
      if (taus->size() != 2 || !((*taus)[0] > 0.0) || !((*taus)[0] < (*taus)[1]))
        y_.problem(y_.child(noise, np, "flicker_correlation_times_s", false), np + ".flicker_correlation_times_s",
                   "expected [min, max] with 0 < min < max");
      else
        n.flicker_tau_min_s = (*taus)[0], n.flicker_tau_max_s = (*taus)[1];
    }
  }

  ImuDefinition read_imu(const YAML::Node& node, double reference_temp_c) {
    const std::string p = "imu";
    ImuDefinition imu;
    imu.reference_temp_c = reference_temp_c;
    if (!y_.map(node, p, {"up_direction", "gravity_mps2", "instances"})) return imu;
    if (const auto up = y_.numbers(node, p, "up_direction", false)) {
      if (up->size() != 3 || Eigen::Vector3d((*up)[0], (*up)[1], (*up)[2]).norm() == 0.0)
        y_.problem(y_.child(node, p, "up_direction", false), p + ".up_direction",
                   "expected [x, y, z], the 'up' direction in the IMU's axes (not all zero)");
      else
        imu.up = Eigen::Vector3d((*up)[0], (*up)[1], (*up)[2]).normalized();
    }
    imu.gravity_mps2 = y_.number_or(node, p, "gravity_mps2", kStandardGravity, Bounds::positive());
    const YAML::Node instances = y_.child(node, p, "instances", true);
    if (!instances.IsDefined()) return imu;
    if (!instances.IsSequence() || instances.size() == 0 || instances.size() > kMaxImuInstances) {
      y_.problem(instances, p + ".instances",
                 "expected a list of 1 to " + std::to_string(kMaxImuInstances) +
                     " IMU instances ({device_id, thermal, temperature_sensor, gyro, accel})");
      return imu;
    }
    for (std::size_t i = 0; i < instances.size(); ++i)
      imu.instances.push_back(read_imu_instance(instances[i], p + ".instances[" + std::to_string(i) + "]"));
    return imu;
  }

  ImuInstance read_imu_instance(const YAML::Node& node, const std::string& p) {
    ImuInstance instance;
    if (!y_.map(node, p, {"device_id", "thermal", "temperature_sensor", "gyro", "accel"})) return instance;
    if (const auto id = y_.number(node, p, "device_id", false, Bounds::between(0.0, 4294967295.0))) {
      if (*id != std::floor(*id))
        y_.problem(y_.child(node, p, "device_id", false), p + ".device_id", "expected a whole number");
      else
        instance.device_id = *id;
    }
    Thermal thermal;
    read_thermal(y_.child(node, p, "thermal", false), p + ".thermal", thermal);
    instance.die_time_constant_s = thermal.die_time_constant_s;
    instance.sensor_time_constant_s = thermal.sensor_time_constant_s;
    const std::string tp = p + ".temperature_sensor";
    if (const YAML::Node t = y_.child(node, p, "temperature_sensor", false);
        t.IsDefined() && y_.map(t, tp, {"noise_c", "resolution_c"})) {
      instance.temperature_noise_c = y_.number_or(t, tp, "noise_c", 0.0, Bounds::non_negative());
      instance.temperature_resolution_c = y_.number_or(t, tp, "resolution_c", 0.0, Bounds::non_negative());
    }
    read_imu_sensor(y_.child(node, p, "gyro", true), p + ".gyro", kGyroNoise, "bias_polynomial_dps", kRadPerDeg,
                    instance.gyro);
    read_imu_sensor(y_.child(node, p, "accel", true), p + ".accel", kAccelNoise, "bias_polynomial_mg",
                    1e-3 * kStandardGravity, instance.accel);
    return instance;
  }

  // A sensor block {noise, x, y, z}: an axis's own noise replaces the sensor's.
  void read_imu_sensor(const YAML::Node& node, const std::string& p, const NoiseKeys& noise_keys,
                       const std::string& bias_key, double bias_scale, ImuSensor& sensor) {
    if (!node.IsDefined() || !y_.map(node, p, {"noise", "x", "y", "z"})) return;
    error_model::NoiseTerms shared;
    if (const YAML::Node noise = y_.child(node, p, "noise", false); noise.IsDefined())
      read_noise(noise, p + ".noise", noise_keys, shared);
    for (std::size_t a = 0; a < 3; ++a) {
      const std::string name(1, "xyz"[a]), ap = p + "." + name;
      ImuAxis& axis = sensor.axes[a];
      axis.noise = shared;
      const YAML::Node n = y_.child(node, p, name, true);
      if (!n.IsDefined() || !y_.map(n, ap, {bias_key, "scale_factor_polynomial_ppm", "lag_s", "noise"})) continue;
      if (const auto bias = y_.numbers(n, ap, bias_key, true))
        for (double c : *bias) axis.bias_polynomial.push_back(c * bias_scale);
      if (const auto sf = y_.numbers(n, ap, "scale_factor_polynomial_ppm", false))
        for (double c : *sf) axis.scale_factor_polynomial.push_back(c * kPpm);
      axis.lag_s = y_.number_or(n, ap, "lag_s", 0.0, Bounds::non_negative());
      if (const YAML::Node own = y_.child(n, ap, "noise", false); own.IsDefined()) {
        axis.noise = error_model::NoiseTerms{};
        read_noise(own, ap + ".noise", noise_keys, axis.noise);
      }
    }
  }

  // Bounds from the physics rather than per-key ranges: over the temperature range the device is
  // used in (its temperature channel's range, else -55..125 degC) both modes keep a positive
  // frequency and Q, and every model response is finite.
  void check_responses(const YAML::Node& root, const DeviceDefinition& d, const DeviceModel& model) {
    double lo = -55.0, hi = 125.0;
    for (const auto& c : d.channels)
      if (c.role == "temperature" && std::isfinite(c.range_min) && std::isfinite(c.range_max)) {
        lo = std::max(c.range_min, -273.0);
        hi = c.range_max;
      }
    const YAML::Node modes = y_.child(root, "", "modes", false);
    constexpr int kPoints = 64;
    for (int i = 0; i <= kPoints; ++i) {
      const double t = lo + (hi - lo) * i / kPoints;
      for (const auto* mode : {&d.physics.drive, &d.physics.sense}) {
        const std::string name = mode == &d.physics.drive ? "drive" : "sense";
        const double f = model.frequency_hz(*mode, t), q = model.quality_factor(*mode, t);
        if (!(f > 0.0) || !std::isfinite(f) || !(q > 0.0) || !std::isfinite(q)) {
          std::ostringstream msg;
          msg << "at " << t << " degC (inside the device's temperature range [" << lo << ", " << hi << "] degC) the "
              << name << " mode would have frequency " << f << " Hz and Q " << q
              << "; its temperature coefficients are not physical";
          const YAML::Node m = y_.child(modes, "modes", name, false);
          y_.problem(m.IsDefined() ? m : root, "modes." + name, msg.str());
          return;
        }
      }
      const auto r = model.response(t);
      const auto sense = model.sense_response(t);
      if (!std::isfinite(r.scale_factor) || !std::isfinite(r.bias_rad_s) || !std::isfinite(r.drive_frequency_hz) ||
          !std::isfinite(sense.amplitude_m_per_rad_s) || !std::isfinite(sense.phase_lag_rad) ||
          !std::isfinite(model.drive_force_n(t))) {
        std::ostringstream msg;
        msg << "the device model gives a non-finite response at " << t << " degC (scale factor " << r.scale_factor
            << ", bias " << r.bias_rad_s << " rad/s); check the modes, electronics and reference_temp_c";
        y_.problem(root, "modes", msg.str());
        return;
      }
    }
  }

  void check_consistency(const YAML::Node& root, DeviceDefinition& d) {
    const YAML::Node structure = y_.child(root, "", "structure", false);
    const YAML::Node suspension = y_.child(structure, "structure", "suspension", false);
    try {
      const DeviceModel model(d.physics);
      check_responses(root, d, model);
      const double die_size = std::max(d.physics.structure.length_m, d.physics.structure.width_m);
      for (const auto* mode : {&d.physics.drive, &d.physics.sense}) {
        const double beam = model.implied_beam_length_m(*mode);
        if (beam > die_size) {
          std::ostringstream msg;
          msg << "the " << (mode == &d.physics.drive ? "drive" : "sense")
              << " stiffness k = " << model.stiffness_n_per_m(*mode) << " N/m needs suspension beams " << beam * 1e6
              << " um long, longer than the die (" << die_size * 1e6
              << " um); use fewer or narrower beams or a larger proof-mass fraction";
          y_.problem(suspension.IsDefined() ? suspension : structure, "structure.suspension", msg.str());
        }
      }
    } catch (const ConfigError& e) {
      for (auto problem : e.problems()) {
        problem.where.file = y_.file();
        problem.where.line = YamlFields::line_of(root);
        problems_.push_back(problem);
      }
    }
  }

  YamlFields y_;
  std::vector<Diagnostic>& problems_;
};

std::vector<std::string> effect_names() {
  std::vector<std::string> names;
  for (const auto& e : effect_catalogue()) names.push_back(e.name);
  return names;
}

std::string number_text(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

}  // namespace

const ChannelSpec* DeviceDefinition::find_channel(const std::string& role) const {
  for (const auto& c : channels)
    if (c.role == role) return &c;
  return nullptr;
}

void require_single_axis(const DeviceDefinition& d) {
  if (d.imu)
    throw ConfigError({d.source, 0, "imu"}, "device '" + d.name +
                                                "' describes a whole IMU (imu:); this needs a single-axis gyro "
                                                "(structure, modes, channels, error_model)");
}

DeviceDefinition parse_device(const std::string& yaml_text, const std::string& file) {
  const YAML::Node root = load_yaml_checked(yaml_text, file);
  std::vector<Diagnostic> problems;
  DeviceReader reader(file, problems);
  DeviceDefinition d = reader.read(root);
  if (!problems.empty()) throw ConfigError(std::move(problems));
  return d;
}

DeviceDefinition load_device_file(const std::filesystem::path& path) {
  const YAML::Node root = load_yaml_file(path, "device file");
  std::vector<Diagnostic> problems;
  DeviceReader reader(path.string(), problems);
  DeviceDefinition d = reader.read(root);
  if (!problems.empty()) throw ConfigError(std::move(problems));
  return d;
}

std::vector<std::filesystem::path> list_device_files(const std::filesystem::path& dir) {
  if (!std::filesystem::is_directory(dir))
    throw ConfigError({dir.string(), 0, ""},
                      "devices directory does not exist (use --devices-dir or DRIFTLAB_DEVICES_DIR)");
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    if (entry.is_regular_file() && entry.path().extension() == ".yaml") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

std::filesystem::path find_device_file(const std::string& argument, const std::filesystem::path& dir) {
  const std::filesystem::path path(argument);
  if (std::filesystem::exists(path)) return path;
  const std::string file_name = path.filename().string();
  const auto in_dir = dir / (path.extension() == ".yaml" ? file_name : file_name + ".yaml");
  return std::filesystem::exists(in_dir) ? in_dir : path;
}

void parse_effects(const YAML::Node& node, const std::string& file, const std::string& path,
                   error_model::Effects& effects, std::vector<Diagnostic>& problems) {
  YamlFields y(file, problems);
  if (!y.map(node, path, effect_names())) return;
  for (const auto& entry : effect_catalogue()) {
    const YAML::Node params = y.child(node, path, entry.name, false);
    if (!params.IsDefined()) continue;
    const std::string p = YamlFields::join(path, entry.name);
    std::vector<std::string> keys;
    for (const auto& k : entry.keys) keys.push_back(k.key);
    if (!y.map(params, p, keys)) continue;
    std::vector<std::vector<double>> values;
    bool complete = true;
    for (const auto& key : entry.keys) {
      std::vector<double> v;
      if (key.list) {
        v = y.numbers(params, p, key.key, true).value_or(std::vector<double>{});
        if (v.empty()) complete = false;
      } else if (auto x = y.number(params, p, key.key, true, key.positive ? Bounds::positive() : Bounds{})) {
        v.push_back(*x);
      } else {
        complete = false;
      }
      for (double& x : v) x *= key.to_si;
      values.push_back(std::move(v));
    }
    if (complete) error_model::set_effect(effects, entry.name, values);
  }
}

void apply_effect_option(const std::string& text, error_model::Effects& effects) {
  const std::string field = "--effect " + text;
  const auto colon = text.find(':');
  const std::string name = text.substr(0, colon);
  std::string yaml = "{" + name + ": {";
  if (colon != std::string::npos) {
    int depth = 0;
    std::string item;
    bool first = true;
    auto flush = [&] {
      const auto eq = item.find('=');
      if (eq == std::string::npos)
        throw ConfigError({"", 0, field}, "expected NAME:key=value,key=value; got '" + item + "'");
      yaml += (first ? "" : ", ") + item.substr(0, eq) + ": " + item.substr(eq + 1);
      first = false;
      item.clear();
    };
    for (char ch : text.substr(colon + 1)) {
      if (ch == '[') ++depth;
      if (ch == ']') --depth;
      if (ch == ',' && depth == 0)
        flush();
      else
        item += ch;
    }
    if (!item.empty()) flush();
  }
  yaml += "}}";
  std::vector<Diagnostic> problems;
  const YAML::Node node = load_yaml_checked(yaml, "--effect " + field);  // syntax, repeated keys
  parse_effects(node, "", "", effects, problems);
  for (auto& p : problems) {
    p.where.line = 0;
    p.where.field = "--effect " + p.where.field;
  }
  if (!problems.empty()) throw ConfigError(std::move(problems));
}

std::vector<std::string> describe_effects(const error_model::Effects& e) {
  std::vector<std::string> out;
  for (const auto& [name, si_values] : error_model::effect_parameters(e)) {
    const auto& keys = effect_info(name).keys;
    std::string text = name + "{";
    for (std::size_t i = 0; i < keys.size(); ++i) {
      text += (i ? ", " : "") + keys[i].key + "=";
      std::string list;
      for (double v : si_values[i]) list += (list.empty() ? "" : ", ") + number_text(v / keys[i].to_si);
      text += keys[i].list ? "[" + list + "]" : list;
    }
    out.push_back(text + "}");
  }
  return out;
}

}  // namespace driftlab::devices
