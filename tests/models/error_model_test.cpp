#include "models/error_model/error_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "models/allan/confidence.hpp"
#include "models/allan/deviation.hpp"
#include "models/allan/gmwm.hpp"
#include "framework/units.hpp"

namespace driftlab::error_model {
namespace {

std::vector<allan::Deviation> oadev(const Eigen::VectorXd& rate, double fs, const std::vector<std::size_t>& factors) {
  const Eigen::VectorXd angle = allan::angle_from_rate(rate, 1.0 / fs);
  return allan::deviations(allan::Kind::Oadev, angle, 1.0 / fs, factors);
}

TEST(ErrorModel, PolynomialIsEvaluatedInAscendingPowers) {
  EXPECT_DOUBLE_EQ(polynomial({1.0, 2.0, 3.0}, 2.0), 1.0 + 4.0 + 12.0);
  EXPECT_DOUBLE_EQ(polynomial({}, 5.0), 0.0);
}

TEST(ErrorModel, FlickerComponentsShareTheVarianceOfTheBToGaussMarkovMapping) {
  constexpr double kLastPole = 1e-9;  // s: the last of the 10^(k/2)-s poles lands on 1000 s to rounding
  constexpr double kSigma = 1e-18;    // rad/s on 6e-5: the closed form to rounding (relative 2e-14)
  NoiseTerms terms;
  terms.bias_instability_rad_s = 1e-4;
  terms.flicker_tau_min_s = 1.0;
  terms.flicker_tau_max_s = 1000.0;
  terms.flicker_poles_per_decade = 2.0;
  const auto components = flicker_components(terms);
  ASSERT_EQ(components.size(), 7u);  // ceil(2 * 3) + 1
  EXPECT_DOUBLE_EQ(components.front().tau_s, 1.0);
  EXPECT_NEAR(components.back().tau_s, 1000.0, kLastPole);
  for (const auto& c : components)
    EXPECT_NEAR(c.sigma_rad_s, 1e-4 * std::sqrt(std::numbers::ln10 / (std::numbers::pi * 2.0)), kSigma);
}

TEST(ErrorModel, WhiteNoiseHasTheAllanSignatureOfN) {
  // The configured N/sqrt(tau) lies inside the estimator's own 99.7 % chi-square interval.
  constexpr double kConfidence = 0.997;
  NoiseTerms terms;
  terms.arw_rad_sqrt_s = 2e-4;
  const double fs = 100.0;
  const Eigen::VectorXd noise = rate_noise(terms, fs, 200000, 11);
  const std::vector<std::size_t> factors{1, 10, 100, 1000, 10000};
  const auto estimates = allan::estimate(allan::Kind::Oadev, allan::angle_from_rate(noise, 1.0 / fs), 1.0 / fs,
                                         allan::InputType::Rate, factors, kConfidence);
  for (const auto& e : estimates) {
    const double truth = terms.arw_rad_sqrt_s / std::sqrt(e.tau);
    EXPECT_LE(e.dev_lo, truth) << "tau " << e.tau;
    EXPECT_GE(e.dev_hi, truth) << "tau " << e.tau;
  }
}

TEST(ErrorModel, GaussMarkovSumGivesTheFlickerFloorOfB) {
  // Flat floor B sqrt(2 ln2 / pi) for tau well inside [tau_min, tau_max]; +-5 % ripple with two poles
  // per decade plus the estimator's scatter (about 8 % at tau = 300 s in 20 h).
  constexpr double kFloorTolerance = 0.15;
  NoiseTerms terms;
  terms.bias_instability_rad_s = 1e-4;
  terms.flicker_tau_min_s = 0.5;
  terms.flicker_tau_max_s = 5000.0;
  const double fs = 5.0;
  const Eigen::VectorXd noise = rate_noise(terms, fs, static_cast<Eigen::Index>(20 * kSecondsPerHour * fs), 5);
  const double floor = terms.bias_instability_rad_s * std::sqrt(2.0 * std::numbers::ln2 / std::numbers::pi);
  for (const auto& d : oadev(noise, fs, {10, 25, 50, 100, 250, 500, 1500}))
    EXPECT_NEAR(d.dev / floor, 1.0, kFloorTolerance) << "tau " << d.tau;
}

TEST(ErrorModel, AnExplicitGaussMarkovTermHasTheClosedFormAllanVarianceOfGmwm) {
  constexpr double kAllanTolerance = 0.1;  // 20 h against a 100-s process: the estimator's scatter
  NoiseTerms terms;
  terms.gauss_markov.push_back({100.0, 2e-4});
  const double fs = 5.0;
  const Eigen::VectorXd noise = rate_noise(terms, fs, static_cast<Eigen::Index>(20 * kSecondsPerHour * fs), 8);
  for (const auto& d : oadev(noise, fs, {5, 50, 250, 1000, 2500})) {
    const double sigma_tau = std::sqrt(allan::gmwm::process_variance(
        allan::gmwm::Process::GaussMarkov, std::vector<double>{2e-4, 100.0}, d.tau * fs, 1.0 / fs));
    EXPECT_NEAR(d.dev / sigma_tau, 1.0, kAllanTolerance) << "tau " << d.tau;
  }
}

TEST(ErrorModel, RateRandomWalkHasTheAllanSignatureOfK) {
  constexpr double kAllanTolerance = 0.2;  // few independent long-tau intervals in the record
  NoiseTerms terms;
  terms.rate_random_walk_rad_s_sqrt_s = 1e-5;
  const double fs = 10.0;
  const Eigen::VectorXd noise = rate_noise(terms, fs, 1000000, 3);
  for (const auto& d : oadev(noise, fs, {100, 1000, 5000}))
    EXPECT_NEAR(d.dev / (terms.rate_random_walk_rad_s_sqrt_s * std::sqrt(d.tau / 3.0)), 1.0, kAllanTolerance) << d.tau;
}

TEST(ErrorModel, SameSeedSameNoiseAndEachTermHasItsOwnStream) {
  NoiseTerms terms;
  terms.arw_rad_sqrt_s = 1e-4;
  terms.bias_instability_rad_s = 1e-4;
  const Eigen::VectorXd a = rate_noise(terms, 100.0, 1000, 9);
  EXPECT_EQ(a, rate_noise(terms, 100.0, 1000, 9));
  EXPECT_NE(a, rate_noise(terms, 100.0, 1000, 10));
  NoiseTerms white_only = terms;
  white_only.bias_instability_rad_s = 0.0;
  NoiseTerms flicker_only = terms;
  flicker_only.arw_rad_sqrt_s = 0.0;
  constexpr double kRoundingTolerance = 1e-18;  // one addition per sample
  EXPECT_LT(
      (a - rate_noise(white_only, 100.0, 1000, 9) - rate_noise(flicker_only, 100.0, 1000, 9)).cwiseAbs().maxCoeff(),
      kRoundingTolerance);
}

TEST(ErrorModel, AdditiveEffectsFollowTheirDefinitions) {
  constexpr double kRoundingTolerance = 1e-15;
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(101, 0.0, 100.0);
  const Eigen::VectorXd temp = 0.5 * t;  // 0.5 K/s
  Effects e;
  e.temperature_rate = TemperatureRate{2e-5};
  e.warmup_transient = WarmupTransient{1e-4, 20.0};
  e.periodic_disturbance = PeriodicDisturbance{3e-5, 25.0, 0.0};
  const Eigen::VectorXd sum = additive_effects(e, t, temp);
  for (Eigen::Index k = 0; k < t.size(); k += 10) {
    const double expected =
        2e-5 * 0.5 + 1e-4 * std::exp(-t[k] / 20.0) + 3e-5 * std::sin(2 * std::numbers::pi * t[k] / 25.0);
    EXPECT_NEAR(sum[k], expected, kRoundingTolerance) << t[k];
  }
}

TEST(ErrorModel, SystematicRateCombinesDevicePhysicsAndPolynomials) {
  constexpr double kRoundingTolerance = 1e-15;  // rad/s: a few products and sums on a 0.5-rad/s value
  Config c;
  c.reference_temp_c = 25.0;
  c.bias_polynomial_rad_s = {1e-3, 1e-5};
  c.scale_factor_polynomial = {1e-4};
  const DeviceResponse device{1.01, 2e-4, 30000.0};
  const double t = 35.0, w = 0.5;
  EXPECT_NEAR(systematic_rate(c, device, t, w), 1.01 * (1 + 1e-4 * 10) * w + 2e-4 + 1e-3 + 1e-5 * 10,
              kRoundingTolerance);
}

}  // namespace
}  // namespace driftlab::error_model
