// The Allan analysis of models/allan/analysis.hpp and its noise identification at long tau, on
// seeded records from the error model's noise generator (models/error_model: white, flicker as a
// Gauss-Markov sum, random walk).
#include "models/allan/analysis.hpp"
#include "models/allan/confidence.hpp"
#include "models/allan/deviation.hpp"
#include "models/allan/tau_grid.hpp"
#include "models/error_model/error_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace driftlab::allan {
namespace {

constexpr double kRadPerSecPerDph = 3.14159265358979323846 / 180.0 / 3600.0;

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

}  // namespace
}  // namespace driftlab::allan
