// Noise-term fit: unit conversions, exact recovery from a noiseless model curve, and
// simulate-and-recover of angle random walk N, rate random walk K and bias instability B from
// seeded simulated gyro records.
#include "models/allan/confidence.hpp"
#include "models/allan/deviation.hpp"
#include "models/allan/noise_fit.hpp"
#include "models/allan/tau_grid.hpp"
#include "framework/error.hpp"
#include "framework/units.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

namespace driftlab::allan {
namespace {

// Portable standard normal numbers (Box-Muller on mt19937_64), same on every standard library.
class Normal {
 public:
  explicit Normal(std::uint64_t seed) : engine_(seed) {}
  double operator()() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = (static_cast<double>(engine_() >> 11) + 0.5) * 0x1.0p-53;
    const double u2 = static_cast<double>(engine_() >> 11) * 0x1.0p-53;
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2.0 * kPi * u2);
    has_spare_ = true;
    return r * std::cos(2.0 * kPi * u2);
  }

 private:
  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

struct TrueTerms {
  double n = 0.0;  // rad/sqrt(s)
  double b = 0.0;  // rad/s
  double k = 0.0;  // rad/s/sqrt(s)
};

// Rate samples (rad/s) spaced tau0: white noise of density N (std N/sqrt(tau0)), a random walk
// with increments K sqrt(tau0), and flicker-like noise from a sum of first-order Gauss-Markov
// processes with time constants spaced by octaves over [tau0, 8 T_record]: each with variance
// B^2 ln 2 / pi makes the one-sided PSD approximately B^2 / (pi f) between those limits, i.e.
// IEEE 952 C.1's two-sided bias-instability spectrum B^2 / (2 pi f), whose Allan deviation floor
// is sqrt(2 ln 2 / pi) B = 0.664 B. (IEEE 952's PSDs are two-sided: white rate N^2, random walk
// K^2 / (2 pi f)^2, matching the white std N / sqrt(tau0) and walk steps K sqrt(tau0) here.)
Eigen::VectorXd simulate(const TrueTerms& truth, std::size_t samples, double tau0, std::uint64_t seed) {
  Normal normal(seed);
  Eigen::VectorXd rate(static_cast<Eigen::Index>(samples));
  const double white = truth.n / std::sqrt(tau0);
  const double step = truth.k * std::sqrt(tau0);
  std::vector<double> pole;
  std::vector<double> drive;
  std::vector<double> state;
  if (truth.b > 0.0) {
    const double variance = truth.b * truth.b * std::log(2.0) / kPi;
    for (double t = tau0; t < 8.0 * tau0 * static_cast<double>(samples); t *= 2.0) {
      const double a = std::exp(-tau0 / t);
      pole.push_back(a);
      drive.push_back(std::sqrt(variance * (1.0 - a * a)));
      state.push_back(std::sqrt(variance) * normal());
    }
  }
  double walk = 0.0;
  for (Eigen::Index i = 0; i < rate.size(); ++i) {
    double flicker = 0.0;
    for (std::size_t j = 0; j < state.size(); ++j) {
      state[j] = pole[j] * state[j] + drive[j] * normal();
      flicker += state[j];
    }
    rate(i) = white * normal() + walk + flicker;
    walk += step * normal();
  }
  return rate;
}

NoiseFit fit_record(const Eigen::VectorXd& rate, double tau0) {
  const Eigen::VectorXd angle = angle_from_rate(rate, tau0);
  const auto n = static_cast<std::size_t>(angle.size());
  const auto factors = averaging_factors(TauGrid{}, Kind::Oadev, n, tau0);
  const auto curve = estimate(Kind::Oadev, angle, tau0, InputType::Rate, factors);
  return fit_noise_terms(curve);
}

bool inside(const TermEstimate& t, double truth, double width) { return std::abs(t.value - truth) <= width * t.sigma; }

// deg/sqrt(h), deg/h, deg/h/sqrt(h) -> SI.
constexpr double arw(double deg_per_sqrt_h) { return deg_per_sqrt_h * kRadPerDeg / kSqrtSecondsPerHour; }
constexpr double bias(double deg_per_h) { return deg_per_h * kRadPerSecPerDph; }
constexpr double rrw(double deg_per_h_sqrt_h) { return deg_per_h_sqrt_h * kRadPerSecPerDph / kSqrtSecondsPerHour; }

TEST(NoiseFitUnits, ConvertEveryTermToTheUsualGyroUnits) {
  constexpr double kConversionTolerance = 1e-12;  // a few roundings of exact factors
  const auto factor = [](Term t) { return kIeee952Units[static_cast<std::size_t>(t)].factor; };
  EXPECT_NEAR(factor(Term::Q) * (kPi / 180.0), 1.0, kConversionTolerance);
  EXPECT_NEAR(factor(Term::N) * arw(1.0), 1.0, kConversionTolerance);
  EXPECT_NEAR(factor(Term::B) * bias(1.0), 1.0, kConversionTolerance);
  EXPECT_NEAR(factor(Term::K) * rrw(1.0), 1.0, kConversionTolerance);
  EXPECT_NEAR(factor(Term::R) * (kPi / 180.0 / 3600.0 / 3600.0), 1.0, kConversionTolerance);
  // 1 deg/sqrt(h) = 60 deg/h/sqrt(Hz): sqrt(h) = 60 sqrt(s) and 1/sqrt(Hz) = sqrt(s).
  EXPECT_NEAR(kNoiseDensityDegPerHour.factor / factor(Term::N), 60.0, 60.0 * kConversionTolerance);
  EXPECT_EQ(kIeee952Units[1].unit, "deg/sqrt(h)");
  EXPECT_EQ(kIeee952Units[3].unit, "deg/h/sqrt(h)");
  // Kalibr's continuous-time parameters are N and K in SI.
  EXPECT_EQ(kKalibrUnits[0].term, Term::N);
  EXPECT_EQ(kKalibrUnits[0].factor, 1.0);
  EXPECT_EQ(kKalibrUnits[1].term, Term::K);
  EXPECT_EQ(kKalibrUnits[1].unit, "rad/s^2/sqrt(Hz)");
}

TEST(NoiseFit, RecoversEveryTermOfANoiselessModelCurve) {
  constexpr double kExactTolerance = 1e-6;  // relative; conditioning of a 5-term fit over 1e7 in tau
  NoiseFit truth;
  const std::array<double, kTermCount> values{1e-6, arw(0.2), bias(3.0), rrw(2.0), 1e-9};
  for (std::size_t t = 0; t < kTermCount; ++t) truth.terms[t].value = values[t];
  std::vector<Estimate> curve;
  for (double tau = 0.01; tau < 1e5; tau *= 2.0) {
    const double dev = truth.model_deviation(tau);
    curve.push_back({0, tau, dev, 0.99 * dev, 1.01 * dev, 100, 0, 5000.0});
  }
  const NoiseFit fit = fit_noise_terms(curve);
  for (std::size_t t = 0; t < kTermCount; ++t) {
    EXPECT_TRUE(fit.terms[t].fitted) << t;
    EXPECT_NEAR(fit.terms[t].value / values[t], 1.0, kExactTolerance) << t;
  }
}

// 40 seeded records of 2^17 samples at 10 Hz (3.6 h) with N = 0.3 deg/sqrt(h) and
// K = 10 deg/h/sqrt(h) (they cross near tau = 190 s). Nominal coverage of +-2 sigma is 95 %; the
// overlap of neighbouring octave points makes the weights somewhat optimistic, so at least 80 %
// of the trials must land inside.
TEST(NoiseFit, RecoversAngleAndRateRandomWalkInsideTheirIntervals) {
  constexpr int kTrials = 40;
  constexpr double kRequiredFraction = 0.8;
  constexpr double kIntervalWidth = 2.0;  // sigmas
  const TrueTerms truth{arw(0.3), 0.0, rrw(10.0)};
  int n_inside = 0;
  int k_inside = 0;
  for (int trial = 0; trial < kTrials; ++trial) {
    const NoiseFit fit = fit_record(simulate(truth, 1 << 17, 0.1, 1000 + trial), 0.1);
    n_inside += inside(fit[Term::N], truth.n, kIntervalWidth);
    k_inside += inside(fit[Term::K], truth.k, kIntervalWidth);
  }
  std::printf("inside +-2 sigma: N %d, K %d of %d trials\n", n_inside, k_inside, kTrials);
  EXPECT_GE(n_inside, kRequiredFraction * kTrials);
  EXPECT_GE(k_inside, kRequiredFraction * kTrials);
}

// 30 seeded records of 2^16 samples at 5 Hz (3.6 h) with N = 0.3 deg/sqrt(h) and B = 3 deg/h
// (floor from about 80 s on). The flicker is only approximately 1/f (octave-spaced Gauss-Markov sum), so B must
// land within 2 sigma plus 10 % of its true value in at least 80 % of the trials.
TEST(NoiseFit, RecoversBiasInstabilityWithinItsWiderTolerance) {
  constexpr int kTrials = 30;
  constexpr double kRequiredFraction = 0.8;
  constexpr double kIntervalWidth = 2.0;
  constexpr double kFlickerModelTolerance = 0.10;  // of B, for the approximate 1/f spectrum
  const TrueTerms truth{arw(0.3), bias(3.0), 0.0};
  int n_inside = 0;
  int b_inside = 0;
  for (int trial = 0; trial < kTrials; ++trial) {
    const NoiseFit fit = fit_record(simulate(truth, 1 << 16, 0.2, 5000 + trial), 0.2);
    n_inside += inside(fit[Term::N], truth.n, kIntervalWidth);
    b_inside += std::abs(fit[Term::B].value - truth.b) <=
                kIntervalWidth * fit[Term::B].sigma + kFlickerModelTolerance * truth.b;
  }
  std::printf("inside: N %d (+-2 sigma), B %d (+-2 sigma + 10 %%) of %d trials\n", n_inside, b_inside, kTrials);
  EXPECT_GE(n_inside, kRequiredFraction * kTrials);
  EXPECT_GE(b_inside, kRequiredFraction * kTrials);
}

TEST(NoiseFit, RejectsACurveWithoutIntervals) {
  const std::vector<Estimate> curve{{1, 1.0, 1.0, 0.0, 0.0, 10, 0, 0.0}};
  EXPECT_THROW(fit_noise_terms(curve), DataError);
}

}  // namespace
}  // namespace driftlab::allan
