#include "plugins/svr/svr.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "plugins/builtins.hpp"
#include "framework/error.hpp"
#include "framework/params_io.hpp"
#include "framework/registry.hpp"
#include "framework/seeded_random.hpp"

namespace driftlab {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct Data {
  Eigen::MatrixXd X;
  Eigen::VectorXd y, truth;
};

// y = 2 + sin(x) + 0.3 cos(3 x) on [0, 2 pi], plus seeded uniform noise of half-width `noise`.
Data known_function(Eigen::Index n, double noise, double offset = 0.0) {
  Data d{Eigen::MatrixXd(n, 1), Eigen::VectorXd(n), Eigen::VectorXd(n)};
  SeededRandom random(9);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double x = 2.0 * kPi * (static_cast<double>(i) + offset) / static_cast<double>(n);
    d.X(i, 0) = x;
    d.truth[i] = 2.0 + std::sin(x) + 0.3 * std::cos(3.0 * x);
    d.y[i] = d.truth[i] + noise * (2.0 * random.uniform() - 1.0);
  }
  return d;
}

double rmse(const Eigen::VectorXd& a, const Eigen::VectorXd& b) { return std::sqrt((a - b).squaredNorm() / a.size()); }

TEST(Svr, RecoversAKnownFunctionFromNoisySamples) {
  // Noise half-width 0.1 (SD 0.058); the fit to the noise-free truth between the samples is
  // better than the noise itself.
  constexpr double kRmseTolerance = 0.03;
  const auto train = known_function(400, 0.1), test = known_function(400, 0.0, 0.5);
  const auto r = svr::fit(train.X, train.y, {.c = 10.0, .epsilon = 0.05, .gamma = 2.0});
  EXPECT_LT(rmse(r.model.predict(test.X.topRows(399)), test.truth.head(399)), kRmseTolerance);
  EXPECT_EQ(r.training_rows, 400u);
}

TEST(Svr, PointsInsideTheEpsilonTubeAreNotSupportVectorsAndAWideTubeNeedsNone) {
  // KKT: every training point with |residual| > epsilon is a support vector, so the count of
  // points outside the tube bounds the count of support vectors from below.
  const auto d = known_function(300, 0.2);
  const double sd = std::sqrt((d.y.array() - d.y.mean()).square().mean());
  for (const double eps : {0.05, 0.2, 0.5}) {
    const auto r = svr::fit(d.X, d.y, {.c = 10.0, .epsilon = eps, .gamma = 2.0});
    const Eigen::ArrayXd residual = (r.model.predict(d.X) - d.y).array().abs();
    const auto outside = static_cast<std::size_t>((residual > eps * sd * 1.001).count());
    EXPECT_GE(r.model.support_vectors(), outside) << eps;
  }
  // A tube wider than the target's whole range: no support vectors, the prediction is constant.
  const auto flat = svr::fit(d.X, d.y, {.epsilon = 10.0});
  EXPECT_EQ(flat.model.support_vectors(), 0u);
  const Eigen::VectorXd p = flat.model.predict(d.X);
  EXPECT_DOUBLE_EQ(p.maxCoeff(), p.minCoeff());
}

TEST(Svr, TrainsOnAnEvenlySpacedSubsampleOfAtMostMaxSamplesRows) {
  constexpr double kRmseTolerance = 0.03;
  const auto d = known_function(5000, 0.1);
  const auto r = svr::fit(d.X, d.y, {.gamma = 2.0, .max_samples = 500});
  EXPECT_EQ(r.training_rows, 500u);
  EXPECT_LT(rmse(r.model.predict(d.X), d.truth), kRmseTolerance);
}

TEST(Svr, IsDeterministicAndRejectsBadInput) {
  const auto d = known_function(200, 0.1);
  EXPECT_EQ(svr::fit(d.X, d.y, {}).model.predict(d.X), svr::fit(d.X, d.y, {}).model.predict(d.X));
  EXPECT_THROW(svr::fit(d.X, d.y.head(5), {}), std::invalid_argument);
  EXPECT_THROW(svr::fit(d.X, d.y, {.c = 0.0}), std::invalid_argument);
  EXPECT_THROW(svr::fit(d.X, d.y, {}).model.predict(Eigen::MatrixXd::Zero(2, 2)), std::invalid_argument);
}

std::unique_ptr<Regressor> make(const std::vector<std::string>& assignments) {
  Registry r;
  register_builtin_plugins(r);
  return r.create_as<Regressor>({"regressor/svr", params_from_assignments(r, "regressor/svr", assignments)});
}

TEST(SvrPlugin, PredictBeforeFitThrowsAndTuningByPagmoBeatsAPoorStart) {
  const auto d = known_function(400, 0.1);
  auto poor = make({"gamma=0.001", "c=0.1"});
  EXPECT_THROW(poor->predict(d.X), NotFittedError);
  RunContext ctx;
  poor->fit(d.X, d.y, ctx);
  const double poor_error = rmse(poor->predict(d.X), d.truth);

  auto tuned = make({"gamma=0.001", "c=0.1", "tune=true",
                     "optimizer={plugin: optimizer/pagmo, params: {algorithm: de, population: 8, generations: 6}}"});
  RunContext tctx;
  tuned->fit(d.X, d.y, tctx);
  EXPECT_LT(rmse(tuned->predict(d.X), d.truth), 0.5 * poor_error);
  EXPECT_EQ(tctx.diagnostics["tuning"]["objectives"].size(), 1u);
}

TEST(SvrPlugin, TunesTwoObjectivesWithNsga2) {
  const auto d = known_function(300, 0.1);
  auto tuned = make(
      {"tune=true", "optimizer={plugin: optimizer/pagmo, params: {algorithm: nsga2, population: 8, generations: 3}}"});
  RunContext ctx;
  tuned->fit(d.X, d.y, ctx);
  EXPECT_EQ(ctx.diagnostics["tuning"]["objectives"], nlohmann::json({"holdout_rmse", "support_vector_share"}));
}

}  // namespace
}  // namespace driftlab
