#include "models/discrepancy/workflow.hpp"

#include <limits>
#include <stdexcept>

#include "framework/golden_section.hpp"

namespace driftlab::discrepancy::detail {
namespace {

constexpr int kMaxPeriodGrid = 4000;

}  // namespace

std::optional<Axis> Workflow::axis(const EffectParameter& p) const {
  Axis a{p.scale, p.lower, p.upper};
  if (p.scale == EffectParameter::Scale::Period) {
    a.lo = std::max(a.lo, 4.0 * blocks_.median_spacing_s());
    a.hi = std::min(a.hi, 0.5 * blocks_.duration_s());
  }
  if (!(a.lo > 0.0) || !(a.lo < a.hi)) return std::nullopt;
  return a;
}

std::vector<double> Workflow::grid(const Axis& a) const {
  const double u0 = a.to_u(a.lo), u1 = a.to_u(a.hi);
  int count;
  if (a.scale == EffectParameter::Scale::Log) {
    count = std::max(3, static_cast<int>(std::ceil(std::log10(a.hi / a.lo) * options_.grid_points_per_decade)) + 1);
  } else {
    count =
        std::clamp(static_cast<int>(std::ceil(std::abs(u1 - u0) * 4.0 * blocks_.duration_s())) + 1, 3, kMaxPeriodGrid);
  }
  std::vector<double> u(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) u[static_cast<std::size_t>(i)] = u0 + (u1 - u0) * i / (count - 1);
  return u;
}

double Workflow::search_coordinate(const std::function<double(const Eigen::VectorXd&)>& chi2, const Axis& a,
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

void Workflow::refine_coordinate(const std::function<double(const Eigen::VectorXd&)>& chi2, const Axis& a,
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

std::vector<Score> Workflow::score_all(const State& state) const {
  std::vector<Score> scores;
  const bool has_mover = std::any_of(state.terms.begin(), state.terms.end(),
                                     [&](const Term& t) { return effect(t).moves_model_temperature(); });
  const double scale = chi2_scale(state);
  const double log_blocks = std::log(static_cast<double>(blocks_.size()));
  for (std::size_t c = 0; c < candidates_.size(); ++c) {
    Score s;
    s.effect = candidates_[c].name;
    if (std::any_of(state.terms.begin(), state.terms.end(), [&](const Term& t) { return t.candidate == c; })) continue;
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

double Workflow::candidate_chi2(const State& state, std::size_t c, const Eigen::VectorXd& theta) const {
  const Effect& e = *candidates_[c].effect;
  if (e.moves_model_temperature()) {
    std::vector<Term> terms = state.terms;
    terms.push_back({c, theta});
    return chi2_of(terms);
  }
  return added_columns_chi2(state, e.evaluate(state.design.moved, context_, theta).basis).chi2;
}

Workflow::Added Workflow::added_columns_chi2(const State& state, const Eigen::MatrixXd& columns) const {
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

State Workflow::refined(std::vector<Term> terms) const {
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

std::size_t Workflow::candidate_index(const std::string& name) const {
  for (std::size_t c = 0; c < candidates_.size(); ++c)
    if (candidates_[c].name == name) return c;
  throw std::logic_error("unknown candidate " + name);
}

}  // namespace driftlab::discrepancy::detail
