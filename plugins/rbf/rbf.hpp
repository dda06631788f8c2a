// Gaussian radial-basis-function network (Li et al., Micromachines 2023, 14, 971, eqs. 6-9).
//
// Inputs are standardized per feature with the mean and population standard deviation of the
// training data (a constant feature keeps scale 1). In standardized units u = (x - mean) / std:
//   a_j(u) = exp(-||u - c_j||^2 / (2 sigma^2)),  j = 1..K                       (eqs. 6-7)
//   y(u)   = sum_j w_j a_j(u) + b                                                (eq. 8)
// All units share one width sigma (the width the paper's GA tunes). The bias b is the weight of a
// constant unit a_0 = 1, so a = (a_1..a_K, 1) in what follows. With `linear_tail`, the network also
// has a linear term in the standardized inputs (the usual polynomial augmentation of RBF
// interpolation, Buhmann 2003, ch. 5):
//   y(u)   = sum_j w_j a_j(u) + b + v^T u,    a = (a_1..a_K, 1, u_1..u_d)
// so a target whose large part is (nearly) linear in the inputs, like a gyro bias over a 90 degC
// range, is carried by v, and the Gaussians only model the curvature. Without it, the Gaussians must
// build the whole range from bumps, which needs a tiny ridge and is ill-conditioned.
//
// Centres:
//   KMeans  Lloyd's k-means with k-means++ seeding (Arthur & Vassilvitskii 2007) on at most
//           `kmeans_sample` rows drawn without replacement (seeded) from the standardized data;
//           stops when no assignment changes or after `kmeans_iterations`. An emptied cluster is
//           moved to the sample point farthest from its centre.
//   Grid    `grid_points` per axis, evenly spaced over each standardized feature's [min, max]
//           (K = grid_points^d).
// Output weights:
//   LeastSquares  ridge regression on the normal equations, (A^T A / N + lambda I') w = A^T y / N,
//                 solved by Eigen's LDLT; I' is the identity on the Gaussian weights only (the bias
//                 and the linear tail are not penalized). lambda = `regularization` (units of a^2, scale-free in N).
//   Lms           the paper's normalized LMS rule (eq. 9), from w = 0, rows in order, `lms_epochs`
//                 passes:  w(l+1) = w(l) + beta (y_d - y) a / (a^T a),  0 < beta < 2.
//                 For targets the network can represent exactly, ||w - w*|| never increases:
//                 ||w(l+1) - w*||^2 = ||w(l) - w*||^2 - beta (2 - beta) e^2 / (a^T a).
//
// Cost: fit O(N K d) for the activations plus O(N K^2) for A^T A (least squares; activations are
// built in row blocks, so memory is O(K^2 + block K) and not O(N K)), or O(epochs N K) for LMS
// (which keeps the N x (K+1) activations); k-means O(min(N, kmeans_sample) K d iterations).
// predict O(N K d). The N K exponentials dominate (see BM_RbfFit in driftlab-bench).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace driftlab::rbf {

enum class CentreMethod { KMeans, Grid };
enum class WeightSolver { LeastSquares, Lms };

struct Config {
  CentreMethod centre_method = CentreMethod::KMeans;
  std::size_t centres = 20;     // K for k-means, >= 1 and <= rows used by k-means
  std::size_t grid_points = 5;  // per axis for Grid, >= 1
  double sigma = 1.0;           // unit width in standardized input units, > 0
  WeightSolver solver = WeightSolver::LeastSquares;
  double regularization = 1e-8;        // ridge lambda, >= 0
  double lms_rate = 0.5;               // beta of eq. 9, in (0, 2)
  std::size_t lms_epochs = 50;         // passes over the data for Lms
  std::size_t kmeans_iterations = 50;  // Lloyd iterations cap
  std::size_t kmeans_sample = 2000;    // rows used by k-means at most
  std::uint64_t seed = 1;              // k-means subsample and seeding
  bool linear_tail = false;            // add v^T u (see above)
  unsigned threads = 1;                // least-squares blocks in parallel; results do not depend on it
};

class Network {
 public:
  Network(Eigen::RowVectorXd mean, Eigen::RowVectorXd scale, Eigen::MatrixXd centres, double sigma,
          Eigen::VectorXd weights, double bias, Eigen::VectorXd linear = {});

  // X: samples x features (same features as in fit), rows in blocks on `threads` threads. Throws
  // std::invalid_argument on a column count mismatch.
  Eigen::VectorXd predict(const Eigen::MatrixXd& X, unsigned threads = 1) const;

  const Eigen::RowVectorXd& mean() const { return mean_; }
  const Eigen::RowVectorXd& scale() const { return scale_; }
  const Eigen::MatrixXd& centres() const { return centres_; }  // K x d, standardized units
  double sigma() const { return sigma_; }
  const Eigen::VectorXd& weights() const { return weights_; }  // w_1..w_K
  double bias() const { return bias_; }
  const Eigen::VectorXd& linear() const { return linear_; }  // v (empty without a linear tail)

 private:
  Eigen::RowVectorXd mean_, scale_;
  Eigen::MatrixXd centres_;
  double sigma_;
  Eigen::VectorXd weights_;
  double bias_;
  Eigen::VectorXd linear_;
};

struct FitResult {
  Network network;
  std::vector<double> lms_rmse;  // training RMSE after each LMS epoch (empty for LeastSquares)
};

// Throws std::invalid_argument for mismatched sizes, fewer rows than centres, non-finite data or
// an invalid config.
FitResult fit(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const Config& config);

// One LMS step (eq. 9) on the weights w given the activation vector a (bias entry included) and
// the desired output y_d. A zero activation vector leaves w unchanged.
void lms_step(Eigen::VectorXd& w, const Eigen::Ref<const Eigen::VectorXd>& a, double y_d, double beta);

// Activations a_j(u) of standardized rows U against centres C (N x K, no bias column).
Eigen::MatrixXd activations(const Eigen::MatrixXd& U, const Eigen::MatrixXd& C, double sigma);

}  // namespace driftlab::rbf
