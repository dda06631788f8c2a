// Lumped two-degree-of-freedom model of a vibratory MEMS gyroscope (Li et al., Micromachines 2023,
// 14, 971, Fig. 1b): a drive mode x and a sense mode y of one modal mass m, each a mass-spring-damper,
// coupled by the Coriolis force and by quadrature stiffness. SI units, absolute temperature in degC.
//
//   m x'' + (m w_x / Q_x) x' + k_x x = F_d                  (drive, held at amplitude X0 by the loop)
//   m y'' + (m w_y / Q_y) y' + k_y y = -2 m W x' - k_yx x   (sense, open loop)
//
// Assumptions (stated once, used everywhere):
// - The drive loop (PLL + PI amplitude control) keeps x = X0 sin(w_d t) at the drive resonance,
//   w_d = w_x(T); X0 does not change with temperature.
// - The modal mass equals the Coriolis mass: m = rho * L * W * t * proof_mass_area_fraction, i.e. the
//   four proof masses fill that fraction of the die footprint at full thickness (the rest is anchors,
//   frames, electrodes and etch holes). Stiffness follows from mass and frequency, k = m (2 pi f)^2.
// - Consistency with the dimensions: each mode's stiffness is carried by n clamped-guided beams of
//   width w (in the direction of motion) and thickness t, k = n E t w^3 / L^3, so the implied beam
//   length L = (n E t w^3 / k)^(1/3) must fit within the die (checked when the file is loaded).
// - Temperature: f(T) = f0 (1 + a1 dT + a2 dT^2), dT = T - T0. For silicon a1 ~ TCE/2 ~ -30 ppm/K
//   (TCE ~ -60 ppm/K); the two modes get slightly different a1, so the split df(T) drifts.
//   Q(T) = Q0 ((T0 + 273.15) / (T + 273.15))^n: damping grows with temperature, Q falls.
//   Quadrature W_q(T) = W_q0 (1 + c_q dT) (thermal stress changes the coupling stiffness).
//
// Open-loop sense response at the drive frequency (steady state of the sense equation):
//   Y / W = 2 w_d X0 |H|,   |H| = 1 / sqrt((w_y^2 - w_d^2)^2 + (w_y w_d / Q_y)^2),
//   phase lag phi_y = atan2(w_y w_d / Q_y, w_y^2 - w_d^2).
// The quadrature force -k_yx x is in phase with x, 90 deg from the Coriolis force; as an equivalent
// rate W_q = k_yx / (2 m w_d). The demodulator reference is set at T0 to the Coriolis phase plus a
// phase error theta_e; at T the error is theta(T) = theta_e + phi_y(T0) - phi_y(T). Demodulated
// output, calibrated so the scale factor is 1 at T0:
//   W_out = g(T) (W cos theta(T) + W_q(T) sin theta(T)),   g(T) = |H(T)| / (|H(T0)| cos theta_e)
// so the scale factor s_dev(T) = g cos theta and the bias b_dev(T) = g W_q sin theta.
// Cost: O(1) per temperature (a few transcendental functions).
#pragma once

#include "models/error_model/error_model.hpp"

namespace driftlab::devices {

inline constexpr double kZeroCelsiusK = 273.15;

struct Structure {
  double youngs_modulus_pa = 169e9;
  double youngs_modulus_tc_per_k = -60e-6;  // TCE, 1/K (informative; modes carry their own a1)
  double poisson_ratio = 0.27;
  double density_kg_m3 = 2328.3;
  double length_m = 3015e-6;
  double width_m = 2331e-6;
  double thickness_m = 60e-6;
  double proof_mass_area_fraction = 0.3;  // moving fraction of the footprint, 0..1
  int beams_per_mode = 16;
  double beam_width_m = 5e-6;
};

struct Mode {
  double frequency_hz = 0.0;             // f0 at T0
  double quality_factor = 0.0;           // Q0 at T0
  double frequency_tc_per_k = -30e-6;    // a1, 1/K
  double frequency_tc2_per_k2 = 0.0;     // a2, 1/K^2
  double quality_factor_exponent = 1.0;  // n in Q(T) = Q0 (T0_K / T_K)^n
};

struct Electronics {
  double drive_amplitude_m = 5e-6;            // X0
  double quadrature_rad_s = 0.0;              // W_q at T0, rad/s equivalent rate
  double quadrature_tc_per_k = 0.0;           // c_q, 1/K
  double demodulation_phase_error_rad = 0.0;  // theta_e
};

struct PhysicsConfig {
  double reference_temp_c = 25.0;  // T0: calibration temperature, degC
  Structure structure;
  Mode drive;
  Mode sense;
  Electronics electronics;
};

// Steady-state open-loop sense response at one temperature.
struct SenseResponse {
  double amplitude_m_per_rad_s;  // Y / W = 2 w_d X0 |H|
  double phase_lag_rad;          // phi_y
};

class DeviceModel {
 public:
  // Throws ConfigError when a parameter is non-physical (non-positive frequency, Q, mass, ...).
  explicit DeviceModel(PhysicsConfig config);

  const PhysicsConfig& config() const { return config_; }

  double proof_mass_kg() const;
  double stiffness_n_per_m(const Mode& mode) const;      // k = m (2 pi f0)^2
  double implied_beam_length_m(const Mode& mode) const;  // (n E t w^3 / k)^(1/3)
  double drive_force_n(double temp_c) const;             // k_x X0 / Q_x(T) at resonance

  double frequency_hz(const Mode& mode, double temp_c) const;
  double quality_factor(const Mode& mode, double temp_c) const;
  double drive_frequency_hz(double temp_c) const { return frequency_hz(config_.drive, temp_c); }
  double sense_frequency_hz(double temp_c) const { return frequency_hz(config_.sense, temp_c); }
  double split_hz(double temp_c) const { return sense_frequency_hz(temp_c) - drive_frequency_hz(temp_c); }

  // The closed form above for given modes (also used directly by tests and describe).
  static SenseResponse sense_response(double drive_hz, double sense_hz, double sense_q, double drive_amplitude_m);
  SenseResponse sense_response(double temp_c) const;

  double demodulation_phase_error_rad(double temp_c) const;  // theta(T)
  double quadrature_rad_s(double temp_c) const;              // W_q(T)

  // s_dev(T), b_dev(T) and the drive frequency, for the error model.
  error_model::DeviceResponse response(double temp_c) const;

 private:
  PhysicsConfig config_;
  double reference_amplitude_ = 1.0;  // |Y/W| at T0
  double reference_phase_ = 0.0;      // phi_y(T0)
};

}  // namespace driftlab::devices
