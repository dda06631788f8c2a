#include "plugins/ga/ga.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <stdexcept>

#include "plugins/builtins.hpp"
#include "framework/params_io.hpp"
#include "framework/registry.hpp"

namespace driftlab {
namespace {

constexpr double kPi = 3.14159265358979323846;

const Eigen::Vector3d kRastriginShift{1.3, -0.7, 2.1};

double shifted_rastrigin(const Eigen::VectorXd& x) {
  double f = 10.0 * static_cast<double>(x.size());
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const double z = x[i] - kRastriginShift[i];
    f += z * z - 10.0 * std::cos(2.0 * kPi * z);
  }
  return f;
}

double rosenbrock(const Eigen::VectorXd& x) {
  return 100.0 * std::pow(x[1] - x[0] * x[0], 2) + std::pow(1.0 - x[0], 2);
}

ga::Config config_with_seed(std::uint64_t seed) {
  ga::Config c;
  c.population = 60;
  c.generations = 150;
  c.seed = seed;
  return c;
}

TEST(Ga, FindsTheGlobalMinimumOfAShiftedRastriginIn3D) {
  // Neighbouring local minima lie ~1 apart; 1e-2 proves the global basin was found and refined.
  constexpr double kLocationTolerance = 1e-2;
  const std::vector<ga::Bound> bounds(3, {-5.12, 5.12, false});
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const auto r = ga::minimize(shifted_rastrigin, bounds, config_with_seed(seed));
    EXPECT_LT((r.best - Eigen::VectorXd(kRastriginShift)).cwiseAbs().maxCoeff(), kLocationTolerance)
        << "seed " << seed << " best " << r.best.transpose();
  }
}

TEST(Ga, FindsTheMinimumOfRosenbrockIn2D) {
  // The banana valley is nearly flat along x2 = x1^2: f < 1e-3 still allows |x - 1| ~ 0.05.
  constexpr double kLocationTolerance = 0.05;
  constexpr double kValueTolerance = 1e-3;
  const std::vector<ga::Bound> bounds(2, {-2.0, 2.0, false});
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const auto r = ga::minimize(rosenbrock, bounds, config_with_seed(seed));
    EXPECT_LT((r.best.array() - 1.0).abs().maxCoeff(), kLocationTolerance) << "seed " << seed;
    EXPECT_LT(r.best_value, kValueTolerance) << "seed " << seed;
  }
}

TEST(Ga, KeepsIntegerParametersIntegralAndEveryParameterWithinItsBounds) {
  std::atomic<int> violations{0};
  const std::vector<ga::Bound> bounds{{-3.5, 7.2, true}, {0.0, 1.0, false}, {10.0, 12.0, true}};
  const auto objective = [&](const Eigen::VectorXd& x) {
    const bool integral = x[0] == std::round(x[0]) && x[2] == std::round(x[2]);
    const bool inside = x[0] >= -3 && x[0] <= 7 && x[1] >= 0 && x[1] <= 1 && x[2] >= 10 && x[2] <= 12;
    if (!integral || !inside) ++violations;
    return std::pow(x[0] - 4.3, 2) + std::pow(x[1] - 0.5, 2) + std::pow(x[2] - 20.0, 2);
  };
  ga::Config c = config_with_seed(3);
  c.threads = 2;
  const auto r = ga::minimize(objective, bounds, c);
  EXPECT_EQ(violations.load(), 0);
  EXPECT_EQ(r.best[0], 4.0);
  EXPECT_EQ(r.best[2], 12.0);  // the unconstrained optimum 20 lies above the bound
}

TEST(Ga, GivesTheSameHistoryAndResultForOneTwoAndThreeThreads) {
  const std::vector<ga::Bound> bounds(3, {-5.12, 5.12, false});
  ga::Config c = config_with_seed(11);
  c.generations = 30;
  c.threads = 1;
  const auto reference = ga::minimize(shifted_rastrigin, bounds, c);
  for (unsigned threads : {2u, 3u}) {
    c.threads = threads;
    const auto r = ga::minimize(shifted_rastrigin, bounds, c);
    EXPECT_EQ(r.history, reference.history) << threads << " threads";
    EXPECT_EQ(r.best, reference.best) << threads << " threads";
    EXPECT_EQ(r.evaluations, reference.evaluations);
  }
}

TEST(Ga, ReportsProgressAfterEveryGenerationButTheLastAndGivesTheSameResult) {
  const std::vector<ga::Bound> bounds(3, {-5.12, 5.12, false});
  ga::Config c = config_with_seed(12);
  c.generations = 9;
  const auto plain = ga::minimize(shifted_rastrigin, bounds, c);
  std::vector<double> fractions;
  c.progress = [&](double f) { fractions.push_back(f); };
  const auto r = ga::minimize(shifted_rastrigin, bounds, c);
  EXPECT_EQ(r.history, plain.history);
  EXPECT_EQ(r.best, plain.best);
  ASSERT_EQ(fractions.size(), c.generations);  // generations 0 .. G_MAX - 1
  for (std::size_t g = 0; g < fractions.size(); ++g) EXPECT_DOUBLE_EQ(fractions[g], (g + 1.0) / (c.generations + 1.0));
}

TEST(Ga, GivesADifferentHistoryForADifferentSeed) {
  const std::vector<ga::Bound> bounds(3, {-5.12, 5.12, false});
  ga::Config c = config_with_seed(11);
  c.generations = 30;
  const auto first = ga::minimize(shifted_rastrigin, bounds, c);
  c.seed = 12;
  const auto second = ga::minimize(shifted_rastrigin, bounds, c);
  EXPECT_NE(first.history, second.history);
}

TEST(Ga, NeverLosesItsBestIndividualWithElitism) {
  const std::vector<ga::Bound> bounds(3, {-5.12, 5.12, false});
  ga::Config c = config_with_seed(5);
  c.generations = 40;
  const auto r = ga::minimize(shifted_rastrigin, bounds, c);
  ASSERT_EQ(r.history.size(), c.generations + 1);
  for (std::size_t g = 1; g < r.history.size(); ++g) EXPECT_LE(r.history[g], r.history[g - 1]);
  EXPECT_EQ(r.best_value, r.history.back());
  EXPECT_EQ(r.evaluations, static_cast<std::int64_t>(c.population + c.generations * (c.population - c.elites)));
}

TEST(Ga, RethrowsAnExceptionThrownByTheObjective) {
  const std::vector<ga::Bound> bounds(2, {0.0, 1.0, false});
  ga::Config c = config_with_seed(1);
  c.threads = 2;
  const auto objective = [](const Eigen::VectorXd& x) -> double {
    if (x[0] > 0.5) throw std::runtime_error("objective failed");
    return x[0];
  };
  EXPECT_THROW(ga::minimize(objective, bounds, c), std::runtime_error);
}

TEST(Ga, RejectsAnEmptyIntegerBound) {
  EXPECT_THROW(ga::minimize(rosenbrock, {{0.2, 0.8, true}, {0.0, 1.0, false}}, ga::Config{}), std::invalid_argument);
}

TEST(GaPlugin, MinimizesThroughTheRegistryAndLogsTheHistoryInTheDiagnostics) {
  Registry registry;
  register_builtin_plugins(registry);
  const auto params = params_from_assignments(registry, "optimizer/ga", {"population=30", "generations=20", "seed=4"});
  auto optimizer = registry.create_as<Optimizer>({"optimizer/ga", params});
  RunContext ctx;
  ctx.threads = 2;
  const std::vector<Bound> bounds{{"x", -2.0, 2.0, false}, {"y", -2.0, 2.0, false}};
  const auto r = optimizer->minimize(rosenbrock, bounds, ctx);
  ASSERT_EQ(r.history.size(), 21u);
  EXPECT_EQ(ctx.diagnostics["history"].get<std::vector<double>>(), r.history);
  EXPECT_EQ(ctx.diagnostics["best"]["x"].get<double>(), r.best[0]);
  EXPECT_EQ(ctx.diagnostics["evaluations"].get<std::int64_t>(), r.evaluations);
}

TEST(GaPlugin, ReportsAnEmptyBoundAsAConfigError) {
  Registry registry;
  register_builtin_plugins(registry);
  auto optimizer =
      registry.create_as<Optimizer>({"optimizer/ga", params_from_assignments(registry, "optimizer/ga", {})});
  RunContext ctx;
  EXPECT_THROW(optimizer->minimize(rosenbrock, {{"x", 1.0, 0.0, false}, {"y", 0.0, 1.0, false}}, ctx), ConfigError);
}

}  // namespace
}  // namespace driftlab
