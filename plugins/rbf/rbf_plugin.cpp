// regressor/rbf: adapter of plugins/rbf/rbf.hpp. With tune = true, fit() runs the shared tuning
// loop (plugins/tuning): the samples split by holdout::blocked_holdout, the nested optimizer
// minimizing the held-out RMSE over sigma, log10(regularization), (k-means only) the integer number
// of centres and (tune_linear_tail) the linear tail on or off; then it refits on all samples with
// the best values; ctx.diagnostics["tuning"] logs the start, the best and the per-generation
// history. Tuning sees at most tune_max_samples means of consecutive rows (see tuned()). Hyperparameters
// that make the kernel reject the fit score +infinity.
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "framework/error.hpp"
#include "framework/registry.hpp"
#include "plugins/common/holdout.hpp"
#include "plugins/rbf/rbf.hpp"
#include "plugins/tuning/tuning.hpp"

namespace driftlab {
namespace {

struct SearchRange {
  double low, high;
};

SearchRange range_of(const ParamValues& p, const std::string& key) {
  const auto& v = p.reals(key);
  return {v[0], v[1]};
}

class RbfPlugin final : public Regressor {
 public:
  RbfPlugin(const ParamValues& p, const Registry& registry)
      : config_{.centre_method =
                    p.text("centre_method") == "grid" ? rbf::CentreMethod::Grid : rbf::CentreMethod::KMeans,
                .centres = static_cast<std::size_t>(p.integer("centres")),
                .grid_points = static_cast<std::size_t>(p.integer("grid_points")),
                .sigma = p.real("sigma"),
                .solver = p.text("solver") == "lms" ? rbf::WeightSolver::Lms : rbf::WeightSolver::LeastSquares,
                .regularization = p.real("regularization"),
                .lms_rate = p.real("lms_rate"),
                .lms_epochs = static_cast<std::size_t>(p.integer("lms_epochs")),
                .kmeans_iterations = static_cast<std::size_t>(p.integer("kmeans_iterations")),
                .kmeans_sample = static_cast<std::size_t>(p.integer("kmeans_sample")),
                .seed = static_cast<std::uint64_t>(p.integer("seed")),
                .linear_tail = p.boolean("linear_tail")},
        sigma_range_(range_of(p, "tune_sigma")),
        centres_range_(range_of(p, "tune_centres")),
        log10_regularization_range_(range_of(p, "tune_log10_regularization")),
        tuning_{.plugin = "regressor/rbf",
                .holdout_fraction = p.real("holdout_fraction"),
                .holdout_blocks = static_cast<std::size_t>(p.integer("holdout_blocks")),
                .max_samples = static_cast<std::size_t>(p.integer("tune_max_samples")),
                .rows = tuning::Rows::RunMeans,
                .seed = static_cast<std::uint64_t>(p.integer("seed"))},
        tune_linear_tail_(p.boolean("tune_linear_tail")) {
    if (p.boolean("tune")) optimizer_ = registry.create_as<Optimizer>(p.plugin("optimizer"));
  }

  void fit(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, RunContext& ctx) override {
    network_.reset();
    try {
      rbf::Config config = optimizer_ ? tuned(X, y, ctx) : config_;
      config.threads = ctx.threads;
      threads_ = ctx.threads;
      auto result = rbf::fit(X, y, config);
      if (!result.lms_rmse.empty()) ctx.diagnostics["lms_rmse"] = result.lms_rmse;
      network_ = std::move(result.network);
    } catch (const std::invalid_argument& e) {
      throw DataError({"", 0, "features"}, std::string("regressor/rbf: ") + e.what());
    }
  }

  Eigen::VectorXd predict(const Eigen::MatrixXd& X) const override {
    if (!network_) throw NotFittedError("regressor/rbf: predict called before fit");
    try {
      return network_->predict(X, threads_);
    } catch (const std::invalid_argument& e) {
      throw DataError({"", 0, "features"}, std::string("regressor/rbf: ") + e.what());
    }
  }

 private:
  bool tunes_centres() const { return config_.centre_method == rbf::CentreMethod::KMeans; }

  rbf::Config decode(const Eigen::VectorXd& v) const {
    rbf::Config c = config_;
    c.sigma = v[0];
    c.regularization = std::pow(10.0, v[1]);
    if (tunes_centres()) c.centres = static_cast<std::size_t>(std::llround(v[2]));
    if (tune_linear_tail_) c.linear_tail = v[v.size() - 1] >= 0.5;
    return c;
  }

  nlohmann::json describe(const rbf::Config& c, double holdout_rmse) const {
    nlohmann::json out{{"sigma", c.sigma},
                       {"regularization", c.regularization},
                       {"linear_tail", c.linear_tail},
                       {"holdout_rmse", holdout_rmse}};
    if (tunes_centres()) {
      out["centres"] = c.centres;
    } else {
      out["grid_points"] = c.grid_points;
    }
    return out;
  }

  // Tuning sees the means of consecutive runs of rows (tuning::Rows::RunMeans, at most tune_max_samples of
  // them); the final fit uses every row.
  rbf::Config tuned(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, RunContext& ctx) const {
    const tuning::Split data = tuning::split(X, y, tuning_);
    const auto holdout_rmse = [&](const rbf::Config& c) {
      try {
        return holdout::rmse(rbf::fit(data.X_train, data.y_train, c).network.predict(data.X_holdout), data.y_holdout);
      } catch (const std::invalid_argument&) {
        return std::numeric_limits<double>::infinity();
      }
    };

    std::vector<Bound> bounds{
        {"sigma", sigma_range_.low, sigma_range_.high, false},
        {"log10_regularization", log10_regularization_range_.low, log10_regularization_range_.high, false}};
    if (tunes_centres()) {
      const double usable = static_cast<double>(
          std::min<std::size_t>(static_cast<std::size_t>(data.X_train.rows()), config_.kmeans_sample));
      bounds.push_back({"centres", centres_range_.low, std::min(centres_range_.high, usable), true});
    }
    if (tune_linear_tail_) bounds.push_back({"linear_tail", 0.0, 1.0, true});
    const auto fit_and_score = [&](const tuning::Split& d, const Eigen::VectorXd& v) {
      return tuning::Score{rbf::fit(d.X_train, d.y_train, decode(v)).network.predict(d.X_holdout)};
    };
    const tuning::Search found = tuning::search(*optimizer_, bounds, tuning_, data, fit_and_score, ctx);
    const OptimizationResult& result = found.result;
    const rbf::Config best = decode(result.best);
    ctx.diagnostics["tuning"] = {{"objective", "RMSE on a blocked holdout (unit of the target)"},
                                 {"holdout",
                                  {{"fraction", tuning_.holdout_fraction},
                                   {"blocks", tuning_.holdout_blocks},
                                   {"row_stride", data.row_stride},
                                   {"train_samples", data.X_train.rows()},
                                   {"holdout_samples", data.X_holdout.rows()}}},
                                 {"start", describe(config_, holdout_rmse(config_))},
                                 {"best", describe(best, result.best_value)},
                                 {"history", result.history},
                                 {"evaluations", result.evaluations},
                                 {"notes", tuning::search_notes(result, bounds)},
                                 {"optimizer", found.optimizer_diagnostics}};
    return best;
  }

  rbf::Config config_;
  SearchRange sigma_range_, centres_range_, log10_regularization_range_;
  tuning::Settings tuning_;  // one objective, the held-out RMSE
  bool tune_linear_tail_;
  std::unique_ptr<Optimizer> optimizer_;
  std::optional<rbf::Network> network_;
  unsigned threads_ = 1;
};

ParamSpec search_range(std::string key, std::vector<double> def, std::string doc) {
  return tuning::search_range(std::move(key), std::move(def), "1", std::move(doc));
}

}  // namespace

void register_rbf_plugins(Registry& registry) {
  registry.add(
      {.name = "regressor/rbf",
       .summary = "Gaussian RBF network (k-means or grid centres, ridge or LMS weights), optionally tuned",
       .reference = "Li et al. 2023 eqs. 6-9",
       .params =
           ParamTable{{param::choice("centre_method", "kmeans", {"kmeans", "grid"},
                                     "centres by seeded k-means (k-means++ start) or on a regular grid"),
                       param::integer("centres", 20, "1", "number of centres K (kmeans)").at_least(1),
                       param::integer("grid_points", 5, "1",
                                      "centres per standardized input axis (grid; K = grid_points^features)")
                           .at_least(1),
                       param::real("sigma", 1.0, "1", "Gaussian width in standardized input units (feature std = 1)")
                           .greater_than(0),
                       param::choice("solver", "least_squares", {"least_squares", "lms"},
                                     "output weights by ridge least squares (LDLT) or the paper's LMS rule (eq. 9)"),
                       param::real("regularization", 1e-8, "1", "ridge lambda on the mean-square normal equations")
                           .at_least(0),
                       param::real("lms_rate", 0.5, "1", "beta of the LMS rule (eq. 9)").greater_than(0).less_than(2),
                       param::integer("lms_epochs", 50, "1", "passes over the data for the LMS rule").at_least(1),
                       param::integer("kmeans_iterations", 50, "1", "cap on Lloyd iterations").at_least(1),
                       param::integer("kmeans_sample", 2000, "1", "rows used by k-means at most (seeded subsample)")
                           .at_least(1),
                       param::boolean("linear_tail", false,
                                      "add a linear term in the standardized inputs (y = sum w a + b + v.u): the "
                                      "Gaussians then model only the curvature of a nearly linear target"),
                       param::boolean("tune", false,
                                      "tune sigma, regularization and (kmeans) centres with the nested optimizer on "
                                      "the blocked-holdout RMSE, then fit all samples"),
                       param::nested("optimizer", "optimizer", "optimizer/ga",
                                     "optimizer used when tune is true; objective: held-out RMSE"),
                       param::boolean("tune_linear_tail", false,
                                      "when tuning, the optimizer also chooses whether the network has the linear "
                                      "tail (a 0/1 gene)"),
                       search_range("tune_sigma", {0.05, 3.0}, "search range for sigma").greater_than(0),
                       search_range("tune_centres", {4, 60}, "search range for centres (kmeans)").at_least(1),
                       search_range("tune_log10_regularization", {-10, -2}, "search range for log10(regularization)"),
                       param::real("holdout_fraction", 0.2, "1", "share of samples held out when tuning")
                           .greater_than(0)
                           .less_than(1),
                       param::integer("holdout_blocks", 10, "1", "evenly spread contiguous held-out runs when tuning")
                           .at_least(1),
                       tuning::max_samples_param(tuning::Rows::RunMeans),
                       param::seed()},
                      {{"centres <= kmeans_sample",
                        {"centres", "kmeans_sample"},
                        [](const ParamValues& p) { return p.integer("centres") <= p.integer("kmeans_sample"); }}}},
       .make = [](const ParamValues& p, const Registry& plugins) { return std::make_unique<RbfPlugin>(p, plugins); }});
}

}  // namespace driftlab
