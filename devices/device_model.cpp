#include "devices/device_model.hpp"

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "framework/error.hpp"

namespace driftlab::devices {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

void require_positive(std::vector<Diagnostic>& problems, const std::string& field, double value) {
  if (!(value > 0.0) || !std::isfinite(value))
    problems.push_back({{"", 0, field}, "must be a positive finite number, got " + std::to_string(value)});
}

}  // namespace

DeviceModel::DeviceModel(PhysicsConfig config) : config_(std::move(config)) {
  std::vector<Diagnostic> problems;
  const Structure& s = config_.structure;
  require_positive(problems, "structure.youngs_modulus", s.youngs_modulus_pa);
  require_positive(problems, "structure.density", s.density_kg_m3);
  require_positive(problems, "structure.length", s.length_m);
  require_positive(problems, "structure.width", s.width_m);
  require_positive(problems, "structure.thickness", s.thickness_m);
  require_positive(problems, "structure.proof_mass_area_fraction", s.proof_mass_area_fraction);
  require_positive(problems, "structure.suspension.beam_width", s.beam_width_m);
  if (s.beams_per_mode < 1) problems.push_back({{"", 0, "structure.suspension.beams_per_mode"}, "must be >= 1"});
  require_positive(problems, "modes.drive.frequency", config_.drive.frequency_hz);
  require_positive(problems, "modes.sense.frequency", config_.sense.frequency_hz);
  require_positive(problems, "modes.drive.quality_factor", config_.drive.quality_factor);
  require_positive(problems, "modes.sense.quality_factor", config_.sense.quality_factor);
  require_positive(problems, "electronics.drive_amplitude", config_.electronics.drive_amplitude_m);
  if (config_.drive.frequency_hz == config_.sense.frequency_hz)
    problems.push_back({{"", 0, "modes"}, "drive and sense frequencies are equal; the open-loop model needs a split"});
  if (!problems.empty()) throw ConfigError(std::move(problems));

  const SenseResponse reference = sense_response(config_.reference_temp_c);
  reference_amplitude_ = reference.amplitude_m_per_rad_s;
  reference_phase_ = reference.phase_lag_rad;
}

double DeviceModel::proof_mass_kg() const {
  const Structure& s = config_.structure;
  return s.density_kg_m3 * s.length_m * s.width_m * s.thickness_m * s.proof_mass_area_fraction;
}

double DeviceModel::stiffness_n_per_m(const Mode& mode) const {
  const double w = kTwoPi * mode.frequency_hz;
  return proof_mass_kg() * w * w;
}

double DeviceModel::implied_beam_length_m(const Mode& mode) const {
  const Structure& s = config_.structure;
  const double per_length_cubed = s.beams_per_mode * s.youngs_modulus_pa * s.thickness_m * std::pow(s.beam_width_m, 3);
  return std::cbrt(per_length_cubed / stiffness_n_per_m(mode));
}

double DeviceModel::drive_force_n(double temp_c) const {
  return stiffness_n_per_m(config_.drive) * config_.electronics.drive_amplitude_m /
         quality_factor(config_.drive, temp_c);
}

double DeviceModel::frequency_hz(const Mode& mode, double temp_c) const {
  const double dt = temp_c - config_.reference_temp_c;
  return mode.frequency_hz * (1.0 + dt * (mode.frequency_tc_per_k + dt * mode.frequency_tc2_per_k2));
}

double DeviceModel::quality_factor(const Mode& mode, double temp_c) const {
  const double ratio = (config_.reference_temp_c + kZeroCelsiusK) / (temp_c + kZeroCelsiusK);
  return mode.quality_factor * std::pow(ratio, mode.quality_factor_exponent);
}

SenseResponse DeviceModel::sense_response(double drive_hz, double sense_hz, double sense_q, double drive_amplitude_m) {
  const double wd = kTwoPi * drive_hz;
  const double wy = kTwoPi * sense_hz;
  const double detuning = wy * wy - wd * wd;
  const double damping = wy * wd / sense_q;
  return {2.0 * wd * drive_amplitude_m / std::hypot(detuning, damping), std::atan2(damping, detuning)};
}

SenseResponse DeviceModel::sense_response(double temp_c) const {
  return sense_response(drive_frequency_hz(temp_c), sense_frequency_hz(temp_c), quality_factor(config_.sense, temp_c),
                        config_.electronics.drive_amplitude_m);
}

double DeviceModel::demodulation_phase_error_rad(double temp_c) const {
  return config_.electronics.demodulation_phase_error_rad + reference_phase_ - sense_response(temp_c).phase_lag_rad;
}

double DeviceModel::quadrature_rad_s(double temp_c) const {
  return config_.electronics.quadrature_rad_s *
         (1.0 + config_.electronics.quadrature_tc_per_k * (temp_c - config_.reference_temp_c));
}

error_model::DeviceResponse DeviceModel::response(double temp_c) const {
  const double drive_hz = drive_frequency_hz(temp_c);
  const SenseResponse sense =
      sense_response(drive_hz, sense_frequency_hz(temp_c), quality_factor(config_.sense, temp_c),
                     config_.electronics.drive_amplitude_m);
  const double theta = config_.electronics.demodulation_phase_error_rad + reference_phase_ - sense.phase_lag_rad;
  const double gain =
      sense.amplitude_m_per_rad_s / (reference_amplitude_ * std::cos(config_.electronics.demodulation_phase_error_rad));
  return {gain * std::cos(theta), gain * quadrature_rad_s(temp_c) * std::sin(theta), drive_hz};
}

}  // namespace driftlab::devices
