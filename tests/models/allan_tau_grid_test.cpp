// Tau grids (Stable32's octave/decade conventions and limits, dense and explicit grids) and the
// confidence-interval machinery's closed forms (chi-square bounds, white-noise edf).
#include "framework/error.hpp"
#include "models/allan/confidence.hpp"
#include "models/allan/tau_grid.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace driftlab::allan {
namespace {

using Factors = std::vector<std::size_t>;

TEST(TauGrid, OctaveAndDecadeFollowStable32sLimits) {
  // GPS record, 241218 phase points: OADEV octave to 32768 and TOTDEV to 65536 (Stable32 tables).
  EXPECT_EQ(averaging_factors(TauGrid{}, Kind::Oadev, 241218, 1.0).back(), 32768u);
  EXPECT_EQ(averaging_factors(TauGrid{}, Kind::Totdev, 241218, 1.0).back(), 65536u);
  // Cs5071A, 556990 points: decade 1, 2, 4, 10, ... 100000 for ADEV, TOTDEV to 200000.
  const TauGrid decade{GridKind::Decade, 10, {}};
  const Factors adev = averaging_factors(decade, Kind::Adev, 556990, 1.0);
  EXPECT_EQ(adev, (Factors{1, 2, 4, 10, 20, 40, 100, 200, 400, 1000, 2000, 4000, 10000, 20000, 40000, 100000}));
  EXPECT_EQ(averaging_factors(decade, Kind::Totdev, 556990, 1.0).back(), 200000u);
  // PHASE.DAT, 1001 points: ADEV/HDEV octave to 128, TOTDEV to 256.
  EXPECT_EQ(averaging_factors(TauGrid{}, Kind::Hdev, 1001, 1.0).back(), 128u);
  EXPECT_EQ(averaging_factors(TauGrid{}, Kind::Totdev, 1001, 1.0).back(), 256u);
}

TEST(TauGrid, DenseGridHasTheRequestedPointsPerDecadeWithoutDuplicates) {
  const TauGrid dense = parse_tau_grid("dense:4");
  EXPECT_EQ(averaging_factors(dense, Kind::Oadev, 4001, 0.01),
            (Factors{1, 2, 3, 6, 10, 18, 32, 56, 100, 178, 316, 562, 1000}));
}

TEST(TauGrid, ExplicitTausRoundToTheSampleIntervalAndRespectTheRecord) {
  const TauGrid list = parse_tau_grid("0.1,0.02,0.1049,5");
  EXPECT_EQ(averaging_factors(list, Kind::Oadev, 1001, 0.01), (Factors{2, 10, 500}));
  EXPECT_THROW(averaging_factors(parse_tau_grid("0.004"), Kind::Oadev, 1001, 0.01), ConfigError);
  EXPECT_THROW(averaging_factors(parse_tau_grid("5.01"), Kind::Oadev, 1001, 0.01), ConfigError);
  EXPECT_THROW(parse_tau_grid("1,x"), ConfigError);
  EXPECT_THROW(parse_tau_grid("-1"), ConfigError);
  EXPECT_THROW(parse_tau_grid(""), ConfigError);
}

TEST(Confidence, ChiSquareBoundsMatchTheClosedFormForTwoDegreesOfFreedom) {
  // chi2 with 2 dof is exponential: quantile(p) = -2 ln(1 - p).
  constexpr double kQuantileTolerance = 1e-12;
  const double confidence = 0.9;
  const Interval b = chi_square_interval(1.0, 2.0, confidence);
  EXPECT_NEAR(b.lo, std::sqrt(2.0 / (-2.0 * std::log(0.05))), kQuantileTolerance);
  EXPECT_NEAR(b.hi, std::sqrt(2.0 / (-2.0 * std::log(0.95))), kQuantileTolerance);
  EXPECT_THROW(chi_square_interval(1.0, 2.0, 1.0), ConfigError);
}

TEST(Confidence, NonOverlappingWhiteRateEdfIsTwoThirdsOfTheTermCount) {
  // Greenhall's basic sum for ADEV and white FM reduces to edf = 2M / (3 - 1/M) exactly.
  constexpr double kClosedFormTolerance = 1e-9;
  for (const std::size_t m : {200u, 1000u, 4000u}) {
    const double terms = static_cast<double>(term_count(Kind::Adev, 556990, m));
    EXPECT_NEAR(equivalent_dof(Kind::Adev, 0, 556990, m) / (2.0 * terms / (3.0 - 1.0 / terms)), 1.0,
                kClosedFormTolerance);
  }
}

}  // namespace
}  // namespace driftlab::allan
