#include "plugins/elm/elm.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "framework/seeded_random.hpp"
#include "plugins/common/ridge.hpp"

namespace driftlab::elm {
namespace {

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument("elm: " + what); }

void apply(Activation g, Eigen::MatrixXd& Z) {
  switch (g) {
    case Activation::Sigmoid:
      Z.array() = 1.0 / (1.0 + (-Z.array()).exp());
      break;
    case Activation::Tanh:
      Z.array() = Z.array().tanh();
      break;
    case Activation::Sine:
      Z.array() = Z.array().sin();
      break;
    case Activation::Relu:
      Z.array() = Z.array().max(0.0);
      break;
  }
}

// g(U W + b) for standardized rows U.
Eigen::MatrixXd layer(const Eigen::MatrixXd& U, const Eigen::MatrixXd& W, const Eigen::RowVectorXd& b, Activation g) {
  Eigen::MatrixXd Z = U * W;
  Z.rowwise() += b;
  apply(g, Z);
  return Z;
}

}  // namespace

Model::Model(Eigen::RowVectorXd mean, Eigen::RowVectorXd scale, Eigen::MatrixXd input_weights,
             Eigen::RowVectorXd hidden_bias, Activation activation, Eigen::VectorXd output_weights, double output_bias)
    : mean_(std::move(mean)),
      scale_(std::move(scale)),
      input_weights_(std::move(input_weights)),
      hidden_bias_(std::move(hidden_bias)),
      activation_(activation),
      output_weights_(std::move(output_weights)),
      output_bias_(output_bias) {}

Eigen::MatrixXd Model::hidden(const Eigen::MatrixXd& X) const {
  if (X.cols() != mean_.size()) {
    fail("got " + std::to_string(X.cols()) + " features, the model was fitted on " + std::to_string(mean_.size()));
  }
  return layer(ridge::Standardizer{mean_, scale_}.apply(X), input_weights_, hidden_bias_, activation_);
}

Eigen::VectorXd Model::predict(const Eigen::MatrixXd& X) const {
  if (X.cols() != mean_.size()) {
    fail("got " + std::to_string(X.cols()) + " features, the model was fitted on " + std::to_string(mean_.size()));
  }
  Eigen::VectorXd out(X.rows());
  for (Eigen::Index start = 0; start < X.rows(); start += ridge::kBlockRows) {
    const Eigen::Index len = std::min(ridge::kBlockRows, X.rows() - start);
    out.segment(start, len) = (hidden(X.middleRows(start, len)) * output_weights_).array() + output_bias_;
  }
  return out;
}

Model fit(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const Config& c) {
  if (X.rows() == 0 || X.cols() == 0) fail("no training data");
  if (X.rows() != y.size()) {
    fail("X has " + std::to_string(X.rows()) + " rows but y has " + std::to_string(y.size()));
  }
  if (!X.allFinite() || !y.allFinite()) fail("training data contain NaN or Inf");
  if (c.hidden == 0) fail("hidden must be at least 1");
  if (!(c.input_scale > 0) || !std::isfinite(c.input_scale)) fail("input_scale must be positive");
  if (!(c.regularization >= 0) || !std::isfinite(c.regularization)) fail("regularization must be >= 0");

  const auto d = X.cols();
  const auto L = static_cast<Eigen::Index>(c.hidden);
  SeededRandom random(c.seed);
  Eigen::MatrixXd W(d, L);
  Eigen::RowVectorXd b(L);
  for (Eigen::Index j = 0; j < L; ++j) {
    for (Eigen::Index k = 0; k < d; ++k) W(k, j) = c.input_scale * (2.0 * random.uniform() - 1.0);
    b[j] = c.input_scale * (2.0 * random.uniform() - 1.0);
  }
  const auto standardizer = ridge::Standardizer::fit(X);
  const Eigen::MatrixXd U = standardizer.apply(X);
  // ridge::solve on one thread forms the blocks in order, on this thread (header, "Progress").
  const Eigen::Index blocks = (U.rows() + ridge::kBlockRows - 1) / ridge::kBlockRows;
  const Eigen::Index stride = (blocks + 99) / 100;
  const auto design = [&](Eigen::Index start, Eigen::Index len) {
    if (c.progress && start > 0 && (start / ridge::kBlockRows) % stride == 0)
      c.progress(static_cast<double>(start) / static_cast<double>(U.rows()));
    return layer(U.middleRows(start, len), W, b, c.activation);
  };
  Eigen::VectorXd beta;
  try {
    beta = ridge::solve(U.rows(), L, design, y, c.regularization);
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
  return Model(standardizer.mean, standardizer.scale, std::move(W), std::move(b), c.activation, beta.head(L), beta[L]);
}

}  // namespace driftlab::elm
