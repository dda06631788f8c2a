// Effect kernels and plugins (plugins/effects): closed forms, identity with the simulator's effect
// terms (models/error_model), and the plugins' reported keys against the device-file catalogue.
#include "plugins/effects/effects.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <set>

#include "plugins/builtins.hpp"
#include "devices/device_file.hpp"
#include "framework/effect_catalogue.hpp"
#include "framework/params_io.hpp"
#include "framework/registry.hpp"
#include "framework/units.hpp"
#include "models/error_model/error_model.hpp"

namespace driftlab {
namespace {

constexpr double kRoundingTolerance = 1e-12;  // a few operations on O(1) values

Eigen::VectorXd seconds(Eigen::Index n, double dt) {
  return Eigen::VectorXd::LinSpaced(n, 0.0, dt * static_cast<double>(n - 1));
}

TEST(EffectKernels, LagOfARampTrailsByTauOnceTheTransientHasDecayed) {
  constexpr double kExactDiscretization = 1e-10;  // the step is exact for inputs linear between samples
  const double tau = 50.0, slope = 0.02;
  const Eigen::VectorXd t = seconds(2001, 0.5);
  const Eigen::VectorXd ramp = slope * t;
  const Eigen::VectorXd lagged = effects::lagged_temperature(t, ramp, tau);
  // Closed form of y' = (x - y)/tau, x = s t, y(0) = 0: y = s (t - tau (1 - exp(-t/tau))).
  for (Eigen::Index k = 0; k < t.size(); k += 97)
    EXPECT_NEAR(lagged[k], slope * (t[k] - tau * (1.0 - std::exp(-t[k] / tau))), kExactDiscretization) << t[k];
}

TEST(EffectKernels, TemperatureRateOfARampIsItsSlope) {
  const Eigen::VectorXd t = seconds(101, 2.0);
  const Eigen::VectorXd rate = effects::temperature_rate(t, (3.0 - 0.01 * t.array()).matrix());
  for (double r : rate) EXPECT_NEAR(r, -0.01, kRoundingTolerance);
}

TEST(EffectKernels, PlayOperatorIgnoresReversalsInsideItsDeadband) {
  Eigen::VectorXd x(7);
  x << 0.0, 0.04, -0.03, 0.05, 0.5, 0.46, 0.3;
  const Eigen::VectorXd y = effects::play(x, 0.05);
  Eigen::VectorXd expected(7);
  expected << 0.0, 0.0, 0.0, 0.0, 0.45, 0.45, 0.35;
  for (Eigen::Index k = 0; k < x.size(); ++k) EXPECT_NEAR(y[k], expected[k], kRoundingTolerance) << k;
}

TEST(EffectKernels, HysteresisBasisSaturatesAtHalfTheHeightAndKeepsItThroughNoise) {
  constexpr double kSteps = 1e-9;  // 199 exponential steps against one exp of their sum: rounding
  // Held: the noise's last 0.12 K of play travel moves the saturated basis by 1.4e-6, while without
  // the deadband the reversals drag it by more than 0.2.
  constexpr double kHeld = 1e-4;
  // Heat by 20 K, then hold with +-0.02 K sensor noise: the branch stays at -1/2 (heating).
  const int n = 400;
  Eigen::VectorXd temp(n);
  for (int k = 0; k < n; ++k) temp[k] = k < 200 ? 0.1 * k : 20.0 + (k % 2 ? 0.02 : -0.02);
  const Eigen::VectorXd with_deadband = effects::hysteresis_basis(temp, 2.0, 0.05);
  // The play output trails the input by the half-width: 19.85 K of travel by sample 199.
  EXPECT_NEAR(with_deadband[199], -0.5 * (1.0 - std::exp(-19.85 / 2.0)), kSteps);
  EXPECT_NEAR(with_deadband[n - 1], with_deadband[199], kHeld);
  // Without the play operator the noise reversals drag the state towards 0.
  EXPECT_GT(effects::hysteresis_basis(temp, 2.0, 0.0)[n - 1], -0.3);
}

TEST(EffectKernels, PeriodicBasisRecoversTheSimulatorsAmplitudeAndPhase) {
  // Least squares on an exact sinusoid: rounding only (relative 4e-12 of the amplitude; the phase
  // through atan2).
  constexpr double kAmplitude = 1e-15, kPhase = 1e-10;  // rad/s, rad
  const Eigen::VectorXd t = seconds(3000, 1.0);
  error_model::Effects e;
  e.periodic_disturbance = error_model::PeriodicDisturbance{2.5e-4, 377.0, -2.2};
  const Eigen::VectorXd signal = error_model::additive_effects(e, t, Eigen::VectorXd::Zero(t.size()));
  const Eigen::MatrixXd basis = effects::periodic_basis(t, 377.0);
  const Eigen::Vector2d c = basis.colPivHouseholderQr().solve(signal);
  const auto s = effects::sinusoid_from_coefficients(c[0], c[1]);
  EXPECT_NEAR(s.amplitude, 2.5e-4, kAmplitude);
  EXPECT_NEAR(s.phase_rad, -2.2, kPhase);
}

TEST(EffectKernels, WarmupBasisTimesAmplitudeIsTheSimulatorsTransient) {
  const Eigen::VectorXd t = seconds(500, 3.0);
  error_model::Effects e;
  e.warmup_transient = error_model::WarmupTransient{1e-3, 420.0};
  const Eigen::VectorXd expected = error_model::additive_effects(e, t, Eigen::VectorXd::Zero(t.size()));
  const Eigen::VectorXd basis = effects::warmup_basis(t, 0.0, 420.0);
  EXPECT_LT((1e-3 * basis - expected).cwiseAbs().maxCoeff(), 1e-18);
}

TEST(EffectKernels, ScaleFactorBasisTimesCoefficientsIsTheSimulatorsExtraScaleFactor) {
  const Eigen::VectorXd temp = Eigen::VectorXd::LinSpaced(50, -30.0, 60.0);
  const Eigen::VectorXd rate = Eigen::VectorXd::LinSpaced(50, -1.0, 1.0);
  error_model::Effects e;
  e.scale_factor_temperature = error_model::ScaleFactorTemperature{{80e-6, -1.5e-6}};
  const Eigen::MatrixXd basis = effects::scale_factor_basis(temp, rate, 25.0, 2);
  const Eigen::VectorXd fitted = basis * Eigen::Vector2d(80e-6, -1.5e-6);
  for (Eigen::Index k = 0; k < temp.size(); ++k)
    EXPECT_NEAR(fitted[k], (error_model::effect_scale_factor(e, 25.0, temp[k]) - 1.0) * rate[k], kRoundingTolerance);
}

TEST(EffectKernels, ResonatorTemperatureInvertsTheDriveFrequencyLine) {
  constexpr double kExactLine = 1e-9;  // Hz/K: a line fitted through points exactly on it: rounding
  const Eigen::VectorXd temp = Eigen::VectorXd::LinSpaced(40, -30.0, 60.0);
  const Eigen::VectorXd resonator = temp.array() - 1.5;  // the resonator runs 1.5 K colder
  const double f0 = 30740.0, slope = -0.9222;
  const Eigen::VectorXd f = (f0 + slope * (resonator.array() - 25.0)).matrix();
  const auto known = effects::resonator_temperature(temp, f, 25.0, f0, slope);
  EXPECT_LT((known.temperature_c - resonator).cwiseAbs().maxCoeff(), 1e-9);
  // Fitted line: the constant offset is absorbed into f_ref, the slope is exact.
  const auto fitted = effects::resonator_temperature(temp, f, 25.0);
  EXPECT_NEAR(fitted.slope_hz_per_k, slope, kExactLine);
  EXPECT_LT((fitted.temperature_c - temp).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_THROW(effects::resonator_temperature(Eigen::VectorXd::Constant(5, 20.0), f.head(5), 25.0),
               std::invalid_argument);
}

// ---- plugins ---------------------------------------------------------------------------------

class EffectPlugins : public ::testing::Test {
 protected:
  EffectPlugins() { register_builtin_plugins(registry_); }
  std::unique_ptr<Effect> make(const std::string& name) {
    return registry_.create_as<Effect>({name, params_from_assignments(registry_, name, {})});
  }
  Registry registry_;
};

TimeSeries oven_record() {
  const Eigen::VectorXd t = seconds(600, 10.0);
  TimeSeries r(t);
  Eigen::VectorXd temp(t.size()), rate(t.size()), drive(t.size());
  for (Eigen::Index k = 0; k < t.size(); ++k) {
    temp[k] = k < 300 ? -30.0 + 0.03 * t[k] : 60.0 - 0.02 * (t[k] - 3000.0);
    rate[k] = (k / 20) % 2 ? 0.5 : -0.5;
  }
  drive = (30740.0 - 0.92 * (temp.array() - 25.0)).matrix();
  r.set_channel({role::kTemperature, "degC", "temp_c", temp});
  r.set_channel({role::kTrueRate, "rad/s", "true_rate_dps", rate});
  r.set_channel({role::kDriveFrequency, "Hz", "drive_freq_hz", drive});
  return r;
}

TEST_F(EffectPlugins, EveryEffectGivesOneBasisColumnPerCoefficientAndFiniteValues) {
  const TimeSeries record = oven_record();
  const EffectContext context{25.0, 0.0};
  for (const auto* info : registry_.list("effect")) {
    const auto e = make(info->name);
    Eigen::VectorXd theta(static_cast<Eigen::Index>(e->nonlinear_parameters().size()));
    for (Eigen::Index k = 0; k < theta.size(); ++k) {
      const auto& p = e->nonlinear_parameters()[static_cast<std::size_t>(k)];
      theta[k] = std::sqrt(p.lower * std::min(p.upper, 1e4));
    }
    const auto term = e->evaluate(record, context, theta);
    EXPECT_EQ(term.basis.rows(), record.size()) << info->name;
    EXPECT_EQ(term.basis.cols(), static_cast<Eigen::Index>(e->coefficient_names().size())) << info->name;
    EXPECT_TRUE(term.basis.allFinite()) << info->name;
    EXPECT_EQ(term.model_temperature_c.size() != 0, e->moves_model_temperature()) << info->name;
    if (e->moves_model_temperature()) {
      EXPECT_TRUE(term.model_temperature_c.allFinite()) << info->name;
    }
  }
}

TEST_F(EffectPlugins, ReportTheDeviceFileKeysOfTheEffectsTheSimulatorKnows) {
  const TimeSeries record = oven_record();
  for (const auto& entry : effect_catalogue()) {
    const auto e = make("effect/" + entry.name);
    const Eigen::VectorXd theta =
        Eigen::VectorXd::Constant(static_cast<Eigen::Index>(e->nonlinear_parameters().size()), 100.0);
    const Eigen::VectorXd c = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(e->coefficient_names().size()), 1e-4);
    std::set<std::string> reported, catalogue;
    for (const auto& v : e->describe(record, {}, theta, c)) reported.insert(v.key);
    for (const auto& k : entry.keys) catalogue.insert(k.key);
    EXPECT_EQ(reported, catalogue) << entry.name;
  }
}

TEST_F(EffectPlugins, ReportTemperatureRateAndHysteresisInDeviceFileUnits) {
  constexpr double kUnitRoundTrip = 1e-9;  // deg/h: given in rad/s here, reported in device-file units
  constexpr double kAsGiven = 0.0;         // the width is reported as it was given, unconverted
  const TimeSeries record = oven_record();
  const double rad_s_per_dph = kRadPerSecPerDph;
  const auto rate = make("effect/temperature_rate")
                        ->describe(record, {}, {}, Eigen::VectorXd::Constant(1, 60.0 * rad_s_per_dph * 60.0));
  EXPECT_NEAR(rate[0].values[0], 60.0, kUnitRoundTrip);  // 60 deg/h per degC/min
  Eigen::VectorXd width(1);
  width << 2.5;
  const auto hysteresis =
      make("effect/hysteresis")->describe(record, {}, width, Eigen::VectorXd::Constant(1, 150.0 * rad_s_per_dph));
  EXPECT_NEAR(hysteresis[0].values[0], 150.0, kUnitRoundTrip);
  EXPECT_NEAR(hysteresis[1].values[0], 2.5, kAsGiven);
}

TEST_F(EffectPlugins, RefuseToRunAsPipelineSteps) {
  RunContext ctx;
  EXPECT_THROW(make("effect/thermal_lag")->run({}, ctx), ConfigError);
}

TEST_F(EffectPlugins, NameTheMissingDriveFrequencyChannel) {
  TimeSeries record(seconds(10, 1.0));
  record.set_channel({role::kTemperature, "degC", "temp_c", Eigen::VectorXd::LinSpaced(10, 0, 9)});
  EXPECT_THROW(make("effect/mode_split_drift")->evaluate(record, {}, {}), DataError);
}

}  // namespace
}  // namespace driftlab
