// pagmo2 (ESA, Biscani & Izzo 2020; Debian libpagmo-dev) algorithms behind one call, by name.
//
// The kernel keeps the algorithms it offers as data (algorithms()): pagmo's name, whether it is
// multi-objective, the smallest population it accepts and each option with pagmo's default, range
// and meaning. The adapter turns that table into the plugin's parameter table, so every option is
// validated, documented and listed by `driftlab plugins describe` from this one place.
//
// How a run goes:
//   1. a pagmo problem wraps the objective: the decision vector is clamped into the bounds and
//      integer parameters are rounded before each evaluation (pagmo's integer support differs per
//      algorithm; rounding works with all of them), so the objective only sees admissible points;
//   2. the initial population of `population` individuals is drawn uniformly inside the bounds
//      by pagmo, seeded; the algorithm is constructed with the options, `generations` and a seed,
//      then evolves the population once;
//   3. single objective: the result is the best point evaluated (first one on ties). Several
//      objectives: the first non-dominated front of the final population (fast non-dominated
//      sorting) is returned, sorted by the first objective, and one point of it is chosen:
//        closest_to_ideal  each objective is scaled to [0, 1] over the front (min..max; a constant
//                          objective scales to 0) and the point nearest (Euclidean) the ideal
//                          point (0, ..., 0) wins, first on ties (a compromise, no weights);
//        min_first         the point with the smallest first objective (first on ties).
//
// Determinism: both seeds derive from `seed` (splitmix64, truncated to pagmo's 32-bit seeds).
// pagmo's algorithms draw their random numbers serially. The initial population, and every
// generation of the algorithms that accept a batch evaluator (gaco, nsga2, nspso), are evaluated
// by a batch evaluator whose `threads` workers write their own slots, recorded in index order; the
// other algorithms evaluate serially. The result is the same for every thread count.
//
// history: the best (first) objective value seen after each block of `population` evaluations
// (one entry per generation for the generational algorithms), plus a last entry at the end.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace driftlab::pagmo_optimizer {

struct Option {
  enum class Type { Integer, Real, Boolean, Choice };
  std::string key;         // snake_case; the plugin parameter is "<algorithm>_<key>"
  std::string pagmo_name;  // the constructor argument in pagmo's documentation
  Type type = Type::Real;
  double default_number = 0.0;  // Integer, Real, Boolean (0 / 1)
  std::string default_choice;   // Choice
  std::vector<std::string> choices;
  std::optional<double> min, max;
  bool min_exclusive = false, max_exclusive = false;
  // -1 is also accepted and selects pagmo's own formula (cmaes, xnes); min/max bound the others.
  bool minus_one_is_automatic = false;
  std::string doc;
};

struct Algorithm {
  std::string name;     // pagmo's name, e.g. "nsga2"
  std::string summary;  // one line
  bool multi_objective = false;
  std::size_t min_population = 1;
  std::size_t population_multiple_of = 1;  // nsga2: 4
  bool uses_generations = true;            // false: the budget comes from its own options
  std::vector<Option> options;
};

// Every algorithm this kernel runs, in display order.
const std::vector<Algorithm>& algorithms();
// Throws std::invalid_argument naming the known algorithms.
const Algorithm& algorithm(const std::string& name);

using OptionValue = std::variant<double, std::string>;  // numbers (bool as 0/1) or a choice

enum class ParetoChoice { ClosestToIdeal, MinFirst };

struct Config {
  std::string algorithm = "sga";
  std::size_t population = 40;
  std::size_t generations = 50;
  std::map<std::string, OptionValue> options;  // by Option::key; absent keys take the default
  ParetoChoice pareto_choice = ParetoChoice::ClosestToIdeal;
  std::uint64_t seed = 1;
  unsigned threads = 1;
};

struct Bound {
  double lower = 0.0, upper = 1.0;
  bool integer = false;
};

// Returns one value per objective; called from several threads when threads > 1.
using Objective = std::function<Eigen::VectorXd(const Eigen::VectorXd&)>;

struct Result {
  Eigen::VectorXd best;         // chosen point (clamped, integers rounded)
  Eigen::VectorXd best_values;  // its objectives
  std::vector<double> history;
  std::int64_t evaluations = 0;
  Eigen::MatrixXd pareto_x, pareto_f;  // several objectives: the front, sorted by objective 1
};

// Throws std::invalid_argument for an unknown algorithm, an objective count the algorithm does
// not handle (single-objective algorithms take 1, multi-objective ones 2 or more), empty or
// inverted bounds, a population the algorithm refuses, or an option pagmo rejects (its message).
// A non-finite objective value is handed to pagmo as the largest finite double (ranked last).
Result minimize(const Objective& objective, std::size_t objectives, const std::vector<Bound>& bounds,
                const Config& config);

}  // namespace driftlab::pagmo_optimizer
