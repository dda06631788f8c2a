// optimizer/pagmo: adapter of plugins/pagmo/pagmo_optimizer.hpp. The parameter table is built
// from the kernel's algorithm table: `algorithm`, `population`, `generations`, `pareto_choice`,
// `seed`, then every option of every algorithm as `<algorithm>_<option>` with pagmo's default,
// range and meaning. Options of an algorithm other than the selected one must keep their
// defaults (a cross rule), so an option given to the wrong algorithm is an error, not ignored.
#include <cmath>
#include <limits>
#include <stdexcept>

#include "framework/error.hpp"
#include "framework/registry.hpp"
#include "plugins/pagmo/pagmo_optimizer.hpp"

namespace driftlab {
namespace {

namespace po = pagmo_optimizer;

std::string option_key(const po::Algorithm& a, const po::Option& o) { return a.name + "_" + o.key; }

double as_number(const ParamValue& v) {
  if (const auto* d = std::get_if<double>(&v)) return *d;
  if (const auto* i = std::get_if<std::int64_t>(&v)) return static_cast<double>(*i);
  if (const auto* b = std::get_if<bool>(&v)) return *b ? 1.0 : 0.0;
  return std::numeric_limits<double>::quiet_NaN();
}

ParamSpec spec_of(const po::Algorithm& a, const po::Option& o) {
  const std::string key = option_key(a, o);
  const std::string doc = a.name + ": " + o.doc + (o.pagmo_name != o.key ? " (pagmo: " + o.pagmo_name + ")" : "");
  ParamSpec s;
  switch (o.type) {
    case po::Option::Type::Integer:
      s = param::integer(key, static_cast<std::int64_t>(o.default_number), "1", doc);
      break;
    case po::Option::Type::Real:
      s = param::real(key, o.default_number, "1", doc);
      break;
    case po::Option::Type::Boolean:
      s = param::boolean(key, o.default_number != 0.0, doc);
      break;
    case po::Option::Type::Choice:
      s = param::choice(key, o.default_choice, o.choices, doc);
      break;
  }
  if (!o.minus_one_is_automatic) {
    if (o.min) o.min_exclusive ? s.greater_than(*o.min) : s.at_least(*o.min);
    if (o.max) o.max_exclusive ? s.less_than(*o.max) : s.at_most(*o.max);
    return s;
  }
  const std::string range = std::string(o.min_exclusive ? "(" : "[") + "0, 1]";
  s.must(
      "-1 (automatic) or in " + range,
      [o, range](const ParamValue& v) -> std::string {
        const double x = as_number(v);
        if (x == -1.0) return "";
        const bool low_ok = o.min_exclusive ? x > *o.min : x >= *o.min;
        return low_ok && x <= *o.max ? "" : "must be -1 (automatic) or in " + range;
      },
      -0.5);
  return s;
}

bool equals_default(const ParamValues& p, const std::string& key, const po::Option& o) {
  if (o.type == po::Option::Type::Choice) return p.text(key) == o.default_choice;
  return as_number(p.at(key)) == o.default_number;
}

std::vector<CrossRule> rules() {
  std::vector<CrossRule> r;
  for (const auto& a : po::algorithms()) {
    std::string rule = "population >= " + std::to_string(a.min_population);
    if (a.population_multiple_of > 1) rule += " and a multiple of " + std::to_string(a.population_multiple_of);
    r.push_back({"algorithm " + a.name + ": " + rule,
                 {"algorithm", "population"},
                 [name = a.name, min = a.min_population, mult = a.population_multiple_of](const ParamValues& p) {
                   if (p.text("algorithm") != name) return true;
                   const auto n = static_cast<std::size_t>(p.integer("population"));
                   return n >= min && n % mult == 0;
                 }});
    if (a.options.empty()) continue;
    std::vector<std::string> keys{"algorithm"};
    for (const auto& o : a.options) keys.push_back(option_key(a, o));
    r.push_back(
        {a.name + "_* options are used only with algorithm: " + a.name + " (elsewhere they keep their defaults)", keys,
         [a](const ParamValues& p) {
           if (p.text("algorithm") == a.name) return true;
           for (const auto& o : a.options) {
             if (!equals_default(p, option_key(a, o), o)) return false;
           }
           return true;
         }});
  }
  const auto when = [](std::string alg, std::function<bool(const ParamValues&)> f) {
    return
        [alg = std::move(alg), f = std::move(f)](const ParamValues& p) { return p.text("algorithm") != alg || f(p); };
  };
  r.push_back({"sga_param_s <= population", {"sga_param_s", "population"}, when("sga", [](const ParamValues& p) {
                 return p.integer("sga_param_s") <= p.integer("population");
               })});
  r.push_back({"sga_crossover sbx needs an even population",
               {"sga_crossover", "population"},
               when("sga", [](const ParamValues& p) {
                 return p.text("sga_crossover") != "sbx" || p.integer("population") % 2 == 0;
               })});
  r.push_back({"sga_param_m in [1, 100] for polynomial mutation, in [0, 1] otherwise",
               {"sga_param_m", "sga_mutation"},
               [](const ParamValues& p) {
                 const double m = p.real("sga_param_m");
                 return p.text("sga_mutation") == "polynomial" ? m >= 1.0 && m <= 100.0 : m >= 0.0 && m <= 1.0;
               }});
  r.push_back({"gaco_ker <= population", {"gaco_ker", "population"}, when("gaco", [](const ParamValues& p) {
                 return p.integer("gaco_ker") <= p.integer("population");
               })});
  r.push_back({"gaco_threshold <= generations (unless generations is 0)",
               {"gaco_threshold", "generations"},
               when("gaco", [](const ParamValues& p) {
                 return p.integer("generations") == 0 || p.integer("gaco_threshold") <= p.integer("generations");
               })});
  r.push_back(
      {"moead_neighbours < population", {"moead_neighbours", "population"}, when("moead", [](const ParamValues& p) {
         return p.integer("moead_neighbours") < p.integer("population");
       })});
  r.push_back(
      {"simulated_annealing_tf <= simulated_annealing_ts",
       {"simulated_annealing_tf", "simulated_annealing_ts"},
       [](const ParamValues& p) { return p.real("simulated_annealing_tf") <= p.real("simulated_annealing_ts"); }});
  r.push_back({"compass_search_stop_range < compass_search_start_range",
               {"compass_search_stop_range", "compass_search_start_range"},
               [](const ParamValues& p) {
                 return p.real("compass_search_stop_range") < p.real("compass_search_start_range");
               }});
  return r;
}

ParamTable table() {
  std::vector<std::string> names;
  for (const auto& a : po::algorithms()) names.push_back(a.name);
  std::string doc = "pagmo algorithm:";
  for (const auto& a : po::algorithms()) doc += " " + a.name + (a.multi_objective ? " (multi-objective)" : "");
  ParamTable t{
      {param::choice("algorithm", "sga", names, doc),
       param::integer("population", 40, "1", "individuals (initial points drawn uniformly in the bounds)").at_least(1),
       param::integer("generations", 50, "1",
                      "generations (pagmo's gen); unused by simulated_annealing and compass_search")
           .at_least(0),
       param::choice("pareto_choice", "closest_to_ideal", {"closest_to_ideal", "min_first"},
                     "several objectives: the point chosen from the final front, nearest the ideal point "
                     "with each objective scaled to [0, 1] over the front, or the smallest first objective"),
       param::seed()},
      rules()};
  for (const auto& a : po::algorithms()) {
    for (const auto& o : a.options) t.params.push_back(spec_of(a, o));
  }
  return t;
}

class PagmoPlugin final : public Optimizer {
 public:
  explicit PagmoPlugin(const ParamValues& p)
      : algorithm_(po::algorithm(p.text("algorithm"))),
        config_{.algorithm = p.text("algorithm"),
                .population = static_cast<std::size_t>(p.integer("population")),
                .generations = static_cast<std::size_t>(p.integer("generations")),
                .pareto_choice = p.text("pareto_choice") == "min_first" ? po::ParetoChoice::MinFirst
                                                                        : po::ParetoChoice::ClosestToIdeal,
                .seed = static_cast<std::uint64_t>(p.integer("seed"))} {
    for (const auto& o : algorithm_.options) {
      const std::string key = option_key(algorithm_, o);
      if (o.type == po::Option::Type::Choice) {
        config_.options[o.key] = p.text(key);
      } else {
        config_.options[o.key] = as_number(p.at(key));
      }
    }
  }

  std::size_t max_objectives() const override {
    return algorithm_.multi_objective ? std::numeric_limits<std::size_t>::max() : 1;
  }

  OptimizationResult minimize(const Objective& f, const std::vector<Bound>& bounds, RunContext& ctx) override {
    return run([&](const Eigen::VectorXd& x) { return Eigen::VectorXd::Constant(1, f(x)); }, 1, bounds, ctx);
  }

  OptimizationResult minimize_objectives(const VectorObjective& f, std::size_t objectives,
                                         const std::vector<Bound>& bounds, RunContext& ctx) override {
    return run(f, objectives, bounds, ctx);
  }

 private:
  OptimizationResult run(const po::Objective& f, std::size_t objectives, const std::vector<Bound>& bounds,
                         RunContext& ctx) const {
    std::vector<po::Bound> genes;
    for (const auto& b : bounds) genes.push_back({b.lower, b.upper, b.integer});
    po::Config config = config_;
    config.threads = ctx.threads;
    po::Result r;
    try {
      r = po::minimize(f, objectives, genes, config);
    } catch (const std::invalid_argument& e) {
      throw ConfigError({"", 0, "algorithm"}, "optimizer/pagmo (" + config.algorithm + "): " + e.what());
    }
    const auto named = [&](const Eigen::VectorXd& x) {
      nlohmann::json j = nlohmann::json::object();
      for (std::size_t i = 0; i < bounds.size(); ++i) j[bounds[i].name] = x[static_cast<Eigen::Index>(i)];
      return j;
    };
    ctx.diagnostics["algorithm"] = config.algorithm;
    ctx.diagnostics["history"] = r.history;
    ctx.diagnostics["best"] = named(r.best);
    ctx.diagnostics["best_value"] = r.best_values[0];
    ctx.diagnostics["evaluations"] = r.evaluations;
    if (objectives > 1) {
      nlohmann::json front = nlohmann::json::array();
      for (Eigen::Index i = 0; i < r.pareto_x.rows(); ++i) {
        front.push_back({{"x", named(r.pareto_x.row(i).transpose())},
                         {"objectives", std::vector<double>(r.pareto_f.row(i).data(),
                                                            r.pareto_f.row(i).data() + r.pareto_f.cols())}});
      }
      ctx.diagnostics["pareto_front"] = front;
      ctx.diagnostics["best_values"] =
          std::vector<double>(r.best_values.data(), r.best_values.data() + r.best_values.size());
      ctx.diagnostics["pareto_choice"] =
          config.pareto_choice == po::ParetoChoice::MinFirst ? "min_first" : "closest_to_ideal";
    }
    OptimizationResult out{r.best, r.best_values[0], r.history, r.evaluations};
    out.pareto_x = r.pareto_x;
    out.pareto_f = r.pareto_f;
    out.best_values = r.best_values;
    return out;
  }

  const po::Algorithm& algorithm_;
  po::Config config_;
};

}  // namespace

void register_pagmo_plugins(Registry& registry) {
  registry.add({.name = "optimizer/pagmo",
                .summary = "any of pagmo2's algorithms by name (single- and multi-objective), options passed through",
                .reference = "Biscani & Izzo 2020, pagmo2 (JOSS 5(53), 2338); Deb et al. 2002 (NSGA-II)",
                .params = table(),
                .make = [](const ParamValues& p, const Registry&) { return std::make_unique<PagmoPlugin>(p); }});
}

}  // namespace driftlab
