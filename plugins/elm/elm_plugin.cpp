// regressor/elm: adapter of plugins/elm/elm.hpp. With tune = true, fit() tunes the number of
// hidden units, log10(regularization) and the input-weight scale with the nested optimizer on a
// blocked holdout (plugins/tuning), by the held-out RMSE alone or, with a multi-objective
// optimizer (the 2024 paper's NSGA-II: optimizer/pagmo, algorithm nsga2), by the held-out RMSE
// and the output-weight norm ||beta||_2 together; then it fits all samples with the chosen values.
#include <cmath>
#include <optional>
#include <stdexcept>

#include "framework/error.hpp"
#include "framework/registry.hpp"
#include "plugins/elm/elm.hpp"
#include "plugins/tuning/tuning.hpp"

namespace driftlab {
namespace {

elm::Activation activation_of(const std::string& name) {
  if (name == "tanh") return elm::Activation::Tanh;
  if (name == "sine") return elm::Activation::Sine;
  if (name == "relu") return elm::Activation::Relu;
  return elm::Activation::Sigmoid;
}

class ElmPlugin final : public Regressor {
 public:
  ElmPlugin(const ParamValues& p, const Registry& registry)
      : config_{.hidden = static_cast<std::size_t>(p.integer("hidden")),
                .activation = activation_of(p.text("activation")),
                .input_scale = p.real("input_scale"),
                .regularization = p.real("regularization"),
                .seed = static_cast<std::uint64_t>(p.integer("seed"))},
        hidden_range_(p.reals("tune_hidden")),
        regularization_range_(p.reals("tune_log10_regularization")),
        scale_range_(p.reals("tune_input_scale")) {
    if (p.boolean("tune")) {
      optimizer_ = registry.create_as<Optimizer>(p.plugin("optimizer"));
      settings_ = tuning::settings(p, *optimizer_, "regressor/elm", "output_weight_norm");
    }
  }

  void fit(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, RunContext& ctx) override {
    model_.reset();
    try {
      elm::Config config = optimizer_ ? tuned(X, y, ctx) : config_;
      if (!optimizer_) config.progress = ctx.progress;  // tuned: the optimizer's progress is the step's
      model_ = elm::fit(X, y, config);
      ctx.diagnostics["hidden"] = config.hidden;
      ctx.diagnostics["regularization"] = config.regularization;
      ctx.diagnostics["input_scale"] = config.input_scale;
      ctx.diagnostics["output_weight_norm"] = model_->output_weight_norm();
    } catch (const std::invalid_argument& e) {
      throw DataError({"", 0, "features"}, std::string("regressor/elm: ") + e.what());
    }
  }

  Eigen::VectorXd predict(const Eigen::MatrixXd& X) const override {
    if (!model_) throw NotFittedError("regressor/elm: predict called before fit");
    try {
      return model_->predict(X);
    } catch (const std::invalid_argument& e) {
      throw DataError({"", 0, "features"}, std::string("regressor/elm: ") + e.what());
    }
  }

 private:
  elm::Config decode(const Eigen::VectorXd& v) const {
    elm::Config c = config_;
    c.hidden = static_cast<std::size_t>(std::llround(v[0]));
    c.regularization = std::pow(10.0, v[1]);
    c.input_scale = v[2];
    return c;
  }

  elm::Config tuned(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, RunContext& ctx) const {
    const std::vector<Bound> bounds{{"hidden", hidden_range_[0], hidden_range_[1], true},
                                    {"log10_regularization", regularization_range_[0], regularization_range_[1], false},
                                    {"input_scale", scale_range_[0], scale_range_[1], false}};
    const auto fit_and_score = [&](const tuning::Split& d, const Eigen::VectorXd& v) {
      const auto model = elm::fit(d.X_train, d.y_train, decode(v));
      return tuning::Score{model.predict(d.X_holdout), model.output_weight_norm()};
    };
    return decode(tuning::run(*optimizer_, bounds, *settings_, X, y, fit_and_score, ctx));
  }

  elm::Config config_;
  std::vector<double> hidden_range_, regularization_range_, scale_range_;
  std::unique_ptr<Optimizer> optimizer_;
  std::optional<tuning::Settings> settings_;
  std::optional<elm::Model> model_;
};

ParamTable table() {
  ParamTable t{
      {param::integer("hidden", 50, "1", "hidden units L").at_least(1),
       param::choice("activation", "sigmoid", {"sigmoid", "tanh", "sine", "relu"}, "hidden activation g"),
       param::real("input_scale", 1.0, "1",
                   "random input weights and biases uniform in [-input_scale, input_scale] (standardized inputs)")
           .greater_than(0),
       param::real("regularization", 1e-8, "1",
                   "ridge lambda on the mean-square normal equations of the output weights")
           .at_least(0),
       tuning::search_range("tune_hidden", {5, 200}, "1", "search range for hidden").at_least(1),
       tuning::search_range("tune_log10_regularization", {-10, -1}, "1", "search range for log10(regularization)"),
       tuning::search_range("tune_input_scale", {0.1, 5}, "1", "search range for input_scale").greater_than(0),
       param::seed()},
      {}};
  auto shared = tuning::params("weight_norm", "the output-weight norm ||beta||_2 (Zhang et al. 2024)");
  t.params.insert(t.params.end() - 1, shared.begin(), shared.end());
  return t;
}

}  // namespace

void register_elm_plugins(Registry& registry) {
  registry.add(
      {.name = "regressor/elm",
       .summary = "extreme learning machine (seeded random hidden layer, ridge output weights), optionally tuned",
       .reference = "Huang, Zhu & Siew 2006; Zhang et al., Micromachines 2024, 15(5), 609 (NSGA-II-tuned ELM)",
       .params = table(),
       .make = [](const ParamValues& p, const Registry& plugins) { return std::make_unique<ElmPlugin>(p, plugins); }});
}

}  // namespace driftlab
