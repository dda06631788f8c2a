#include "devices/simulator.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <numbers>

#include "framework/units.hpp"
#include "models/allan/deviation.hpp"
#include "tests/devices/simulation_fixtures.hpp"

namespace driftlab::devices {
namespace {

constexpr double kDph = kRadPerSecPerDph;  // rad/s per deg/h

DeviceDefinition fmvmg() { return load_device_file(std::string(DRIFTLAB_SOURCE_DIR) + "/devices/fmvmg.yaml"); }

using testing::options;
using testing::static_at;

std::vector<allan::Deviation> oadev(const Eigen::VectorXd& rate, double fs, std::vector<std::size_t> factors = {}) {
  const Eigen::VectorXd angle = allan::angle_from_rate(rate, 1.0 / fs);
  if (factors.empty())
    for (std::size_t m = 1; m <= (static_cast<std::size_t>(angle.size()) - 1) / 8; m *= 2) factors.push_back(m);
  return allan::deviations(allan::Kind::Oadev, angle, 1.0 / fs, factors);
}

TEST(Simulator, SameSeedSameOutputDifferentSeedDifferentNoise) {
  const DeviceDefinition device = fmvmg();
  const SimulationProfile profile = default_oven_profile();
  const auto a = simulate(device, profile, options(20.0, 1800.0, 7));
  const auto b = simulate(device, profile, options(20.0, 1800.0, 7));
  const auto c = simulate(device, profile, options(20.0, 1800.0, 8));
  EXPECT_EQ(a.rate_rad_s, b.rate_rad_s);
  EXPECT_EQ(a.temp_c, b.temp_c);
  EXPECT_EQ(a.drive_frequency_hz, b.drive_frequency_hz);
  EXPECT_EQ(a.systematic_rate_rad_s, c.systematic_rate_rad_s);  // the seed only moves the noise
  EXPECT_EQ(a.die_temp_c, c.die_temp_c);
  const Eigen::VectorXd difference = a.rate_rad_s - c.rate_rad_s;
  // Independent white parts: the difference has sqrt(2) times the per-sample white std.
  const double white = device.error_model.noise.arw_rad_sqrt_s * std::sqrt(20.0);
  const double rms = std::sqrt(difference.squaredNorm() / static_cast<double>(difference.size()));
  EXPECT_GT(rms, 1.2 * white);
  EXPECT_NE(a.temp_c, c.temp_c);
}

TEST(Simulator, AllanAnalysisOfAStaticRecordRecoversNAndK) {
  // White rate + rate random walk only; least squares of sigma^2(tau) = N^2/tau + K^2 tau/3 over an
  // octave OADEV grid, weighted by the number of terms over sigma^4 (chi-square scatter).
  constexpr double kNTolerance = 0.05;  // N rests on millions of short-tau terms
  constexpr double kKTolerance = 0.25;  // K rests on a few tens of independent long intervals
  DeviceDefinition device = fmvmg();
  auto& noise = device.error_model.noise;
  noise.arw_rad_sqrt_s = 99.6 * kDph;
  noise.bias_instability_rad_s = 0.0;
  noise.rate_random_walk_rad_s_sqrt_s = 300.0 * kDph / 60.0;  // 300 deg/h/sqrt(h)
  const double fs = 10.0;
  const auto record = simulate(device, static_at(25.0), options(fs, 20 * kSecondsPerHour, 21));
  Eigen::MatrixXd a(0, 2);
  Eigen::VectorXd y(0);
  for (const auto& d : oadev(record.rate_rad_s, fs)) {
    const double w = std::sqrt(static_cast<double>(d.terms)) / (d.dev * d.dev);
    a.conservativeResize(a.rows() + 1, 2);
    y.conservativeResize(y.size() + 1);
    a.row(a.rows() - 1) << w / d.tau, w * d.tau / 3.0;
    y[y.size() - 1] = w * d.dev * d.dev;
  }
  const Eigen::Vector2d fit = a.colPivHouseholderQr().solve(y);
  EXPECT_NEAR(std::sqrt(fit[0]) / noise.arw_rad_sqrt_s, 1.0, kNTolerance);
  EXPECT_NEAR(std::sqrt(fit[1]) / noise.rate_random_walk_rad_s_sqrt_s, 1.0, kKTolerance);
}

TEST(Simulator, LeastSquaresBiasVersusTemperatureMatchesTheModel) {
  DeviceDefinition device = fmvmg();
  device.error_model.noise.bias_instability_rad_s = 0.0;
  device.error_model.noise.rate_random_walk_rad_s_sqrt_s = 0.0;
  const double fs = 10.0;
  const auto record = simulate(device, default_oven_profile(), options(fs, 0, 3));
  const int degree = 4;
  const Eigen::Index n = record.time_s.size();
  Eigen::MatrixXd vandermonde(n, degree + 1);
  for (Eigen::Index k = 0; k < n; ++k)
    for (int j = 0; j <= degree; ++j) vandermonde(k, j) = std::pow((record.die_temp_c[k] - 15.0) / 45.0, j);
  const Eigen::VectorXd coefficients = vandermonde.colPivHouseholderQr().solve(record.rate_rad_s);
  // Fit scatter: white std sigma / sqrt(n / (degree + 1)) per coefficient; 6 of those plus the
  // degree-4 truncation of the physics (below 0.5 deg/h over the range).
  const double sigma = device.error_model.noise.arw_rad_sqrt_s * std::sqrt(fs);
  const double tolerance = 6.0 * sigma / std::sqrt(static_cast<double>(n) / (degree + 1)) + 0.5 * kDph;
  const DeviceModel model(device.physics);
  double swing_lo = 1e9, swing_hi = -1e9;
  for (double t = -28.0; t <= 58.0; t += 2.0) {
    double fitted = 0.0;
    for (int j = 0; j <= degree; ++j) fitted += coefficients[j] * std::pow((t - 15.0) / 45.0, j);
    const double truth = error_model::systematic_rate(device.error_model, model.response(t), t, 0.0);
    EXPECT_NEAR(fitted, truth, tolerance) << "at " << t << " degC";
    swing_lo = std::min(swing_lo, truth), swing_hi = std::max(swing_hi, truth);
  }
  EXPECT_GT(swing_hi - swing_lo, 10.0 * tolerance);  // the curve stands far above the fit's scatter
}

TEST(Simulator, StaticFmvmgOvenRunShowsThePapersRawStatistics) {
  // Paper Table 2 (original): B = 34.66 deg/h, N = 99.608 deg/h/sqrt(Hz). N read at tau = 1 s,
  // B = min sigma / 0.664, over the whole default oven run including its temperature drift.
  constexpr double kPaperTolerance = 0.15;  // flicker adds ~2 % at 1 s; floor ripple and scatter
  const double fs = 50.0;
  const auto record = simulate(fmvmg(), default_oven_profile(), options(fs, 0, 1));
  std::vector<std::size_t> factors;
  for (double tau : {1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0})
    factors.push_back(static_cast<std::size_t>(tau * fs));
  const auto devs = oadev(record.rate_rad_s, fs, factors);
  double at_one_second = 0.0, minimum = 1e9;
  for (const auto& d : devs) {
    if (d.m == static_cast<std::size_t>(fs)) at_one_second = d.dev;
    minimum = std::min(minimum, d.dev);
  }
  const double n_estimate = at_one_second / kDph;
  const double b_estimate = minimum / std::sqrt(2.0 * std::numbers::ln2 / std::numbers::pi) / kDph;
  EXPECT_NEAR(n_estimate / 99.608, 1.0, kPaperTolerance) << "N = " << n_estimate << " deg/h/sqrt(Hz)";
  EXPECT_NEAR(b_estimate / 34.66, 1.0, kPaperTolerance) << "B = " << b_estimate << " deg/h";
}

TEST(Simulator, DieLagsTheChamberAndTheSensorLagsTheDie) {
  constexpr double kExactDiscretization = 1e-9;  // degC; lags are exact for piecewise-linear input
  const DeviceDefinition device = fmvmg();
  DeviceDefinition noiseless = device;
  for (auto& c : noiseless.channels) c.noise = 0.0, c.resolution = 0.0;
  const auto r = simulate(noiseless, default_oven_profile(), options(1.0, 0, 1));
  const double ramp = 1.0 / 60.0;      // degC/s
  const Eigen::Index k = 1800 + 2700;  // middle of the heating ramp, 15 die time constants in
  EXPECT_NEAR(r.chamber_temp_c[k] - r.die_temp_c[k], ramp * device.thermal.die_time_constant_s, kExactDiscretization);
  EXPECT_NEAR(r.die_temp_c[k] - r.temp_c[k], ramp * device.thermal.sensor_time_constant_s, kExactDiscretization);
  EXPECT_DOUBLE_EQ(r.die_temp_c[0], -30.0);
}

TEST(Simulator, EffectsChangeOnlyTheSystematicPart) {
  constexpr double kQuantization = 1e-5 * kRadPerDeg;  // rate channel LSB
  DeviceDefinition device = fmvmg();
  const auto base = simulate(device, default_oven_profile(), options(5.0, 7200.0, 4));
  apply_effect_option("periodic_disturbance:amplitude_dph=40,period_s=600,phase_deg=0", device.error_model.effects);
  const auto with = simulate(device, default_oven_profile(), options(5.0, 7200.0, 4));
  for (Eigen::Index k = 0; k < base.time_s.size(); k += 97) {
    const double disturbance = 40.0 * kDph * std::sin(2.0 * std::numbers::pi * base.time_s[k] / 600.0);
    EXPECT_NEAR(with.rate_rad_s[k] - base.rate_rad_s[k], disturbance, kQuantization);
  }
}

TEST(Simulator, ThermalLagEffectMakesTheDieLagTheSensor) {
  DeviceDefinition device = fmvmg();
  apply_effect_option("thermal_lag:tau_s=400", device.error_model.effects);
  const auto r = simulate(device, default_oven_profile(), options(1.0, 0, 1));
  const Eigen::Index k = 1800 + 2700;                            // heating
  EXPECT_GT(r.temp_c[k] - r.die_temp_c[k], 0.8 * 400.0 / 60.0);  // ~ rate * tau once settled
  EXPECT_LT(r.temp_c[k] - r.die_temp_c[k], 400.0 / 60.0);
}

TEST(Simulator, RateTableProfileIsScaledByTheScaleFactor) {
  constexpr double kRounding = 1e-12;             // rad/s: the profile's 100 deg/s converted
  constexpr double kRateLsb = 1e-5 * kRadPerDeg;  // the FMVMG rate channel's resolution: quantisation
  DeviceDefinition device = fmvmg();
  device.error_model.noise = {};
  const SimulationProfile profile = parse_profile(
      "format: driftlab-profile/1\nchamber: {start_c: 60}\n"
      "rate: {start_dps: 0, segments: [{hold_s: 10}, {to_dps: 100, duration_s: 0}, {hold_s: 10}]}\n",
      "table.yaml");
  const auto r = simulate(device, profile, options(10.0, 0, 1));
  const DeviceModel model(device.physics);
  const double s = model.response(60.0).scale_factor * error_model::empirical_scale_factor(device.error_model, 60.0);
  const double bias = error_model::systematic_rate(device.error_model, model.response(60.0), 60.0, 0.0);
  EXPECT_NEAR(r.true_rate_rad_s[150], 100.0 * kRadPerDeg, kRounding);
  EXPECT_NEAR(r.rate_rad_s[150], s * 100.0 * kRadPerDeg + bias, kRateLsb);
  EXPECT_NEAR(r.rate_rad_s[50], bias, kRateLsb);
}

TEST(Simulator, DefaultOvenProfileCyclesMinus30ToPlus60) {
  const SimulationProfile p = default_oven_profile();
  EXPECT_DOUBLE_EQ(p.duration_s(), 3 * 1800.0 + 2 * 5400.0);
  EXPECT_DOUBLE_EQ(p.chamber_c.value_at(0.0), -30.0);
  EXPECT_DOUBLE_EQ(p.chamber_c.value_at(1800.0 + 2700.0), 15.0);
  EXPECT_DOUBLE_EQ(p.chamber_c.value_at(1800.0 + 5400.0 + 900.0), 60.0);
  EXPECT_DOUBLE_EQ(p.chamber_c.value_at(1e6), -30.0);
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(1001, 0.0, p.duration_s());
  const Eigen::VectorXd sampled = p.chamber_c.sample(t);
  for (Eigen::Index k = 0; k < t.size(); ++k) EXPECT_DOUBLE_EQ(sampled[k], p.chamber_c.value_at(t[k]));
}

TEST(Simulator, ProfileFileErrorsNameLineAndKey) {
  const std::string text =
      "format: driftlab-profile/1\n"
      "chamber:\n"
      "  start_c: 20\n"
      "  segments:\n"
      "    - {hold_s: 60}\n"
      "    - {to_c: 40}\n"
      "    - {to_c: 40, duration_s: -5}\n"
      "    - {hold_s: 10, to_c: 3}\n";
  try {
    parse_profile(text, "bad_profile.yaml");
    FAIL();
  } catch (const ConfigError& e) {
    ASSERT_EQ(e.problems().size(), 3u) << e.what();
    EXPECT_EQ(e.problems()[0].where.line, 6);
    EXPECT_EQ(e.problems()[0].where.field, "chamber.segments[1]");
    EXPECT_EQ(e.problems()[1].where.line, 7);
    EXPECT_EQ(e.problems()[1].where.field, "chamber.segments[2].duration_s");
    EXPECT_EQ(e.problems()[2].where.line, 8);
    EXPECT_EQ(e.problems()[0].where.file, "bad_profile.yaml");
  }
}

TEST(Simulator, RejectsAStaticProfileWithoutDuration) {
  EXPECT_THROW(simulate(fmvmg(), static_at(25.0), SimulationOptions{}), ConfigError);
}

TEST(Simulator, RecordBecomesATimeSeriesWithTheContractRoles) {
  const auto r = simulate(fmvmg(), static_at(25.0), options(10.0, 10.0, 1));
  const TimeSeries series = r.to_time_series();
  for (const char* role : {"rate", "temperature", "true_rate", "die_temperature", "drive_frequency"})
    EXPECT_TRUE(series.has(role)) << role;
  EXPECT_EQ(series.size(), 100);
}

}  // namespace
}  // namespace driftlab::devices
