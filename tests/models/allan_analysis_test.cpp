// The Allan analysis of models/allan/analysis.hpp and its noise identification at long tau, on
// seeded records from the error model's noise generator (models/error_model: white, flicker as a
// Gauss-Markov sum, random walk).
#include "models/allan/analysis.hpp"
#include "framework/sampling.hpp"
#include "framework/units.hpp"
#include "models/allan/confidence.hpp"
#include "models/allan/deviation.hpp"
#include "models/allan/tau_grid.hpp"
#include "models/error_model/error_model.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace driftlab::allan {
namespace {

Eigen::VectorXd white_rate(double arw_rad_sqrt_s, double fs_hz, Eigen::Index n, std::uint64_t seed) {
  error_model::NoiseTerms terms;
  terms.arw_rad_sqrt_s = arw_rad_sqrt_s;
  return error_model::rate_noise(terms, fs_hz, n, seed);
}

// White rate noise is never taken for angle noise at the longest taus of an octave grid (a few
// averages: the B1 ratio, or a lag-1 autocorrelation of ~30 points). Before estimate() held the
// type from rising with tau, 5 of these 300 taus came out as flicker angle noise (alpha = 1), with
// an edf of 60-440 instead of 3-36: intervals far too narrow where the curve is least certain.
TEST(NoiseIdentification, NeverCallsWhiteRateNoiseAngleNoiseAtLongTau) {
  constexpr int kRecords = 20;
  constexpr double kFs = 10.0;
  int angle_noise = 0, points = 0;
  double last_edf_max = 0.0;
  for (int seed = 1; seed <= kRecords; ++seed) {
    const Eigen::VectorXd angle = angle_from_rate(white_rate(1e-4, kFs, 1 << 16, seed), 1.0 / kFs);
    const auto factors = averaging_factors(TauGrid{}, Kind::Oadev, static_cast<std::size_t>(angle.size()), 1.0 / kFs);
    const auto curve = estimate(Kind::Oadev, angle, 1.0 / kFs, InputType::Rate, factors);
    for (const auto& e : curve) {
      ++points;
      if (e.alpha > 0) ++angle_noise;
    }
    last_edf_max = std::max(last_edf_max, curve.back().edf);
  }
  std::printf("white rate noise: %d of %d taus identified as angle noise; largest edf at the last tau %.3g\n",
              angle_noise, points, last_edf_max);
  EXPECT_EQ(angle_noise, 0);
  // Greenhall & Riley's edf of OADEV at m = 16384 of 65537 angle samples: 4.9 for white rate noise,
  // less for the redder types a few averages may suggest; flicker angle noise would give 60.
  constexpr double kLargestPlausibleEdf = 10.0;
  EXPECT_LT(last_edf_max, kLargestPlausibleEdf);
}

// Regular bursts cut from a continuous record read the continuous record's Allan deviation at every
// tau within a burst: the continuous value (from 60x more data) lies inside the pooled estimate's
// interval about as often as the interval's confidence says. The bursts are 5 s of a 50-Hz record of
// white noise plus a rate random walk, one every 300 s, like the LSM6DSM thermal-vacuum run;
// 95 % intervals, so that the few taus outside are chance, not a too-small edf.
TEST(Bursts, ReadTheContinuousRecordsDeviationWithinTheirIntervals) {
  constexpr double kFs = 50.0, kBurstS = 5.0, kPeriodS = 300.0, kConfidence = 0.95;
  constexpr int kBursts = 25, kRecords = 10;
  const Eigen::Index per_burst = static_cast<Eigen::Index>(kBurstS * kFs);
  const Eigen::Index period = static_cast<Eigen::Index>(kPeriodS * kFs);
  error_model::NoiseTerms terms;
  terms.arw_rad_sqrt_s = 0.01 * 3.14159265358979323846 / 180.0;                 // 0.6 deg/sqrt(h)
  terms.rate_random_walk_rad_s_sqrt_s = 1e-3 * 3.14159265358979323846 / 180.0;  // 3.6 deg/h/sqrt(s)
  int inside = 0, checked = 0;
  for (int seed = 1; seed <= kRecords; ++seed) {
    const Eigen::VectorXd rate = error_model::rate_noise(terms, kFs, kBursts * period, 100 + seed);
    Eigen::VectorXd cut(kBursts * per_burst);
    std::vector<sampling::Segment> segments;
    for (int b = 0; b < kBursts; ++b) {
      cut.segment(b * per_burst, per_burst) = rate.segment(b * period, per_burst);
      segments.push_back({b * per_burst, per_burst});
    }
    const Analysis bursts = analyze_segments(cut, segments, kFs, {.confidence = kConfidence});
    const Analysis continuous = analyze_rate(rate, kFs, {.confidence = kConfidence});
    EXPECT_EQ(bursts.segments, static_cast<std::size_t>(kBursts));
    EXPECT_LE(bursts.curve.back().tau, kBurstS);
    for (const auto& e : bursts.curve) {
      const auto same =
          std::find_if(continuous.curve.begin(), continuous.curve.end(), [&](const Estimate& c) { return c.m == e.m; });
      ASSERT_NE(same, continuous.curve.end());
      ++checked;
      inside += e.dev_lo <= same->dev && same->dev <= e.dev_hi;
    }
  }
  std::printf("continuous deviation inside the bursts' 95 %% interval at %d of %d taus\n", inside, checked);
  // 95 % intervals over 60 taus: fewer than 85 % inside would mean the summed edf overstates what
  // the bursts know (binomial: P(below 85 %) < 0.5 % for correct intervals, ignoring the taus' correlation).
  constexpr double kLeastCoverage = 0.85;
  EXPECT_GE(inside, kLeastCoverage * checked);
}

// The same bursts read as one contiguous record (what `--max-gap 0` used to do) give taus beyond a
// burst, and there a wrong deviation: the random walk of 300 s between bursts is squeezed into one
// step, so at the glued record's longest tau the deviation lies far above the continuous record's at
// that tau, outside both intervals.
TEST(Bursts, ReadAsOneContiguousRecordGiveAWrongDeviationBeyondTheBurst) {
  constexpr double kFs = 50.0;
  constexpr int kBursts = 25;
  const Eigen::Index per_burst = 250, period = 15000;
  error_model::NoiseTerms terms;
  terms.arw_rad_sqrt_s = 0.01 * 3.14159265358979323846 / 180.0;
  terms.rate_random_walk_rad_s_sqrt_s = 1e-3 * 3.14159265358979323846 / 180.0;
  const Eigen::VectorXd rate = error_model::rate_noise(terms, kFs, kBursts * period, 101);
  Eigen::VectorXd cut(kBursts * per_burst);
  for (int b = 0; b < kBursts; ++b) cut.segment(b * per_burst, per_burst) = rate.segment(b * period, per_burst);
  const Analysis glued = analyze_rate(cut, kFs);
  const Analysis continuous = analyze_rate(rate, kFs);
  const auto& last = glued.curve.back();
  const auto same =
      std::find_if(continuous.curve.begin(), continuous.curve.end(), [&](const Estimate& c) { return c.m == last.m; });
  ASSERT_NE(same, continuous.curve.end());
  EXPECT_GT(last.tau, 5.0);
  EXPECT_GT(last.dev_lo, same->dev_hi) << "tau " << last.tau;
}

// B is a value only where the deviation has a floor. White noise alone falls to the end of the
// record: B is a bound there, with no value.
TEST(FloorReading, IsOnlyABoundWhereTheDeviationIsStillFalling) {
  const Analysis a = analyze_rate(white_rate(1e-4, 10.0, 1 << 16, 7), 10.0);
  EXPECT_FALSE(a.bias_instability.resolved);
  EXPECT_DOUBLE_EQ(a.bias_instability.longest_tau_s, a.curve.back().tau);
  EXPECT_GE(a.bias_instability.high, a.bias_instability.value);
}

// A 100-h record at 1 Hz of a gyro with a true floor: B = 1 deg/h (flicker, Gauss-Markov poles from
// 2 s to 1e6 s so that it is flat over the whole record), N = 0.1 deg/sqrt(h), K = 0.3 deg/h/sqrt(h):
// white noise meets the floor near 80 s and the random walk near 15 h, so the deviation has a floor
// between. B is resolved and the true 1 deg/h lies in its interval.
TEST(FloorReading, ReadsATrueFloorWithinItsInterval) {
  constexpr double kFs = 1.0, kHours = 100.0, kTrueB = 1.0;  // deg/h
  error_model::NoiseTerms terms;
  terms.arw_rad_sqrt_s = 0.1 / 60.0 * 3.14159265358979323846 / 180.0;
  terms.bias_instability_rad_s = kTrueB * kRadPerSecPerDph;
  terms.rate_random_walk_rad_s_sqrt_s = 0.3 / 60.0 * kRadPerSecPerDph;
  terms.flicker_tau_min_s = 2.0;
  terms.flicker_tau_max_s = 1e6;
  const Analysis a = analyze_rate(
      error_model::rate_noise(terms, kFs, static_cast<Eigen::Index>(kHours * kSecondsPerHour * kFs), 11), kFs);
  const auto& b = a.bias_instability;
  std::printf("B = %.3g [%.3g, %.3g] deg/h at tau = %g s (resolved: %d)\n", b.value / kRadPerSecPerDph,
              b.low / kRadPerSecPerDph, b.high / kRadPerSecPerDph, b.tau_s, b.resolved);
  EXPECT_TRUE(b.resolved);
  EXPECT_LE(b.low / kRadPerSecPerDph, kTrueB);
  EXPECT_GE(b.high / kRadPerSecPerDph, kTrueB);
}

}  // namespace
}  // namespace driftlab::allan
