#include "plugins/svr/svr.hpp"

#include <dlib/svm.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "plugins/common/ridge.hpp"

namespace driftlab::svr {
namespace {

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument("svr: " + what); }

using Sample = dlib::matrix<double, 0, 1>;
using Kernel = dlib::radial_basis_kernel<Sample>;

}  // namespace

Model::Model(Eigen::RowVectorXd mean, Eigen::RowVectorXd scale, double y_mean, double y_scale, Eigen::MatrixXd support,
             Eigen::VectorXd alpha, double b, double gamma)
    : mean_(std::move(mean)),
      scale_(std::move(scale)),
      y_mean_(y_mean),
      y_scale_(y_scale),
      support_(std::move(support)),
      alpha_(std::move(alpha)),
      b_(b),
      gamma_(gamma) {}

Eigen::VectorXd Model::predict(const Eigen::MatrixXd& X) const {
  if (X.cols() != mean_.size()) {
    fail("got " + std::to_string(X.cols()) + " features, the model was fitted on " + std::to_string(mean_.size()));
  }
  const ridge::Standardizer standardizer{mean_, scale_};
  const Eigen::RowVectorXd support_norms = support_.rowwise().squaredNorm().transpose();
  Eigen::VectorXd out(X.rows());
  for (Eigen::Index start = 0; start < X.rows(); start += ridge::kBlockRows) {
    const Eigen::Index len = std::min(ridge::kBlockRows, X.rows() - start);
    const Eigen::MatrixXd U = standardizer.apply(X.middleRows(start, len));
    Eigen::MatrixXd K = -2.0 * U * support_.transpose();
    K.colwise() += U.rowwise().squaredNorm();
    K.rowwise() += support_norms;
    K = (-gamma_ * K.array().max(0.0)).exp().matrix();
    out.segment(start, len) = ((K * alpha_).array() - b_) * y_scale_ + y_mean_;
  }
  return out;
}

FitResult fit(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const Config& c) {
  if (X.rows() == 0 || X.cols() == 0) fail("no training data");
  if (X.rows() != y.size()) fail("X has " + std::to_string(X.rows()) + " rows but y has " + std::to_string(y.size()));
  if (!X.allFinite() || !y.allFinite()) fail("training data contain NaN or Inf");
  if (!(c.c > 0) || !std::isfinite(c.c)) fail("C must be positive");
  if (!(c.epsilon >= 0) || !std::isfinite(c.epsilon)) fail("epsilon must be >= 0");
  if (!(c.gamma > 0) || !std::isfinite(c.gamma)) fail("gamma must be positive");
  if (c.max_samples == 0 || c.cache_rows == 0 || !(c.tolerance > 0)) fail("max_samples, cache_rows, tolerance > 0");

  const auto n = static_cast<std::size_t>(X.rows());
  const std::size_t keep = std::min(n, c.max_samples);
  std::vector<Eigen::Index> rows(keep);
  for (std::size_t i = 0; i < keep; ++i) rows[i] = static_cast<Eigen::Index>(i * n / keep);
  const Eigen::MatrixXd Xs = X(rows, Eigen::all);
  const Eigen::VectorXd ys = y(rows);

  const auto standardizer = ridge::Standardizer::fit(Xs);
  const Eigen::MatrixXd U = standardizer.apply(Xs);
  const double y_mean = ys.mean();
  double y_scale = std::sqrt((ys.array() - y_mean).square().mean());
  if (!(y_scale > 0)) y_scale = 1.0;

  std::vector<Sample> samples(keep);
  std::vector<double> targets(keep);
  for (std::size_t i = 0; i < keep; ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    samples[i].set_size(U.cols());
    for (Eigen::Index k = 0; k < U.cols(); ++k) samples[i](k) = U(r, k);
    targets[i] = (ys[r] - y_mean) / y_scale;
  }
  dlib::svr_trainer<Kernel> trainer;
  trainer.set_kernel(Kernel(c.gamma));
  trainer.set_c(c.c);
  trainer.set_epsilon_insensitivity(c.epsilon);
  trainer.set_epsilon(c.tolerance);
  trainer.set_cache_size(static_cast<long>(c.cache_rows));
  const auto df = trainer.train(samples, targets);

  const auto s = static_cast<Eigen::Index>(df.basis_vectors.size());
  Eigen::MatrixXd support(s, U.cols());
  Eigen::VectorXd alpha(s);
  for (Eigen::Index i = 0; i < s; ++i) {
    for (Eigen::Index k = 0; k < U.cols(); ++k) support(i, k) = df.basis_vectors(i)(k);
    alpha[i] = df.alpha(i);
  }
  return {Model(standardizer.mean, standardizer.scale, y_mean, y_scale, std::move(support), std::move(alpha), df.b,
                c.gamma),
          keep};
}

}  // namespace driftlab::svr
