#include "models/discrepancy/workflow.hpp"

namespace driftlab::discrepancy::detail {
namespace {

constexpr double kRankThreshold = 1e-10;  // relative column norm below which a direction is dropped
constexpr double kDifferenceStep = 1e-4;  // relative step of the finite differences

}  // namespace

Eigen::VectorXd column_norms(const Eigen::MatrixXd& m) {
  Eigen::VectorXd n = m.colwise().norm().transpose();
  for (double& v : n)
    if (!(v > 0.0)) v = 1.0;
  return n;
}

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

TimeSeries Workflow::moved_record(const TimeSeries& rec, const std::vector<Term>& terms) const {
  TimeSeries moved = rec;
  for (const auto& t : terms) {
    if (!effect(t).moves_model_temperature()) continue;
    moved.set_channel({role::kTemperature, "degC", "model temperature",
                       effect(t).evaluate(rec, context_, t.theta).model_temperature_c});
  }
  return moved;
}

Design Workflow::design(const TimeSeries& rec, const std::vector<Term>& terms) const {
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

Fit Workflow::fit(const Design& d) const {
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

State Workflow::fitted(std::vector<Term> terms) const {
  State s{std::move(terms), {}, {}};
  s.design = design(block_record_, s.terms);
  s.fit = fit(s.design);
  return s;
}

Eigen::VectorXd Workflow::full_model(const State& s) const {
  const Design d = design(smooth_record_, s.terms);
  return d.offset + d.columns * s.fit.beta;
}

std::vector<double> Workflow::bias_coefficients(const State& s) const {
  return {s.fit.beta.data(), s.fit.beta.data() + options_.bias_degree + 1};
}

Eigen::Index Workflow::parameter_count(const State& s) const {
  Eigen::Index p = s.design.columns.cols();
  for (const auto& t : s.terms) p += t.theta.size();
  return p;
}

double Workflow::chi2_scale(const State& s) const {
  const double dof = static_cast<double>(blocks_.size() - parameter_count(s));
  return dof > 0.0 ? std::max(1.0, s.fit.chi2 / dof) : 1.0;
}

Eigen::MatrixXd Workflow::parameter_covariance(const State& s) const {
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

std::vector<ReportedValue> Workflow::describe(const State& s, std::size_t term,
                                              const Eigen::MatrixXd& covariance) const {
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

}  // namespace driftlab::discrepancy::detail
