#include "models/discrepancy/discrepancy.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <stdexcept>

#include "framework/error.hpp"
#include "framework/sampling.hpp"
#include "framework/golden_section.hpp"
#include "framework/signal.hpp"
#include "framework/units.hpp"
#include "models/allan/analysis.hpp"

namespace driftlab::discrepancy {
namespace {

constexpr double kTargetBlocks = 400.0;
constexpr double kRankThreshold = 1e-10;  // relative column norm below which a direction is dropped
constexpr double kDifferenceStep = 1e-4;  // relative step of the finite differences
constexpr int kMaxPeriodGrid = 4000;

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

Eigen::VectorXd column_norms(const Eigen::MatrixXd& m) {
  Eigen::VectorXd n = m.colwise().norm().transpose();
  for (double& v : n)
    if (!(v > 0.0)) v = 1.0;
  return n;
}

// Least squares on unit-norm columns with a rank-revealing QR; dependent columns get 0.
struct LeastSquares {
  Eigen::VectorXd beta;
  Eigen::MatrixXd orthonormal;
};
LeastSquares least_squares(const Eigen::MatrixXd& a, const Eigen::VectorXd& b) {
  if (a.cols() == 0) return {Eigen::VectorXd(0), Eigen::MatrixXd(a.rows(), 0)};
  const Eigen::VectorXd norms = column_norms(a);
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a * norms.cwiseInverse().asDiagonal());
  qr.setThreshold(kRankThreshold);
  LeastSquares ls;
  ls.beta = qr.solve(b).cwiseQuotient(norms);
  ls.orthonormal = qr.householderQ() * Eigen::MatrixXd::Identity(a.rows(), qr.rank());
  return ls;
}

double rms(const Eigen::VectorXd& x) {
  return std::sqrt(x.squaredNorm() / static_cast<double>(std::max<Eigen::Index>(1, x.size())));
}

class Workflow {
 public:
  Workflow(const TimeSeries& record, const std::vector<Candidate>& candidates, const Options& options)
      : record_(record), candidates_(candidates), options_(options) {
    validate_options();
    const Eigen::VectorXd& t = record.time();
    if (t.size() < 2) throw DataError({"", 0, "rate"}, "the record has fewer than 2 samples");
    record.channel(role::kRate);
    record.channel(role::kTemperature);
    const double duration = t[t.size() - 1] - t[0];
    block_s_ = options.block_s > 0.0 ? options.block_s : std::max(signal::median_step(t), duration / kTargetBlocks);
    blocks_ = make_blocks(t, block_s_);
    evenly_sampled_ = sampling::facts_of(t).evenly_sampled();
    free_scale_factor_ = !options.prior && record.has(role::kTrueRate) &&
                         record.channel(role::kTrueRate).values.cwiseAbs().maxCoeff() > 0.0;
    const Eigen::Index parameters = model_columns();
    if (blocks_.size() < 3 * parameters)
      throw DataError({"", 0, "rate"}, "the record has " + std::to_string(blocks_.size()) +
                                           " blocks; the model needs at least " + std::to_string(3 * parameters));
    context_ = {options.reference_temp_c, t[0], options.drive_frequency_at_reference_hz,
                options.drive_frequency_slope_hz_per_k};
    y_ = block_means(blocks_, record.channel(role::kRate).values);
    block_record_ = TimeSeries(blocks_.time_s);
    smooth_record_ = TimeSeries(t);
    for (const char* role : {role::kTemperature, role::kTrueRate, role::kDriveFrequency}) {
      if (!record.has(role)) continue;
      const Channel& c = record.channel(role);
      Eigen::VectorXd means = block_means(blocks_, c.values);
      if (std::string(role) == role::kTemperature)
        means += options.sensor_time_constant_s * signal::time_derivative(blocks_.time_s, means);
      block_record_.set_channel({c.role, c.unit, c.source, means});
      smooth_record_.set_channel(
          {c.role, c.unit, c.source, std::string(role) == role::kTrueRate ? c.values : interpolate(blocks_, means, t)});
    }
  }

  Result run() {
    Result result;
    result.block_s = block_s_;
    result.blocks = blocks_.size();
    set_noise(result);
    State state = fitted({});
    result.chi2_initial = state.fit.chi2;
    result.gap_initial_rad_s = gap(state);
    result.noise_floor_rad_s = noise_floor(state.design);
    result.bias_coefficients_initial = bias_coefficients(state);
    result.model_initial_rad_s = full_model(state);
    result.initial_views = views(state, result.model_initial_rad_s);

    while (static_cast<int>(result.steps.size()) < options_.max_effects) {
      auto scores = score_all(state);
      result.unexplained = structure_tests(state);
      const double best_view = result.unexplained.views.front().delta_bic;
      const bool candidate_passes =
          !scores.empty() && scores.front().applicable && scores.front().delta_bic > options_.significance;
      if (!candidate_passes || scores.front().delta_bic < best_view - options_.significance) {
        result.final_scores = std::move(scores);
        break;
      }
      Step step;
      step.effect = scores.front().effect;
      step.delta_chi2 = scores.front().delta_chi2;
      step.delta_bic = scores.front().delta_bic;
      step.chi2_scale = chi2_scale(state);
      step.gap_before_rad_s = gap(state);
      const std::size_t chosen = candidate_index(step.effect);
      std::vector<Term> terms = state.terms;
      terms.push_back({chosen, scores.front().theta});
      state = refined(std::move(terms));
      step.gap_after_rad_s = gap(state);
      step.scores = std::move(scores);
      result.steps.push_back(std::move(step));
    }

    result.unexplained = structure_tests(state);
    const Eigen::MatrixXd covariance = parameter_covariance(state);
    for (std::size_t i = 0; i < result.steps.size(); ++i) result.steps[i].parameters = describe(state, i, covariance);
    result.chi2_final = state.fit.chi2;
    result.gap_final_rad_s = gap(state);
    result.bias_coefficients_final = bias_coefficients(state);
    result.model_final_rad_s = full_model(state);
    result.final_views = views(state, result.model_final_rad_s);
    return result;
  }

 private:
  void validate_options() const {
    std::vector<Diagnostic> problems;
    if (options_.bias_degree < 0 || options_.bias_degree > 6)
      problems.push_back({{"", 0, "bias_degree"}, "must be in [0, 6]"});
    if (options_.block_s < 0.0) problems.push_back({{"", 0, "block_s"}, "must be >= 0 (0 = automatic)"});
    if (!(options_.significance >= 0.0)) problems.push_back({{"", 0, "significance"}, "must be >= 0"});
    if (options_.max_effects < 0) problems.push_back({{"", 0, "max_effects"}, "must be >= 0"});
    if (options_.grid_points_per_decade < 1) problems.push_back({{"", 0, "grid_points_per_decade"}, "must be >= 1"});
    if (options_.golden_iterations < 0) problems.push_back({{"", 0, "golden_iterations"}, "must be >= 0"});
    if (!(options_.sensor_time_constant_s >= 0.0))
      problems.push_back({{"", 0, "sensor_time_constant_s"}, "must be >= 0"});
    for (const auto& c : candidates_)
      if (!c.effect) problems.push_back({{"", 0, c.name}, "candidate without an effect"});
    if (!problems.empty()) throw ConfigError(std::move(problems));
  }

  // ---- noise model ----------------------------------------------------------------------------
  void set_noise(Result& result) {
    if (options_.noise) {
      noise_ = *options_.noise;
    } else {
      if (!evenly_sampled_)
        throw DataError({"", 0, "rate"},
                        "the record has gaps: give the device's noise terms (--device) to test effects");
      // The noise terms come from the part of the residual that no candidate reaches: the model
      // plus every applicable candidate at its best parameters (ordinary least squares on the
      // blocks), so that a lag, a hysteresis, a dT/dt term, a warm-up or a periodic term is not
      // counted as noise (it would inflate K and B and hide itself).
      whitener_ = Eigen::MatrixXd::Identity(blocks_.size(), blocks_.size());
      const State ordinary = fitted({});
      std::vector<Term> reach;
      bool mover = false;
      for (const auto& score : score_all(ordinary)) {
        if (!score.applicable || !(score.delta_chi2 > 0.0)) continue;
        const std::size_t c = candidate_index(score.effect);
        if (candidates_[c].effect->moves_model_temperature()) {
          if (mover) continue;
          mover = true;
        }
        reach.push_back({c, score.theta});
      }
      const State reached = fitted(std::move(reach));
      Eigen::VectorXd residual = record_.channel(role::kRate).values - full_model(reached);
      // ... and what the views that live in temperature take (a step at one temperature, a
      // branch offset, dT/dt terms); the views in time are left out: they would take the random
      // walk itself.
      const Thermal block = thermal(reached.design.moved);
      const Thermal full = thermal(moved_record(smooth_record_, reached.terms));
      const auto step = temperature_step(reached, block, full.temp).step;
      const Eigen::VectorXd full_step =
          step ? step_column(full.temp, step->level_c) : Eigen::VectorXd(Eigen::VectorXd::Zero(full.temp.size()));
      const auto columns = [&](const Thermal& th, const Eigen::VectorXd& step_values) {
        Eigen::MatrixXd m(th.temp.size(), 6);
        m << step_values, branch_columns(th), rate_columns(th);
        return m;
      };
      const Eigen::MatrixXd block_columns = columns(block, block_means(blocks_, full_step));
      residual -= columns(full, full_step) * least_squares(block_columns, y_ - block_model(reached)).beta;
      noise_ = estimated_noise(residual);
      result.noise_estimated = true;
    }
    result.noise = noise_;
    Eigen::MatrixXd c = noise_covariance(blocks_, noise_);
    const double jitter = 1e-12 * c.diagonal().mean();
    if (!(jitter > 0.0))
      throw DataError({"", 0, "noise"}, "the noise terms are all zero: the test needs a noise model");
    c.diagonal().array() += jitter;
    Eigen::LLT<Eigen::MatrixXd> llt(c);
    if (llt.info() != Eigen::Success)
      throw DataError({"", 0, "noise"}, "the noise covariance is not positive definite");
    whitener_ = llt.matrixL();
    covariance_trace_ = c.trace();
  }

  error_model::NoiseTerms estimated_noise(const Eigen::VectorXd& residual) const {
    const double tau0 = blocks_.sample_interval_s;
    const auto analysis = allan::analyze_rate(residual, 1.0 / tau0);
    if (!analysis.fit) throw DataError({"", 0, "rate"}, "the residual's Allan curve has too few points for noise terms");
    const auto& fit = *analysis.fit;
    error_model::NoiseTerms n;
    n.arw_rad_sqrt_s = fit[allan::Term::N].value;
    n.bias_instability_rad_s = fit[allan::Term::B].value;
    n.rate_random_walk_rad_s_sqrt_s = fit[allan::Term::K].value;
    n.flicker_tau_min_s = std::max(n.flicker_tau_min_s, tau0);
    n.flicker_tau_max_s = std::max(n.flicker_tau_max_s, blocks_.duration_s());
    return n;
  }

  // ---- model ----------------------------------------------------------------------------------
  const Effect& effect(const Term& t) const { return *candidates_[t.candidate].effect; }

  // The record as the model sees it: its temperature replaced by the model temperature of the
  // term that moves it, if any (at most one).
  TimeSeries moved_record(const TimeSeries& rec, const std::vector<Term>& terms) const {
    TimeSeries moved = rec;
    for (const auto& t : terms) {
      if (!effect(t).moves_model_temperature()) continue;
      moved.set_channel(
          {role::kTemperature, "degC", "model temperature", effect(t).evaluate(rec, context_, t.theta).model_temperature_c});
    }
    return moved;
  }

  Design design(const TimeSeries& rec, const std::vector<Term>& terms) const {
    Design d;
    d.moved = moved_record(rec, terms);
    const Eigen::VectorXd& temp = d.moved.channel(role::kTemperature).values;
    const Eigen::Index n = rec.size();
    std::vector<Eigen::MatrixXd> bases;
    Eigen::Index columns = model_columns();
    for (const auto& t : terms) {
      d.first_column.push_back(columns);
      if (effect(t).moves_model_temperature()) continue;
      bases.push_back(effect(t).evaluate(d.moved, context_, t.theta).basis);
      columns += bases.back().cols();
    }
    d.columns.resize(n, columns);
    const Eigen::ArrayXd x = temp.array() - options_.reference_temp_c;
    Eigen::ArrayXd power = Eigen::ArrayXd::Ones(n);
    const Eigen::VectorXd w = rec.has(role::kTrueRate) ? rec.channel(role::kTrueRate).values : Eigen::VectorXd::Zero(n);
    const Eigen::Index degree = options_.bias_degree;
    for (Eigen::Index i = 0; i <= degree; ++i, power *= x) {
      d.columns.col(i) = power.matrix();
      if (free_scale_factor_) d.columns.col(degree + 1 + i) = (power * w.array()).matrix();
    }
    Eigen::Index at = model_columns();
    for (const auto& b : bases) {
      d.columns.middleCols(at, b.cols()) = b;
      at += b.cols();
    }
    d.offset = options_.prior ? options_.prior(rec.time(), temp, w) : w;
    return d;
  }

  Eigen::MatrixXd whiten(const Eigen::MatrixXd& m) const { return whitener_.triangularView<Eigen::Lower>().solve(m); }

  Fit fit(const Design& d) const {
    const Eigen::VectorXd z = whiten(y_ - d.offset);
    const Eigen::MatrixXd w = whiten(d.columns);
    auto ls = least_squares(w, z);
    Fit f;
    f.beta = std::move(ls.beta);
    f.whitened_residual = z - w * f.beta;
    f.chi2 = f.whitened_residual.squaredNorm();
    f.orthonormal = std::move(ls.orthonormal);
    return f;
  }

  State fitted(std::vector<Term> terms) const {
    State s{std::move(terms), {}, {}};
    s.design = design(block_record_, s.terms);
    s.fit = fit(s.design);
    return s;
  }

  double chi2_of(const std::vector<Term>& terms) const { return fit(design(block_record_, terms)).chi2; }

  Eigen::VectorXd block_model(const State& s) const { return s.design.offset + s.design.columns * s.fit.beta; }
  double gap(const State& s) const { return rms(y_ - block_model(s)); }

  Eigen::VectorXd full_model(const State& s) const {
    const Design d = design(smooth_record_, s.terms);
    return d.offset + d.columns * s.fit.beta;
  }

  std::vector<double> bias_coefficients(const State& s) const {
    return {s.fit.beta.data(), s.fit.beta.data() + options_.bias_degree + 1};
  }

  Eigen::Index parameter_count(const State& s) const {
    Eigen::Index p = s.design.columns.cols();
    for (const auto& t : s.terms) p += t.theta.size();
    return p;
  }

  double chi2_scale(const State& s) const {
    const double dof = static_cast<double>(blocks_.size() - parameter_count(s));
    return dof > 0.0 ? std::max(1.0, s.fit.chi2 / dof) : 1.0;
  }

  double noise_floor(const Design& d) const {
    const Eigen::MatrixXd w = whiten(d.columns);
    const Eigen::MatrixXd information = w.transpose() * w;
    const Eigen::MatrixXd gram = d.columns.transpose() * d.columns;
    const double leaked = information.completeOrthogonalDecomposition().pseudoInverse().cwiseProduct(gram).sum();
    return std::sqrt(std::max(0.0, covariance_trace_ - leaked) / static_cast<double>(blocks_.size()));
  }

  // ---- searches -------------------------------------------------------------------------------
  std::optional<Axis> axis(const EffectParameter& p) const {
    Axis a{p.scale, p.lower, p.upper};
    if (p.scale == EffectParameter::Scale::Period) {
      a.lo = std::max(a.lo, 4.0 * blocks_.median_spacing_s());
      a.hi = std::min(a.hi, 0.5 * blocks_.duration_s());
    }
    if (!(a.lo > 0.0) || !(a.lo < a.hi)) return std::nullopt;
    return a;
  }

  std::vector<double> grid(const Axis& a) const {
    const double u0 = a.to_u(a.lo), u1 = a.to_u(a.hi);
    int count;
    if (a.scale == EffectParameter::Scale::Log) {
      count = std::max(3, static_cast<int>(std::ceil(std::log10(a.hi / a.lo) * options_.grid_points_per_decade)) + 1);
    } else {
      count = std::clamp(static_cast<int>(std::ceil(std::abs(u1 - u0) * 4.0 * blocks_.duration_s())) + 1, 3,
                         kMaxPeriodGrid);
    }
    std::vector<double> u(static_cast<std::size_t>(count));
    for (int i = 0; i < count; ++i) u[static_cast<std::size_t>(i)] = u0 + (u1 - u0) * i / (count - 1);
    return u;
  }

  // Minimizes chi2(theta) over coordinate k on the grid, then golden-section between the neighbours.
  double search_coordinate(const std::function<double(const Eigen::VectorXd&)>& chi2, const Axis& a,
                           Eigen::VectorXd& theta, Eigen::Index k) const {
    const auto u = grid(a);
    auto at = [&](double value) {
      Eigen::VectorXd th = theta;
      th[k] = a.from_u(value);
      return chi2(th);
    };
    std::size_t best = 0;
    double best_value = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < u.size(); ++i) {
      const double v = at(u[i]);
      if (v < best_value) best_value = v, best = i;
    }
    const double lo = u[best == 0 ? 0 : best - 1], hi = u[std::min(best + 1, u.size() - 1)];
    const auto refined = golden_section_minimize(at, std::min(lo, hi), std::max(lo, hi), options_.golden_iterations);
    theta[k] = a.from_u(refined.value < best_value ? refined.x : u[best]);
    return std::min(refined.value, best_value);
  }

  // Golden-section refinement of coordinate k within one grid step around its value.
  void refine_coordinate(const std::function<double(const Eigen::VectorXd&)>& chi2, const Axis& a,
                         Eigen::VectorXd& theta, Eigen::Index k) const {
    const auto u = grid(a);
    const double step = std::abs(u[1] - u[0]);
    const double center = a.to_u(theta[k]);
    const double lo = std::max(std::min(u.front(), u.back()), center - step);
    const double hi = std::min(std::max(u.front(), u.back()), center + step);
    auto at = [&](double value) {
      Eigen::VectorXd th = theta;
      th[k] = a.from_u(value);
      return chi2(th);
    };
    const double current = at(center);
    if (const auto refined = golden_section_minimize(at, lo, hi, options_.golden_iterations); refined.value < current)
      theta[k] = a.from_u(refined.x);
  }

  std::vector<Score> score_all(const State& state) const {
    std::vector<Score> scores;
    const bool has_mover = std::any_of(state.terms.begin(), state.terms.end(),
                                       [&](const Term& t) { return effect(t).moves_model_temperature(); });
    const double scale = chi2_scale(state);
    const double log_blocks = std::log(static_cast<double>(blocks_.size()));
    for (std::size_t c = 0; c < candidates_.size(); ++c) {
      Score s;
      s.effect = candidates_[c].name;
      if (std::any_of(state.terms.begin(), state.terms.end(), [&](const Term& t) { return t.candidate == c; }))
        continue;
      const Effect& e = *candidates_[c].effect;
      for (const auto& role : e.required_roles())
        if (!block_record_.has(role)) s.note = "the record has no " + role + " channel";
      if (s.note.empty() && e.moves_model_temperature() && has_mover)
        s.note = "the model temperature is already moved by another effect";
      const auto params = e.nonlinear_parameters();
      std::vector<Axis> axes;
      for (const auto& p : params) {
        if (auto a = axis(p))
          axes.push_back(*a);
        else if (s.note.empty())
          s.note = "the record does not resolve " + p.name + " in its search interval";
      }
      if (!s.note.empty()) {
        s.applicable = false;
        scores.push_back(std::move(s));
        continue;
      }
      const std::function<double(const Eigen::VectorXd&)> chi2 = [&](const Eigen::VectorXd& theta) {
        return candidate_chi2(state, c, theta);
      };
      s.theta.resize(static_cast<Eigen::Index>(axes.size()));
      for (std::size_t k = 0; k < axes.size(); ++k)
        s.theta[static_cast<Eigen::Index>(k)] = std::sqrt(axes[k].lo * axes[k].hi);
      double best = s.theta.size() == 0 ? chi2(s.theta) : 0.0;
      for (std::size_t k = 0; k < axes.size(); ++k)
        best = search_coordinate(chi2, axes[k], s.theta, static_cast<Eigen::Index>(k));
      s.added_parameters = static_cast<int>(params.size() + e.coefficient_names().size());
      s.delta_chi2 = state.fit.chi2 - best;
      s.delta_bic = s.delta_chi2 / scale - s.added_parameters * log_blocks;
      scores.push_back(std::move(s));
    }
    std::stable_sort(scores.begin(), scores.end(), [](const Score& a, const Score& b) {
      if (a.applicable != b.applicable) return a.applicable;
      return a.delta_bic > b.delta_bic;
    });
    return scores;
  }

  // chi2 of the state plus candidate c at theta. Effects that keep the model temperature only add
  // columns: their whitened columns are projected off the current span (no refit of the rest).
  double candidate_chi2(const State& state, std::size_t c, const Eigen::VectorXd& theta) const {
    const Effect& e = *candidates_[c].effect;
    if (e.moves_model_temperature()) {
      std::vector<Term> terms = state.terms;
      terms.push_back({c, theta});
      return chi2_of(terms);
    }
    return added_columns_chi2(state, e.evaluate(state.design.moved, context_, theta).basis).chi2;
  }

  // chi2 of the state with extra columns (block level): their whitened columns are projected off
  // the current span (no refit of the rest); `kept` counts the columns outside it.
  struct Added {
    double chi2;
    Eigen::Index kept = 0;
    Eigen::VectorXd component;  // the fitted extra component at the blocks (unwhitened), rad/s
  };
  Added added_columns_chi2(const State& state, const Eigen::MatrixXd& columns) const {
    const Eigen::MatrixXd basis = whiten(columns);
    if (basis.cols() == 0) return {state.fit.chi2};
    const Eigen::MatrixXd& q = state.fit.orthonormal;
    const Eigen::MatrixXd perpendicular = basis - q * (q.transpose() * basis);
    Eigen::MatrixXd kept(basis.rows(), 0);
    for (Eigen::Index j = 0; j < basis.cols(); ++j) {
      if (perpendicular.col(j).norm() <= 1e-6 * basis.col(j).norm()) continue;
      kept.conservativeResize(Eigen::NoChange, kept.cols() + 1);
      kept.col(kept.cols() - 1) = perpendicular.col(j);
    }
    if (kept.cols() == 0) return {state.fit.chi2};
    const auto ls = least_squares(kept, state.fit.whitened_residual);
    const Eigen::VectorXd explained = ls.orthonormal * (ls.orthonormal.transpose() * state.fit.whitened_residual);
    return {state.fit.chi2 - explained.squaredNorm(), ls.orthonormal.cols(),
            whitener_.triangularView<Eigen::Lower>() * explained};
  }

  // ---- structure no candidate explains -----------------------------------------------------------
  static constexpr int kViewBins = 8;

  // Indicator columns of kViewBins bins of `key`: equal counts (quantiles) or equal spans.
  static Eigen::MatrixXd bin_columns(const Eigen::VectorXd& key, bool equal_counts, std::vector<double>& edges) {
    const Eigen::Index n = key.size();
    std::vector<double> sorted(key.data(), key.data() + n);
    std::sort(sorted.begin(), sorted.end());
    edges.clear();
    for (int b = 0; b <= kViewBins; ++b) {
      const double f = static_cast<double>(b) / kViewBins;
      edges.push_back(equal_counts ? sorted[std::min<std::size_t>(static_cast<std::size_t>(f * static_cast<double>(n)),
                                                                  static_cast<std::size_t>(n - 1))]
                                   : sorted.front() + f * (sorted.back() - sorted.front()));
    }
    Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n, kViewBins);
    for (Eigen::Index k = 0; k < n; ++k) {
      const auto b = std::upper_bound(edges.begin() + 1, edges.end() - 1, key[k]) - (edges.begin() + 1);
      m(k, b) = 1.0;
    }
    return m;
  }

  // What the generic views see of a record: its (model) temperature, x = T - T0, dT/dt and the
  // branch sgn(dT/dt) (0 while the chamber holds).
  struct Thermal {
    Eigen::VectorXd temp, rate;
    Eigen::ArrayXd x, branch;
  };
  Thermal thermal(const TimeSeries& rec) const {
    Thermal th;
    th.temp = rec.channel(role::kTemperature).values;
    th.x = th.temp.array() - options_.reference_temp_c;
    th.rate = signal::time_derivative(rec.time(), th.temp);
    const double soak = 1e-3 * th.rate.cwiseAbs().maxCoeff();  // below this the chamber holds
    th.branch = th.rate.array().unaryExpr([&](double r) { return r > soak ? 1.0 : r < -soak ? -1.0 : 0.0; });
    return th;
  }
  static Eigen::MatrixXd branch_columns(const Thermal& th) {
    Eigen::MatrixXd m(th.temp.size(), 2);
    m.col(0) = th.branch.matrix();
    m.col(1) = (th.branch * th.x).matrix();
    return m;
  }
  static Eigen::MatrixXd rate_columns(const Thermal& th) {
    Eigen::MatrixXd m(th.temp.size(), 3);
    m.col(0) = th.rate;
    m.col(1) = (th.rate.array() * th.x).matrix();
    m.col(2) = (th.rate.array() * th.x.square()).matrix();
    return m;
  }
  // 1 where the temperature is above level_c; at the blocks, the block mean of that at full rate
  // (a crossing inside a block gives the fraction of the block above the level).
  static Eigen::VectorXd step_column(const Eigen::VectorXd& temp_c, double level_c) {
    return (temp_c.array() > level_c).cast<double>().matrix();
  }
  Eigen::VectorXd block_step_column(const Eigen::VectorXd& full_temp_c, double level_c) const {
    return block_means(blocks_, step_column(full_temp_c, level_c));
  }
  Eigen::VectorXd full_model_temperature(const State& s) const {
    return moved_record(smooth_record_, s.terms).channel(role::kTemperature).values;
  }

  // The temperature view's second form: a step in bias where the temperature crosses one level,
  // searched over kStepLevels equal-count levels between the kStepTail and 1 - kStepTail quantiles
  // (q = 2: size and level). Bins cannot follow a sharp edge that falls between their own edges.
  static constexpr int kStepLevels = 64;
  static constexpr double kStepTail = 0.05;
  // Empty `step` when no level leaves a column outside the model's span.
  StructureTest temperature_step(const State& state, const Thermal& th, const Eigen::VectorXd& full_temp_c) const {
    std::vector<double> sorted(th.temp.data(), th.temp.data() + th.temp.size());
    std::sort(sorted.begin(), sorted.end());
    std::vector<double> levels;
    for (int l = 0; l < kStepLevels; ++l) {
      const double f = kStepTail + (1.0 - 2.0 * kStepTail) * l / (kStepLevels - 1);
      levels.push_back(sorted[static_cast<std::size_t>(f * static_cast<double>(sorted.size() - 1))]);
    }
    const auto chi2_at = [&](double level) { return added_columns_chi2(state, block_step_column(full_temp_c, level)); };
    std::size_t best = 0;
    double best_chi2 = std::numeric_limits<double>::infinity();
    for (std::size_t l = 0; l < levels.size(); ++l) {
      const auto a = chi2_at(levels[l]);
      if (a.kept > 0 && a.chi2 < best_chi2) best_chi2 = a.chi2, best = l;
    }
    StructureTest view{"temperature", 0.0, -std::numeric_limits<double>::infinity(), 0, 0.0, "", std::nullopt};
    if (!std::isfinite(best_chi2)) return view;
    // The level between the neighbouring grid levels (golden section, as for the candidates).
    double level = levels[best];
    const double lo = levels[best == 0 ? 0 : best - 1], hi = levels[std::min(best + 1, levels.size() - 1)];
    if (const auto refined = golden_section_minimize([&](double l) { return chi2_at(l).chi2; }, lo, hi,
                                                     options_.golden_iterations);
        refined.value < best_chi2)
      level = refined.x;
    const auto a = chi2_at(level);
    view.parameters = static_cast<int>(a.kept) + 1;
    view.delta_chi2 = state.fit.chi2 - a.chi2;
    view.delta_bic = view.delta_chi2 / chi2_scale(state) - view.parameters * std::log(static_cast<double>(blocks_.size()));
    view.size_rad_s = rms(a.component);
    // The step's size from the joint fit with the model (the view's component is only the part
    // the model cannot take: a polynomial absorbs much of a step).
    Design joint = state.design;
    joint.columns.conservativeResize(Eigen::NoChange, joint.columns.cols() + 1);
    joint.columns.rightCols(1) = block_step_column(full_temp_c, level);
    const Fit f = fit(joint);
    view.step = StructureTest::TemperatureStep{level, f.beta[f.beta.size() - 1]};
    char text[160];
    std::snprintf(text, sizeof text, "a step of %+.3g deg/h where the temperature crosses %.3g degC",
                  view.step->size_rad_s * kDphPerRadPerSec, level);
    view.where = text;
    return view;
  }

  Unexplained structure_tests(const State& state) const {
    const TimeSeries& rec = state.design.moved;
    const Thermal th = thermal(rec);
    const Eigen::VectorXd& temp = th.temp;
    constexpr double kDph = kDphPerRadPerSec;  // the texts are in deg/h
    const double scale = chi2_scale(state);
    const double log_blocks = std::log(static_cast<double>(blocks_.size()));
    Unexplained u;
    auto add = [&](const std::string& view, const Eigen::MatrixXd& columns,
                   const std::function<std::string(const Eigen::VectorXd&)>& where) {
      const auto a = added_columns_chi2(state, columns);
      StructureTest t{view, state.fit.chi2 - a.chi2, -std::numeric_limits<double>::infinity(),
                      static_cast<int>(a.kept), 0.0, ""};
      if (a.kept > 0) {
        t.delta_bic = t.delta_chi2 / scale - static_cast<double>(a.kept) * log_blocks;
        t.size_rad_s = rms(a.component);
        t.where = where(a.component);
      }
      u.views.push_back(std::move(t));
    };
    auto largest_bin = [&](const Eigen::VectorXd& key, const std::vector<double>& edges, const Eigen::VectorXd& c,
                           const std::string& unit) {
      int best = 0;
      double best_value = 0.0;
      for (int b = 0; b < kViewBins; ++b) {
        double sum = 0.0;
        int count = 0;
        for (Eigen::Index k = 0; k < key.size(); ++k)
          if (key[k] >= edges[b] && (key[k] < edges[b + 1] || b == kViewBins - 1)) sum += c[k], ++count;
        const double mean = count ? sum / count : 0.0;
        if (std::abs(mean) > std::abs(best_value)) best_value = mean, best = b;
      }
      char text[160];
      std::snprintf(text, sizeof text, "largest at %.4g .. %.4g %s (%+.3g deg/h)", edges[best], edges[best + 1],
                    unit.c_str(), best_value * kDph);
      return std::string(text);
    };
    std::vector<double> temp_edges, time_edges;
    const Eigen::MatrixXd temp_bins = bin_columns(temp, true, temp_edges);
    add("temperature", temp_bins, [&](const Eigen::VectorXd& c) { return largest_bin(temp, temp_edges, c, "degC"); });
    if (auto step = temperature_step(state, th, full_model_temperature(state)); step.delta_bic > u.views.back().delta_bic)
      u.views.back() = std::move(step);
    add("heating_vs_cooling", branch_columns(th), [&](const Eigen::VectorXd& c) {
      double heating = 0.0, cooling = 0.0;
      int nh = 0, nc = 0;
      for (Eigen::Index k = 0; k < c.size(); ++k) {
        if (th.branch[k] > 0) heating += c[k], ++nh;
        if (th.branch[k] < 0) cooling += c[k], ++nc;
      }
      char text[160];
      std::snprintf(text, sizeof text, "heating %+.3g deg/h, cooling %+.3g deg/h on average",
                    nh ? heating / nh * kDph : 0.0, nc ? cooling / nc * kDph : 0.0);
      return std::string(text);
    });
    add("temperature_rate", rate_columns(th), [&](const Eigen::VectorXd& c) {
      const Eigen::Index k = [&] { Eigen::Index i; c.cwiseAbs().maxCoeff(&i); return i; }();
      char text[160];
      std::snprintf(text, sizeof text, "follows dT/dt with a temperature-dependent factor; largest %+.3g deg/h at %.3g degC, "
                    "%.3g degC/min", c[k] * kDph, temp[k], th.rate[k] * 60.0);
      return std::string(text);
    });
    add("time", bin_columns(rec.time(), false, time_edges),
        [&](const Eigen::VectorXd& c) { return largest_bin(rec.time(), time_edges, c, "s"); });
    std::stable_sort(u.views.begin(), u.views.end(),
                     [](const StructureTest& a, const StructureTest& b) { return a.delta_bic > b.delta_bic; });
    u.found = u.views.front().delta_bic > options_.significance;
    return u;
  }

  State refined(std::vector<Term> terms) const {
    for (std::size_t i = 0; i < terms.size(); ++i) {
      const auto params = effect(terms[i]).nonlinear_parameters();
      for (std::size_t k = 0; k < params.size(); ++k) {
        const auto a = axis(params[k]);
        if (!a) continue;
        const std::function<double(const Eigen::VectorXd&)> chi2 = [&](const Eigen::VectorXd& theta) {
          auto trial = terms;
          trial[i].theta = theta;
          return chi2_of(trial);
        };
        refine_coordinate(chi2, *a, terms[i].theta, static_cast<Eigen::Index>(k));
      }
    }
    return fitted(std::move(terms));
  }

  std::size_t candidate_index(const std::string& name) const {
    for (std::size_t c = 0; c < candidates_.size(); ++c)
      if (candidates_[c].name == name) return c;
    throw std::logic_error("unknown candidate " + name);
  }

  // ---- uncertainties --------------------------------------------------------------------------
  // Covariance of [beta; theta of every term, in order] (Gauss-Newton, scaled by chi2_scale).
  Eigen::MatrixXd parameter_covariance(const State& s) const {
    const Eigen::Index linear = s.design.columns.cols();
    Eigen::MatrixXd j(blocks_.size(), parameter_count(s));
    j.leftCols(linear) = whiten(s.design.columns);
    Eigen::Index col = linear;
    for (std::size_t i = 0; i < s.terms.size(); ++i) {
      for (Eigen::Index k = 0; k < s.terms[i].theta.size(); ++k, ++col) {
        const double h = kDifferenceStep * s.terms[i].theta[k];
        auto model_at = [&](double delta) {
          auto terms = s.terms;
          terms[i].theta[k] += delta;
          const Design d = design(block_record_, terms);
          return Eigen::VectorXd(d.offset + d.columns * s.fit.beta);
        };
        j.col(col) = whiten((model_at(h) - model_at(-h)) / (2.0 * h));
      }
    }
    const Eigen::VectorXd norms = column_norms(j);
    const Eigen::MatrixXd jn = j * norms.cwiseInverse().asDiagonal();
    const Eigen::MatrixXd inverse = (jn.transpose() * jn).completeOrthogonalDecomposition().pseudoInverse();
    return chi2_scale(s) * norms.cwiseInverse().asDiagonal() * inverse * norms.cwiseInverse().asDiagonal();
  }

  std::vector<ReportedValue> describe(const State& s, std::size_t term, const Eigen::MatrixXd& covariance) const {
    const Term& t = s.terms[term];
    const Effect& e = effect(t);
    const TimeSeries& rec = e.moves_model_temperature() ? block_record_ : s.design.moved;
    const auto coefficients = static_cast<Eigen::Index>(e.coefficient_names().size());
    const Eigen::Index first = e.moves_model_temperature() ? 0 : s.design.first_column[term];
    Eigen::Index theta_index = s.design.columns.cols();
    for (std::size_t i = 0; i < term; ++i) theta_index += s.terms[i].theta.size();

    std::vector<Eigen::Index> indices;
    for (Eigen::Index k = 0; k < t.theta.size(); ++k) indices.push_back(theta_index + k);
    for (Eigen::Index k = 0; k < coefficients; ++k) indices.push_back(first + k);
    const auto p = static_cast<Eigen::Index>(indices.size());
    Eigen::VectorXd v(p);
    for (Eigen::Index k = 0; k < t.theta.size(); ++k) v[k] = t.theta[k];
    for (Eigen::Index k = 0; k < coefficients; ++k) v[t.theta.size() + k] = s.fit.beta[first + k];
    Eigen::MatrixXd sigma(p, p);
    for (Eigen::Index a = 0; a < p; ++a)
      for (Eigen::Index b = 0; b < p; ++b)
        sigma(a, b) = covariance(indices[static_cast<std::size_t>(a)], indices[static_cast<std::size_t>(b)]);

    auto values_at = [&](const Eigen::VectorXd& x) {
      const auto described = e.describe(rec, context_, x.head(t.theta.size()), x.tail(coefficients));
      std::vector<double> flat;
      for (const auto& d : described) flat.insert(flat.end(), d.values.begin(), d.values.end());
      return flat;
    };
    const auto central = e.describe(rec, context_, t.theta, v.tail(coefficients));
    const auto flat = values_at(v);
    Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(flat.size()), p);
    for (Eigen::Index k = 0; k < p; ++k) {
      const double h = kDifferenceStep * std::max({std::abs(v[k]), std::sqrt(std::max(0.0, sigma(k, k))), 1e-300});
      Eigen::VectorXd up = v, down = v;
      up[k] += h;
      down[k] -= h;
      const auto fu = values_at(up), fd = values_at(down);
      for (std::size_t r = 0; r < flat.size(); ++r)
        jacobian(static_cast<Eigen::Index>(r), k) = (fu[r] - fd[r]) / (2.0 * h);
    }
    std::vector<ReportedValue> out;
    Eigen::Index row = 0;
    for (const auto& d : central) {
      ReportedValue r{d.key, d.unit, d.values, {}};
      for (std::size_t i = 0; i < d.values.size(); ++i, ++row) {
        const Eigen::RowVectorXd g = jacobian.row(row);
        r.sigmas.push_back(g.isZero(0.0) ? std::numeric_limits<double>::quiet_NaN()
                                         : std::sqrt(std::max(0.0, (g * sigma * g.transpose())(0, 0))));
      }
      out.push_back(std::move(r));
    }
    return out;
  }

  // ---- views ----------------------------------------------------------------------------------
  Views views(const State& s, const Eigen::VectorXd& full_model_rad_s) const {
    const Eigen::VectorXd full_residual =
        evenly_sampled_ ? Eigen::VectorXd(record_.channel(role::kRate).values - full_model_rad_s) : Eigen::VectorXd();
    return residual_views(blocks_, block_record_.channel(role::kTemperature).values, y_ - block_model(s), full_residual,
                          noise_);
  }

  // The model's own columns: the bias polynomial, and without a device prior on a record with a
  // true rate also a free scale-factor polynomial (w (T - T0)^i): without a device file there is no
  // scale factor to differ from, so its temperature dependence is part of the model.
  Eigen::Index model_columns() const { return (options_.bias_degree + 1) * (free_scale_factor_ ? 2 : 1); }

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

}  // namespace

Result find_missing_effects(const TimeSeries& record, const std::vector<Candidate>& candidates,
                            const Options& options) {
  return Workflow(record, candidates, options).run();
}

}  // namespace driftlab::discrepancy
