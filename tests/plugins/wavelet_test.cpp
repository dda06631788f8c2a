#include "plugins/wavelet/wavelet.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <stdexcept>
#include <vector>

#include "plugins/builtins.hpp"
#include "framework/error.hpp"
#include "framework/params_io.hpp"
#include "framework/registry.hpp"
#include "tests/plugins/progress_check.hpp"
#include "tests/plugins/seeded_noise.hpp"

namespace driftlab {
namespace {

using testing_noise::kPi;
using testing_noise::standard_normal;

constexpr double kClosedForm = 1e-12;  // a closed form on O(1) values, evaluated another way: rounding

double mse(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).squaredNorm() / static_cast<double>(a.size());
}

double sgn(double v) { return static_cast<double>((v > 0.0) - (v < 0.0)); }

// Donoho & Johnstone 1994, Table 1 / Fig. 1, on t_i = i / n, rescaled to standard deviation 7 so
// that unit-variance noise gives their SNR of 7.
Eigen::VectorXd test_function(const std::string& name, Eigen::Index n) {
  Eigen::VectorXd f(n);
  const std::vector<double> tj{0.1, 0.13, 0.15, 0.23, 0.25, 0.40, 0.44, 0.65, 0.76, 0.78, 0.81};
  for (Eigen::Index i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / static_cast<double>(n);
    double v = 0.0;
    if (name == "heavisine") {
      v = 4.0 * std::sin(4.0 * kPi * t) - sgn(t - 0.3) - sgn(0.72 - t);
    } else if (name == "doppler") {
      constexpr double eps = 0.05;
      v = std::sqrt(t * (1.0 - t)) * std::sin(2.0 * kPi * (1.0 + eps) / (t + eps));
    } else if (name == "blocks") {
      const std::vector<double> h{4, -5, 3, -4, 5, -4.2, 2.1, 4.3, -3.1, 2.1, -4.2};
      for (std::size_t j = 0; j < tj.size(); ++j) v += h[j] * (1.0 + sgn(t - tj[j])) / 2.0;
    } else {  // bumps
      const std::vector<double> h{4, 5, 3, 4, 5, 4.2, 2.1, 4.3, 3.1, 5.1, 4.2};
      const std::vector<double> w{.005, .005, .006, .01, .01, .03, .01, .01, .005, .008, .005};
      for (std::size_t j = 0; j < tj.size(); ++j) v += h[j] * std::pow(1.0 + std::abs((t - tj[j]) / w[j]), -4.0);
    }
    f[i] = v;
  }
  const double sd = std::sqrt((f.array() - f.mean()).square().mean());
  return f * (7.0 / sd);
}

TEST(WaveletThresholds, MatchTheirClosedForms) {
  constexpr double kSameFormula = 1e-15;  // sqrt(2 ln n) both sides: an ulp or two of ~3.7 (ulp 4.4e-16)
  constexpr double kTenDigits = 1e-9;     // the reference value is printed with 10 digits (+-5e-10)
  // Universal: sqrt(2 ln n).
  EXPECT_NEAR(wavelet::universal_threshold(1024), std::sqrt(2.0 * std::log(1024.0)), kSameFormula);
  EXPECT_NEAR(wavelet::universal_threshold(1024), 3.723297411, kTenDigits);
  // MAD: median(|c|) / 0.6745 (the median of |Z|, Z standard normal: 0.674489750...).
  EXPECT_NEAR(wavelet::mad_sigma({1.0, -2.0, 3.0, -4.0, 5.0}), 3.0 / 0.6744897501960817, kClosedForm);
  EXPECT_NEAR(wavelet::mad_sigma({-1.0, 2.0, -3.0, 4.0}), 2.5 / 0.6744897501960817, kClosedForm);
  // SURE on y = (0.1, -0.5, 3, 4): SURE(t) = 4 - 2 #{|y| <= t} + sum min(|y|, t)^2;
  // t = 0: 4, t = 0.1: 2.04, t = 0.5: 0.76, t = 3: 16.26 -> 0.5 (below the cap sqrt(2 ln 4) = 1.665).
  const std::vector<double> y{0.1, -0.5, 3.0, 4.0};
  EXPECT_NEAR(wavelet::sure_risk(y, 0.0), 4.0, kClosedForm);
  EXPECT_NEAR(wavelet::sure_risk(y, 0.1), 2.04, kClosedForm);
  EXPECT_NEAR(wavelet::sure_risk(y, 0.5), 0.76, kClosedForm);
  EXPECT_NEAR(wavelet::sure_risk(y, 1.0), 4.0 - 4.0 + 0.01 + 0.25 + 1.0 + 1.0, kClosedForm);
  EXPECT_DOUBLE_EQ(wavelet::sure_threshold(y), 0.5);
  // Hybrid: s^2 = (sum y^2 - n) / n = (25.26 - 4) / 4 = 5.315 > (log2 4)^1.5 / sqrt(4) = 1.414: SURE.
  EXPECT_DOUBLE_EQ(wavelet::hybrid_sure_threshold(y), 0.5);
  // A sparse level (energy below n): universal sqrt(2 ln 4).
  EXPECT_NEAR(wavelet::hybrid_sure_threshold({0.1, 0.2, -0.1, 0.3}), std::sqrt(2.0 * std::log(4.0)), kSameFormula);
  // Shrinkage rules.
  EXPECT_DOUBLE_EQ(wavelet::soft(3.0, 1.0), 2.0);
  EXPECT_DOUBLE_EQ(wavelet::soft(-3.0, 1.0), -2.0);
  EXPECT_DOUBLE_EQ(wavelet::soft(0.5, 1.0), 0.0);
  EXPECT_DOUBLE_EQ(wavelet::hard(3.0, 1.0), 3.0);
  EXPECT_DOUBLE_EQ(wavelet::hard(-0.5, 1.0), 0.0);
}

TEST(WaveletDenoise, EstimatesTheWhiteNoiseLevelFromTheFinestDetails) {
  // MAD of 2048 Gaussian coefficients: relative standard error ~1.166 / sqrt(2048) = 2.6 %; 3 sigma.
  constexpr double kMadSpread = 0.08;  // relative: 3 x 2.6 %
  const Eigen::VectorXd noise = 2.0 * standard_normal(4096, 1);
  const wavelet::Result r = wavelet::denoise(noise, {});
  ASSERT_EQ(r.levels, 5);
  EXPECT_NEAR(r.sigma[0], 2.0, 2.0 * kMadSpread);
  // Universal threshold in signal units.
  EXPECT_NEAR(r.thresholds[0], r.sigma[0] * std::sqrt(2.0 * std::log(4096.0)), kClosedForm);
}

TEST(WaveletDenoise, PureNoiseIsRemovedByTheUniversalThreshold) {
  const Eigen::VectorXd noise = standard_normal(4096, 2);
  const wavelet::Result r = wavelet::denoise(noise, {.levels = 12, .shrink = wavelet::Shrink::Hard});
  // Max of n Gaussians exceeds sqrt(2 ln n) with probability -> 0 (Donoho & Johnstone 1994, Sec. 1.4):
  // almost every coefficient is zeroed. Only the scaling coefficient (the mean) survives.
  std::size_t kept = 0;
  for (const auto k : r.kept) kept += k;
  EXPECT_LE(kept, 2u);
  EXPECT_LT(std::sqrt(mse(r.denoised, Eigen::VectorXd::Zero(4096))), 0.1);
}

TEST(WaveletDenoise, ANoiselessPolynomialPassesUnchanged) {
  // db4 (k = 8) has 4 vanishing moments: the details of a cubic vanish away from the padding seam,
  // so the median of |d| is 0, every threshold is 0 and the transform is inverted exactly.
  const Eigen::Index n = 1000;
  Eigen::VectorXd x(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / static_cast<double>(n);
    x[i] = 1.0 + 2.0 * t - 3.0 * t * t + 0.5 * t * t * t;
  }
  const wavelet::Result r = wavelet::denoise(x, {});
  EXPECT_LT(r.thresholds[0], 1e-12);  // the median |d| is rounding noise
  EXPECT_LT((r.denoised - x).cwiseAbs().maxCoeff(), 1e-12);
}

struct DonohoJohnstoneCase {
  std::string function;
  double universal_mse_max, sure_mse_max;
};

// VisuShrink (universal, soft) and SureShrink (hybrid SURE, soft) on the four Donoho-Johnstone
// signals at SNR 7, n = 2048, unit noise, db8 (k = 16, close to their Symmlet 8), every level down
// to 32 coarse coefficients (L = 6), as in Donoho & Johnstone 1995 Sec. 5. Bounds: the values
// measured here (seed 3) x 1.3; noise alone has MSE 1. Measured MSE, universal / SURE:
// HeaviSine 0.125 / 0.075, Doppler 0.371 / 0.090, Blocks 1.144 / 0.397, Bumps 1.426 / 0.280:
// VisuShrink's universal threshold kills the narrow bumps and blurs the jumps (its MSE there is
// above the noise's), while SURE's per-level thresholds keep them, the contrast of DJ 1995 Fig. 2-3.
class WaveletDonohoJohnstone : public ::testing::TestWithParam<DonohoJohnstoneCase> {};

TEST_P(WaveletDonohoJohnstone, VisuShrinkAndSureShrinkReachTheirRiskAndSureBeatsVisu) {
  const Eigen::Index n = 2048;
  const Eigen::VectorXd f = test_function(GetParam().function, n);
  const Eigen::VectorXd y = f + standard_normal(n, 3);
  const wavelet::Config visu{.order = 16, .levels = 6};
  const wavelet::Result universal = wavelet::denoise(y, visu);
  wavelet::Config sure_config = visu;
  sure_config.rule = wavelet::ThresholdRule::SureHybrid;
  const wavelet::Result sure = wavelet::denoise(y, sure_config);
  const double mse_universal = mse(universal.denoised, f);
  const double mse_sure = mse(sure.denoised, f);
  RecordProperty("mse_universal", std::to_string(mse_universal));
  RecordProperty("mse_sure", std::to_string(mse_sure));
  EXPECT_LT(mse_universal, GetParam().universal_mse_max);
  EXPECT_LT(mse_sure, GetParam().sure_mse_max);
  // SureShrink adapts per level and beats VisuShrink's oversmoothing (DJ 1995).
  EXPECT_LT(mse_sure, mse_universal);
  EXPECT_LT(mse(y, f), 1.2);  // the noise really is unit variance
}

INSTANTIATE_TEST_SUITE_P(Signals, WaveletDonohoJohnstone,
                         ::testing::Values(DonohoJohnstoneCase{"heavisine", 0.16, 0.10},
                                           DonohoJohnstoneCase{"doppler", 0.48, 0.12},
                                           DonohoJohnstoneCase{"blocks", 1.49, 0.52},
                                           DonohoJohnstoneCase{"bumps", 1.85, 0.37}),
                         [](const auto& test) { return test.param.function; });

TEST(WaveletDenoise, PaddedLengthsAndEveryFamilyRoundTripWithZeroThreshold) {
  const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(777, 0.0, 1.0).array().square();  // smooth
  for (const auto& [family, order] : std::vector<std::pair<wavelet::Family, int>>{
           {wavelet::Family::Haar, 2}, {wavelet::Family::DaubechiesCentered, 4}, {wavelet::Family::Bspline, 309}}) {
    // Hard rule at a zero threshold: a noiseless ramp squared has many zero finest details only for
    // the Daubechies family; check the transform pair through the configuration's full path.
    const wavelet::Result r =
        wavelet::denoise(x, {.family = family, .order = order, .levels = 1, .shrink = wavelet::Shrink::Hard});
    ASSERT_EQ(r.denoised.size(), 777);
    EXPECT_LT(std::sqrt(mse(r.denoised, x)), 0.01) << order;
  }
}

// Progress (wavelet::Config::progress): after the forward transform and after each level, counted
// in coefficients, increasing in [0, 1), and the same bits with or without a listener.
TEST(WaveletDenoise, ReportsTheTransformAndEachLevelAndGivesTheSameBits) {
  const Eigen::VectorXd y = test_function("heavisine", 1000) + standard_normal(1000, 12);
  wavelet::Config c{.levels = 5, .rule = wavelet::ThresholdRule::Sure, .noise = wavelet::NoiseEstimate::PerLevel};
  const wavelet::Result plain = wavelet::denoise(y, c);
  testing_progress::Recorder recorder;
  c.progress = recorder.listener();
  const wavelet::Result r = wavelet::denoise(y, c);
  EXPECT_EQ(r.denoised, plain.denoised);
  EXPECT_EQ(r.thresholds, plain.thresholds);
  const auto fractions = testing_progress::checked_fractions(recorder.fractions);
  // M = 1024: forward 1024, levels 512 + 256 + 128 + 64 + 32, inverse 1024 coefficients.
  constexpr double kWork = 1024.0 + 992.0 + 1024.0;
  ASSERT_EQ(fractions.size(), 6u);
  EXPECT_DOUBLE_EQ(fractions.front(), 1024.0 / kWork);
  EXPECT_DOUBLE_EQ(fractions[1], 1536.0 / kWork);
  EXPECT_DOUBLE_EQ(fractions.back(), 2016.0 / kWork);
}

TEST(WaveletDenoise, RejectsOrdersTheFamilyLacksAndBadData) {
  const Eigen::VectorXd x = Eigen::VectorXd::Ones(64);
  EXPECT_THROW(wavelet::denoise(x, {.order = 5}), std::invalid_argument);
  EXPECT_THROW(wavelet::denoise(x, {.family = wavelet::Family::Haar, .order = 4}), std::invalid_argument);
  EXPECT_THROW(wavelet::denoise(x, {.levels = 0}), std::invalid_argument);
  EXPECT_THROW(wavelet::denoise(Eigen::VectorXd::Ones(7), {}), std::domain_error);
  Eigen::VectorXd bad = x;
  bad[3] = INFINITY;
  EXPECT_THROW(wavelet::denoise(bad, {}), std::domain_error);
  EXPECT_TRUE(wavelet::valid_order(wavelet::Family::Bspline, 103));
  EXPECT_FALSE(wavelet::valid_order(wavelet::Family::Bspline, 104));
}

TEST(WaveletPlugin, FiltersThroughTheRegistryAndRejectsAMismatchedOrder) {
  Registry registry;
  register_builtin_plugins(registry);
  EXPECT_THROW(params_from_assignments(registry, "filter/wavelet", {"wavelet=haar", "order=8"}), ConfigError);
  auto filter = registry.create_as<Filter>(
      {"filter/wavelet", params_from_assignments(registry, "filter/wavelet", {"threshold=sure_hybrid", "levels=4"})});
  const Eigen::VectorXd f = test_function("heavisine", 1024);
  const Eigen::VectorXd y = f + standard_normal(1024, 9);
  RunContext ctx;
  testing_progress::Recorder recorder;
  ctx.progress = recorder.listener();
  const Eigen::VectorXd out = filter->filter(y, ctx);
  EXPECT_EQ(testing_progress::checked_fractions(recorder.fractions).size(), 5u) << "the step's progress";
  EXPECT_LT(mse(out, f), 0.5 * mse(y, f));
  EXPECT_EQ(ctx.diagnostics["levels"].get<int>(), 4);
  EXPECT_EQ(ctx.diagnostics["threshold_per_level"].size(), 4u);
  EXPECT_THROW(filter->filter(Eigen::VectorXd::Ones(4), ctx), DataError);
}

}  // namespace
}  // namespace driftlab
