#include "plugins/polynomial/polynomial.hpp"

#include <gtest/gtest.h>

#include <random>

#include "plugins/builtins.hpp"
#include "framework/error.hpp"
#include "framework/params_io.hpp"
#include "framework/registry.hpp"

namespace driftlab {
namespace {

constexpr double kRounding = 1e-9;  // relative: double least squares on well-scaled columns

Eigen::VectorXd ramp(Eigen::Index n, double lo, double hi) { return Eigen::VectorXd::LinSpaced(n, lo, hi); }

TEST(Polynomial, RecoversAnExactCubicInPowersOfXMinusX0) {
  const Eigen::VectorXd x = ramp(400, -30, 60);
  const std::vector<double> a{1e-3, -2e-5, 3e-7, -4e-9};
  Eigen::VectorXd y(x.size());
  for (Eigen::Index i = 0; i < x.size(); ++i) y[i] = polynomial::evaluate(a, 25.0, x[i]);
  const auto fit = polynomial::fit(x, y, {.min_order = 3, .max_order = 3, .blocks = 4, .x0 = 25.0});
  ASSERT_EQ(fit.order, 3);
  for (int i = 0; i <= 3; ++i) EXPECT_NEAR(fit.coefficients[i], a[i], kRounding * std::abs(a[i]) + 1e-18) << i;
}

TEST(Polynomial, BlockedCrossValidationEqualsRefittingWithoutEachBlock) {
  constexpr double kSameFits = 1e-12;  // the same least-squares fits, redone here block by block: rounding
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 0.1);
  const Eigen::VectorXd x = ramp(90, 0, 1);
  Eigen::VectorXd y = (x.array() * 2.0 + 1.0).matrix();
  for (auto& v : y) v += noise(rng);
  const Eigen::MatrixXd A = polynomial::scaled_powers(x, 0.0, 1.0, 2);
  double ss = 0.0;
  for (int b = 0; b < 3; ++b) {
    std::vector<Eigen::Index> train, test;
    for (Eigen::Index i = 0; i < 90; ++i) (i / 30 == b ? test : train).push_back(i);
    const auto lf = polynomial::least_squares(A(train, Eigen::all), y(train));
    ss += (y(test) - A(test, Eigen::all) * lf.coefficients).squaredNorm();
  }
  EXPECT_NEAR(polynomial::blocked_cv_rmse(A, y, 3), std::sqrt(ss / 90.0), kSameFits);
}

TEST(Polynomial, OrderChoiceOnHeldOutBlocksFindsAQuadraticUnderNoise) {
  constexpr double kSigmas = 5.0;  // a noisy fit's coefficient against its truth, in its own standard errors
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.01);
  const Eigen::VectorXd x = ramp(2000, -30, 60);
  Eigen::VectorXd y(x.size());
  for (Eigen::Index i = 0; i < x.size(); ++i) y[i] = polynomial::evaluate({0.5, 0.02, 1e-3}, 25.0, x[i]) + noise(rng);
  const auto fit = polynomial::fit(x, y, {.min_order = 1, .max_order = 6, .blocks = 8, .x0 = 25.0});
  EXPECT_GE(fit.order, 2);
  EXPECT_LE(fit.order, 4);
  EXPECT_EQ(fit.cv_rmse.size(), 6u);
  EXPECT_NEAR(fit.coefficients[2], 1e-3, kSigmas * fit.standard_errors[2]);
}

TEST(Polynomial, RejectsTooFewRowsAndNonFiniteData) {
  const Eigen::VectorXd x = ramp(3, 0, 1);
  EXPECT_THROW(polynomial::fit(x, x, {.min_order = 5, .max_order = 5, .blocks = 2}), std::invalid_argument);
  Eigen::VectorXd bad = ramp(50, 0, 1);
  bad[3] = std::nan("");
  EXPECT_THROW(polynomial::fit(ramp(50, 0, 1), bad, {}), std::invalid_argument);
}

TEST(PolynomialPlugin, PredictsAfterFitAndRefusesBeforeOrWithTwoFeatures) {
  Registry registry;
  register_builtin_plugins(registry);
  auto reg = registry.create_as<Regressor>(
      {"regressor/polynomial", params_from_assignments(registry, "regressor/polynomial", {"order=2", "center=0"})});
  const Eigen::MatrixXd X = ramp(100, -1, 1);
  EXPECT_THROW(reg->predict(X), NotFittedError);
  const Eigen::VectorXd y = (X.col(0).array().square() * 3.0 + 1.0).matrix();
  RunContext ctx;
  reg->fit(X, y, ctx);
  EXPECT_NEAR(reg->predict(X)(10), y(10), kRounding);  // an exact quadratic, y ~ 3
  EXPECT_EQ(ctx.diagnostics["order"], 2);
  EXPECT_THROW(reg->fit(Eigen::MatrixXd::Ones(100, 2), y, ctx), DataError);
}

}  // namespace
}  // namespace driftlab
