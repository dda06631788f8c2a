// The checks of issue 13 on simulated oven runs of the FMVMG device file: calibrate on one run,
// score on another seed with another chamber profile (warm start, other ramp rates, partial range).
#include <gtest/gtest.h>

#include <cstdio>

#include <cmath>

#include "devices/device_file.hpp"
#include "devices/simulator.hpp"
#include "framework/units.hpp"
#include "models/calibration/calibration_model.hpp"
#include "models/calibration/fit.hpp"
#include "models/evaluation/evaluation.hpp"

namespace driftlab::calibration {
namespace {

constexpr double kSampleRateHz = 2.0;  // enough for 60-s block means; keeps every test to well under a second

devices::DeviceDefinition fmvmg(bool with_effects) {
  auto d = devices::load_device_file(std::string(DRIFTLAB_SOURCE_DIR) + "/devices/fmvmg.yaml");
  // The intrinsic noise the temperature drift is compensated down to (issue 12 sets the device's
  // bias instability to ~1-2 deg/h). Fixed here, so these checks do not depend on that change.
  d.error_model.noise.bias_instability_rad_s = 1.5 * kRadPerSecPerDph;
  d.error_model.noise.rate_random_walk_rad_s_sqrt_s = 0.5 * kRadPerSecPerDph / 60.0;
  if (with_effects) {  // non-polynomial drift: lag, dT/dt and hysteresis
    d.error_model.effects.thermal_lag = error_model::ThermalLag{400.0};
    d.error_model.effects.temperature_rate = error_model::TemperatureRate{30.0 * kRadPerSecPerDph * 60.0};
    d.error_model.effects.hysteresis = error_model::Hysteresis{40.0 * kRadPerSecPerDph, 2.0};
  }
  return d;
}

Record run(const devices::DeviceDefinition& device, const devices::SimulationProfile& profile, std::uint64_t seed) {
  const auto s = devices::simulate(device, profile, {.sample_rate_hz = kSampleRateHz, .seed = seed});
  return {"seed " + std::to_string(seed), s.time_s, s.rate_rad_s, s.temp_c, s.true_rate_rad_s, s.systematic_rate_rad_s};
}

// Warm start at 25 degC, 2 degC/min up to 50, 0.5 degC/min down to -10, 1.5 degC/min back to 30.
devices::SimulationProfile other_profile() {
  devices::SimulationProfile p;
  p.chamber_c = devices::Profile(25.0);
  p.chamber_c.hold(600)
      .ramp_at_rate(50, 2.0 / 60)
      .hold(900)
      .ramp_at_rate(-10, 0.5 / 60)
      .hold(900)
      .ramp_at_rate(30, 1.5 / 60);
  return p;
}

double drift(const Record& r, const std::optional<CalibrationModel>& m) {
  const Eigen::VectorXd out = m ? compensate(*m, r.time_s, r.rate_rad_s, r.temp_c).rate_rad_s : r.rate_rad_s;
  return evaluation::block_mean_rms(r.time_s, out - r.true_rate_rad_s);
}

CalibrationModel fit(const Record& r, ModelKind kind) {
  FitOptions o;
  o.kind = kind;
  return fit_calibration({r}, o);
}

TEST(CalibrationEvidence, APolynomialModelCutsTheHeldOutDriftOfAnotherSeedAndProfileFiveTimes) {
  const auto device = fmvmg(false);
  const Record cal = run(device, devices::default_oven_profile(), 1);
  const Record test = run(device, other_profile(), 2);
  const double raw = drift(test, std::nullopt), compensated = drift(test, fit(cal, ModelKind::Polynomial));
  EXPECT_GT(raw / compensated, 5.0) << "raw " << raw / kRadPerSecPerDph << " deg/h, compensated "
                                    << compensated / kRadPerSecPerDph << " deg/h";
}

TEST(CalibrationEvidence, ThePhysicalModelBeatsThePolynomialWhereTheDriftIsNotPolynomial) {
  const auto device = fmvmg(true);
  const Record cal = run(device, devices::default_oven_profile(), 1);
  const Record test = run(device, other_profile(), 2);
  const double poly = drift(test, fit(cal, ModelKind::Polynomial));
  const double physical = drift(test, fit(cal, ModelKind::Physical));
  const double rbf = drift(test, fit(cal, ModelKind::Rbf));
  EXPECT_LT(physical, 0.8 * poly) << "physical " << physical / kRadPerSecPerDph << " vs poly "
                                  << poly / kRadPerSecPerDph;
  EXPECT_LT(rbf, 0.8 * poly) << "rbf " << rbf / kRadPerSecPerDph << " vs poly " << poly / kRadPerSecPerDph;
}

TEST(CalibrationEvidence, ThePhysicalModelRecoversTheLagAndReachesTheIntrinsicFloorOnAnotherProfile) {
  // The lag grid doubles (240, 480 s): the fitted lag is refined between its neighbours. Measured
  // on this single 2-Hz calibration run: grid only 480 s and 18.1 deg/h held out (both checks
  // fail); refined 433 s and 15.2 deg/h against an intrinsic floor of 12.7 deg/h.
  constexpr double kLagTolerance = 0.125;
  constexpr double kFloorFactor = 1.3;
  const auto device = fmvmg(true);
  const Record cal = run(device, devices::default_oven_profile(), 1);
  const Record test = run(device, other_profile(), 2);
  const CalibrationModel m = fit(cal, ModelKind::Physical);
  EXPECT_NEAR(m.lag_tau_s, 400.0, kLagTolerance * 400.0);
  const double floor = evaluation::block_mean_rms(test.time_s, test.rate_rad_s - test.systematic_rad_s);
  const double physical = drift(test, m);
  EXPECT_LT(physical, kFloorFactor * floor)
      << "physical " << physical / kRadPerSecPerDph << " deg/h, floor " << floor / kRadPerSecPerDph << " deg/h";
  std::printf("[ summary  ] lag %.1f s (truth 400); held-out drift %.2f deg/h, intrinsic floor %.2f deg/h\n",
              m.lag_tau_s, physical / kRadPerSecPerDph, floor / kRadPerSecPerDph);
}

// The hysteresis a model reports is the effect catalogue's height (cooling minus heating branch,
// the convention of the device file and of `driftlab discrepancy`): a simulated device with only a
// hysteresis of +150 deg/h (cooling branch above) reads back +150 within 20 %, not -75 (the
// coefficient of the branch state) or -150.
TEST(CalibrationEvidence, TheFittedHysteresisIsTheCataloguesHeightWithItsSign) {
  constexpr double kHeightDph = 150.0, kRelativeTolerance = 0.2;
  auto device = fmvmg(false);
  device.error_model.effects.hysteresis = error_model::Hysteresis{kHeightDph * kRadPerSecPerDph, 2.0};
  const CalibrationModel m = fit(run(device, devices::default_oven_profile(), 1), ModelKind::Physical);
  ASSERT_GT(m.hysteresis_width_k, 0.0) << m.fit.selection;
  const double height = m.hysteresis_height() / kRadPerSecPerDph,
               sigma = m.hysteresis_height_sigma() / kRadPerSecPerDph;
  EXPECT_NEAR(height, kHeightDph, kRelativeTolerance * kHeightDph) << "sigma " << sigma;
  std::printf("[ summary  ] hysteresis height %.1f +- %.1f deg/h (truth %.0f), width %.2f K (truth 2)\n", height, sigma,
              kHeightDph, m.hysteresis_width_k);
}

TEST(CalibrationEvidence, ThePhysicalModelDoesNoWorseWhereTheDriftIsPolynomial) {
  // No effects: the device's bias(T) is smooth. Held-out noise makes two fits differ a little.
  constexpr double kNoiseTolerance = 1.05;
  const auto device = fmvmg(false);
  const Record cal = run(device, devices::default_oven_profile(), 1);
  const Record test = run(device, other_profile(), 2);
  const double poly = drift(test, fit(cal, ModelKind::Polynomial));
  const double physical = drift(test, fit(cal, ModelKind::Physical));
  EXPECT_LT(physical, kNoiseTolerance * poly) << physical / kRadPerSecPerDph << " vs " << poly / kRadPerSecPerDph;
}

// The accuracy a model states (fit.holdout_rms_rad_s: pooled rms of its held-out bin residuals
// on the calibration run) is what it delivers on a run it never saw: the same statistic (rms of
// bin_s-s means of output - truth) on another seed and profile lies within 1.5x of it either way,
// for every kind, with and without history effects in the drift. Measured (seed 1 -> 2): 0.69 (poly
// on the drift with history effects: the other profile's ramps excite less of them) to 0.98 (printed).
constexpr double kStatedAccuracyFactor = 1.5;

TEST(CalibrationEvidence, TheStatedHeldOutAccuracyHoldsOnAnUnseenRunOfAnotherProfile) {
  for (const bool effects : {false, true}) {
    const auto device = fmvmg(effects);
    const Record cal = run(device, devices::default_oven_profile(), 1);
    const Record test = run(device, other_profile(), 2);
    for (const auto kind : {ModelKind::Polynomial, ModelKind::Physical, ModelKind::Rbf}) {
      const CalibrationModel m = fit(cal, kind);
      const Eigen::VectorXd out = compensate(m, test.time_s, test.rate_rad_s, test.temp_c).rate_rad_s;
      const double unseen = evaluation::block_mean_rms(test.time_s, out - test.true_rate_rad_s, m.fit.bin_s);
      const double ratio = unseen / m.fit.holdout_rms_rad_s;
      std::printf("effects %d, %s (kept %s): stated %.2f deg/h, unseen %.2f deg/h, ratio %.2f\n", effects,
                  to_string(kind).c_str(), to_string(m.kind).c_str(), m.fit.holdout_rms_rad_s / kRadPerSecPerDph,
                  unseen / kRadPerSecPerDph, ratio);
      EXPECT_LT(ratio, kStatedAccuracyFactor) << to_string(kind) << ", effects " << effects;
      EXPECT_GT(ratio, 1.0 / kStatedAccuracyFactor) << to_string(kind) << ", effects " << effects;
    }
  }
}

TEST(CalibrationEvidence, OutsideThePartialCalibratedRangeThePolicyHoldsAndIsReported) {
  const auto device = fmvmg(false);
  devices::SimulationProfile partial;
  partial.chamber_c = devices::Profile(10.0);
  partial.chamber_c.hold(600).ramp_at_rate(40, 1.0 / 60).hold(600).ramp_at_rate(10, 1.0 / 60).hold(600);
  const CalibrationModel m = fit(run(device, partial, 1), ModelKind::Polynomial);
  const Record test = run(device, devices::default_oven_profile(), 2);  // -30 .. 60 degC
  const auto c = compensate(m, test.time_s, test.rate_rad_s, test.temp_c);
  int outside = 0;
  for (Eigen::Index i = 0; i < test.time_s.size(); ++i) {
    const bool out = test.temp_c[i] < m.valid_min_c || test.temp_c[i] > m.valid_max_c;
    ASSERT_EQ(c.outside[static_cast<std::size_t>(i)], out ? kOutsideTemperature : 0u) << i;
    if (out) {
      ++outside;
      const double edge = test.temp_c[i] < m.valid_min_c ? m.valid_min_c : m.valid_max_c;
      ASSERT_EQ(c.bias_rad_s[i], m.polynomial_bias_rad_s(edge)) << "clamp: the edge value";
    }
  }
  EXPECT_GT(outside, test.time_s.size() / 4);
}

}  // namespace
}  // namespace driftlab::calibration
