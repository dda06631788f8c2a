// Signal helpers shared by the error model and the effect plugins (framework/signal.hpp).
#include "framework/signal.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace driftlab::signal {
namespace {

TEST(Signal, FirstOrderLagOfARampTrailsByRateTimesTau) {
  constexpr double kExactDiscretization = 1e-10;  // the step is exact for inputs linear between samples
  const double tau = 50.0, rate = 0.02;
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(2001, 0.0, 1000.0);
  const Eigen::VectorXd x = rate * t;
  const Eigen::VectorXd y = first_order_lag(t, x, tau);
  for (Eigen::Index k = 0; k < t.size(); k += 100)
    EXPECT_NEAR(y[k], rate * (t[k] - tau * (1.0 - std::exp(-t[k] / tau))), kExactDiscretization) << t[k];
  EXPECT_EQ(first_order_lag(t, x, 0.0), x);
}

TEST(Signal, HysteresisSwitchesBranchOnReversalAndSaturates) {
  // The state approaches its branch as exp(-travel / width): 10 widths leave at most 2 exp(-10) =
  // 9.1e-5 of the way (s[400], after the reversal from +1); s[200] has exp(-10), s[220] exp(-11).
  constexpr double kSaturated = 1e-4;
  const double width = 2.0;
  Eigen::VectorXd temp(401);
  for (int k = 0; k <= 200; ++k) temp[k] = 0.1 * k;                   // heat 0 -> 20
  for (int k = 201; k <= 400; ++k) temp[k] = 20.0 - 0.1 * (k - 200);  // cool 20 -> 0
  const Eigen::VectorXd s = hysteresis_state(temp, width);
  EXPECT_NEAR(s[200], 1.0, kSaturated);                          // 20 K of travel = 10 widths
  EXPECT_NEAR(s[220], -1.0 + 2.0 * std::exp(-1.0), kSaturated);  // 2 K = one width after reversal
  EXPECT_NEAR(s[400], -1.0, kSaturated);
}

TEST(Signal, DerivativeOfAQuadraticIsExactInsideAndOneSidedAtTheEnds) {
  constexpr double kRoundingTolerance = 1e-12;
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(11, 0.0, 5.0);  // 0.5 s steps
  const Eigen::VectorXd x = t.array().square().matrix();
  const Eigen::VectorXd d = time_derivative(t, x);
  for (Eigen::Index k = 1; k + 1 < t.size(); ++k) EXPECT_NEAR(d[k], 2.0 * t[k], kRoundingTolerance) << k;
  EXPECT_NEAR(d[0], 0.5, kRoundingTolerance);                    // (0.25 - 0) / 0.5
  EXPECT_NEAR(d[10], (25.0 - 20.25) / 0.5, kRoundingTolerance);  // one-sided
}

}  // namespace
}  // namespace driftlab::signal
