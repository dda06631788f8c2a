// Extreme learning machine (Huang, Zhu & Siew, Neurocomputing 70 (2006) 489-501) for regression,
// as used for the drift part by Zhang et al., Micromachines 2024, 15(5), 609.
//
// Inputs are standardized per feature (mean, population standard deviation; a constant feature
// keeps scale 1): u = (x - mean) / std. A single hidden layer of L units with random, fixed input
// weights and biases:
//   h_j(u) = g(w_j . u + b_j),   w_jk, b_j ~ uniform[-input_scale, input_scale]   (seeded)
//   y(u)   = sum_j beta_j h_j(u) + beta_0
// g is sigmoid 1 / (1 + e^-z), tanh, sin, or relu max(0, z). Only the output weights are learned,
// by ridge least squares on the mean-square normal equations
//   (H^T H / N + lambda I') beta = H^T y / N
// with a constant column for beta_0 that is not penalized (I' = identity without that entry), solved
// by Eigen's LDLT. lambda = `regularization`: scale-free in N; lambda -> 0 gives the Moore-Penrose
// least-squares solution of the original ELM, lambda > 0 the regularized ELM that trades training
// error against ||beta|| (the two objectives that the 2024 paper's NSGA-II balances).
//
// Draw order: for j = 1..L: w_j1..w_jd, then b_j, from SeededRandom(seed): same seed, same model.
// Progress (Config::progress): the fraction of the N rows whose hidden-layer outputs are in H^T H,
// reported on the calling thread before each of the ridge::kBlockRows-row blocks but the first (at
// most 100 calls: every ceil(blocks / 100)-th block), in (0, 1), increasing; the solve for beta, a
// small L x L system, is the caller's to end. Empty: not called. It never changes the model.
// Cost: fit O(N L d) for the activations plus O(N L^2) for H^T H, built in row blocks (memory
// O(L^2 + block L), not O(N L)); predict O(N L d).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>

namespace driftlab::elm {

enum class Activation { Sigmoid, Tanh, Sine, Relu };

struct Config {
  std::size_t hidden = 50;  // L, >= 1
  Activation activation = Activation::Sigmoid;
  double input_scale = 1.0;      // half-width of the uniform input weights and biases, > 0
  double regularization = 1e-8;  // ridge lambda, >= 0
  std::uint64_t seed = 1;
  std::function<void(double fraction)> progress;  // see "Progress" above
};

class Model {
 public:
  Model(Eigen::RowVectorXd mean, Eigen::RowVectorXd scale, Eigen::MatrixXd input_weights,
        Eigen::RowVectorXd hidden_bias, Activation activation, Eigen::VectorXd output_weights, double output_bias);

  // Throws std::invalid_argument on a feature-count mismatch.
  Eigen::VectorXd predict(const Eigen::MatrixXd& X) const;
  // Hidden-layer outputs H (N x L) of raw feature rows X.
  Eigen::MatrixXd hidden(const Eigen::MatrixXd& X) const;

  const Eigen::MatrixXd& input_weights() const { return input_weights_; }    // d x L
  const Eigen::RowVectorXd& hidden_bias() const { return hidden_bias_; }     // L
  const Eigen::VectorXd& output_weights() const { return output_weights_; }  // beta_1..beta_L
  double output_bias() const { return output_bias_; }                        // beta_0
  // ||beta||_2 over beta_1..beta_L (the paper's second objective).
  double output_weight_norm() const { return output_weights_.norm(); }

 private:
  Eigen::RowVectorXd mean_, scale_;
  Eigen::MatrixXd input_weights_;
  Eigen::RowVectorXd hidden_bias_;
  Activation activation_;
  Eigen::VectorXd output_weights_;
  double output_bias_;
};

// Throws std::invalid_argument for mismatched sizes, no rows, non-finite data, an invalid config,
// or a singular system (lambda = 0 with more hidden units than independent rows).
Model fit(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const Config& config);

}  // namespace driftlab::elm
