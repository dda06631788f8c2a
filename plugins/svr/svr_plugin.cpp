// regressor/svr: adapter of plugins/svr/svr.hpp. With tune = true, fit() tunes log10(C),
// log10(gamma) and epsilon with the nested optimizer on a blocked holdout (plugins/tuning), by the
// held-out RMSE alone (the sibling paper's cuckoo search tuned C and gamma for the error) or, with
// a multi-objective optimizer, by the held-out RMSE and the share of training rows that become
// support vectors (model complexity); then it fits all samples (up to max_samples) with them.
#include <cmath>
#include <optional>
#include <stdexcept>

#include "framework/error.hpp"
#include "framework/registry.hpp"
#include "plugins/svr/svr.hpp"
#include "plugins/tuning/tuning.hpp"

namespace driftlab {
namespace {

class SvrPlugin final : public Regressor {
 public:
  SvrPlugin(const ParamValues& p, const Registry& registry)
      : config_{.c = p.real("c"),
                .epsilon = p.real("epsilon"),
                .gamma = p.real("gamma"),
                .max_samples = static_cast<std::size_t>(p.integer("max_samples")),
                .tolerance = p.real("tolerance"),
                .cache_rows = static_cast<std::size_t>(p.integer("cache_rows"))},
        c_range_(p.reals("tune_log10_c")),
        gamma_range_(p.reals("tune_log10_gamma")),
        epsilon_range_(p.reals("tune_epsilon")) {
    if (p.boolean("tune")) {
      optimizer_ = registry.create_as<Optimizer>(p.plugin("optimizer"));
      settings_ = tuning::settings(p, *optimizer_, "regressor/svr", "support_vector_share");
    }
  }

  void fit(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, RunContext& ctx) override {
    model_.reset();
    try {
      const svr::Config config = optimizer_ ? tuned(X, y, ctx) : config_;
      auto result = svr::fit(X, y, config);
      ctx.diagnostics["c"] = config.c;
      ctx.diagnostics["epsilon"] = config.epsilon;
      ctx.diagnostics["gamma"] = config.gamma;
      ctx.diagnostics["training_rows"] = result.training_rows;
      ctx.diagnostics["support_vectors"] = result.model.support_vectors();
      model_ = std::move(result.model);
    } catch (const std::invalid_argument& e) {
      throw DataError({"", 0, "features"}, std::string("regressor/svr: ") + e.what());
    }
  }

  Eigen::VectorXd predict(const Eigen::MatrixXd& X) const override {
    if (!model_) throw NotFittedError("regressor/svr: predict called before fit");
    try {
      return model_->predict(X);
    } catch (const std::invalid_argument& e) {
      throw DataError({"", 0, "features"}, std::string("regressor/svr: ") + e.what());
    }
  }

 private:
  svr::Config decode(const Eigen::VectorXd& v) const {
    svr::Config c = config_;
    c.c = std::pow(10.0, v[0]);
    c.gamma = std::pow(10.0, v[1]);
    c.epsilon = v[2];
    return c;
  }

  svr::Config tuned(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, RunContext& ctx) const {
    const std::vector<Bound> bounds{{"log10_c", c_range_[0], c_range_[1], false},
                                    {"log10_gamma", gamma_range_[0], gamma_range_[1], false},
                                    {"epsilon", epsilon_range_[0], epsilon_range_[1], false}};
    const auto fit_and_score = [&](const tuning::Split& d, const Eigen::VectorXd& v) {
      const auto r = svr::fit(d.X_train, d.y_train, decode(v));
      return tuning::Score{r.model.predict(d.X_holdout),
                           static_cast<double>(r.model.support_vectors()) / static_cast<double>(r.training_rows)};
    };
    return decode(tuning::run(*optimizer_, bounds, *settings_, X, y, fit_and_score, ctx));
  }

  svr::Config config_;
  std::vector<double> c_range_, gamma_range_, epsilon_range_;
  std::unique_ptr<Optimizer> optimizer_;
  std::optional<tuning::Settings> settings_;
  std::optional<svr::Model> model_;
};

ParamTable table() {
  ParamTable t{
      {param::real("c", 10.0, "1", "C: penalty on deviations beyond epsilon (standardized target)").greater_than(0),
       param::real("epsilon", 0.1, "1", "insensitive-zone half width in target standard deviations").at_least(0),
       param::real("gamma", 0.5, "1", "RBF kernel exp(-gamma ||u - v||^2), u in standardized feature units")
           .greater_than(0),
       param::integer("max_samples", 2000, "1",
                      "training uses an evenly spaced subsample of at most this many rows (SMO is O(n^2))")
           .at_least(2),
       param::real("tolerance", 1e-3, "1", "SMO stopping tolerance (dlib's epsilon)").greater_than(0),
       param::integer("cache_rows", 200, "1", "kernel columns cached by dlib's solver").at_least(1),
       tuning::search_range("tune_log10_c", {-1, 3}, "1", "search range for log10(c)"),
       tuning::search_range("tune_log10_gamma", {-3, 1}, "1", "search range for log10(gamma)"),
       tuning::search_range("tune_epsilon", {0.01, 0.5}, "1", "search range for epsilon").at_least(0)},
      {}};
  auto shared = tuning::params("support_vectors", "the share of training rows that are support vectors");
  t.params.insert(t.params.end(), shared.begin(), shared.end());
  t.params.push_back(param::seed());
  return t;
}

}  // namespace

void register_svr_plugins(Registry& registry) {
  registry.add(
      {.name = "regressor/svr",
       .summary = "epsilon-SVR with a Gaussian kernel (dlib's SMO), optionally tuned",
       .reference = "Smola & Schoelkopf 2004; Sensors 2020, PMC7345257 (CS-SVR drift model); dlib svr_trainer",
       .params = table(),
       .make = [](const ParamValues& p, const Registry& plugins) { return std::make_unique<SvrPlugin>(p, plugins); }});
}

}  // namespace driftlab
