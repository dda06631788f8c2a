#include "plugins/rbf/rbf.hpp"

#include "plugins/common/holdout.hpp"
#include "plugins/common/ridge.hpp"

#include "framework/parallel.hpp"
#include "framework/seeded_random.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>

namespace driftlab::rbf {
namespace {

Eigen::MatrixXd squared_distances(const Eigen::MatrixXd& U, const Eigen::MatrixXd& C) {
  Eigen::MatrixXd D(U.rows(), C.rows());
  for (Eigen::Index j = 0; j < C.rows(); ++j) {
    auto column = D.col(j).array();
    column = (U.col(0).array() - C(j, 0)).square();
    for (Eigen::Index f = 1; f < U.cols(); ++f) column += (U.col(f).array() - C(j, f)).square();
  }
  return D;
}

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument("rbf: " + what); }

void check(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const Config& c) {
  if (X.rows() == 0 || X.cols() == 0) fail("no training data");
  if (X.rows() != y.size()) {
    fail("X has " + std::to_string(X.rows()) + " rows but y has " + std::to_string(y.size()));
  }
  if (!X.allFinite() || !y.allFinite()) fail("training data contain NaN or Inf");
  if (!(c.sigma > 0) || !std::isfinite(c.sigma)) fail("sigma must be positive");
  if (!(c.regularization >= 0)) fail("regularization must be non-negative");
  if (c.solver == WeightSolver::Lms && !(c.lms_rate > 0 && c.lms_rate < 2)) {
    fail("lms_rate (beta) must lie in (0, 2)");
  }
  if (c.centre_method == CentreMethod::KMeans) {
    const auto used = std::min<std::size_t>(static_cast<std::size_t>(X.rows()), c.kmeans_sample);
    if (c.centres < 1 || c.centres > used) {
      fail("k-means needs 1 <= centres <= rows used (" + std::to_string(used) + "), got " + std::to_string(c.centres));
    }
  } else {
    constexpr double kMaxGridCentres = 1e5;
    if (c.grid_points < 1 ||
        std::pow(static_cast<double>(c.grid_points), static_cast<double>(X.cols())) > kMaxGridCentres) {
      fail("grid_points^features must lie in [1, 1e5]");
    }
  }
}

std::vector<Eigen::Index> subsample(Eigen::Index n, std::size_t cap, SeededRandom& rng) {
  std::vector<Eigen::Index> rows(static_cast<std::size_t>(n));
  std::iota(rows.begin(), rows.end(), 0);
  if (rows.size() <= cap) return rows;
  for (std::size_t i = 0; i < cap; ++i) std::swap(rows[i], rows[i + rng.index(rows.size() - i)]);
  rows.resize(cap);
  std::sort(rows.begin(), rows.end());
  return rows;
}

Eigen::MatrixXd kmeans(const Eigen::MatrixXd& U, const Config& c) {
  SeededRandom rng(c.seed);
  const auto rows = subsample(U.rows(), c.kmeans_sample, rng);
  const auto s = static_cast<Eigen::Index>(rows.size());
  const auto k = static_cast<Eigen::Index>(c.centres);
  Eigen::MatrixXd P(s, U.cols());
  for (Eigen::Index i = 0; i < s; ++i) P.row(i) = U.row(rows[static_cast<std::size_t>(i)]);

  Eigen::MatrixXd C(k, U.cols());
  C.row(0) = P.row(static_cast<Eigen::Index>(rng.index(rows.size())));
  Eigen::VectorXd nearest = (P.rowwise() - C.row(0)).rowwise().squaredNorm();
  for (Eigen::Index j = 1; j < k; ++j) {
    const double total = nearest.sum();
    Eigen::Index pick = 0;
    if (total > 0) {
      const double target = rng.uniform() * total;
      double cumulative = 0;
      for (pick = 0; pick < s - 1; ++pick) {
        cumulative += nearest[pick];
        if (cumulative > target) break;
      }
    } else {
      pick = static_cast<Eigen::Index>(rng.index(rows.size()));
    }
    C.row(j) = P.row(pick);
    nearest = nearest.cwiseMin((P.rowwise() - C.row(j)).rowwise().squaredNorm());
  }

  std::vector<Eigen::Index> label(static_cast<std::size_t>(s), -1);
  Eigen::VectorXd distance(s);
  for (std::size_t iter = 0; iter < c.kmeans_iterations; ++iter) {
    bool changed = false;
    const Eigen::MatrixXd D = squared_distances(P, C);
    for (Eigen::Index i = 0; i < s; ++i) {
      Eigen::Index best;
      distance[i] = D.row(i).minCoeff(&best);
      if (label[static_cast<std::size_t>(i)] != best) {
        label[static_cast<std::size_t>(i)] = best;
        changed = true;
      }
    }
    if (!changed) break;
    Eigen::MatrixXd sums = Eigen::MatrixXd::Zero(k, U.cols());
    Eigen::VectorXd counts = Eigen::VectorXd::Zero(k);
    for (Eigen::Index i = 0; i < s; ++i) {
      sums.row(label[static_cast<std::size_t>(i)]) += P.row(i);
      counts[label[static_cast<std::size_t>(i)]] += 1;
    }
    for (Eigen::Index j = 0; j < k; ++j) {
      if (counts[j] > 0) {
        C.row(j) = sums.row(j) / counts[j];
      } else {
        Eigen::Index farthest;
        distance.maxCoeff(&farthest);
        C.row(j) = P.row(farthest);
        distance[farthest] = 0;
      }
    }
  }
  return C;
}

Eigen::MatrixXd grid(const Eigen::MatrixXd& U, std::size_t points) {
  const Eigen::Index d = U.cols();
  const auto m = static_cast<Eigen::Index>(points);
  Eigen::Index k = 1;
  for (Eigen::Index f = 0; f < d; ++f) k *= m;
  const Eigen::RowVectorXd lo = U.colwise().minCoeff();
  const Eigen::RowVectorXd hi = U.colwise().maxCoeff();
  Eigen::MatrixXd C(k, d);
  for (Eigen::Index j = 0; j < k; ++j) {
    Eigen::Index rest = j;
    for (Eigen::Index f = 0; f < d; ++f) {
      const Eigen::Index step = rest % m;
      rest /= m;
      C(j, f) = m == 1 ? 0.5 * (lo[f] + hi[f])
                       : lo[f] + (hi[f] - lo[f]) * static_cast<double>(step) / static_cast<double>(m - 1);
    }
  }
  return C;
}

// The regressors of the rows of U without the constant: (a_1..a_K[, u_1..u_d]).
Eigen::MatrixXd design(const Eigen::MatrixXd& U, const Eigen::MatrixXd& C, const Config& c) {
  if (!c.linear_tail) return activations(U, C, c.sigma);
  Eigen::MatrixXd B(U.rows(), C.rows() + U.cols());
  B.leftCols(C.rows()) = activations(U, C, c.sigma);
  B.rightCols(U.cols()) = U;
  return B;
}

Eigen::VectorXd least_squares(const Eigen::MatrixXd& U, const Eigen::VectorXd& y, const Eigen::MatrixXd& C,
                              const Config& c) {
  try {
    return ridge::solve(
        U.rows(), C.rows() + (c.linear_tail ? U.cols() : 0),
        [&](Eigen::Index start, Eigen::Index len) { return design(U.middleRows(start, len), C, c); }, y,
        c.regularization, C.rows(), c.threads);
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
}

Eigen::VectorXd lms(const Eigen::MatrixXd& U, const Eigen::VectorXd& y, const Eigen::MatrixXd& C, const Config& c,
                    std::vector<double>& epoch_rmse) {
  const Eigen::MatrixXd d = design(U, C, c);
  Eigen::MatrixXd rows_as_columns(d.cols() + 1, d.rows());
  rows_as_columns.topRows(d.cols()) = d.transpose();
  rows_as_columns.bottomRows(1).setOnes();
  Eigen::VectorXd w = Eigen::VectorXd::Zero(rows_as_columns.rows());
  for (std::size_t epoch = 0; epoch < c.lms_epochs; ++epoch) {
    for (Eigen::Index i = 0; i < rows_as_columns.cols(); ++i) {
      lms_step(w, rows_as_columns.col(i), y[i], c.lms_rate);
    }
    epoch_rmse.push_back(holdout::rmse(rows_as_columns.transpose() * w, y));
  }
  return w;
}

}  // namespace

Network::Network(Eigen::RowVectorXd mean, Eigen::RowVectorXd scale, Eigen::MatrixXd centres, double sigma,
                 Eigen::VectorXd weights, double bias, Eigen::VectorXd linear)
    : mean_(std::move(mean)),
      scale_(std::move(scale)),
      centres_(std::move(centres)),
      sigma_(sigma),
      weights_(std::move(weights)),
      bias_(bias),
      linear_(std::move(linear)) {}

Eigen::VectorXd Network::predict(const Eigen::MatrixXd& X, unsigned threads) const {
  if (X.cols() != mean_.size()) {
    fail("predict got " + std::to_string(X.cols()) + " features, the network was fitted on " +
         std::to_string(mean_.size()));
  }
  Eigen::VectorXd out(X.rows());
  const auto blocks = static_cast<std::size_t>((X.rows() + ridge::kBlockRows - 1) / ridge::kBlockRows);
  parallel_for(blocks, threads, [&](std::size_t block) {
    const Eigen::Index start = static_cast<Eigen::Index>(block) * ridge::kBlockRows;
    const Eigen::Index len = std::min(ridge::kBlockRows, X.rows() - start);
    const Eigen::MatrixXd U = (X.middleRows(start, len).rowwise() - mean_).array().rowwise() / scale_.array();
    out.segment(start, len) = (activations(U, centres_, sigma_) * weights_).array() + bias_;
    if (linear_.size() > 0) out.segment(start, len) += U * linear_;
  });
  return out;
}

Eigen::MatrixXd activations(const Eigen::MatrixXd& U, const Eigen::MatrixXd& C, double sigma) {
  Eigen::MatrixXd A = squared_distances(U, C);
  A.array() = (A.array() * (-0.5 / (sigma * sigma))).exp();
  return A;
}

void lms_step(Eigen::VectorXd& w, const Eigen::Ref<const Eigen::VectorXd>& a, double y_d, double beta) {
  const double energy = a.squaredNorm();
  if (energy == 0) return;
  w += (beta * (y_d - w.dot(a)) / energy) * a;
}

FitResult fit(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const Config& config) {
  check(X, y, config);
  const auto standardizer = ridge::Standardizer::fit(X);
  const Eigen::RowVectorXd& mean = standardizer.mean;
  const Eigen::RowVectorXd& scale = standardizer.scale;
  const Eigen::MatrixXd U = standardizer.apply(X);
  Eigen::MatrixXd C = config.centre_method == CentreMethod::KMeans ? kmeans(U, config) : grid(U, config.grid_points);
  std::vector<double> epoch_rmse;
  const Eigen::VectorXd w =
      config.solver == WeightSolver::LeastSquares ? least_squares(U, y, C, config) : lms(U, y, C, config, epoch_rmse);
  const Eigen::Index k = C.rows();
  // w = (Gaussian weights, linear tail if any, constant last)
  return {Network(mean, scale, std::move(C), config.sigma, w.head(k), w[w.size() - 1], w.segment(k, w.size() - k - 1)),
          std::move(epoch_rmse)};
}

}  // namespace driftlab::rbf
