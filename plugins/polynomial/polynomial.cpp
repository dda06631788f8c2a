#include "plugins/polynomial/polynomial.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace driftlab::polynomial {
namespace {

void check_inputs(const Eigen::MatrixXd& A, const Eigen::VectorXd& y) {
  if (A.rows() != y.size()) throw std::invalid_argument("design matrix and target differ in length");
  if (A.cols() < 1) throw std::invalid_argument("no columns to fit");
  if (A.rows() < A.cols()) {
    throw std::invalid_argument("fewer rows (" + std::to_string(A.rows()) + ") than coefficients (" +
                                std::to_string(A.cols()) + ")");
  }
  if (!A.allFinite() || !y.allFinite()) throw std::invalid_argument("non-finite value in the data");
}

// Solves G c = h with column scaling; a relative ridge of 1e-12 when G is singular.
Eigen::VectorXd solve_gram(const Eigen::MatrixXd& G, const Eigen::VectorXd& h, Eigen::MatrixXd* inverse = nullptr) {
  const Eigen::Index c = G.rows();
  Eigen::VectorXd d(c);
  for (Eigen::Index i = 0; i < c; ++i) d[i] = G(i, i) > 0 ? 1.0 / std::sqrt(G(i, i)) : 1.0;
  Eigen::MatrixXd S = d.asDiagonal() * G * d.asDiagonal();
  Eigen::LDLT<Eigen::MatrixXd> ldlt(S);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1e-13 * ldlt.vectorD().maxCoeff())) {
    S.diagonal().array() += 1e-12;
    ldlt.compute(S);
    if (ldlt.info() != Eigen::Success) throw std::invalid_argument("singular least-squares system");
  }
  const Eigen::VectorXd z = ldlt.solve(d.asDiagonal() * h);
  if (inverse) {
    *inverse = d.asDiagonal() * ldlt.solve(Eigen::MatrixXd::Identity(c, c)) * d.asDiagonal();
  }
  return d.asDiagonal() * z;
}

}  // namespace

LinearFit least_squares(const Eigen::MatrixXd& A, const Eigen::VectorXd& y) {
  check_inputs(A, y);
  const Eigen::MatrixXd G = A.transpose() * A;
  const Eigen::VectorXd h = A.transpose() * y;
  Eigen::MatrixXd inverse;
  LinearFit out;
  out.coefficients = solve_gram(G, h, &inverse);
  const Eigen::VectorXd r = y - A * out.coefficients;
  const double ss = r.squaredNorm();
  out.rms_residual = std::sqrt(ss / static_cast<double>(A.rows()));
  const double dof = static_cast<double>(std::max<Eigen::Index>(1, A.rows() - A.cols()));
  out.standard_errors = (inverse.diagonal().array().max(0.0) * (ss / dof)).sqrt();
  return out;
}

std::vector<int> block_labels(Eigen::Index rows, std::size_t blocks, const std::vector<Eigen::Index>& group_ends) {
  if (blocks < 2) throw std::invalid_argument("need at least 2 held-out blocks");
  std::vector<Eigen::Index> ends = group_ends;
  if (ends.empty() || ends.back() != rows) ends.push_back(rows);
  std::vector<int> label(static_cast<std::size_t>(rows), 0);
  Eigen::Index begin = 0;
  int base = 0;
  for (const Eigen::Index end : ends) {
    const Eigen::Index n = end - begin;
    if (n < static_cast<Eigen::Index>(blocks)) {
      throw std::invalid_argument("a record has fewer rows (" + std::to_string(n) + ") than held-out blocks (" +
                                  std::to_string(blocks) + ")");
    }
    for (Eigen::Index i = 0; i < n; ++i) {
      label[static_cast<std::size_t>(begin + i)] = base + static_cast<int>((i * static_cast<Eigen::Index>(blocks)) / n);
    }
    base += static_cast<int>(blocks);
    begin = end;
  }
  return label;
}

double blocked_cv_rmse(const Eigen::MatrixXd& A, const Eigen::VectorXd& y, std::size_t blocks,
                       const std::vector<Eigen::Index>& group_ends) {
  check_inputs(A, y);
  return labelled_cv_rmse(A, y, block_labels(A.rows(), blocks, group_ends));
}

namespace {

// Per group: A_g^T A_g, A_g^T y_g, y_g^T y_g; and their sums.
struct GroupGrams {
  std::vector<Eigen::MatrixXd> G;
  std::vector<Eigen::VectorXd> h;
  std::vector<double> yy;
  Eigen::MatrixXd G_total;
  Eigen::VectorXd h_total;
};

GroupGrams group_grams(const Eigen::MatrixXd& A, const Eigen::VectorXd& y, const std::vector<int>& label) {
  check_inputs(A, y);
  if (label.size() != static_cast<std::size_t>(A.rows())) throw std::invalid_argument("one label per row needed");
  const int nb = label.empty() ? 0 : *std::max_element(label.begin(), label.end()) + 1;
  if (nb < 2 || *std::min_element(label.begin(), label.end()) < 0)
    throw std::invalid_argument("need labels 0 .. G-1, G >= 2");
  const Eigen::Index c = A.cols();
  GroupGrams g{std::vector<Eigen::MatrixXd>(static_cast<std::size_t>(nb), Eigen::MatrixXd::Zero(c, c)),
               std::vector<Eigen::VectorXd>(static_cast<std::size_t>(nb), Eigen::VectorXd::Zero(c)),
               std::vector<double>(static_cast<std::size_t>(nb), 0.0), Eigen::MatrixXd::Zero(c, c),
               Eigen::VectorXd::Zero(c)};
  Eigen::Index begin = 0;
  while (begin < A.rows()) {
    Eigen::Index end = begin;
    const auto b = static_cast<std::size_t>(label[static_cast<std::size_t>(begin)]);
    while (end < A.rows() && label[static_cast<std::size_t>(end)] == static_cast<int>(b)) ++end;
    const auto Ab = A.middleRows(begin, end - begin);
    const auto yb = y.segment(begin, end - begin);
    g.G[b].noalias() += Ab.transpose() * Ab;
    g.h[b].noalias() += Ab.transpose() * yb;
    g.yy[b] += yb.squaredNorm();
    begin = end;
  }
  for (std::size_t b = 0; b < g.G.size(); ++b) {
    g.G_total += g.G[b];
    g.h_total += g.h[b];
  }
  return g;
}

}  // namespace

double labelled_cv_rmse(const Eigen::MatrixXd& A, const Eigen::VectorXd& y, const std::vector<int>& label) {
  const GroupGrams g = group_grams(A, y, label);
  double ss = 0.0;
  for (std::size_t k = 0; k < g.G.size(); ++k) {
    Eigen::VectorXd coef;
    try {
      coef = solve_gram(g.G_total - g.G[k], g.h_total - g.h[k]);
    } catch (const std::invalid_argument&) {
      return std::numeric_limits<double>::infinity();
    }
    // sum over the group of (y - A c)^2 = yy - 2 c.h + c^T G c
    ss += std::max(0.0, g.yy[k] - 2.0 * coef.dot(g.h[k]) + coef.dot(g.G[k] * coef));
  }
  return std::sqrt(ss / static_cast<double>(A.rows()));
}

Eigen::VectorXd jackknife_standard_errors(const Eigen::MatrixXd& A, const Eigen::VectorXd& y,
                                          const std::vector<int>& label) {
  const GroupGrams g = group_grams(A, y, label);
  const auto n = static_cast<double>(g.G.size());
  Eigen::MatrixXd coef(A.cols(), static_cast<Eigen::Index>(g.G.size()));
  for (std::size_t k = 0; k < g.G.size(); ++k)
    coef.col(static_cast<Eigen::Index>(k)) = solve_gram(g.G_total - g.G[k], g.h_total - g.h[k]);
  const Eigen::VectorXd mean = coef.rowwise().mean();
  return ((n - 1.0) / n * (coef.colwise() - mean).rowwise().squaredNorm()).cwiseSqrt();
}

Eigen::MatrixXd scaled_powers(const Eigen::VectorXd& x, double x0, double s, int order) {
  if (order < 0) throw std::invalid_argument("negative polynomial order");
  if (!(s > 0)) throw std::invalid_argument("polynomial scale must be positive");
  Eigen::MatrixXd V(x.size(), order + 1);
  V.col(0).setOnes();
  const Eigen::ArrayXd u = (x.array() - x0) / s;
  for (int i = 1; i <= order; ++i) V.col(i) = V.col(i - 1).array() * u;
  return V;
}

Fit fit(const Eigen::VectorXd& x, const Eigen::VectorXd& y, const Config& config,
        const std::vector<Eigen::Index>& group_ends) {
  if (config.min_order < 0 || config.max_order < config.min_order) {
    throw std::invalid_argument("polynomial orders need 0 <= min_order <= max_order");
  }
  if (x.size() != y.size()) throw std::invalid_argument("x and y differ in length");
  if (!x.allFinite()) throw std::invalid_argument("non-finite value in x");
  const double half_range = 0.5 * (x.maxCoeff() - x.minCoeff());
  const double s =
      std::max({half_range, std::abs(x.maxCoeff() - config.x0), std::abs(x.minCoeff() - config.x0), 1e-12});
  Fit out;
  out.x0 = config.x0;
  double best = std::numeric_limits<double>::infinity();
  int best_order = config.min_order;
  const Eigen::MatrixXd V = scaled_powers(x, config.x0, s, config.max_order);
  if (config.min_order == config.max_order) {
    out.cv_rmse.push_back(blocked_cv_rmse(V, y, config.blocks, group_ends));
  } else {
    for (int p = config.min_order; p <= config.max_order; ++p) {
      const double e = blocked_cv_rmse(V.leftCols(p + 1), y, config.blocks, group_ends);
      out.cv_rmse.push_back(e);
      if (e < best) {
        best = e;
        best_order = p;
      }
    }
  }
  out.order = best_order;
  const LinearFit lf = least_squares(V.leftCols(best_order + 1), y);
  out.rms_residual = lf.rms_residual;
  double si = 1.0;
  for (int i = 0; i <= best_order; ++i) {
    out.coefficients.push_back(lf.coefficients[i] / si);
    out.standard_errors.push_back(lf.standard_errors[i] / si);
    si *= s;
  }
  return out;
}

}  // namespace driftlab::polynomial
