#include "plugins/pagmo/pagmo_optimizer.hpp"

#include <pagmo/algorithm.hpp>
#include <pagmo/algorithms/bee_colony.hpp>
#include <pagmo/algorithms/cmaes.hpp>
#include <pagmo/algorithms/compass_search.hpp>
#include <pagmo/algorithms/de.hpp>
#include <pagmo/algorithms/gaco.hpp>
#include <pagmo/algorithms/gwo.hpp>
#include <pagmo/algorithms/moead.hpp>
#include <pagmo/algorithms/nsga2.hpp>
#include <pagmo/algorithms/nspso.hpp>
#include <pagmo/algorithms/pso.hpp>
#include <pagmo/algorithms/sade.hpp>
#include <pagmo/algorithms/sea.hpp>
#include <pagmo/algorithms/sga.hpp>
#include <pagmo/algorithms/simulated_annealing.hpp>
#include <pagmo/algorithms/xnes.hpp>
#include <pagmo/bfe.hpp>
#include <pagmo/population.hpp>
#include <pagmo/problem.hpp>
#include <pagmo/utils/multi_objective.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <numeric>
#include <stdexcept>

#include "framework/parallel.hpp"
#include "framework/seeded_random.hpp"

namespace driftlab::pagmo_optimizer {
namespace {

using Type = Option::Type;

Option real(std::string key, std::string pagmo_name, double def, std::string doc) {
  return {.key = std::move(key),
          .pagmo_name = std::move(pagmo_name),
          .type = Type::Real,
          .default_number = def,
          .doc = std::move(doc)};
}
Option integer(std::string key, std::string pagmo_name, double def, std::string doc) {
  return {.key = std::move(key),
          .pagmo_name = std::move(pagmo_name),
          .type = Type::Integer,
          .default_number = def,
          .doc = std::move(doc)};
}
Option boolean(std::string key, std::string pagmo_name, bool def, std::string doc) {
  return {.key = std::move(key),
          .pagmo_name = std::move(pagmo_name),
          .type = Type::Boolean,
          .default_number = def ? 1.0 : 0.0,
          .doc = std::move(doc)};
}
Option choice(std::string key, std::string pagmo_name, std::string def, std::vector<std::string> choices,
              std::string doc) {
  return {.key = std::move(key),
          .pagmo_name = std::move(pagmo_name),
          .type = Type::Choice,
          .default_choice = std::move(def),
          .choices = std::move(choices),
          .doc = std::move(doc)};
}
Option in(Option o, std::optional<double> lo, std::optional<double> hi, bool lo_open = false, bool hi_open = false) {
  o.min = lo;
  o.max = hi;
  o.min_exclusive = lo_open;
  o.max_exclusive = hi_open;
  return o;
}
Option automatic(Option o) {
  o.minus_one_is_automatic = true;
  return o;
}
Option tolerance(std::string key, std::string what) {
  return in(real(key, key, 1e-6, "stop when the population's " + what + " spread falls below this"), 0.0, {});
}

std::vector<Algorithm> make_table() {
  std::vector<Algorithm> t;
  t.push_back(
      {"sga",
       "simple genetic algorithm (selection, crossover, mutation)",
       false,
       2,
       1,
       true,
       {in(real("cr", "cr", 0.9, "crossover probability"), 0.0, 1.0),
        in(real("eta_c", "eta_c", 1.0, "SBX distribution index (crossover sbx)"), 1.0, 100.0),
        in(real("m", "m", 0.02, "mutation probability per gene"), 0.0, 1.0),
        in(real("param_m", "param_m", 1.0,
                "mutation parameter: polynomial distribution index in [1, 100]; gaussian/uniform width "
                "as a share of the bounds in [0, 1]"),
           0.0, 100.0),
        in(integer("param_s", "param_s", 2, "tournament size (tournament) or number of best parents (truncated)"), 1.0,
           {}),
        choice("crossover", "crossover", "exponential", {"exponential", "binomial", "sbx", "single"},
               "crossover operator (sbx needs an even population)"),
        choice("mutation", "mutation", "polynomial", {"gaussian", "uniform", "polynomial"}, "mutation operator"),
        choice("selection", "selection", "tournament", {"tournament", "truncated"}, "selection operator")}});
  t.push_back(
      {"de",
       "differential evolution (Storn & Price 1997)",
       false,
       5,
       1,
       true,
       {in(real("f", "F", 0.8, "weight coefficient F"), 0.0, 1.0),
        in(real("cr", "CR", 0.9, "crossover probability CR"), 0.0, 1.0),
        in(integer("variant", "variant", 2, "mutation variant (1 best/1/exp ... 10 rand-to-best/1/bin, pagmo's list)"),
           1.0, 10.0),
        tolerance("ftol", "objective"), tolerance("xtol", "decision-vector")}});
  t.push_back({"sade",
               "self-adaptive differential evolution (jDE / iDE)",
               false,
               7,
               1,
               true,
               {in(integer("variant", "variant", 2, "mutation variant (pagmo's list of 18)"), 1.0, 18.0),
                in(integer("variant_adptv", "variant_adptv", 1, "adaptation: 1 jDE, 2 iDE"), 1.0, 2.0),
                tolerance("ftol", "objective"), tolerance("xtol", "decision-vector")}});
  t.push_back({"pso",
               "particle swarm optimization",
               false,
               1,
               1,
               true,
               {in(real("omega", "omega", 0.7298, "inertia weight (or constriction factor)"), 0.0, 1.0),
                in(real("eta1", "eta1", 2.05, "social component"), 0.0, 4.0),
                in(real("eta2", "eta2", 2.05, "cognitive component"), 0.0, 4.0),
                in(real("max_vel", "max_vel", 0.5, "maximum velocity as a share of the bounds' width"), 0.0, 1.0, true),
                in(integer("variant", "variant", 5, "algorithm variant (pagmo's list of 6)"), 1.0, 6.0),
                in(integer("neighb_type", "neighb_type", 2,
                           "swarm topology: 1 gbest, 2 lbest, 3 Von Neumann, 4 adaptive random"),
                   1.0, 4.0),
                in(integer("neighb_param", "neighb_param", 4, "topology parameter (lbest: neighbours)"), 1.0, {})}});
  t.push_back(
      {"cmaes",
       "covariance matrix adaptation evolution strategy",
       false,
       5,
       1,
       true,
       {automatic(in(real("cc", "cc", -1, "backward time horizon of the evolution path (-1: automatic)"), 0.0, 1.0)),
        automatic(in(real("cs", "cs", -1, "makes partly up for the small variance loss (-1: automatic)"), 0.0, 1.0)),
        automatic(in(real("c1", "c1", -1, "learning rate of the rank-one update (-1: automatic)"), 0.0, 1.0)),
        automatic(in(real("cmu", "cmu", -1, "learning rate of the rank-mu update (-1: automatic)"), 0.0, 1.0)),
        in(real("sigma0", "sigma0", 0.5, "initial step size as a share of the bounds' width"), 0.0, {}, true),
        tolerance("ftol", "objective"), tolerance("xtol", "decision-vector"),
        boolean("force_bounds", "force_bounds", true,
                "keep samples inside the bounds (else they are clamped before evaluation)")}});
  t.push_back(
      {"xnes",
       "exponential natural evolution strategies",
       false,
       5,
       1,
       true,
       {automatic(in(real("eta_mu", "eta_mu", -1, "learning rate of the mean (-1: automatic)"), 0.0, 1.0, true)),
        automatic(
            in(real("eta_sigma", "eta_sigma", -1, "learning rate of the step size (-1: automatic)"), 0.0, 1.0, true)),
        automatic(in(real("eta_b", "eta_b", -1, "learning rate of the covariance (-1: automatic)"), 0.0, 1.0, true)),
        automatic(in(real("sigma0", "sigma0", -1, "initial step size as a share of the bounds' width (-1: automatic)"),
                     0.0, 1.0, true)),
        tolerance("ftol", "objective"), tolerance("xtol", "decision-vector"),
        boolean("force_bounds", "force_bounds", true,
                "keep samples inside the bounds (else they are clamped before evaluation)")}});
  t.push_back(
      {"gaco",
       "extended ant colony optimization",
       false,
       2,
       1,
       true,
       {in(integer("ker", "ker", 10, "solution archive size (pagmo's default 63); at most the population"), 2.0, {}),
        in(real("q", "q", 1.0, "convergence speed parameter"), 0.0, {}),
        real("oracle", "oracle", 0.0, "oracle parameter of the penalty method"),
        in(real("acc", "acc", 0.01, "accuracy parameter of the penalty method"), 0.0, {}),
        in(integer("threshold", "threshold", 1, "generation from which the focus parameter acts; at most generations"),
           1.0, {}),
        in(integer("n_gen_mark", "n_gen_mark", 7, "generations over which the standard deviations shrink"), 1.0, {}),
        in(integer("impstop", "impstop", 100000, "stop after this many generations without improvement"), 1.0, {}),
        in(integer("evalstop", "evalstop", 100000, "stop after this many evaluations without improvement"), 1.0, {}),
        in(real("focus", "focus", 0.0, "focus parameter (larger: search nearer the best)"), 0.0, {})}});
  t.push_back({"gwo", "grey wolf optimizer", false, 3, 1, true, {}});
  t.push_back(
      {"bee_colony",
       "artificial bee colony",
       false,
       2,
       1,
       true,
       {in(integer("limit", "limit", 20, "trials without improvement before a food source is abandoned"), 1.0, {})}});
  t.push_back({"sea", "(N+1)-evolution strategy", false, 1, 1, true, {}});
  t.push_back({"simulated_annealing",
               "Corana's simulated annealing (budget n_t_adj * n_range_adj * bin_size * dimension; generations unused)",
               false,
               1,
               1,
               false,
               {in(real("ts", "Ts", 10.0, "starting temperature"), 0.0, {}, true),
                in(real("tf", "Tf", 0.1, "final temperature (at most ts)"), 0.0, {}, true),
                in(integer("n_t_adj", "n_T_adj", 10, "temperature adjustments"), 1.0, {}),
                in(integer("n_range_adj", "n_range_adj", 1, "range adjustments per temperature"), 1.0, {}),
                in(integer("bin_size", "bin_size", 20, "mutations per range adjustment"), 1.0, {}),
                in(real("start_range", "start_range", 1.0, "starting neighbourhood as a share of the bounds' width"),
                   0.0, 1.0, true)}});
  t.push_back(
      {"compass_search",
       "compass search (pattern search from the best individual; generations unused)",
       false,
       1,
       1,
       false,
       {in(integer("max_fevals", "max_fevals", 1000, "evaluation budget"), 1.0, {}),
        in(real("start_range", "start_range", 0.1, "starting step as a share of the bounds' width"), 0.0, 1.0, true),
        in(real("stop_range", "stop_range", 0.01, "stop when the step falls below this (less than start_range)"), 0.0,
           1.0, true),
        in(real("reduction_coeff", "reduction_coeff", 0.5, "step reduction factor"), 0.0, 1.0, true, true)}});
  t.push_back({"nsga2",
               "non-dominated sorting genetic algorithm II (Deb et al. 2002), two or more objectives",
               true,
               8,
               4,
               true,
               {in(real("cr", "cr", 0.95, "SBX crossover probability"), 0.0, 1.0, false, true),
                in(real("eta_c", "eta_c", 10.0, "SBX distribution index"), 1.0, 100.0),
                in(real("m", "m", 0.01, "mutation probability per gene"), 0.0, 1.0),
                in(real("eta_m", "eta_m", 50.0, "polynomial-mutation distribution index"), 1.0, 100.0)}});
  t.push_back(
      {"moead",
       "multi-objective evolutionary algorithm by decomposition (DE variant), two or more objectives",
       true,
       3,
       1,
       true,
       {choice("weight_generation", "weight_generation", "grid", {"grid", "random", "low_discrepancy"},
               "how the weight vectors are made"),
        choice("decomposition", "decomposition", "tchebycheff", {"tchebycheff", "weighted", "bi"},
               "decomposition of the objectives"),
        in(integer("neighbours", "neighbours", 20, "size of the weights' neighbourhood; less than the population"), 2.0,
           {}),
        in(real("cr", "CR", 1.0, "DE crossover probability"), 0.0, 1.0),
        in(real("f", "F", 0.5, "DE weight coefficient"), 0.0, 1.0),
        in(real("eta_m", "eta_m", 20.0, "polynomial-mutation distribution index"), 0.0, {}),
        in(real("realb", "realb", 0.9, "chance that parents come from the neighbourhood"), 0.0, 1.0),
        in(integer("limit", "limit", 2, "most individuals a child may replace"), 0.0, {}),
        boolean("preserve_diversity", "preserve_diversity", true, "apply the diversity preservation mechanism")}});
  t.push_back({"nspso",
               "non-dominated sorting particle swarm optimization, two or more objectives",
               true,
               2,
               1,
               true,
               {in(real("omega", "omega", 0.6, "particles' inertia weight"), 0.0, 1.0),
                in(real("c1", "c1", 2.0, "magnitude of the force towards the particle's best"), 0.0, {}, true),
                in(real("c2", "c2", 2.0, "magnitude of the force towards the leader"), 0.0, {}, true),
                in(real("chi", "chi", 1.0, "velocity scaling factor"), 0.0, {}, true),
                in(real("v_coeff", "v_coeff", 0.5, "velocity limit as a share of the bounds' width"), 0.0, 1.0, true),
                in(integer("leader_selection_range", "leader_selection_range", 60,
                           "percent of the front leaders are drawn from"),
                   0.0, 100.0),
                choice("diversity_mechanism", "diversity_mechanism", "crowding_distance",
                       {"crowding_distance", "niche_count", "max_min"}, "diversity mechanism for leader selection")}});
  return t;
}

double number(const Algorithm& a, const Config& c, const std::string& key) {
  const auto it = c.options.find(key);
  if (it != c.options.end()) {
    if (const auto* v = std::get_if<double>(&it->second)) return *v;
    throw std::invalid_argument(a.name + " option " + key + " needs a number");
  }
  for (const auto& o : a.options) {
    if (o.key == key) return o.default_number;
  }
  throw std::logic_error("pagmo_optimizer: " + a.name + " has no option " + key);
}

std::string text(const Algorithm& a, const Config& c, const std::string& key) {
  const auto it = c.options.find(key);
  std::string value;
  if (it != c.options.end()) {
    const auto* v = std::get_if<std::string>(&it->second);
    if (!v) throw std::invalid_argument(a.name + " option " + key + " needs a choice");
    value = *v;
  } else {
    for (const auto& o : a.options) {
      if (o.key == key) value = o.default_choice;
    }
  }
  std::replace(value.begin(), value.end(), '_', ' ');  // pagmo spells "low discrepancy", "crowding distance"
  return value;
}

unsigned u(double v) { return static_cast<unsigned>(std::llround(v)); }

unsigned seed32(std::uint64_t seed, std::uint64_t stream) {
  return static_cast<unsigned>(splitmix64(seed ^ splitmix64(stream)) >> 32);
}

pagmo::algorithm make_algorithm(const Algorithm& a, const Config& c, unsigned seed) {
  const auto n = [&](const std::string& k) { return number(a, c, k); };
  const auto s = [&](const std::string& k) { return text(a, c, k); };
  const unsigned gen = static_cast<unsigned>(c.generations);
  const std::string& name = a.name;
  if (name == "sga") {
    return pagmo::algorithm(pagmo::sga(gen, n("cr"), n("eta_c"), n("m"), n("param_m"), u(n("param_s")), s("crossover"),
                                       s("mutation"), s("selection"), seed));
  }
  if (name == "de")
    return pagmo::algorithm(pagmo::de(gen, n("f"), n("cr"), u(n("variant")), n("ftol"), n("xtol"), seed));
  if (name == "sade") {
    return pagmo::algorithm(
        pagmo::sade(gen, u(n("variant")), u(n("variant_adptv")), n("ftol"), n("xtol"), false, seed));
  }
  if (name == "pso") {
    return pagmo::algorithm(pagmo::pso(gen, n("omega"), n("eta1"), n("eta2"), n("max_vel"), u(n("variant")),
                                       u(n("neighb_type")), u(n("neighb_param")), false, seed));
  }
  if (name == "cmaes") {
    return pagmo::algorithm(pagmo::cmaes(gen, n("cc"), n("cs"), n("c1"), n("cmu"), n("sigma0"), n("ftol"), n("xtol"),
                                         false, n("force_bounds") != 0.0, seed));
  }
  if (name == "xnes") {
    return pagmo::algorithm(pagmo::xnes(gen, n("eta_mu"), n("eta_sigma"), n("eta_b"), n("sigma0"), n("ftol"), n("xtol"),
                                        false, n("force_bounds") != 0.0, seed));
  }
  if (name == "gaco") {
    pagmo::gaco g(gen, u(n("ker")), n("q"), n("oracle"), n("acc"), u(n("threshold")), u(n("n_gen_mark")),
                  u(n("impstop")), u(n("evalstop")), n("focus"), false, seed);
    return pagmo::algorithm(std::move(g));
  }
  if (name == "gwo") return pagmo::algorithm(pagmo::gwo(gen, seed));
  if (name == "bee_colony") return pagmo::algorithm(pagmo::bee_colony(gen, u(n("limit")), seed));
  if (name == "sea") return pagmo::algorithm(pagmo::sea(gen, seed));
  if (name == "simulated_annealing") {
    return pagmo::algorithm(pagmo::simulated_annealing(n("ts"), n("tf"), u(n("n_t_adj")), u(n("n_range_adj")),
                                                       u(n("bin_size")), n("start_range"), seed));
  }
  if (name == "compass_search") {
    return pagmo::algorithm(
        pagmo::compass_search(u(n("max_fevals")), n("start_range"), n("stop_range"), n("reduction_coeff")));
  }
  if (name == "nsga2") return pagmo::algorithm(pagmo::nsga2(gen, n("cr"), n("eta_c"), n("m"), n("eta_m"), seed));
  if (name == "moead") {
    return pagmo::algorithm(pagmo::moead(gen, s("weight_generation"), s("decomposition"),
                                         static_cast<pagmo::population::size_type>(n("neighbours")), n("cr"), n("f"),
                                         n("eta_m"), n("realb"), u(n("limit")), n("preserve_diversity") != 0.0, seed));
  }
  if (name == "nspso") {
    return pagmo::algorithm(pagmo::nspso(gen, n("omega"), n("c1"), n("c2"), n("chi"), n("v_coeff"),
                                         u(n("leader_selection_range")), s("diversity_mechanism"), false, seed));
  }
  throw std::logic_error("pagmo_optimizer: no constructor for " + name);
}

// Shared by every copy pagmo makes of the problem.
struct Evaluation {
  const Objective* objective = nullptr;
  std::vector<Bound> bounds;
  std::size_t objectives = 1;
  std::size_t block = 1;  // evaluations per history entry
  std::mutex mutex;
  std::int64_t evaluations = 0;
  double best_first = std::numeric_limits<double>::infinity();
  Eigen::VectorXd best_x, best_f;
  std::vector<double> history;

  Eigen::VectorXd admissible(const pagmo::vector_double& x) const {
    Eigen::VectorXd v(static_cast<Eigen::Index>(x.size()));
    for (std::size_t i = 0; i < x.size(); ++i) {
      double xi = std::clamp(x[i], bounds[i].lower, bounds[i].upper);
      if (bounds[i].integer) xi = std::clamp(std::round(xi), std::ceil(bounds[i].lower), std::floor(bounds[i].upper));
      v[static_cast<Eigen::Index>(i)] = xi;
    }
    return v;
  }

  pagmo::vector_double evaluate(const Eigen::VectorXd& x) const {
    const Eigen::VectorXd f = (*objective)(x);
    if (static_cast<std::size_t>(f.size()) != objectives) {
      throw std::invalid_argument("the objective returned " + std::to_string(f.size()) + " values, expected " +
                                  std::to_string(objectives));
    }
    pagmo::vector_double out(objectives);
    for (std::size_t k = 0; k < objectives; ++k) {
      const double v = f[static_cast<Eigen::Index>(k)];
      out[k] = std::isfinite(v) ? v : std::numeric_limits<double>::max();
    }
    return out;
  }

  // Called in evaluation order (serially, or batch by batch in index order).
  void record(const Eigen::VectorXd& x, const pagmo::vector_double& f) {
    std::lock_guard<std::mutex> lock(mutex);
    ++evaluations;
    if (f[0] < best_first) {
      best_first = f[0];
      best_x = x;
      best_f = Eigen::Map<const Eigen::VectorXd>(f.data(), static_cast<Eigen::Index>(f.size()));
    }
    if (evaluations % static_cast<std::int64_t>(block) == 0) history.push_back(best_first);
  }
};

struct Problem {
  std::shared_ptr<Evaluation> state;

  pagmo::vector_double fitness(const pagmo::vector_double& x) const {
    const Eigen::VectorXd v = state->admissible(x);
    auto f = state->evaluate(v);
    state->record(v, f);
    return f;
  }
  std::pair<pagmo::vector_double, pagmo::vector_double> get_bounds() const {
    pagmo::vector_double lo, hi;
    for (const auto& b : state->bounds) {
      lo.push_back(b.lower);
      hi.push_back(b.upper);
    }
    return {lo, hi};
  }
  pagmo::vector_double::size_type get_nobj() const { return state->objectives; }
  std::string get_name() const { return "driftlab objective"; }
};

// Batch evaluator: the points are evaluated by parallel_for on `threads` threads, each into its own
// slot, and recorded afterwards in index order, so the result does not depend on the thread count.
struct BatchEvaluator {
  unsigned threads = 1;

  pagmo::vector_double operator()(const pagmo::problem& prob, const pagmo::vector_double& batch) const {
    const auto& p = *prob.extract<Problem>();
    Evaluation& e = *p.state;
    const std::size_t dim = e.bounds.size(), nf = e.objectives;
    const std::size_t count = batch.size() / dim;
    std::vector<Eigen::VectorXd> xs(count);
    std::vector<pagmo::vector_double> fs(count);
    parallel_for(count, threads, [&](std::size_t i) {
      xs[i] = e.admissible(pagmo::vector_double(batch.begin() + static_cast<std::ptrdiff_t>(i * dim),
                                                batch.begin() + static_cast<std::ptrdiff_t>((i + 1) * dim)));
      fs[i] = e.evaluate(xs[i]);
    });
    pagmo::vector_double out;
    out.reserve(count * nf);
    for (std::size_t i = 0; i < count; ++i) {
      e.record(xs[i], fs[i]);
      out.insert(out.end(), fs[i].begin(), fs[i].end());
    }
    prob.increment_fevals(count);
    return out;
  }
  std::string get_name() const { return "driftlab deterministic threads"; }
};

void check_bounds(const std::vector<Bound>& bounds) {
  if (bounds.empty()) throw std::invalid_argument("no parameters to optimize");
  for (std::size_t i = 0; i < bounds.size(); ++i) {
    const auto& b = bounds[i];
    const double lo = b.integer ? std::ceil(b.lower) : b.lower, hi = b.integer ? std::floor(b.upper) : b.upper;
    if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi) {
      throw std::invalid_argument("parameter " + std::to_string(i) + " has an empty bound [" + std::to_string(b.lower) +
                                  ", " + std::to_string(b.upper) + "]");
    }
  }
}

std::size_t choose(const Eigen::MatrixXd& front, ParetoChoice rule) {
  if (rule == ParetoChoice::MinFirst) return 0;  // the front is sorted by objective 1
  const Eigen::RowVectorXd lo = front.colwise().minCoeff(), hi = front.colwise().maxCoeff();
  std::size_t best = 0;
  double best_distance = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < front.rows(); ++i) {
    double d2 = 0.0;
    for (Eigen::Index k = 0; k < front.cols(); ++k) {
      const double span = hi[k] - lo[k];
      const double z = span > 0.0 ? (front(i, k) - lo[k]) / span : 0.0;
      d2 += z * z;
    }
    if (d2 < best_distance) {
      best_distance = d2;
      best = static_cast<std::size_t>(i);
    }
  }
  return best;
}

}  // namespace

const std::vector<Algorithm>& algorithms() {
  static const std::vector<Algorithm> table = make_table();
  return table;
}

const Algorithm& algorithm(const std::string& name) {
  std::string known;
  for (const auto& a : algorithms()) {
    if (a.name == name) return a;
    known += (known.empty() ? "" : ", ") + a.name;
  }
  throw std::invalid_argument("unknown pagmo algorithm '" + name + "' (known: " + known + ")");
}

Result minimize(const Objective& objective, std::size_t objectives, const std::vector<Bound>& bounds,
                const Config& config) {
  const Algorithm& a = algorithm(config.algorithm);
  check_bounds(bounds);
  if (a.multi_objective && objectives < 2) {
    throw std::invalid_argument(a.name + " is multi-objective: it needs two or more objectives, got " +
                                std::to_string(objectives));
  }
  if (!a.multi_objective && objectives != 1) {
    throw std::invalid_argument(a.name + " minimizes one objective; " + std::to_string(objectives) +
                                " were given (multi-objective: nsga2, moead, nspso)");
  }
  if (config.population < a.min_population || config.population % a.population_multiple_of != 0) {
    throw std::invalid_argument(a.name + " needs a population of at least " + std::to_string(a.min_population) +
                                (a.population_multiple_of > 1
                                     ? " and a multiple of " + std::to_string(a.population_multiple_of)
                                     : std::string()) +
                                ", got " + std::to_string(config.population));
  }

  auto state = std::make_shared<Evaluation>();
  state->objective = &objective;
  state->bounds = bounds;
  state->objectives = objectives;
  state->block = config.population;
  const unsigned threads = std::max(1u, config.threads);

  pagmo::algorithm algo = make_algorithm(a, config, seed32(config.seed, 1));
  pagmo::problem prob{Problem{state}};
  const pagmo::bfe batch{BatchEvaluator{threads}};
  // The batch evaluator is used for every thread count (one code path, same result).
  if (auto* g = algo.extract<pagmo::gaco>()) g->set_bfe(batch);
  if (auto* g = algo.extract<pagmo::nsga2>()) g->set_bfe(batch);
  if (auto* g = algo.extract<pagmo::nspso>()) g->set_bfe(batch);
  pagmo::population pop(prob, batch, config.population, seed32(config.seed, 2));
  pop = algo.evolve(pop);

  Result r;
  r.evaluations = state->evaluations;
  r.history = state->history;
  if (r.history.empty() || state->evaluations % static_cast<std::int64_t>(state->block) != 0) {
    r.history.push_back(state->best_first);
  }
  if (objectives == 1) {
    r.best = state->best_x;
    r.best_values = state->best_f;
    return r;
  }
  // The first non-dominated front of the final population, sorted by objective 1 (then 2, ...).
  const auto& fs = pop.get_f();
  const auto& xs = pop.get_x();
  const auto fronts = pagmo::fast_non_dominated_sorting(fs);
  std::vector<pagmo::pop_size_t> front = std::get<0>(fronts).front();
  std::sort(front.begin(), front.end(), [&](auto i, auto j) { return fs[i] != fs[j] ? fs[i] < fs[j] : i < j; });
  front.erase(std::unique(front.begin(), front.end(), [&](auto i, auto j) { return fs[i] == fs[j]; }), front.end());
  const auto rows = static_cast<Eigen::Index>(front.size());
  r.pareto_x.resize(rows, static_cast<Eigen::Index>(bounds.size()));
  r.pareto_f.resize(rows, static_cast<Eigen::Index>(objectives));
  for (Eigen::Index i = 0; i < rows; ++i) {
    const auto idx = front[static_cast<std::size_t>(i)];
    r.pareto_x.row(i) = state->admissible(xs[idx]).transpose();
    for (std::size_t k = 0; k < objectives; ++k) r.pareto_f(i, static_cast<Eigen::Index>(k)) = fs[idx][k];
  }
  const std::size_t chosen = choose(r.pareto_f, config.pareto_choice);
  r.best = r.pareto_x.row(static_cast<Eigen::Index>(chosen)).transpose();
  r.best_values = r.pareto_f.row(static_cast<Eigen::Index>(chosen)).transpose();
  return r;
}

}  // namespace driftlab::pagmo_optimizer
