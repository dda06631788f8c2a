#include "plugins/ga/ga.hpp"

#include "framework/parallel.hpp"
#include "framework/seeded_random.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>

namespace driftlab::ga {
namespace {

struct Gene {
  double lower, upper;
  bool integer;
};

std::vector<Gene> checked_genes(const std::vector<Bound>& bounds) {
  if (bounds.empty()) throw std::invalid_argument("ga: no parameters to optimize");
  std::vector<Gene> genes;
  for (std::size_t i = 0; i < bounds.size(); ++i) {
    const Bound& b = bounds[i];
    Gene g{b.lower, b.upper, b.integer};
    if (b.integer) {
      g.lower = std::ceil(b.lower);
      g.upper = std::floor(b.upper);
    }
    if (!std::isfinite(g.lower) || !std::isfinite(g.upper) || g.lower > g.upper) {
      throw std::invalid_argument("ga: parameter " + std::to_string(i) + " has an empty bound [" +
                                  std::to_string(b.lower) + ", " + std::to_string(b.upper) + "]");
    }
    genes.push_back(g);
  }
  return genes;
}

void check(const Config& c) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("ga: " + what); };
  if (c.population < 2) fail("population must be at least 2");
  if (c.elites >= c.population) fail("elites must be fewer than the population");
  if (c.tournament_size < 1) fail("tournament_size must be at least 1");
  if (!(c.crossover_probability >= 0 && c.crossover_probability <= 1)) fail("crossover_probability outside [0, 1]");
  if (!(c.mutation_probability >= 0 && c.mutation_probability <= 1)) fail("mutation_probability outside [0, 1]");
  if (!(c.crossover_eta > 0) || !(c.mutation_eta > 0)) fail("distribution indices must be positive");
}

double legalize(double x, const Gene& g) {
  if (g.integer) x = std::round(x);
  return std::clamp(x, g.lower, g.upper);
}

double sbx_spread(double u, double beta, double eta) {
  const double alpha = 2.0 - std::pow(beta, -(eta + 1.0));
  if (u <= 1.0 / alpha) return std::pow(u * alpha, 1.0 / (eta + 1.0));
  return std::pow(1.0 / (2.0 - u * alpha), 1.0 / (eta + 1.0));
}

void sbx(Eigen::VectorXd& a, Eigen::VectorXd& b, const std::vector<Gene>& genes, double eta, SeededRandom& rng) {
  constexpr double kSameGene = 1e-14;
  for (std::size_t i = 0; i < genes.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    const double cross = rng.uniform();
    const double u = rng.uniform();
    const double swap = rng.uniform();
    if (cross > 0.5 || std::abs(a[k] - b[k]) <= kSameGene) continue;
    const Gene& g = genes[i];
    const double y1 = std::min(a[k], b[k]);
    const double y2 = std::max(a[k], b[k]);
    const double span = y2 - y1;
    const double c1 = 0.5 * (y1 + y2 - sbx_spread(u, 1.0 + 2.0 * (y1 - g.lower) / span, eta) * span);
    const double c2 = 0.5 * (y1 + y2 + sbx_spread(u, 1.0 + 2.0 * (g.upper - y2) / span, eta) * span);
    a[k] = legalize(swap <= 0.5 ? c2 : c1, g);
    b[k] = legalize(swap <= 0.5 ? c1 : c2, g);
  }
}

void polynomial_mutation(Eigen::VectorXd& x, const std::vector<Gene>& genes, double probability, double eta,
                         SeededRandom& rng) {
  const double power = 1.0 / (eta + 1.0);
  for (std::size_t i = 0; i < genes.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    const double mutate = rng.uniform();
    const double u = rng.uniform();
    const Gene& g = genes[i];
    const double range = g.upper - g.lower;
    if (mutate >= probability || range <= 0) continue;
    double delta;
    if (u <= 0.5) {
      const double xy = 1.0 - (x[k] - g.lower) / range;
      delta = std::pow(2.0 * u + (1.0 - 2.0 * u) * std::pow(xy, eta + 1.0), power) - 1.0;
    } else {
      const double xy = 1.0 - (g.upper - x[k]) / range;
      delta = 1.0 - std::pow(2.0 * (1.0 - u) + 2.0 * (u - 0.5) * std::pow(xy, eta + 1.0), power);
    }
    x[k] = legalize(x[k] + delta * range, g);
  }
}

Eigen::VectorXd random_individual(const std::vector<Gene>& genes, SeededRandom& rng) {
  Eigen::VectorXd x(static_cast<Eigen::Index>(genes.size()));
  for (std::size_t i = 0; i < genes.size(); ++i) {
    const Gene& g = genes[i];
    const auto k = static_cast<Eigen::Index>(i);
    if (g.integer) {
      x[k] = g.lower + static_cast<double>(rng.index(static_cast<std::size_t>(g.upper - g.lower) + 1));
    } else {
      x[k] = g.lower + rng.uniform() * (g.upper - g.lower);
    }
  }
  return x;
}

// Evaluates individuals [first, population.size()) into values on `threads` threads.
void evaluate(const Objective& objective, const std::vector<Eigen::VectorXd>& population, std::size_t first,
              std::vector<double>& values, unsigned threads) {
  parallel_for(population.size() - first, threads, [&](std::size_t j) {
    const double v = objective(population[first + j]);
    values[first + j] = std::isfinite(v) ? v : std::numeric_limits<double>::infinity();
  });
}

std::vector<std::size_t> ranking(const std::vector<double>& values) {
  std::vector<std::size_t> order(values.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
  return order;
}

std::size_t tournament(const std::vector<double>& values, std::size_t size, SeededRandom& rng) {
  std::size_t winner = rng.index(values.size());
  for (std::size_t i = 1; i < size; ++i) {
    const std::size_t challenger = rng.index(values.size());
    if (values[challenger] < values[winner]) winner = challenger;
  }
  return winner;
}

}  // namespace

Result minimize(const Objective& objective, const std::vector<Bound>& bounds, const Config& config) {
  check(config);
  const std::vector<Gene> genes = checked_genes(bounds);
  SeededRandom rng(config.seed);
  const std::size_t n = config.population;

  std::vector<Eigen::VectorXd> population;
  for (std::size_t i = 0; i < n; ++i) population.push_back(random_individual(genes, rng));
  std::vector<double> values(n);
  evaluate(objective, population, 0, values, config.threads);

  Result result;
  result.evaluations = static_cast<std::int64_t>(n);
  auto order = ranking(values);
  result.history.push_back(values[order[0]]);
  result.best = population[order[0]];
  result.best_value = values[order[0]];
  const auto report = [&](std::size_t evaluated) {
    if (config.progress && evaluated <= config.generations)
      config.progress(static_cast<double>(evaluated) / static_cast<double>(config.generations + 1));
  };
  report(1);

  for (std::size_t gen = 0; gen < config.generations; ++gen) {
    std::vector<Eigen::VectorXd> next;
    std::vector<double> next_values(n);
    for (std::size_t e = 0; e < config.elites; ++e) {
      next.push_back(population[order[e]]);
      next_values[e] = values[order[e]];
    }
    while (next.size() < n) {
      Eigen::VectorXd a = population[tournament(values, config.tournament_size, rng)];
      Eigen::VectorXd b = population[tournament(values, config.tournament_size, rng)];
      if (rng.uniform() < config.crossover_probability) sbx(a, b, genes, config.crossover_eta, rng);
      polynomial_mutation(a, genes, config.mutation_probability, config.mutation_eta, rng);
      polynomial_mutation(b, genes, config.mutation_probability, config.mutation_eta, rng);
      next.push_back(std::move(a));
      if (next.size() < n) next.push_back(std::move(b));
    }
    evaluate(objective, next, config.elites, next_values, config.threads);
    result.evaluations += static_cast<std::int64_t>(n - config.elites);
    population = std::move(next);
    values = std::move(next_values);
    order = ranking(values);
    result.history.push_back(values[order[0]]);
    if (values[order[0]] < result.best_value) {
      result.best = population[order[0]];
      result.best_value = values[order[0]];
    }
    report(gen + 2);
  }

  return result;
}

}  // namespace driftlab::ga
