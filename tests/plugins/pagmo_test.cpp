#include "plugins/pagmo/pagmo_optimizer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "plugins/builtins.hpp"
#include "framework/error.hpp"
#include "framework/params_io.hpp"
#include "framework/registry.hpp"

namespace driftlab {
namespace {

namespace po = pagmo_optimizer;

const Eigen::Vector4d kShift{1.3, -0.7, 2.1, 0.4};

Eigen::VectorXd shifted_sphere(const Eigen::VectorXd& x) {
  return Eigen::VectorXd::Constant(1, (x - Eigen::VectorXd(kShift.head(x.size()))).squaredNorm());
}

// Rosenbrock shifted so that its minimum lies at (1.3, 0.3) instead of (1, 1).
Eigen::VectorXd shifted_rosenbrock(const Eigen::VectorXd& x) {
  const double a = x[0] - 0.3, b = x[1] + 0.7;
  return Eigen::VectorXd::Constant(1, 100.0 * std::pow(b - a * a, 2) + std::pow(1.0 - a, 2));
}

// ZDT1 (Zitzler, Deb & Thiele 2000): Pareto front f2 = 1 - sqrt(f1), f1 in [0, 1], at x2..xn = 0.
Eigen::VectorXd zdt1(const Eigen::VectorXd& x) {
  const double g = 1.0 + 9.0 * x.tail(x.size() - 1).sum() / static_cast<double>(x.size() - 1);
  return Eigen::Vector2d(x[0], g * (1.0 - std::sqrt(x[0] / g)));
}

po::Config config(std::string algorithm, std::size_t population, std::size_t generations, std::uint64_t seed = 7) {
  po::Config c;
  c.algorithm = std::move(algorithm);
  c.population = population;
  c.generations = generations;
  c.seed = seed;
  return c;
}

TEST(Pagmo, EverySingleObjectiveGenerationalAlgorithmFindsTheMinimumOfAShiftedSphere) {
  // Per algorithm: population, generations, location tolerance (looser for the slow converging
  // swarm/colony methods; each still far below the 1-wide basin the shift moves the minimum by).
  struct Case {
    std::string name;
    std::size_t population, generations;
    double tolerance;
  };
  const std::vector<Case> cases{{"de", 20, 300, 1e-3},    {"sade", 20, 300, 1e-3}, {"pso", 20, 300, 1e-2},
                                {"cmaes", 10, 300, 1e-3}, {"xnes", 10, 300, 1e-2}, {"sga", 40, 300, 0.1},
                                {"gaco", 20, 300, 1e-2},  {"gwo", 20, 300, 1e-2},  {"bee_colony", 20, 200, 1e-2},
                                {"sea", 10, 2000, 0.1}};
  const std::vector<po::Bound> bounds(3, {-5.0, 5.0, false});
  for (const auto& c : cases) {
    const auto r = po::minimize(shifted_sphere, 1, bounds, config(c.name, c.population, c.generations));
    EXPECT_LT((r.best - Eigen::VectorXd(kShift.head(3))).cwiseAbs().maxCoeff(), c.tolerance) << c.name;
    EXPECT_EQ(r.best_values.size(), 1);
    EXPECT_DOUBLE_EQ(r.best_values[0], shifted_sphere(r.best)[0]) << c.name;
  }
}

TEST(Pagmo, NonGenerationalAlgorithmsFindTheMinimumOfAShiftedSphereWithinTheirOwnBudget) {
  const std::vector<po::Bound> bounds(3, {-5.0, 5.0, false});
  auto sa = config("simulated_annealing", 1, 0);
  sa.options["bin_size"] = 50.0;
  sa.options["tf"] = 1e-4;
  EXPECT_LT((po::minimize(shifted_sphere, 1, bounds, sa).best - Eigen::VectorXd(kShift.head(3))).norm(), 0.2);
  auto cs = config("compass_search", 1, 0);
  cs.options["stop_range"] = 1e-6;
  cs.options["max_fevals"] = 5000.0;
  EXPECT_LT((po::minimize(shifted_sphere, 1, bounds, cs).best - Eigen::VectorXd(kShift.head(3))).norm(), 1e-4);
}

TEST(Pagmo, DeAndCmaesFindTheMinimumOfAShiftedRosenbrock) {
  // The banana valley is nearly flat along its floor: 1e-2 in location still means f < 1e-4.
  constexpr double kLocationTolerance = 1e-2;
  const std::vector<po::Bound> bounds(2, {-2.0, 3.0, false});
  for (const std::string name : {"de", "cmaes"}) {
    const auto r = po::minimize(shifted_rosenbrock, 1, bounds, config(name, 20, 500));
    EXPECT_LT((r.best - Eigen::Vector2d(1.3, 0.3)).cwiseAbs().maxCoeff(), kLocationTolerance) << name;
  }
}

TEST(Pagmo, TheSameSeedReproducesTheRunAndAnotherSeedChangesIt) {
  const std::vector<po::Bound> bounds(3, {-5.0, 5.0, false});
  for (const std::string name : {"sga", "de", "pso", "cmaes", "gaco"}) {
    const auto a = po::minimize(shifted_sphere, 1, bounds, config(name, 20, 20, 11));
    const auto b = po::minimize(shifted_sphere, 1, bounds, config(name, 20, 20, 11));
    const auto c = po::minimize(shifted_sphere, 1, bounds, config(name, 20, 20, 12));
    EXPECT_EQ(a.best, b.best) << name;
    EXPECT_EQ(a.history, b.history) << name;
    EXPECT_EQ(a.evaluations, b.evaluations) << name;
    EXPECT_NE(a.best, c.best) << name;
  }
}

TEST(Pagmo, GivesTheSameResultForOneAndThreeThreads) {
  const std::vector<po::Bound> bounds(5, {0.0, 1.0, false});
  auto one = config("nsga2", 24, 30);
  auto three = one;
  three.threads = 3;
  const auto a = po::minimize(zdt1, 2, bounds, one);
  const auto b = po::minimize(zdt1, 2, bounds, three);
  EXPECT_EQ(a.pareto_f, b.pareto_f);
  EXPECT_EQ(a.best, b.best);
  const std::vector<po::Bound> sphere_bounds(3, {-5.0, 5.0, false});
  auto g1 = config("gaco", 20, 30), g3 = g1;
  g3.threads = 3;
  EXPECT_EQ(po::minimize(shifted_sphere, 1, sphere_bounds, g1).history,
            po::minimize(shifted_sphere, 1, sphere_bounds, g3).history);
}

TEST(Pagmo, Nsga2ApproachesTheZdt1ParetoFrontAndSpreadsAlongIt) {
  // 5 variables, 100 individuals, 250 generations: the front is reached to within 0.02 in f2
  // (the distance g - 1 = 9 mean(x2..x5) that remains) and covers most of f1 in [0, 1].
  constexpr double kFrontTolerance = 0.02;
  const std::vector<po::Bound> bounds(5, {0.0, 1.0, false});
  const auto r = po::minimize(zdt1, 2, bounds, config("nsga2", 100, 250, 3));
  ASSERT_GE(r.pareto_f.rows(), 50);
  double worst = 0.0;
  for (Eigen::Index i = 0; i < r.pareto_f.rows(); ++i) {
    worst = std::max(worst, r.pareto_f(i, 1) - (1.0 - std::sqrt(r.pareto_f(i, 0))));
    if (i > 0) {
      EXPECT_LE(r.pareto_f(i - 1, 0), r.pareto_f(i, 0));  // sorted by f1
    }
  }
  EXPECT_LT(worst, kFrontTolerance);
  EXPECT_LT(r.pareto_f.col(0).minCoeff(), 0.05);
  EXPECT_GT(r.pareto_f.col(0).maxCoeff(), 0.95);
}

TEST(Pagmo, ChoosesTheFrontPointNearestTheScaledIdealPointOrTheSmallestFirstObjective) {
  const std::vector<po::Bound> bounds(5, {0.0, 1.0, false});
  auto c = config("nsga2", 40, 60, 5);
  const auto r = po::minimize(zdt1, 2, bounds, c);
  // Independent check of the documented rule on the returned front.
  const Eigen::RowVectorXd lo = r.pareto_f.colwise().minCoeff(), hi = r.pareto_f.colwise().maxCoeff();
  Eigen::Index expected = 0;
  double best = 1e300;
  for (Eigen::Index i = 0; i < r.pareto_f.rows(); ++i) {
    const double d = ((r.pareto_f.row(i) - lo).array() / (hi - lo).array()).matrix().squaredNorm();
    if (d < best) best = d, expected = i;
  }
  EXPECT_EQ(r.best_values, Eigen::VectorXd(r.pareto_f.row(expected).transpose()));
  EXPECT_EQ(r.best, Eigen::VectorXd(r.pareto_x.row(expected).transpose()));
  c.pareto_choice = po::ParetoChoice::MinFirst;
  const auto m = po::minimize(zdt1, 2, bounds, c);
  EXPECT_EQ(m.best_values[0], m.pareto_f.col(0).minCoeff());
}

TEST(Pagmo, MoeadAndNspsoAlsoReachTheZdt1Front) {
  constexpr double kFrontTolerance = 0.1;  // fewer generations than nsga2's test: a looser band
  const std::vector<po::Bound> bounds(5, {0.0, 1.0, false});
  for (const std::string name : {"moead", "nspso"}) {
    const auto r = po::minimize(zdt1, 2, bounds, config(name, 40, 400, 3));
    ASSERT_GT(r.pareto_f.rows(), 5) << name;
    for (Eigen::Index i = 0; i < r.pareto_f.rows(); ++i) {
      EXPECT_LT(r.pareto_f(i, 1) - (1.0 - std::sqrt(r.pareto_f(i, 0))), kFrontTolerance) << name;
    }
  }
}

TEST(Pagmo, HandsTheObjectiveOnlyAdmissiblePointsWithIntegersRounded) {
  int violations = 0;
  const auto objective = [&](const Eigen::VectorXd& x) {
    if (x[0] != std::round(x[0]) || x[0] < -3 || x[0] > 7 || x[1] < 0 || x[1] > 1) ++violations;
    return Eigen::VectorXd::Constant(1, std::pow(x[0] - 4.3, 2) + std::pow(x[1] - 0.5, 2));
  };
  const std::vector<po::Bound> bounds{{-3.5, 7.2, true}, {0.0, 1.0, false}};
  for (const std::string name : {"cmaes", "de", "pso"}) {
    const auto r = po::minimize(objective, 1, bounds, config(name, 20, 100));
    EXPECT_EQ(r.best[0], 4.0) << name;
  }
  EXPECT_EQ(violations, 0);
}

TEST(Pagmo, RefusesObjectiveCountsPopulationsAndBoundsTheAlgorithmCannotTake) {
  const std::vector<po::Bound> bounds(2, {0.0, 1.0, false});
  EXPECT_THROW(po::minimize(zdt1, 2, bounds, config("de", 20, 5)), std::invalid_argument);
  EXPECT_THROW(po::minimize(shifted_sphere, 1, bounds, config("nsga2", 20, 5)), std::invalid_argument);
  EXPECT_THROW(po::minimize(zdt1, 2, bounds, config("nsga2", 10, 5)), std::invalid_argument);  // not 4k
  EXPECT_THROW(po::minimize(shifted_sphere, 1, bounds, config("de", 4, 5)), std::invalid_argument);
  EXPECT_THROW(po::minimize(shifted_sphere, 1, {{1.0, 0.0, false}}, config("de", 10, 5)), std::invalid_argument);
  EXPECT_THROW(po::minimize(shifted_sphere, 1, bounds, config("nelder_mead", 10, 5)), std::invalid_argument);
}

// ---- the plugin ------------------------------------------------------------------------------

std::unique_ptr<Optimizer> make(const std::vector<std::string>& assignments) {
  Registry r;
  register_builtin_plugins(r);
  return r.create_as<Optimizer>({"optimizer/pagmo", params_from_assignments(r, "optimizer/pagmo", assignments)});
}

TEST(PagmoPlugin, ValidatesOptionsAgainstTheAlgorithmTable) {
  Registry r;
  register_builtin_plugins(r);
  const auto params = [&](std::vector<std::string> a) { return params_from_assignments(r, "optimizer/pagmo", a); };
  EXPECT_NO_THROW(params({"algorithm=de", "de_f=0.5", "de_variant=7"}));
  EXPECT_THROW(params({"algorithm=de", "de_f=1.5"}), ConfigError);          // F in [0, 1]
  EXPECT_THROW(params({"algorithm=pso", "de_f=0.5"}), ConfigError);         // another algorithm's option
  EXPECT_THROW(params({"algorithm=nsga2", "population=30"}), ConfigError);  // not a multiple of 4
  EXPECT_THROW(params({"algorithm=sga", "sga_crossover=sbx", "population=41"}), ConfigError);
  EXPECT_THROW(params({"algorithm=cmaes", "cmaes_cc=-0.5"}), ConfigError);  // -1 or [0, 1]
  EXPECT_NO_THROW(params({"algorithm=cmaes", "cmaes_cc=-1"}));
  EXPECT_THROW(params({"algorithm=gaco", "gaco_ker=50", "population=20"}), ConfigError);
  EXPECT_THROW(params({"algorithm=bogus"}), ConfigError);
}

TEST(PagmoPlugin, MinimizesOneObjectiveAndReportsItsDiagnostics) {
  auto opt = make({"algorithm=de", "population=20", "generations=200", "seed=4"});
  EXPECT_EQ(opt->max_objectives(), 1u);
  RunContext ctx;
  const auto r = opt->minimize([](const Eigen::VectorXd& x) { return shifted_sphere(x)[0]; },
                               {{"a", -5, 5, false}, {"b", -5, 5, false}}, ctx);
  EXPECT_LT((r.best - Eigen::Vector2d(1.3, -0.7)).norm(), 1e-3);
  EXPECT_EQ(ctx.diagnostics["algorithm"], "de");
  EXPECT_TRUE(ctx.diagnostics["best"].contains("a"));
  // One entry per 20 evaluations (de stops early once its population has converged: ftol, xtol).
  EXPECT_EQ(r.history.size(), static_cast<std::size_t>((r.evaluations + 19) / 20));
  EXPECT_EQ(r.history.back(), r.best_value);
}

TEST(PagmoPlugin, Nsga2ReturnsAParetoSetThroughTheTwoObjectiveInterface) {
  auto opt = make({"algorithm=nsga2", "population=40", "generations=40"});
  EXPECT_GE(opt->max_objectives(), 2u);
  RunContext ctx;
  const std::vector<Bound> bounds(4, {"x", 0.0, 1.0, false});
  const auto r = opt->minimize_objectives(zdt1, 2, bounds, ctx);
  EXPECT_GT(r.pareto_f.rows(), 3);
  EXPECT_EQ(r.best_values.size(), 2);
  EXPECT_EQ(r.best_value, r.best_values[0]);
  EXPECT_TRUE(ctx.diagnostics.contains("pareto_front"));
  // nsga2 with a single objective is a configuration error, named.
  EXPECT_THROW(opt->minimize([](const Eigen::VectorXd& x) { return x.sum(); }, bounds, ctx), ConfigError);
}

TEST(SingleObjectiveOptimizers, AcceptOneObjectiveThroughTheVectorInterfaceAndRefuseTwo) {
  Registry r;
  register_builtin_plugins(r);
  auto ga = r.create_as<Optimizer>({"optimizer/ga", params_from_assignments(r, "optimizer/ga", {"generations=5"})});
  RunContext ctx;
  const std::vector<Bound> bounds(2, {"x", -5.0, 5.0, false});
  const auto one = ga->minimize_objectives(shifted_sphere, 1, bounds, ctx);
  EXPECT_EQ(one.best_values.size(), 1);
  EXPECT_THROW(ga->minimize_objectives(zdt1, 2, bounds, ctx), ConfigError);
}

}  // namespace
}  // namespace driftlab
