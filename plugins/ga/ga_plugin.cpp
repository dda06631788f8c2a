#include "plugins/ga/ga_plugin.hpp"

#include <stdexcept>

#include "framework/error.hpp"
#include "framework/registry.hpp"
#include "plugins/ga/ga.hpp"

namespace driftlab {
namespace {

class GaPlugin final : public Optimizer {
 public:
  explicit GaPlugin(const ga::Config& config) : config_(config) {}
  explicit GaPlugin(const ParamValues& p)
      : config_{.population = static_cast<std::size_t>(p.integer("population")),
                .generations = static_cast<std::size_t>(p.integer("generations")),
                .tournament_size = static_cast<std::size_t>(p.integer("tournament_size")),
                .crossover_probability = p.real("crossover_probability"),
                .crossover_eta = p.real("crossover_eta"),
                .mutation_probability = p.real("mutation_probability"),
                .mutation_eta = p.real("mutation_eta"),
                .elites = static_cast<std::size_t>(p.integer("elites")),
                .seed = static_cast<std::uint64_t>(p.integer("seed"))} {}

  double evaluation_budget() const override {
    return static_cast<double>(config_.population) * (static_cast<double>(config_.generations) + 1.0);
  }

  OptimizationResult minimize(const Objective& f, const std::vector<Bound>& bounds, RunContext& ctx) override {
    std::vector<ga::Bound> genes;
    for (const auto& b : bounds) genes.push_back({b.lower, b.upper, b.integer});
    ga::Config config = config_;
    config.threads = ctx.threads;
    config.progress = ctx.progress;
    ga::Result r;
    try {
      r = ga::minimize(f, genes, config);
    } catch (const std::invalid_argument& e) {
      throw ConfigError({"", 0, "bounds"}, std::string("optimizer/ga: ") + e.what());
    }
    nlohmann::json best = nlohmann::json::object();
    for (std::size_t i = 0; i < bounds.size(); ++i) {
      best[bounds[i].name] = r.best[static_cast<Eigen::Index>(i)];
    }
    ctx.diagnostics["history"] = r.history;
    ctx.diagnostics["best"] = best;
    ctx.diagnostics["best_value"] = r.best_value;
    ctx.diagnostics["evaluations"] = r.evaluations;
    return {r.best, r.best_value, r.history, r.evaluations};
  }

 private:
  ga::Config config_;
};

}  // namespace

std::unique_ptr<Optimizer> make_ga_optimizer(const ga::Config& config) { return std::make_unique<GaPlugin>(config); }

void register_ga_plugins(Registry& registry) {
  registry.add(
      {.name = "optimizer/ga",
       .summary = "real-coded genetic algorithm (tournament, SBX, polynomial mutation, elitism)",
       .reference =
           "Li et al. 2023 (GA tuning of the RBF network); Deb & Agrawal 1995 (SBX); Deb & Goyal 1996 (mutation)",
       .params =
           ParamTable{
               {param::integer("population", 40, "1", "individuals per generation").at_least(2).at_most(1e6),
                param::integer("generations", 50, "1", "G_MAX: generations bred after the random initial one")
                    .at_least(0),
                param::integer("tournament_size", 2, "1", "individuals drawn per selection tournament; the best wins")
                    .at_least(1),
                param::real("crossover_probability", 0.9, "1", "probability that a parent pair is crossed by SBX")
                    .at_least(0)
                    .at_most(1),
                param::real("crossover_eta", 15.0, "1",
                            "SBX distribution index; larger keeps children nearer their parents")
                    .greater_than(0),
                param::real("mutation_probability", 0.25, "1", "per-gene probability of polynomial mutation")
                    .at_least(0)
                    .at_most(1),
                param::real("mutation_eta", 20.0, "1",
                            "polynomial-mutation distribution index; larger means smaller steps")
                    .greater_than(0),
                param::integer("elites", 2, "1", "best individuals copied unchanged into the next generation")
                    .at_least(0),
                param::seed()},
               {{"elites < population",
                 {"elites", "population"},
                 [](const ParamValues& p) { return p.integer("elites") < p.integer("population"); }}}},
       .make = [](const ParamValues& p, const Registry&) { return std::make_unique<GaPlugin>(p); }});
}

}  // namespace driftlab
