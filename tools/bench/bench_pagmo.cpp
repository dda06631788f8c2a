// optimizer/pagmo against optimizer/ga on cheap shifted benchmark functions: the time is the
// algorithms' own overhead per evaluation (the objectives cost nanoseconds). One thread.
//   BM_PagmoSphere/<algorithm index>  5-D shifted sphere, population 20, 100 generations
//                                     (sga, de, pso, cmaes, gaco by index 0..4).
//   BM_GaSphere                       the hand-written GA, same population and generations.
//   BM_PagmoNsga2Zdt1                 ZDT1 with 10 variables, nsga2 population 40, 100 generations.
#include <benchmark/benchmark.h>

#include <cmath>
#include <string>
#include <vector>

#include "plugins/builtins.hpp"
#include "framework/params_io.hpp"
#include "framework/registry.hpp"

namespace driftlab {
namespace {

double sphere(const Eigen::VectorXd& x) { return (x.array() - 0.7).square().sum(); }

Eigen::VectorXd zdt1(const Eigen::VectorXd& x) {
  const double g = 1.0 + 9.0 * x.tail(x.size() - 1).sum() / static_cast<double>(x.size() - 1);
  return Eigen::Vector2d(x[0], g * (1.0 - std::sqrt(x[0] / g)));
}

std::unique_ptr<Optimizer> optimizer(const std::string& plugin, const std::vector<std::string>& assignments) {
  Registry registry;
  register_builtin_plugins(registry);
  return registry.create_as<Optimizer>({plugin, params_from_assignments(registry, plugin, assignments)});
}

void BM_PagmoSphere(benchmark::State& state) {
  static const std::vector<std::string> names{"sga", "de", "pso", "cmaes", "gaco"};
  const std::string name = names.at(static_cast<std::size_t>(state.range(0)));
  state.SetLabel(name);
  std::vector<std::string> assignments{"algorithm=" + name, "population=20", "generations=100"};
  if (name == "de" || name == "cmaes") {  // no early stop: all 100 generations are run
    assignments.push_back(name + "_ftol=0");
    assignments.push_back(name + "_xtol=0");
  }
  auto opt = optimizer("optimizer/pagmo", assignments);
  const std::vector<Bound> bounds(5, {"x", -5.0, 5.0, false});
  for (auto _ : state) {
    RunContext ctx;
    benchmark::DoNotOptimize(opt->minimize(sphere, bounds, ctx).best_value);
  }
}

void BM_GaSphere(benchmark::State& state) {
  auto opt = optimizer("optimizer/ga", {"population=20", "generations=100"});
  const std::vector<Bound> bounds(5, {"x", -5.0, 5.0, false});
  for (auto _ : state) {
    RunContext ctx;
    benchmark::DoNotOptimize(opt->minimize(sphere, bounds, ctx).best_value);
  }
}

void BM_PagmoNsga2Zdt1(benchmark::State& state) {
  auto opt = optimizer("optimizer/pagmo", {"algorithm=nsga2", "population=40", "generations=100"});
  const std::vector<Bound> bounds(10, {"x", 0.0, 1.0, false});
  for (auto _ : state) {
    RunContext ctx;
    benchmark::DoNotOptimize(opt->minimize_objectives(zdt1, 2, bounds, ctx).pareto_f.rows());
  }
}

BENCHMARK(BM_PagmoSphere)->DenseRange(0, 4)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GaSphere)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PagmoNsga2Zdt1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace driftlab
