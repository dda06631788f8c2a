#include "plugins/tfpf/tfpf.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <stdexcept>

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

Eigen::VectorXd sampled(Eigen::Index n, const std::function<double(double)>& f) {
  Eigen::VectorXd x(n);
  for (Eigen::Index i = 0; i < n; ++i) x[i] = f(static_cast<double>(i));
  return x;
}

double snr_db(const Eigen::VectorXd& clean, const Eigen::VectorXd& estimate) {
  const double signal = (clean.array() - clean.mean()).square().sum();
  return 10.0 * std::log10(signal / (estimate - clean).squaredNorm());
}

TEST(Tfpf, IsExactForASignalLinearOverTheWindow) {
  // The trapezoidal FM phase makes phi[n+m] - phi[n-m] = 4 pi m x_s[n] exactly for a linear x_s,
  // so the PWVD peak is the signal itself (Boashash & Mesbah 2004, Sec. II).
  const Eigen::VectorXd ramp = sampled(400, [](double i) { return -2.0 + 0.01 * i; });
  const tfpf::Result r = tfpf::filter(ramp, {.rule = tfpf::WindowRule::Fixed, .window = 31});
  EXPECT_EQ(r.window, 31);
  // Interior only: at the ends the reflected extension bends the ramp inside the window.
  constexpr double kNewtonTolerance = 1e-9;  // peak located to ~1e-13 cycles/lag, times range / 0.2
  EXPECT_LT((r.filtered - ramp).segment(15, 370).cwiseAbs().maxCoeff(), kNewtonTolerance);
  // Any symmetric lag weighting keeps the peak where the phase is linear: Hann too.
  const tfpf::Result hann =
      tfpf::filter(ramp, {.rule = tfpf::WindowRule::Fixed, .window = 31, .lag_window = tfpf::LagWindow::Hann});
  EXPECT_LT((hann.filtered - ramp).segment(15, 370).cwiseAbs().maxCoeff(), kNewtonTolerance);
}

TEST(Tfpf, ConstantSignalsPassUnchanged) {
  const Eigen::VectorXd c = Eigen::VectorXd::Constant(50, 3.5);
  EXPECT_EQ(tfpf::filter(c, {}).filtered, c);
}

TEST(Tfpf, RaisesTheSnrOfASlowSineInWhiteNoise) {
  // Period 400 samples, amplitude 1, noise sigma 0.5: input SNR 3 dB.
  // dB: the noise power of 4000 samples scatters by sqrt(2 / 4000) = 2.2 % = 0.1 dB; 3 sigma.
  constexpr double kInputSnrDb = 0.3;
  const Eigen::Index n = 4000;
  const Eigen::VectorXd clean = sampled(n, [](double i) { return std::sin(2.0 * kPi * i / 400.0); });
  const Eigen::VectorXd noisy = clean + 0.5 * standard_normal(n, 1);
  const double in = snr_db(clean, noisy);
  const tfpf::Result fixed = tfpf::filter(noisy, {.rule = tfpf::WindowRule::Fixed, .window = 41});
  const tfpf::Result adaptive = tfpf::filter(noisy, {});
  RecordProperty("snr_in_db", std::to_string(in));
  RecordProperty("snr_fixed41_db", std::to_string(snr_db(clean, fixed.filtered)));
  RecordProperty("snr_adaptive_db", std::to_string(snr_db(clean, adaptive.filtered)));
  RecordProperty("adaptive_window", std::to_string(adaptive.window));
  EXPECT_NEAR(in, 3.0, kInputSnrDb);
  // A window of L samples averages the noise's phase increments over up to L lags; measured (seed 1):
  // L = 41: 3.1 -> 17.5 dB (+14.4 dB); the noise rule picks L = 15 for this noise share (sigma^2 /
  // var = 0.33): 3.1 -> 13.8 dB (+10.7 dB). Bounds leave ~3 dB for other seeds.
  EXPECT_GT(snr_db(clean, fixed.filtered) - in, 11.0);
  EXPECT_GT(snr_db(clean, adaptive.filtered) - in, 8.0);
}

TEST(Tfpf, TracksALinearChirpInWhiteNoise) {
  // Frequency sweeping 0.001 -> 0.005 cycles/sample over 4000 samples, noise sigma 0.3 (SNR 7.4 dB).
  const Eigen::Index n = 4000;
  const Eigen::VectorXd clean = sampled(n, [n](double i) {
    const double f0 = 0.001, f1 = 0.005, rate = (f1 - f0) / static_cast<double>(n);
    return std::sin(2.0 * kPi * (f0 * i + 0.5 * rate * i * i));
  });
  const Eigen::VectorXd noisy = clean + 0.3 * standard_normal(n, 2);
  const double in = snr_db(clean, noisy);
  const tfpf::Result r = tfpf::filter(noisy, {.rule = tfpf::WindowRule::Fixed, .window = 25});
  RecordProperty("snr_in_db", std::to_string(in));
  RecordProperty("snr_out_db", std::to_string(snr_db(clean, r.filtered)));
  constexpr double kMinimumGainDb = 9.0;  // measured (seed 2): 7.3 -> 20.0 dB, +12.6 dB
  EXPECT_GT(snr_db(clean, r.filtered) - in, kMinimumGainDb);
}

TEST(Tfpf, LongerWindowsForNoisierInputsByTheDocumentedRule) {
  // Noise estimate (below): sigma within 3 x the MAD's ~2 % relative standard error (6 % of 2.0);
  // the share sigma^2 / var (clamped at 1) doubles that error (4 %): 2.5 sigmas (measured 0.1 %, 0.4 %).
  constexpr double kNoiseSigma = 0.12, kNoiseShare = 0.1;
  EXPECT_EQ(tfpf::window_for_noise_share(0.05, 9, 65, 10000), 9);
  EXPECT_EQ(tfpf::window_for_noise_share(0.95, 9, 65, 10000), 65);
  // Midway (share 0.5): 9 * (65 / 9)^0.5 = 24.19 -> nearest odd 25.
  EXPECT_EQ(tfpf::window_for_noise_share(0.5, 9, 65, 10000), 25);
  EXPECT_EQ(tfpf::window_for_noise_share(0.95, 9, 65, 40), 39);  // capped by the record
  // Noise estimate: MAD of first differences / sqrt(2) on white noise of sigma 2 (3-sigma band of the
  // MAD's ~2 % relative standard error on 20000 samples).
  const tfpf::NoiseEstimate white = tfpf::estimate_noise(2.0 * standard_normal(20000, 5));
  EXPECT_NEAR(white.sigma, 2.0, kNoiseSigma);
  EXPECT_NEAR(white.share, 1.0, kNoiseShare);
  // A clean slow sine has almost no noise: the short window.
  const Eigen::VectorXd slow = sampled(2000, [](double i) { return std::sin(2.0 * kPi * i / 500.0); });
  EXPECT_LT(tfpf::estimate_noise(slow).share, 0.01);
  EXPECT_EQ(tfpf::filter(slow, {}).window, 9);
  EXPECT_EQ(tfpf::filter(2.0 * standard_normal(2000, 6), {}).window, 65);
}

// Progress (tfpf::Config::progress): one report per block of ceil(N / 100) samples but the last,
// increasing in [0, 1), and the same bits with or without a listener.
TEST(Tfpf, ReportsEachBlockOfSamplesAndGivesTheSameBits) {
  const Eigen::VectorXd x =
      sampled(1001, [](double i) { return std::sin(2.0 * kPi * i / 300.0); }) + 0.3 * standard_normal(1001, 9);
  tfpf::Config c;
  const tfpf::Result plain = tfpf::filter(x, c);
  testing_progress::Recorder recorder;
  c.progress = recorder.listener();
  const tfpf::Result r = tfpf::filter(x, c);
  EXPECT_EQ(r.filtered, plain.filtered);
  const auto fractions = testing_progress::checked_fractions(recorder.fractions);
  ASSERT_EQ(fractions.size(), 90u);  // blocks of 11 samples: after 11, 22, ..., 990
  EXPECT_DOUBLE_EQ(fractions.front(), 11.0 / 1001.0);
  EXPECT_DOUBLE_EQ(fractions.back(), 990.0 / 1001.0);
}

TEST(Tfpf, RejectsBadConfigurationAndBadData) {
  const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(20, 0.0, 1.0);
  EXPECT_THROW(tfpf::filter(x, {.window = 4}), std::invalid_argument);
  EXPECT_THROW(tfpf::filter(x, {.short_window = 11, .long_window = 9}), std::invalid_argument);
  EXPECT_THROW(tfpf::filter(Eigen::VectorXd::Ones(2), {}), std::domain_error);
  Eigen::VectorXd bad = x;
  bad[1] = std::nan("");
  EXPECT_THROW(tfpf::filter(bad, {}), std::domain_error);
}

TEST(TfpfPlugin, FiltersThroughTheRegistryAndReportsTheWindow) {
  constexpr double kWindowSeconds = 1e-9;  // s: 21 samples at the rate of the time stamps, to rounding
  Registry registry;
  register_builtin_plugins(registry);
  EXPECT_THROW(params_from_assignments(registry, "filter/tfpf", {"window=30"}), ConfigError);
  EXPECT_THROW(params_from_assignments(registry, "filter/tfpf", {"short_window=71"}), ConfigError);
  auto filter = registry.create_as<Filter>(
      {"filter/tfpf", params_from_assignments(registry, "filter/tfpf", {"window_rule=fixed", "window=21"})});
  RunContext ctx;
  ctx.time_s = Eigen::VectorXd::LinSpaced(1000, 0.0, 99.9);  // 10 Hz
  testing_progress::Recorder recorder;
  ctx.progress = recorder.listener();
  const Eigen::VectorXd clean = sampled(1000, [](double i) { return std::sin(2.0 * kPi * i / 300.0); });
  const Eigen::VectorXd out = filter->filter(clean + 0.3 * standard_normal(1000, 8), ctx);
  EXPECT_EQ(testing_progress::checked_fractions(recorder.fractions).size(), 99u) << "the step's progress";
  EXPECT_GT(snr_db(clean, out), snr_db(clean, clean + 0.3 * standard_normal(1000, 8)) + 6.0);
  EXPECT_EQ(ctx.diagnostics["window_samples"].get<int>(), 21);
  EXPECT_NEAR(ctx.diagnostics["window_s"].get<double>(), 2.1, kWindowSeconds);
  EXPECT_THROW(filter->filter(Eigen::VectorXd::Ones(2), ctx), DataError);
}

}  // namespace
}  // namespace driftlab
