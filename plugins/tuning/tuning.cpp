#include "plugins/tuning/tuning.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "framework/error.hpp"
#include "framework/number_text.hpp"
#include "framework/resources.hpp"
#include "plugins/common/holdout.hpp"

namespace driftlab::tuning {

ParamSpec search_range(std::string key, std::vector<double> def, std::string unit, std::string doc) {
  return param::reals(std::move(key), std::move(def), std::move(unit), std::move(doc))
      .must(
          "two values [low, high] with low <= high",
          [](const ParamValue& v) -> std::string {
            const auto& r = std::get<std::vector<double>>(v);
            if (r.size() != 2) return "needs exactly two values [low, high]";
            if (!(r[0] <= r[1])) return "low must not exceed high";
            return "";
          },
          std::vector<double>{2.0, 1.0});
}

std::vector<ParamSpec> params(const std::string& complexity_key, const std::string& complexity_doc) {
  return {
      param::boolean("tune", false,
                     "tune the hyperparameters with the nested optimizer on a blocked holdout, then fit all samples"),
      param::nested("optimizer", "optimizer", "optimizer/ga", "optimizer used when tune is true"),
      param::choice("tune_objectives", "auto", {"auto", "rmse", "rmse_and_" + complexity_key},
                    "rmse: held-out RMSE alone; rmse_and_" + complexity_key + ": also " + complexity_doc +
                        " (needs a multi-objective optimizer, e.g. optimizer/pagmo with nsga2); auto: both "
                        "when the optimizer takes two objectives"),
      param::real("holdout_fraction", 0.2, "1", "share of samples held out when tuning").greater_than(0).less_than(1),
      param::integer("holdout_blocks", 10, "1", "evenly spread contiguous held-out runs when tuning").at_least(1),
      max_samples_param(Rows::EvenSubsample)};
}

ParamSpec max_samples_param(Rows rows) {
  return param::integer("tune_max_samples", 20000, "1",
                        rows == Rows::EvenSubsample
                            ? "tuning uses an evenly spaced subsample of at most this many rows (0: all); the final "
                              "fit uses all"
                            : "tuning uses at most this many means of ceil(rows / tune_max_samples) consecutive rows "
                              "(0: every row); the final fit uses all")
      .at_least(0);
}

Settings settings(const ParamValues& p, const Optimizer& optimizer, std::string plugin, std::string complexity_name) {
  Settings s;
  s.plugin = std::move(plugin);
  s.complexity_name = std::move(complexity_name);
  const std::string& wanted = p.text("tune_objectives");
  const bool multi = optimizer.max_objectives() >= 2;
  s.objectives = wanted == "rmse" ? 1 : wanted == "auto" ? (multi ? 2 : 1) : 2;
  if (s.objectives == 2 && !multi) {
    throw ConfigError({"", 0, "tune_objectives"}, s.plugin + ": tune_objectives " + wanted +
                                                      " needs a multi-objective optimizer (e.g. "
                                                      "optimizer/pagmo with algorithm nsga2); " +
                                                      p.plugin("optimizer").name + " takes one");
  }
  s.holdout_fraction = p.real("holdout_fraction");
  s.holdout_blocks = static_cast<std::size_t>(p.integer("holdout_blocks"));
  s.max_samples = static_cast<std::size_t>(p.integer("tune_max_samples"));
  s.seed = static_cast<std::uint64_t>(p.integer("seed"));
  return s;
}

namespace {

// The rows the tuning sees (Settings::rows).
struct Thinned {
  Eigen::MatrixXd X;
  Eigen::VectorXd y;
  Eigen::Index stride = 1;
};

Thinned even_subsample(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, std::size_t max_samples) {
  std::vector<Eigen::Index> rows;
  const auto n = static_cast<std::size_t>(X.rows());
  const std::size_t keep = max_samples == 0 ? n : std::min(n, max_samples);
  for (std::size_t i = 0; i < keep; ++i) rows.push_back(static_cast<Eigen::Index>(i * n / keep));
  return {X(rows, Eigen::all), y(rows)};
}

Thinned run_means(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, std::size_t max_samples) {
  const auto cap = static_cast<Eigen::Index>(max_samples);
  const Eigen::Index stride = cap == 0 ? 1 : std::max<Eigen::Index>(1, (X.rows() + cap - 1) / cap);
  const Eigen::Index runs = X.rows() / stride;
  Thinned out{Eigen::MatrixXd(runs, X.cols()), Eigen::VectorXd(runs), stride};
  for (Eigen::Index r = 0; r < runs; ++r) {
    out.X.row(r) = X.middleRows(r * stride, stride).colwise().mean();
    out.y[r] = y.segment(r * stride, stride).mean();
  }
  return out;
}

}  // namespace

Split split(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const Settings& s) {
  const Thinned r = s.rows == Rows::RunMeans ? run_means(X, y, s.max_samples) : even_subsample(X, y, s.max_samples);
  const auto h = holdout::blocked_holdout(r.X.rows(), s.holdout_fraction, s.holdout_blocks, s.seed);
  return {r.X(h.train, Eigen::all), r.X(h.holdout, Eigen::all), r.y(h.train), r.y(h.holdout), r.stride};
}

Search search(Optimizer& optimizer, const std::vector<Bound>& bounds, const Settings& s, const Split& data,
              const FitAndScore& fit_and_score, RunContext& ctx) {
  const auto criteria = [&](const Eigen::VectorXd& v) -> Eigen::VectorXd {
    try {
      const Score score = fit_and_score(data, v);
      return Eigen::Vector2d(holdout::rmse(score.holdout_prediction, data.y_holdout), score.complexity);
    } catch (const std::invalid_argument&) {
      return Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
    }
  };
  if (const double evaluations = optimizer.evaluation_budget(); evaluations > 0.0) {  // before the work
    const double rows = static_cast<double>(data.X_train.rows() + data.X_holdout.rows());
    char what[200];
    std::snprintf(what, sizeof what, "%.3g objective evaluations x %.3g rows at %.2g s per row and evaluation",
                  evaluations, rows, kSecondsPerRowEvaluation);
    check_time_estimate(evaluations * rows * kSecondsPerRowEvaluation, {"", 0, "optimizer"}, s.plugin + ": " + what);
  }
  RunContext inner;
  inner.seed = ctx.seed;
  inner.threads = ctx.threads;
  inner.progress = ctx.progress;  // the optimizer's progress is the step's
  const auto objective = [&](const Eigen::VectorXd& v) -> Eigen::VectorXd {
    const Eigen::VectorXd c = criteria(v);
    return s.objectives == 1 ? Eigen::VectorXd(c.head(1)) : c;
  };
  OptimizationResult r = optimizer.minimize_objectives(objective, s.objectives, bounds, inner);
  if (!std::isfinite(r.best_value) || r.best_value >= std::numeric_limits<double>::max()) {
    throw DataError({"", 0, "features"}, s.plugin + ": no hyperparameters in the search ranges gave a usable fit");
  }
  return {std::move(r), std::move(inner.diagnostics)};
}

std::vector<std::string> search_notes(const OptimizationResult& r, const std::vector<Bound>& bounds) {
  std::vector<std::string> notes;
  for (std::size_t i = 0; i < bounds.size() && i < static_cast<std::size_t>(r.best.size()); ++i) {
    const Bound& b = bounds[i];
    if (b.integer && b.upper - b.lower <= 1.0) continue;  // a choice between two values, not a range
    const double v = r.best[static_cast<Eigen::Index>(i)], margin = kBoundFraction * (b.upper - b.lower);
    const bool low = v <= b.lower + margin, high = v >= b.upper - margin;
    if (!low && !high) continue;
    notes.push_back(b.name + " ended at its " + (low ? "lower" : "upper") + " search bound (" +
                    format_number(low ? b.lower : b.upper) + ", best " + format_number(v) +
                    "): the optimum may lie outside the range; widen it");
  }
  const auto& h = r.history;
  if (h.size() >= 3 && std::isfinite(h.front()) &&
      std::abs(h.back() - h.front()) <= kFlatFraction * std::abs(h.front()))
    notes.push_back("the best held-out error did not improve over " + std::to_string(h.size()) +
                    " generations (flat history): the result is no better than the first population's best");
  return notes;
}

Eigen::VectorXd run(Optimizer& optimizer, const std::vector<Bound>& bounds, const Settings& s, const Eigen::MatrixXd& X,
                    const Eigen::VectorXd& y, const FitAndScore& fit_and_score, RunContext& ctx) {
  const Split data = split(X, y, s);
  const Search found = search(optimizer, bounds, s, data, fit_and_score, ctx);
  const OptimizationResult& r = found.result;
  const auto named = [&](const Eigen::VectorXd& v) {
    nlohmann::json j = nlohmann::json::object();
    for (std::size_t i = 0; i < bounds.size(); ++i) j[bounds[i].name] = v[static_cast<Eigen::Index>(i)];
    return j;
  };
  std::vector<std::string> objectives{"holdout_rmse"};
  if (s.objectives == 2) objectives.push_back(s.complexity_name);
  nlohmann::json best = named(r.best);
  const Eigen::VectorXd values = r.best_values.size() > 0 ? r.best_values : Eigen::VectorXd::Constant(1, r.best_value);
  for (std::size_t k = 0; k < objectives.size(); ++k) best[objectives[k]] = values[static_cast<Eigen::Index>(k)];
  ctx.diagnostics["tuning"] = {{"objectives", objectives},
                               {"holdout",
                                {{"fraction", s.holdout_fraction},
                                 {"blocks", s.holdout_blocks},
                                 {"train_samples", data.X_train.rows()},
                                 {"holdout_samples", data.X_holdout.rows()}}},
                               {"best", best},
                               {"history", r.history},
                               {"evaluations", r.evaluations},
                               {"notes", search_notes(r, bounds)},
                               {"optimizer", found.optimizer_diagnostics}};
  return r.best;
}

}  // namespace driftlab::tuning
