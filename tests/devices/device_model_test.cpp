#include "devices/device_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>

#include "devices/device_file.hpp"

namespace driftlab::devices {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

PhysicsConfig fmvmg_physics() {
  return load_device_file(std::string(DRIFTLAB_SOURCE_DIR) + "/devices/fmvmg.yaml").physics;
}

// Steady-state amplitude and phase lag of y'' + (w_y/Q) y' + w_y^2 y = -2 W x', x = X0 sin(w_d t),
// by RK4 integration (independent of the closed form) followed by a lock-in over whole cycles.
SenseResponse integrate_sense(double drive_hz, double sense_hz, double q, double x0, double rate) {
  const double wd = kTwoPi * drive_hz, wy = kTwoPi * sense_hz;
  const int steps_per_cycle = 200;
  const double h = 1.0 / (drive_hz * steps_per_cycle);
  const int settle_cycles = static_cast<int>(12.0 * 2.0 * q / wy * drive_hz) + 1;  // 12 decay times
  auto accel = [&](double t, double y, double v) {
    return -2.0 * rate * x0 * wd * std::cos(wd * t) - wy / q * v - wy * wy * y;
  };
  double t = 0, y = 0, v = 0;
  double in_phase = 0, quadrature = 0;
  const int lock_cycles = 20;
  for (int cycle = 0; cycle < settle_cycles + lock_cycles; ++cycle) {
    for (int s = 0; s < steps_per_cycle; ++s) {
      if (cycle >= settle_cycles) {
        in_phase += y * std::cos(wd * t);
        quadrature += y * std::sin(wd * t);
      }
      const double k1y = v, k1v = accel(t, y, v);
      const double k2y = v + 0.5 * h * k1v, k2v = accel(t + 0.5 * h, y + 0.5 * h * k1y, v + 0.5 * h * k1v);
      const double k3y = v + 0.5 * h * k2v, k3v = accel(t + 0.5 * h, y + 0.5 * h * k2y, v + 0.5 * h * k2v);
      const double k4y = v + h * k3v, k4v = accel(t + h, y + h * k3y, v + h * k3v);
      y += h / 6.0 * (k1y + 2 * k2y + 2 * k3y + k4y);
      v += h / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v);
      t += h;
    }
  }
  const double samples = lock_cycles * steps_per_cycle;
  const double a = 2.0 * in_phase / samples, b = 2.0 * quadrature / samples;
  // The Coriolis force -2 W X0 w_d cos(w_d t) is the reference; y = -A cos(w_d t - phi).
  return {std::hypot(a, b) / std::abs(rate), std::atan2(-b, -a)};
}

TEST(DeviceModel, SenseAmplitudeMatchesTheIntegratedTwoDofEquations) {
  constexpr double kIntegrationTolerance = 2e-3;  // RK4 at 200 steps/cycle, lock-in over 20 cycles
  constexpr double kX0 = 5e-6, kRate = 1.0;
  struct Case {
    double split_hz, q;
  };
  for (const Case c : {Case{146.0, 30.0}, Case{40.0, 60.0}, Case{5.8, 100.0}, Case{-80.0, 50.0}}) {
    const double drive = 3000.0, sense = drive + c.split_hz;
    const SenseResponse expected = DeviceModel::sense_response(drive, sense, c.q, kX0);
    const SenseResponse simulated = integrate_sense(drive, sense, c.q, kX0, kRate);
    EXPECT_NEAR(simulated.amplitude_m_per_rad_s / expected.amplitude_m_per_rad_s, 1.0, kIntegrationTolerance)
        << "split " << c.split_hz << " Hz, Q " << c.q;
    EXPECT_NEAR(simulated.phase_lag_rad, expected.phase_lag_rad, kIntegrationTolerance)
        << "split " << c.split_hz << " Hz, Q " << c.q;
  }
}

TEST(DeviceModel, SenseAmplitudeFollowsTheComplexTransferFunctionOverSplitAndQ) {
  constexpr double kRoundingTolerance = 1e-12;  // a handful of operations on doubles
  constexpr double kX0 = 5e-6;
  for (double split : {1.0, 5.8, 50.0, 146.0, 400.0}) {
    for (double q : {100.0, 1000.0, 2500.0, 20000.0}) {
      const double wd = kTwoPi * 30740.0, wy = kTwoPi * (30740.0 + split);
      const std::complex<double> h = 1.0 / std::complex<double>(wy * wy - wd * wd, wy * wd / q);
      const SenseResponse r = DeviceModel::sense_response(30740.0, 30740.0 + split, q, kX0);
      EXPECT_NEAR(r.amplitude_m_per_rad_s / (2.0 * wd * kX0 * std::abs(h)), 1.0, kRoundingTolerance);
      EXPECT_NEAR(r.phase_lag_rad, -std::arg(h), kRoundingTolerance);
    }
  }
}

TEST(DeviceModel, SenseAmplitudeReachesTheMatchedAndWideSplitLimits) {
  constexpr double kRoundingTolerance = 1e-12;  // a zero split makes the general form the matched one
  constexpr double kLimitTolerance = 3e-3;      // wide split: neglected df / (2 f) = 2.4e-3 and f / (Q df)
  constexpr double kX0 = 5e-6;
  const double f = 30740.0, q = 2500.0;
  const SenseResponse matched = DeviceModel::sense_response(f, f, q, kX0);
  EXPECT_NEAR(matched.amplitude_m_per_rad_s / (2.0 * kX0 * q / (kTwoPi * f)), 1.0, kRoundingTolerance);
  EXPECT_NEAR(matched.phase_lag_rad, std::numbers::pi / 2, kRoundingTolerance);
  const double split = 146.0;
  const SenseResponse wide = DeviceModel::sense_response(f, f + split, 1e7, kX0);
  EXPECT_NEAR(wide.amplitude_m_per_rad_s / (kX0 / (kTwoPi * split)), 1.0, kLimitTolerance);
}

TEST(DeviceModel, FrequenciesMoveWithTheConfiguredCoefficients) {
  constexpr double kRoundingTolerance = 1e-9;  // Hz, on ~3e4 Hz values
  PhysicsConfig physics = fmvmg_physics();
  physics.drive.frequency_tc2_per_k2 = -2e-9;
  const DeviceModel model(physics);
  const auto& d = physics.drive;
  const auto& s = physics.sense;
  for (double t : {-30.0, 0.0, 25.0, 60.0}) {
    const double dt = t - physics.reference_temp_c;
    EXPECT_NEAR(model.drive_frequency_hz(t),
                d.frequency_hz * (1 + d.frequency_tc_per_k * dt + d.frequency_tc2_per_k2 * dt * dt),
                kRoundingTolerance);
    EXPECT_NEAR(model.sense_frequency_hz(t), s.frequency_hz * (1 + s.frequency_tc_per_k * dt), kRoundingTolerance);
  }
  // The split drifts by f_s a_s - f_d a_d per kelvin (linear part).
  const double slope = (model.split_hz(26.0) - model.split_hz(24.0)) / 2.0;
  EXPECT_NEAR(slope, s.frequency_hz * s.frequency_tc_per_k - d.frequency_hz * d.frequency_tc_per_k, kRoundingTolerance);
  EXPECT_LT(slope, 0.0);  // the FMVMG file gives the sense mode the larger coefficient
}

TEST(DeviceModel, QualityFactorFallsWithTemperature) {
  constexpr double kRoundingTolerance = 1e-9;  // on a Q of 2000 .. 2500: one power, rounding
  const DeviceModel model(fmvmg_physics());
  const auto& sense = model.config().sense;
  EXPECT_DOUBLE_EQ(model.quality_factor(sense, 25.0), sense.quality_factor);
  EXPECT_GT(model.quality_factor(sense, -30.0), model.quality_factor(sense, 0.0));
  EXPECT_GT(model.quality_factor(sense, 0.0), model.quality_factor(sense, 60.0));
  EXPECT_NEAR(model.quality_factor(sense, 60.0),
              sense.quality_factor * std::pow(298.15 / 333.15, sense.quality_factor_exponent), kRoundingTolerance);
}

TEST(DeviceModel, ScaleFactorAndBiasFollowSplitQAndPhaseErrorByTheClosedForm) {
  constexpr double kRoundingTolerance = 1e-12;
  const DeviceModel model(fmvmg_physics());
  const auto& p = model.config();
  const auto sense_at = [&](double t) {
    return DeviceModel::sense_response(model.drive_frequency_hz(t), model.sense_frequency_hz(t),
                                       model.quality_factor(p.sense, t), p.electronics.drive_amplitude_m);
  };
  const SenseResponse ref = sense_at(p.reference_temp_c);
  const double theta_e = p.electronics.demodulation_phase_error_rad;
  EXPECT_NEAR(model.response(p.reference_temp_c).scale_factor, 1.0, kRoundingTolerance);
  for (double t : {-30.0, 0.0, 45.0, 60.0}) {
    const SenseResponse r = sense_at(t);
    const double theta = theta_e + ref.phase_lag_rad - r.phase_lag_rad;
    const double gain = r.amplitude_m_per_rad_s / (ref.amplitude_m_per_rad_s * std::cos(theta_e));
    const double quadrature = p.electronics.quadrature_rad_s * (1 + p.electronics.quadrature_tc_per_k * (t - 25.0));
    const auto response = model.response(t);
    EXPECT_NEAR(response.scale_factor, gain * std::cos(theta), kRoundingTolerance) << t;
    EXPECT_NEAR(response.bias_rad_s, gain * quadrature * std::sin(theta), kRoundingTolerance) << t;
    EXPECT_DOUBLE_EQ(response.drive_frequency_hz, model.drive_frequency_hz(t));
  }
  // A narrower split (hot) raises the open-loop gain: the scale factor grows with temperature.
  EXPECT_LT(model.response(-30.0).scale_factor, 1.0);
  EXPECT_GT(model.response(60.0).scale_factor, 1.0);
}

TEST(DeviceModel, ProofMassAndStiffnessAreConsistentWithTheDimensions) {
  constexpr double kRoundingTolerance = 1e-12;  // relative
  const DeviceModel model(fmvmg_physics());
  const auto& s = model.config().structure;
  const double mass = 2328.3 * 3015e-6 * 2331e-6 * 60e-6 * s.proof_mass_area_fraction;
  EXPECT_NEAR(model.proof_mass_kg() / mass, 1.0, kRoundingTolerance);
  const double k = model.stiffness_n_per_m(model.config().drive);
  EXPECT_NEAR(std::sqrt(k / mass) / kTwoPi / 30740.0, 1.0, kRoundingTolerance);
  // n clamped-guided beams of the implied length give back the stiffness: k = n E t w^3 / L^3.
  const double length = model.implied_beam_length_m(model.config().drive);
  EXPECT_NEAR(
      s.beams_per_mode * s.youngs_modulus_pa * s.thickness_m * std::pow(s.beam_width_m, 3) / std::pow(length, 3) / k,
      1.0, kRoundingTolerance);
  EXPECT_LT(length, s.length_m);
}

TEST(DeviceModel, RejectsEqualModeFrequencies) {
  PhysicsConfig physics = fmvmg_physics();
  physics.sense.frequency_hz = physics.drive.frequency_hz;
  EXPECT_THROW(DeviceModel{physics}, ConfigError);
}

}  // namespace
}  // namespace driftlab::devices
