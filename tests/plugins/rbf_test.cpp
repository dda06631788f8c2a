#include "plugins/rbf/rbf.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

#include "plugins/builtins.hpp"
#include "framework/error.hpp"
#include "framework/params_io.hpp"
#include "framework/registry.hpp"
#include "plugins/common/holdout.hpp"
#include "plugins/tuning/tuning.hpp"

namespace driftlab {
namespace {

// Uniform points in [lo, hi]^2 from a fixed-seed generator with an explicit transform.
Eigen::MatrixXd uniform_points(Eigen::Index n, double lo, double hi, std::uint64_t seed) {
  std::mt19937_64 engine(seed);
  Eigen::MatrixXd X(n, 2);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index f = 0; f < 2; ++f) X(i, f) = lo + (hi - lo) * static_cast<double>(engine() >> 11) * 0x1.0p-53;
  return X;
}

Eigen::VectorXd sin_cos(const Eigen::MatrixXd& X) { return (X.col(0).array().sin() * X.col(1).array().cos()).matrix(); }

const Registry& builtin_registry() {
  static const Registry& registry = []() -> const Registry& {
    static Registry r;
    register_builtin_plugins(r);
    return r;
  }();
  return registry;
}

std::unique_ptr<Regressor> make_rbf(const std::vector<std::string>& assignments) {
  return builtin_registry().create_as<Regressor>(
      {"regressor/rbf", params_from_assignments(builtin_registry(), "regressor/rbf", assignments)});
}

TEST(Rbf, FitsSinXCosYOfTwoInputsWithKMeansCentres) {
  // 1 % of the function's unit amplitude, on points inside the training square.
  constexpr double kRmseTolerance = 0.01;
  const Eigen::MatrixXd X = uniform_points(2000, -3.0, 3.0, 1);
  const Eigen::MatrixXd X_test = uniform_points(1000, -2.8, 2.8, 2);
  rbf::Config c;
  c.centres = 60;
  c.sigma = 0.8;
  const auto fitted = rbf::fit(X, sin_cos(X), c);
  EXPECT_LT(holdout::rmse(fitted.network.predict(X_test), sin_cos(X_test)), kRmseTolerance);
  EXPECT_TRUE(fitted.lms_rmse.empty());
}

TEST(Rbf, FitsSinXCosYOfTwoInputsWithGridCentres) {
  // 8 x 8 centres over a 6 x 6 square: 2 % of the unit amplitude.
  constexpr double kRmseTolerance = 0.02;
  const Eigen::MatrixXd X = uniform_points(2000, -3.0, 3.0, 1);
  const Eigen::MatrixXd X_test = uniform_points(1000, -2.8, 2.8, 2);
  rbf::Config c;
  c.centre_method = rbf::CentreMethod::Grid;
  c.grid_points = 8;
  c.sigma = 0.3;
  const auto fitted = rbf::fit(X, sin_cos(X), c);
  EXPECT_EQ(fitted.network.centres().rows(), 64);
  EXPECT_LT(holdout::rmse(fitted.network.predict(X_test), sin_cos(X_test)), kRmseTolerance);
}

TEST(Rbf, LmsStepMatchesEquation9OnAHandExample) {
  constexpr double kRoundingTolerance = 1e-15;  // a handful of double operations
  // w = (0.5, -1), a = (1, 2), y_d = 3, beta = 0.5: y = -1.5, a^T a = 5,
  // w + 0.5 * 4.5 / 5 * (1, 2) = (0.95, -0.1).
  Eigen::VectorXd w(2);
  w << 0.5, -1.0;
  Eigen::VectorXd a(2);
  a << 1.0, 2.0;
  rbf::lms_step(w, a, 3.0, 0.5);
  EXPECT_NEAR(w[0], 0.95, kRoundingTolerance);
  EXPECT_NEAR(w[1], -0.1, kRoundingTolerance);
  // The a-posteriori error is (1 - beta) times the a-priori one: 3 - 0.75 = 0.5 * 4.5.
  EXPECT_NEAR(3.0 - w.dot(a), 0.5 * 4.5, kRoundingTolerance);
}

// Activations of random points on random centres plus the bias column, and targets from known
// weights, so that the LMS fixed point w* is known.
struct RealizableProblem {
  Eigen::MatrixXd rows_as_columns;
  Eigen::VectorXd target, w_true;
};

RealizableProblem realizable_problem() {
  const Eigen::MatrixXd U = uniform_points(400, -2.0, 2.0, 3);
  const Eigen::MatrixXd C = uniform_points(8, -2.0, 2.0, 4);
  Eigen::MatrixXd B(U.rows(), C.rows() + 1);
  B.leftCols(C.rows()) = rbf::activations(U, C, 0.8);
  B.col(C.rows()).setOnes();
  const Eigen::VectorXd w_true = Eigen::VectorXd::LinSpaced(B.cols(), -1.0, 1.0);
  return {B.transpose(), B * w_true, w_true};
}

TEST(Rbf, LmsNeverMovesAwayFromTheExactWeightsForBetaBetweenZeroAndTwo) {
  // ||w(l+1) - w*||^2 = ||w(l) - w*||^2 - beta (2 - beta) e^2 / a^T a; allow rounding only.
  constexpr double kRoundingSlack = 1e-12;
  const auto problem = realizable_problem();
  for (double beta : {0.5, 1.5}) {
    Eigen::VectorXd w = Eigen::VectorXd::Zero(problem.w_true.size());
    double distance = (w - problem.w_true).norm();
    const double start = distance;
    for (int epoch = 0; epoch < 20; ++epoch) {
      for (Eigen::Index i = 0; i < problem.rows_as_columns.cols(); ++i) {
        rbf::lms_step(w, problem.rows_as_columns.col(i), problem.target[i], beta);
        const double next = (w - problem.w_true).norm();
        ASSERT_LE(next, distance + kRoundingSlack) << "beta " << beta << " epoch " << epoch;
        distance = next;
      }
    }
    EXPECT_LT(distance, 0.5 * start) << "beta " << beta;
  }
}

TEST(Rbf, LmsMovesAwayFromTheExactWeightsForBetaAboveTwo) {
  const auto problem = realizable_problem();
  Eigen::VectorXd w = Eigen::VectorXd::Zero(problem.w_true.size());
  const double start = (w - problem.w_true).norm();
  for (Eigen::Index i = 0; i < problem.rows_as_columns.cols(); ++i)
    rbf::lms_step(w, problem.rows_as_columns.col(i), problem.target[i], 2.5);
  EXPECT_GT((w - problem.w_true).norm(), start);
}

TEST(Rbf, LmsFitErrorDecreasesEpochByEpochOnARepresentableTarget) {
  const Eigen::MatrixXd X = uniform_points(600, -3.0, 3.0, 6);
  rbf::Config c;
  c.centre_method = rbf::CentreMethod::Grid;
  c.grid_points = 4;
  c.sigma = 0.7;
  // Targets the network can represent exactly: the grid centres depend on X only.
  const auto reference = rbf::fit(X, sin_cos(X), c).network;
  const Eigen::MatrixXd U = (X.rowwise() - reference.mean()).array().rowwise() / reference.scale().array();
  const Eigen::VectorXd w_true = Eigen::VectorXd::LinSpaced(16, -1.0, 1.0);
  const Eigen::VectorXd y = (rbf::activations(U, reference.centres(), c.sigma) * w_true).array() + 0.3;
  const double rms_of_target = std::sqrt(y.squaredNorm() / static_cast<double>(y.size()));
  c.solver = rbf::WeightSolver::Lms;
  c.lms_epochs = 30;
  for (double beta : {0.5, 1.5}) {
    c.lms_rate = beta;
    const auto fitted = rbf::fit(X, y, c);
    ASSERT_EQ(fitted.lms_rmse.size(), c.lms_epochs);
    EXPECT_LT(fitted.lms_rmse.front(), rms_of_target) << "beta " << beta;  // w = 0 before epoch 1
    for (std::size_t e = 1; e < fitted.lms_rmse.size(); ++e)
      EXPECT_LE(fitted.lms_rmse[e], fitted.lms_rmse[e - 1]) << "beta " << beta << " epoch " << e;
    EXPECT_LT(fitted.lms_rmse.back(), 0.1 * fitted.lms_rmse.front()) << "beta " << beta;
  }
}

TEST(Rbf, PredictionsDoNotDependOnTheUnitsOfTheInputs) {
  constexpr double kRoundingTolerance = 1e-9;  // standardization rounds differently per scale
  const Eigen::MatrixXd X = uniform_points(500, -3.0, 3.0, 7);
  Eigen::MatrixXd X_scaled = X;
  X_scaled.col(0) = X.col(0) * 1000.0;
  X_scaled.col(1) = X.col(1).array() * 0.01 + 273.15;
  rbf::Config c;
  c.centres = 15;
  const auto plain = rbf::fit(X, sin_cos(X), c).network.predict(X);
  const auto scaled = rbf::fit(X_scaled, sin_cos(X), c).network.predict(X_scaled);
  EXPECT_LT((plain - scaled).cwiseAbs().maxCoeff(), kRoundingTolerance);
}

TEST(Rbf, BlockedHoldoutPartitionsTheSamplesIntoSpreadRuns) {
  const auto split = holdout::blocked_holdout(1000, 0.2, 10, 3);
  EXPECT_EQ(split.holdout.size(), 200u);
  std::set<Eigen::Index> all(split.train.begin(), split.train.end());
  all.insert(split.holdout.begin(), split.holdout.end());
  EXPECT_EQ(all.size(), 1000u);
  for (Eigen::Index segment = 0; segment < 10; ++segment) {
    const auto held_in_segment =
        std::count_if(split.holdout.begin(), split.holdout.end(), [&](Eigen::Index i) { return i / 100 == segment; });
    EXPECT_EQ(held_in_segment, 20) << "segment " << segment;
  }
}

TEST(RbfPlugin, PredictBeforeFitThrowsNotFittedError) {
  const auto rbf = make_rbf({});
  EXPECT_THROW(rbf->predict(Eigen::MatrixXd::Zero(3, 2)), NotFittedError);
}

TEST(RbfPlugin, ReportsMismatchedInputsAsADataError) {
  const auto rbf = make_rbf({});
  RunContext ctx;
  EXPECT_THROW(rbf->fit(Eigen::MatrixXd::Zero(30, 2), Eigen::VectorXd::Zero(29), ctx), DataError);
}

TEST(RbfPlugin, GaTuningImprovesTheHeldOutRmseOverAPoorStartingSigma) {
  const Eigen::MatrixXd X = uniform_points(1500, -3.0, 3.0, 8);
  const auto rbf = make_rbf({"sigma=0.02", "centres=10", "tune=true",
                             "optimizer={plugin: optimizer/ga, params: {population: 12, generations: 8}}"});
  RunContext ctx;
  rbf->fit(X, sin_cos(X), ctx);
  const auto& tuning = ctx.diagnostics.at("tuning");
  const double start = tuning.at("start").at("holdout_rmse").get<double>();
  const double best = tuning.at("best").at("holdout_rmse").get<double>();
  EXPECT_LT(best, 0.2 * start);
  const auto history = tuning.at("history").get<std::vector<double>>();
  ASSERT_EQ(history.size(), 9u);
  EXPECT_EQ(history.back(), best);
  EXPECT_EQ(tuning.at("optimizer").at("history").get<std::vector<double>>(), history);
}

// A search range that holds the optimum at a bound, and a search that cannot improve on its first
// population, are both said in the tuning's notes (plugins/tuning: search_notes); a parameter with
// room in its range and an improving search say nothing.
TEST(RbfPlugin, TuningSaysWhenItEndsAtASearchBoundOrItsHistoryIsFlat) {
  const Eigen::MatrixXd X = uniform_points(1500, -3.0, 3.0, 8);
  const std::string ga = "optimizer={plugin: optimizer/ga, params: {population: 12, generations: 8}}";
  const auto notes_of = [&](std::vector<std::string> params) {
    params.insert(params.end(), {"centres=10", "tune=true", ga});
    RunContext ctx;
    make_rbf(params)->fit(X, sin_cos(X), ctx);
    return ctx.diagnostics.at("tuning").at("notes").get<std::vector<std::string>>();
  };
  // sin/cos on [-3, 3] with 10 centres wants a width of order 1 (standardized units): 0.02-0.03 is
  // far too narrow, so the best sigma is the range's top.
  const auto narrow = notes_of({"tune_sigma=[0.02, 0.03]"});
  ASSERT_FALSE(narrow.empty());
  EXPECT_NE(narrow.front().find("sigma ended at its upper search bound (0.03"), std::string::npos) << narrow.front();
  for (const auto& note : notes_of({})) EXPECT_EQ(note.find("sigma"), std::string::npos) << note;

  OptimizationResult flat;
  flat.best = Eigen::Vector2d(0.5, -4.0);
  flat.history = {2.0, 2.0, 2.0, 2.0};
  const std::vector<Bound> bounds{{"sigma", 0.0, 1.0, false}, {"log10_regularization", -10.0, -2.0, false}};
  const auto said = tuning::search_notes(flat, bounds);
  ASSERT_EQ(said.size(), 1u);
  EXPECT_NE(said.front().find("did not improve over 4 generations"), std::string::npos) << said.front();
  flat.history.back() = 1.0;
  EXPECT_TRUE(tuning::search_notes(flat, bounds).empty());
  flat.best[1] = -10.0;
  EXPECT_NE(tuning::search_notes(flat, bounds).front().find("log10_regularization ended at its lower search bound"),
            std::string::npos);
}

TEST(RbfPlugin, SameSeedGivesTheSameModelOnAnyThreadCount) {
  const Eigen::MatrixXd X = uniform_points(800, -3.0, 3.0, 9);
  const std::vector<std::string> params{"seed=5", "tune=true",
                                        "optimizer={plugin: optimizer/ga, params: {population: 8, generations: 3}}"};
  Eigen::VectorXd reference;
  for (unsigned threads : {1u, 2u, 3u}) {
    const auto rbf = make_rbf(params);
    RunContext ctx;
    ctx.threads = threads;
    rbf->fit(X, sin_cos(X), ctx);
    const Eigen::VectorXd predicted = rbf->predict(X);
    if (threads == 1) reference = predicted;
    EXPECT_EQ(predicted, reference) << threads << " threads";
  }
}

TEST(RbfPlugin, ADifferentSeedGivesDifferentKMeansCentres) {
  const Eigen::MatrixXd X = uniform_points(800, -3.0, 3.0, 9);
  RunContext ctx;
  const auto first = make_rbf({"seed=5"});
  const auto second = make_rbf({"seed=6"});
  first->fit(X, sin_cos(X), ctx);
  second->fit(X, sin_cos(X), ctx);
  EXPECT_NE(first->predict(X), second->predict(X));
}

}  // namespace
}  // namespace driftlab
