// The discrepancy workflow's inner parts (discrepancy.hpp describes the method): one Workflow holds
// a record's blocks, the noise model that whitens them and the current model, and its members are
// defined by concern, one source each:
//   workflow.cpp         the loop: fit, score the candidates, add the best, refit; the views
//   noise_model.cpp      the noise terms (given, or estimated from what no candidate reaches) and the whitener
//   fitting.cpp          the model's design (bias polynomial, scale factor, effect bases), its
//                        generalised least-squares fit and the parameters' uncertainties
//   searches.cpp         each candidate's nonlinear parameters searched (grid + golden section)
//   structure_tests.cpp  structure no candidate explains (temperature, branch, dT/dt, time views)
// Internal to models/discrepancy: nothing outside includes it.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <algorithm>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "framework/time_series.hpp"
#include "models/discrepancy/blocks.hpp"
#include "models/discrepancy/discrepancy.hpp"
#include "models/discrepancy/views.hpp"

namespace driftlab::discrepancy::detail {

struct Term {
  std::size_t candidate;
  Eigen::VectorXd theta;
};

struct Design {
  Eigen::MatrixXd columns;                 // correction polynomial, then each non-moving term's basis
  Eigen::VectorXd offset;                  // prior
  std::vector<Eigen::Index> first_column;  // per term (moving terms: no columns)
  TimeSeries moved;                        // the record as non-moving effects see it (model temperature)
};

struct Fit {
  Eigen::VectorXd beta;
  double chi2 = 0.0;
  Eigen::VectorXd whitened_residual;
  Eigen::MatrixXd orthonormal;  // orthonormal basis of the whitened columns' span
};

struct State {
  std::vector<Term> terms;
  Design design;
  Fit fit;
};

// One searched coordinate: u = log(theta) (Log) or 1/theta (Period).
struct Axis {
  EffectParameter::Scale scale;
  double lo, hi;  // theta bounds after clamping
  double to_u(double theta) const { return scale == EffectParameter::Scale::Log ? std::log(theta) : 1.0 / theta; }
  double from_u(double u) const { return scale == EffectParameter::Scale::Log ? std::exp(u) : 1.0 / u; }
};

// Column norms of m, 1 where a column is zero.
Eigen::VectorXd column_norms(const Eigen::MatrixXd& m);

// Least squares on unit-norm columns with a rank-revealing QR; dependent columns get 0.
struct LeastSquares {
  Eigen::VectorXd beta;
  Eigen::MatrixXd orthonormal;  // orthonormal basis of the columns' span
};
LeastSquares least_squares(const Eigen::MatrixXd& a, const Eigen::VectorXd& b);

inline double rms(const Eigen::VectorXd& x) {
  return std::sqrt(x.squaredNorm() / static_cast<double>(std::max<Eigen::Index>(1, x.size())));
}

class Workflow {
 public:
  Workflow(const TimeSeries& record, const std::vector<Candidate>& candidates, const Options& options);
  Result run();

 private:
  // the loop (workflow.cpp)
  void validate_options() const;
  Views views(const State& s, const Eigen::VectorXd& full_model_rad_s) const;

  // noise model (noise_model.cpp)
  void set_noise(Result& result);
  error_model::NoiseTerms estimated_noise(const Eigen::VectorXd& residual) const;
  double noise_floor(const Design& d) const;

  // the model and its fit (fitting.cpp)
  const Effect& effect(const Term& t) const { return *candidates_[t.candidate].effect; }
  // The record as the model sees it: its temperature replaced by the model temperature of the
  // term that moves it, if any (at most one).
  TimeSeries moved_record(const TimeSeries& rec, const std::vector<Term>& terms) const;
  Design design(const TimeSeries& rec, const std::vector<Term>& terms) const;
  Eigen::MatrixXd whiten(const Eigen::MatrixXd& m) const { return whitener_.triangularView<Eigen::Lower>().solve(m); }
  Fit fit(const Design& d) const;
  State fitted(std::vector<Term> terms) const;
  double chi2_of(const std::vector<Term>& terms) const { return fit(design(block_record_, terms)).chi2; }
  Eigen::VectorXd block_model(const State& s) const { return s.design.offset + s.design.columns * s.fit.beta; }
  double gap(const State& s) const { return rms(y_ - block_model(s)); }
  Eigen::VectorXd full_model(const State& s) const;
  std::vector<double> bias_coefficients(const State& s) const;
  Eigen::Index parameter_count(const State& s) const;
  double chi2_scale(const State& s) const;
  // Covariance of [beta; theta of every term, in order] (Gauss-Newton, scaled by chi2_scale).
  Eigen::MatrixXd parameter_covariance(const State& s) const;
  std::vector<ReportedValue> describe(const State& s, std::size_t term, const Eigen::MatrixXd& covariance) const;
  // The model's own columns: the bias polynomial, and without a device prior on a record with a
  // true rate also a free scale-factor polynomial (w (T - T0)^i): without a device file there is no
  // scale factor to differ from, so its temperature dependence is part of the model.
  Eigen::Index model_columns() const { return (options_.bias_degree + 1) * (free_scale_factor_ ? 2 : 1); }

  // candidate searches (searches.cpp)
  std::optional<Axis> axis(const EffectParameter& p) const;
  std::vector<double> grid(const Axis& a) const;
  // Minimizes chi2(theta) over coordinate k on the grid, then golden-section between the neighbours.
  double search_coordinate(const std::function<double(const Eigen::VectorXd&)>& chi2, const Axis& a,
                           Eigen::VectorXd& theta, Eigen::Index k) const;
  // Golden-section refinement of coordinate k within one grid step around its value.
  void refine_coordinate(const std::function<double(const Eigen::VectorXd&)>& chi2, const Axis& a,
                         Eigen::VectorXd& theta, Eigen::Index k) const;
  std::vector<Score> score_all(const State& state) const;
  // chi2 of the state plus candidate c at theta. Effects that keep the model temperature only add
  // columns: their whitened columns are projected off the current span (no refit of the rest).
  double candidate_chi2(const State& state, std::size_t c, const Eigen::VectorXd& theta) const;
  // chi2 of the state with extra columns (block level): their whitened columns are projected off
  // the current span (no refit of the rest); `kept` counts the columns outside it.
  struct Added {
    double chi2;
    Eigen::Index kept = 0;
    Eigen::VectorXd component;  // the fitted extra component at the blocks (unwhitened), rad/s
  };
  Added added_columns_chi2(const State& state, const Eigen::MatrixXd& columns) const;
  State refined(std::vector<Term> terms) const;
  std::size_t candidate_index(const std::string& name) const;

  // structure no candidate explains (structure_tests.cpp)
  static constexpr int kViewBins = 8;
  // Indicator columns of kViewBins bins of `key`: equal counts (quantiles) or equal spans.
  static Eigen::MatrixXd bin_columns(const Eigen::VectorXd& key, bool equal_counts, std::vector<double>& edges);
  // What the generic views see of a record: its (model) temperature, x = T - T0, dT/dt and the
  // branch sgn(dT/dt) (0 while the chamber holds).
  struct Thermal {
    Eigen::VectorXd temp, rate;
    Eigen::ArrayXd x, branch;
  };
  Thermal thermal(const TimeSeries& rec) const;
  static Eigen::MatrixXd branch_columns(const Thermal& th);
  static Eigen::MatrixXd rate_columns(const Thermal& th);
  // 1 where the temperature is above level_c; at the blocks, the block mean of that at full rate
  // (a crossing inside a block gives the fraction of the block above the level).
  static Eigen::VectorXd step_column(const Eigen::VectorXd& temp_c, double level_c);
  Eigen::VectorXd block_step_column(const Eigen::VectorXd& full_temp_c, double level_c) const;
  Eigen::VectorXd full_model_temperature(const State& s) const;
  // The temperature view's second form: a step in bias where the temperature crosses one level,
  // searched over kStepLevels equal-count levels between the kStepTail and 1 - kStepTail quantiles
  // (q = 2: size and level). Bins cannot follow a sharp edge that falls between their own edges.
  static constexpr int kStepLevels = 64;
  static constexpr double kStepTail = 0.05;
  // Empty `step` when no level leaves a column outside the model's span.
  StructureTest temperature_step(const State& state, const Thermal& th, const Eigen::VectorXd& full_temp_c) const;
  Unexplained structure_tests(const State& state) const;

  const TimeSeries& record_;
  const std::vector<Candidate>& candidates_;
  const Options& options_;
  Blocks blocks_;
  double block_s_ = 0.0;
  bool evenly_sampled_ = true;
  bool free_scale_factor_ = false;
  EffectContext context_;
  Eigen::VectorXd y_;
  TimeSeries block_record_, smooth_record_;
  error_model::NoiseTerms noise_;
  Eigen::MatrixXd whitener_;
  double covariance_trace_ = 0.0;
};

}  // namespace driftlab::discrepancy::detail
