// Real-coded genetic algorithm for bounded continuous and integer parameters (minimization).
//
// One generation (generational replacement with elitism):
//   1. the `elites` best individuals are copied unchanged;
//   2. the rest of the next population is bred in pairs: two parents by tournament selection
//      (`tournament_size` individuals drawn uniformly with replacement, the lowest value wins),
//      simulated binary crossover (SBX, Deb & Agrawal 1995, bounded form of Deb's NSGA-II code:
//      each gene crossed with probability 1/2 when the pair crosses, distribution index
//      `crossover_eta`), then polynomial mutation of each gene with probability
//      `mutation_probability` (Deb & Goyal 1996, bounded form, distribution index `mutation_eta`);
//   3. the children are evaluated.
// Integer genes are varied as reals on [lower, upper] and rounded to the nearest integer; every
// gene stays within its bounds. Generation 0 is drawn uniformly inside the bounds (integers
// uniformly among the allowed values).
//
// Determinism: every random draw is made serially, in a fixed order, from one std::mt19937_64
// seeded from `seed` (through splitmix64) with explicit uniform transforms; only the objective
// evaluations run in parallel, each writing its own slot. Results are therefore bit-identical for
// any `threads`. Ties in the ranking are broken by position in the population.
// A non-finite objective value ranks as +infinity. An exception thrown by the objective is
// rethrown (the one of the lowest population index) after all workers have stopped.
//
// Why our own code and not pagmo2 (libpagmo-dev): pagmo's sga evaluates its population
// serially (batch evaluators serve only some of its algorithms) and its coarse parallelism is the
// archipelago, whose islands migrate asynchronously so results depend on timing; it would also
// bring TBB and Boost.Serialization into the build, for an algorithm of about 200 lines.
//
// Cost: population + generations * (population - elites) objective evaluations, plus
// O(generations * population * (dimension + log population)) for the algorithm itself.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

namespace driftlab::ga {

struct Bound {
  double lower = 0.0;
  double upper = 1.0;
  bool integer = false;  // the gene takes integer values in [ceil(lower), floor(upper)]
};

struct Config {
  std::size_t population = 40;         // individuals per generation, >= 2
  std::size_t generations = 50;        // G_MAX: generations bred after the initial one
  std::size_t tournament_size = 2;     // >= 1 (1 = random selection)
  double crossover_probability = 0.9;  // per pair, in [0, 1]
  double crossover_eta = 15.0;         // SBX distribution index, > 0 (larger: children nearer parents)
  double mutation_probability = 0.25;  // per gene, in [0, 1]
  double mutation_eta = 20.0;          // polynomial mutation distribution index, > 0
  std::size_t elites = 2;              // best individuals copied unchanged, < population
  std::uint64_t seed = 1;
  unsigned threads = 1;  // evaluation workers; results do not depend on it
  // Called on the calling thread after generation g = 0 .. G_MAX - 1 is evaluated with
  // (g + 1) / (G_MAX + 1), the fraction of the generations evaluated, in (0, 1) (not after the
  // last: the caller says when its own work is done); empty: not called. It never changes the result.
  std::function<void(double fraction)> progress;
};

// Objective to minimize; called concurrently from `threads` workers.
using Objective = std::function<double(const Eigen::VectorXd&)>;

struct Result {
  Eigen::VectorXd best;          // best parameters seen in any generation (first one on ties)
  double best_value = 0.0;       // objective at `best`
  std::vector<double> history;   // best value in generation g, g = 0 .. generations (size G_MAX+1)
  std::int64_t evaluations = 0;  // objective calls
};

// Throws std::invalid_argument for an empty or inverted bound (an integer bound must contain an
// integer), population < 2, elites >= population, tournament_size 0, probabilities outside [0, 1]
// or non-positive distribution indices.
Result minimize(const Objective& objective, const std::vector<Bound>& bounds, const Config& config);

}  // namespace driftlab::ga
