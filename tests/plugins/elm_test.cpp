#include "plugins/elm/elm.hpp"

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>

#include "plugins/builtins.hpp"
#include "framework/error.hpp"
#include "framework/params_io.hpp"
#include "framework/registry.hpp"
#include "plugins/common/ridge.hpp"
#include "tests/plugins/progress_check.hpp"

namespace driftlab {
namespace {

struct Data {
  Eigen::MatrixXd X;
  Eigen::VectorXd y;
};

// y = sin(2 x1) + 0.5 x2^2 on a 40 x 40 grid over [-2, 2]^2 (or offset by half a step).
Data known_function(double offset) {
  Data d{Eigen::MatrixXd(1600, 2), Eigen::VectorXd(1600)};
  for (int i = 0; i < 40; ++i) {
    for (int j = 0; j < 40; ++j) {
      const double x1 = -2.0 + (i + offset) * 0.1, x2 = -2.0 + (j + offset) * 0.1;
      d.X.row(i * 40 + j) << x1, x2;
      d.y[i * 40 + j] = std::sin(2.0 * x1) + 0.5 * x2 * x2;
    }
  }
  return d;
}

double rmse(const Eigen::VectorXd& a, const Eigen::VectorXd& b) { return std::sqrt((a - b).squaredNorm() / a.size()); }

TEST(Elm, LearnsAKnownSmoothFunctionAndPredictsBetweenTheTrainingPoints) {
  // 100 units on 1600 points: interpolation error below 0.5 % of the target's range (~4.7).
  constexpr double kRmseTolerance = 0.02;
  const auto train = known_function(0.0), test = known_function(0.5);
  for (const auto g : {elm::Activation::Sigmoid, elm::Activation::Tanh, elm::Activation::Sine}) {
    const auto model = elm::fit(train.X, train.y, {.hidden = 100, .activation = g, .regularization = 1e-10});
    // The offset grid's last row and column lie outside the training range: left out.
    const Eigen::VectorXd e = model.predict(test.X) - test.y;
    double sq = 0;
    int n = 0;
    for (int i = 0; i < 39; ++i) {
      for (int j = 0; j < 39; ++j, ++n) sq += e[i * 40 + j] * e[i * 40 + j];
    }
    EXPECT_LT(std::sqrt(sq / n), kRmseTolerance) << static_cast<int>(g);
  }
}

TEST(Elm, WithoutRegularizationItsOutputWeightsAreTheLeastSquaresSolutionOnTheHiddenLayer) {
  // Independent truth: Householder QR least squares on [H, 1], not the normal equations.
  constexpr double kTolerance = 1e-5;  // normal equations square the condition number of [H, 1]
  const auto d = known_function(0.0);
  const auto model = elm::fit(d.X, d.y, {.hidden = 20, .regularization = 0.0, .seed = 3});
  Eigen::MatrixXd A(d.X.rows(), 21);
  A.leftCols(20) = model.hidden(d.X);
  A.col(20).setOnes();
  const Eigen::VectorXd w = A.colPivHouseholderQr().solve(d.y);
  EXPECT_LT(rmse(model.predict(d.X), A * w), kTolerance);
}

TEST(Elm, TheSameSeedGivesTheSameModelAndAnotherSeedAnotherHiddenLayer) {
  const auto d = known_function(0.0);
  const auto a = elm::fit(d.X, d.y, {.hidden = 10, .seed = 5});
  const auto b = elm::fit(d.X, d.y, {.hidden = 10, .seed = 5});
  const auto c = elm::fit(d.X, d.y, {.hidden = 10, .seed = 6});
  EXPECT_EQ(a.input_weights(), b.input_weights());
  EXPECT_EQ(a.predict(d.X), b.predict(d.X));
  EXPECT_NE(a.input_weights(), c.input_weights());
  EXPECT_LE(a.input_weights().cwiseAbs().maxCoeff(), 1.0);  // uniform in [-input_scale, input_scale]
}

TEST(Elm, MoreRegularizationShrinksTheOutputWeightsAndRaisesTheTrainingError) {
  // The ridge trade-off the NSGA-II of the 2024 paper explores: both are monotone in lambda.
  const auto d = known_function(0.0);
  double previous_norm = INFINITY, previous_error = 0.0;
  for (const double lambda : {1e-10, 1e-6, 1e-3, 1e-1}) {
    const auto m = elm::fit(d.X, d.y, {.hidden = 50, .regularization = lambda});
    const double error = rmse(m.predict(d.X), d.y);
    EXPECT_LT(m.output_weight_norm(), previous_norm) << lambda;
    EXPECT_GE(error, previous_error) << lambda;
    previous_norm = m.output_weight_norm();
    previous_error = error;
  }
}

// Progress (elm::Config::progress): before each block of ridge::kBlockRows rows but the first,
// increasing in [0, 1), and the same model with or without a listener.
TEST(Elm, ReportsEachBlockOfRowsAndGivesTheSameModel) {
  constexpr Eigen::Index kRows = 20000;  // 5 blocks of 4096 rows
  const Eigen::MatrixXd X = Eigen::VectorXd::LinSpaced(kRows, -2.0, 2.0);
  const Eigen::VectorXd y = X.col(0).array().sin();
  elm::Config c{.hidden = 10};
  const auto plain = elm::fit(X, y, c);
  testing_progress::Recorder recorder;
  c.progress = recorder.listener();
  const auto model = elm::fit(X, y, c);
  EXPECT_EQ(model.output_weights(), plain.output_weights());
  EXPECT_EQ(model.output_bias(), plain.output_bias());
  const auto fractions = testing_progress::checked_fractions(recorder.fractions);
  ASSERT_EQ(fractions.size(), 4u);
  for (std::size_t k = 0; k < fractions.size(); ++k)
    EXPECT_DOUBLE_EQ(fractions[k], static_cast<double>((k + 1) * ridge::kBlockRows) / kRows);
}

TEST(Elm, RejectsBadDataAndConfigurations) {
  const auto d = known_function(0.0);
  EXPECT_THROW(elm::fit(d.X, d.y.head(10), {}), std::invalid_argument);
  EXPECT_THROW(elm::fit(d.X, d.y, {.hidden = 0}), std::invalid_argument);
  Eigen::MatrixXd bad = d.X;
  bad(3, 1) = NAN;
  EXPECT_THROW(elm::fit(bad, d.y, {}), std::invalid_argument);
  const auto m = elm::fit(d.X, d.y, {.hidden = 5});
  EXPECT_THROW(m.predict(Eigen::MatrixXd::Zero(3, 3)), std::invalid_argument);
}

// ---- the plugin ------------------------------------------------------------------------------

std::unique_ptr<Regressor> make(const std::vector<std::string>& assignments) {
  Registry r;
  register_builtin_plugins(r);
  return r.create_as<Regressor>({"regressor/elm", params_from_assignments(r, "regressor/elm", assignments)});
}

TEST(ElmPlugin, PredictBeforeFitThrowsAndFitMatchesTheKernel) {
  auto elm_plugin = make({"hidden=30", "seed=2"});
  const auto d = known_function(0.0);
  EXPECT_THROW(elm_plugin->predict(d.X), NotFittedError);
  RunContext ctx;
  elm_plugin->fit(d.X, d.y, ctx);
  EXPECT_EQ(elm_plugin->predict(d.X), elm::fit(d.X, d.y, {.hidden = 30, .seed = 2}).predict(d.X));
  EXPECT_TRUE(ctx.diagnostics.contains("output_weight_norm"));
  // An untuned fit reports the kernel's progress as the step's (blocks of 4096 rows).
  const Eigen::MatrixXd long_x = Eigen::VectorXd::LinSpaced(20000, -2.0, 2.0);
  testing_progress::Recorder recorder;
  ctx.progress = recorder.listener();
  elm_plugin->fit(long_x, long_x.col(0), ctx);
  EXPECT_EQ(testing_progress::checked_fractions(recorder.fractions).size(), 4u);
}

TEST(ElmPlugin, TunesWithTheGaOnOneObjectiveAndWithNsga2OnTwo) {
  const auto d = known_function(0.0);
  auto by_ga = make({"tune=true", "optimizer={plugin: optimizer/ga, params: {population: 8, generations: 3}}"});
  RunContext ga_ctx;
  by_ga->fit(d.X, d.y, ga_ctx);
  EXPECT_EQ(ga_ctx.diagnostics["tuning"]["objectives"].size(), 1u);
  EXPECT_LT(rmse(by_ga->predict(d.X), d.y), 0.05);

  const std::string nsga2 =
      "optimizer={plugin: optimizer/pagmo, params: {algorithm: nsga2, population: 8, generations: 3}}";
  auto by_nsga2 = make({"tune=true", nsga2});
  RunContext ctx;
  by_nsga2->fit(d.X, d.y, ctx);
  const auto& tuning = ctx.diagnostics["tuning"];
  EXPECT_EQ(tuning["objectives"], nlohmann::json({"holdout_rmse", "output_weight_norm"}));
  EXPECT_TRUE(tuning["optimizer"].contains("pareto_front"));
  EXPECT_LT(rmse(by_nsga2->predict(d.X), d.y), 0.05);
  // The same seed reproduces the tuned model.
  auto again = make({"tune=true", nsga2});
  RunContext ctx2;
  again->fit(d.X, d.y, ctx2);
  EXPECT_EQ(again->predict(d.X), by_nsga2->predict(d.X));
}

TEST(ElmPlugin, RefusesTwoObjectivesWithASingleObjectiveOptimizer) {
  EXPECT_THROW(make({"tune=true", "tune_objectives=rmse_and_weight_norm"}), ConfigError);
  EXPECT_NO_THROW(make({"tune=true", "tune_objectives=rmse"}));
}

}  // namespace
}  // namespace driftlab
