// Hyperparameter tuning shared by the regressor adapters (regressor/elm, regressor/svr,
// regressor/rbf) and by `driftlab calibrate`'s RBF network (models/calibration/fit.cpp): the rows the tuning sees, a
// blocked holdout (holdout::blocked_holdout), the one tuning loop (search(): the nested optimizer plugin minimizing one
// criterion, the held-out RMSE, or two, the held-out RMSE and a complexity measure the regressor names), and the common
// parameters. Adapter-level code: it knows the plugin interfaces, not files.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "framework/params.hpp"
#include "framework/plugin.hpp"

namespace driftlab::tuning {

// The parameters every tunable regressor shares: tune, optimizer, tune_objectives (auto |
// rmse | rmse_and_<complexity_key>), holdout_fraction, holdout_blocks, tune_max_samples.
std::vector<ParamSpec> params(const std::string& complexity_key, const std::string& complexity_doc);

// A `[low, high]` search range parameter.
ParamSpec search_range(std::string key, std::vector<double> def, std::string unit, std::string doc);

// How the rows are thinned before the split (see split()).
enum class Rows { EvenSubsample, RunMeans };

// The `tune_max_samples` parameter (rows the tuning sees at most, 0: all), documented for `rows`:
// the one declaration of it, in params() and in the adapters that thin by RunMeans.
ParamSpec max_samples_param(Rows rows);

struct Settings {
  std::string plugin;           // e.g. "regressor/elm", for messages
  std::string complexity_name;  // e.g. "output_weight_norm"
  std::size_t objectives = 1;   // 1 or 2, resolved from tune_objectives and the optimizer
  double holdout_fraction = 0.2;
  std::size_t holdout_blocks = 10;
  std::size_t max_samples = 0;  // rows the tuning sees at most; 0: all rows
  Rows rows = Rows::EvenSubsample;
  std::uint64_t seed = 1;
};

// Reads the shared parameters (rows: EvenSubsample, max_samples: tune_max_samples); resolves
// tune_objectives "auto" to 2 when the optimizer takes two or more objectives, else 1. Throws
// ConfigError when two are asked of a one-objective optimizer.
Settings settings(const ParamValues& p, const Optimizer& optimizer, std::string plugin, std::string complexity_name);

struct Split {
  Eigen::MatrixXd X_train, X_holdout;
  Eigen::VectorXd y_train, y_holdout;
  Eigen::Index row_stride = 1;  // RunMeans: rows averaged into one
};
// Rows: EvenSubsample takes an evenly spaced subsample of at most max_samples rows (first row kept;
// all when 0 or enough); RunMeans takes the means of consecutive runs of
// row_stride = ceil(rows / max_samples) rows (a trailing partial run dropped), so the cost does not
// grow with the record and a smooth target's held-out error is not drowned in sample noise. Then
// the blocked holdout of holdout::blocked_holdout (holdout_fraction, holdout_blocks, seed).
Split split(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const Settings& s);

// One candidate's fit: its predictions on the held-out rows and its complexity measure.
struct Score {
  Eigen::VectorXd holdout_prediction;
  double complexity = 0.0;
};
// fit_and_score(split, v) fits the candidate v on split's training rows; it may throw
// std::invalid_argument (a hyperparameter the kernel refuses), which scores +infinity.
using FitAndScore = std::function<Score(const Split&, const Eigen::VectorXd&)>;

// What the tuning loop found: the optimizer's result and its diagnostics.
struct Search {
  OptimizationResult result;
  nlohmann::json optimizer_diagnostics;
};

// The cost of one candidate's fit per row it sees, s: a lower bound (10x below the 1e-6 s per bin
// measured for the RBF network in `driftlab calibrate`), so the estimate refuses only searches
// that surely exceed the time budget.
inline constexpr double kSecondsPerRowEvaluation = 1e-7;

// The tuning loop: minimizes the held-out RMSE of fit_and_score on `data` (and, with two
// objectives, its complexity) over `bounds` with the optimizer, on a context with ctx's seed and
// threads (the optimizer's diagnostics are returned, ctx's are left alone). A candidate
// fit_and_score refuses (std::invalid_argument) scores +infinity. Throws DataError when no point
// gave a finite RMSE. Before the first fit, the optimizer's evaluation budget x the rows x
// kSecondsPerRowEvaluation is checked against the time budget (framework/resources.hpp): a
// ConfigError at "optimizer" when above it.
Search search(Optimizer& optimizer, const std::vector<Bound>& bounds, const Settings& s, const Split& data,
              const FitAndScore& fit_and_score, RunContext& ctx);

// What a tuning result does not settle, in words for the reports (empty when nothing):
//   - a parameter whose best value lies within kBoundFraction of its search range's width of a
//     bound: the optimum may lie outside the range, which should be widened (not said of an
//     integer parameter with two values, a choice such as linear_tail);
//   - a best-value history (one value per generation / iteration, at least 3) whose last value is
//     within kFlatFraction (relative) of its first: the search found nothing better than its start,
//     so the result is as good as a random draw from the range.
inline constexpr double kBoundFraction = 0.02;
inline constexpr double kFlatFraction = 1e-3;
std::vector<std::string> search_notes(const OptimizationResult& result, const std::vector<Bound>& bounds);

// split(), then search(); returns the chosen decision vector. Writes ctx.diagnostics["tuning"]
// (objectives, holdout sizes, best, history, evaluations, notes (search_notes), optimizer
// diagnostics).
Eigen::VectorXd run(Optimizer& optimizer, const std::vector<Bound>& bounds, const Settings& s, const Eigen::MatrixXd& X,
                    const Eigen::VectorXd& y, const FitAndScore& fit_and_score, RunContext& ctx);

}  // namespace driftlab::tuning
