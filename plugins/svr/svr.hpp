// epsilon-support vector regression with a Gaussian (RBF) kernel (Vapnik 1995; Smola & Schoelkopf
// 2004), trained by dlib's svr_trainer (SMO; Debian libdlib-dev), as the drift model of the VMD
// sibling paper (Sensors 2020, PMC7345257: CS-SVR).
//
// Features are standardized per feature (mean, population SD) and the target is standardized too,
// so the parameters are scale-free: minimize  1/2 ||w||^2 + C sum_i (xi_i + xi_i*)  subject to
// |t_i - f(u_i)| <= epsilon + slack, with t = (y - mean_y) / sd_y, and kernel
//   k(u, v) = exp(-gamma ||u - v||^2)     (gamma in 1 / standardized-feature units^2).
// The model is  y(x) = mean_y + sd_y (sum_s alpha_s k(u_s, u(x)) - b)  over the support vectors u_s.
//
// Training is O(n^2) in time and kernel cache, so it uses an evenly spaced subsample of at most
// `max_samples` rows (first row kept; all rows when fewer): the drift parts this regressor models
// are smooth and densely sampled, so evenly spaced rows lose little. Deterministic (no random
// draws). Prediction is done here with Eigen in row blocks: O(N S d) for S support vectors.
#pragma once

#include <Eigen/Core>
#include <cstddef>

namespace driftlab::svr {

struct Config {
  double c = 10.0;                 // C, > 0
  double epsilon = 0.1;            // insensitive-zone half width, in target standard deviations, >= 0
  double gamma = 0.5;              // RBF kernel width, > 0
  std::size_t max_samples = 2000;  // rows used for training at most, >= 1
  double tolerance = 1e-3;         // SMO stopping tolerance, > 0
  std::size_t cache_rows = 200;    // kernel columns dlib caches, >= 1
};

class Model {
 public:
  Model(Eigen::RowVectorXd mean, Eigen::RowVectorXd scale, double y_mean, double y_scale, Eigen::MatrixXd support,
        Eigen::VectorXd alpha, double b, double gamma);
  // Throws std::invalid_argument on a feature-count mismatch.
  Eigen::VectorXd predict(const Eigen::MatrixXd& X) const;
  std::size_t support_vectors() const { return static_cast<std::size_t>(support_.rows()); }

 private:
  Eigen::RowVectorXd mean_, scale_;
  double y_mean_, y_scale_;
  Eigen::MatrixXd support_;  // S x d, standardized
  Eigen::VectorXd alpha_;
  double b_, gamma_;
};

struct FitResult {
  Model model;
  std::size_t training_rows = 0;
};

// Throws std::invalid_argument for mismatched sizes, no rows, non-finite data or an invalid config.
FitResult fit(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const Config& config);

}  // namespace driftlab::svr
