// Linear Kalman filter and Rauch-Tung-Striebel smoother.
//
// The five equations of Li et al. 2023 (Micromachines 14, 971), eqs. 10-14, for
//   x_k = F x_{k-1} + w_k,  w ~ N(0, Q);   z_k = H x_k + v_k,  v ~ N(0, R):
//   (10) x_{k|k-1} = F x_{k-1|k-1}                                  predict state
//   (11) P_{k|k-1} = F P_{k-1|k-1} F^T + Q                          predict covariance
//   (12) K_k       = P_{k|k-1} H^T (H P_{k|k-1} H^T + R)^-1           gain
//   (13) x_{k|k}   = x_{k|k-1} + K_k (z_k - H x_{k|k-1})             update state
//   (14) P_{k|k}   = (I - K_k H) P_{k|k-1} (I - K_k H)^T + K_k R K_k^T  update covariance
// (14) is the Joseph form: algebraically equal to the paper's (I - K H) P_{k|k-1}, but it keeps P
// symmetric positive semi-definite under rounding; P is also re-symmetrised after every update.
// Time convention: the initial (x0, P0) is the estimate before the first sample, and every sample
// is one predict (10-11) followed by one update (12-14).
//
// RTS smoother (Rauch, Tung, Striebel 1965), backwards from x_{N-1|N-1}:
//   C_k = P_{k|k} F^T P_{k+1|k}^-1,  x_{k|N} = x_{k|k} + C_k (x_{k+1|N} - x_{k+1|k}),
//   P_{k|N} = P_{k|k} + C_k (P_{k+1|N} - P_{k+1|k}) C_k^T.
// The predictions are recomputed from the stored filtered estimates, so only x_{k|k}, P_{k|k} are
// kept (memory N n (n + 1) doubles).
//
// State models (helpers below):
// - random walk + white measurement noise (the paper's use): x = rate, F = H = 1, Q = q, R = r.
//   Run by the specialised scalar path (no matrices, no allocation per sample). Once P_{k|k} stops
//   changing bit for bit the gain is constant and the rest runs as x += K (z - x), which gives the
//   same numbers as the full recursion (the recursion for P does not depend on the data).
//   Steady state (scalar Riccati equation): P_{k|k-1} -> p = (q + sqrt(q^2 + 4 q r)) / 2,
//   K -> p / (p + r), P_{k|k} -> K r.
// - random walk + first-order Gauss-Markov: x = [random walk, Gauss-Markov], H = [1 1],
//   F = diag(1, phi), phi = exp(-dt / tau), Q = diag(q, sigma^2 (1 - phi^2)), R = r, where sigma is
//   the stationary standard deviation and tau the correlation time of the Gauss-Markov term.
// - general linear time-invariant model: F (n x n), H (p x n), Q (n x n), R (p x p).
//
// Noise variances from Allan terms (IEEE Std 952), for a rate sampled at fs = 1/dt:
// - white rate noise with angle random walk N [rad/s/sqrt(Hz) = rad/sqrt(s)]: two-sided rate PSD
//   N^2, Allan variance N^2 / tau; one sample averages over dt, so its variance is
//     R = N^2 / dt = N^2 fs                                       [(rad/s)^2]
// - rate random walk K [rad/s^2/sqrt(Hz) = rad/s^(3/2)]: the rate integrates white noise of PSD
//   K^2 (Allan variance K^2 tau / 3); its increment over one sample has variance
//     Q = K^2 dt = K^2 / fs                                       [(rad/s)^2]
//   Example: N = 0.3 deg/sqrt(h) = 8.727e-5 rad/sqrt(s) at 100 Hz gives R = 7.62e-7 (rad/s)^2.
//
// Cost: scalar O(N), about 3-4 ns per sample (the latency of x += K (z - x); 1e7 samples in about
// 0.1 s with the output allocation); general O(N (n^3 + p^3)), about 0.25 us per sample for the
// 2-state Gauss-Markov model (dynamic-size Eigen, no allocation per step).
// Errors: std::invalid_argument for inconsistent shapes, negative or non-finite variances, a
// covariance that is not symmetric positive (semi-)definite, or non-finite measurements.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace driftlab::kalman {

// ---- scalar random walk + white measurement noise ---------------------------------------------

struct ScalarModel {
  double q = 0.0;  // random-walk increment variance per sample, (rad/s)^2
  double r = 0.0;  // measurement noise variance, (rad/s)^2
};

// Steady-state prior variance p = lim P_{k|k-1} (positive root of p^2 - q p - q r = 0) and gain.
double steady_state_prior_variance(const ScalarModel& model);
double steady_state_gain(const ScalarModel& model);

// Streaming scalar filter: one predict + update per step().
class ScalarFilter {
 public:
  ScalarFilter(const ScalarModel& model, double x0, double p0);
  double step(double z);  // returns x_{k|k}
  double state() const { return x_; }
  double variance() const { return p_; }
  double gain() const { return gain_; }

 private:
  ScalarModel model_;
  double x_, p_, gain_ = 0.0;
};

struct ScalarEstimates {
  Eigen::VectorXd state;     // x_{k|k} (filter) or x_{k|N} (smoother)
  Eigen::VectorXd variance;  // P_{k|k} or P_{k|N}
};

ScalarEstimates filter(const Eigen::VectorXd& z, const ScalarModel& model, double x0, double p0);
// The same x_{k|k} without the variances (half the memory traffic, for long records).
Eigen::VectorXd filter_states(const Eigen::VectorXd& z, const ScalarModel& model, double x0, double p0);
ScalarEstimates smooth(const Eigen::VectorXd& z, const ScalarModel& model, double x0, double p0);

// ---- general linear model -------------------------------------------------------------------

struct LinearModel {
  Eigen::MatrixXd F, H, Q, R;
  Eigen::Index states() const { return F.rows(); }
  Eigen::Index measurements() const { return H.rows(); }
};

// Throws std::invalid_argument when shapes disagree, Q is not symmetric positive semi-definite or
// R is not symmetric positive definite.
void validate(const LinearModel& model);

LinearModel random_walk_model(double q, double r);
// dt_s: sample interval, tau_s: correlation time, sigma: stationary SD of the Gauss-Markov term.
LinearModel random_walk_gauss_markov_model(double q, double sigma, double tau_s, double dt_s, double r);

// R = N^2 fs and Q = K^2 / fs (see above). arw: rad/s/sqrt(Hz), rrw: rad/s^2/sqrt(Hz), fs: Hz.
double measurement_variance_from_arw(double arw, double sample_rate_hz);
double process_variance_from_rrw(double rrw, double sample_rate_hz);

// Streaming filter for a general model. Works in preallocated storage: no allocation per step.
class LinearFilter {
 public:
  LinearFilter(LinearModel model, Eigen::VectorXd x0, Eigen::MatrixXd p0);
  void predict();                                                           // (10), (11)
  void update(const Eigen::Ref<const Eigen::VectorXd>& z);                  // (12), (13), (14)
  const Eigen::VectorXd& step(const Eigen::Ref<const Eigen::VectorXd>& z);  // predict + update

  const Eigen::VectorXd& state() const { return x_; }
  const Eigen::MatrixXd& covariance() const { return p_; }
  const Eigen::MatrixXd& gain() const { return gain_; }  // n x p
  const LinearModel& model() const { return model_; }

 private:
  LinearModel model_;
  Eigen::VectorXd x_, x_pred_, innovation_;
  Eigen::MatrixXd p_, p_pred_, gain_, gain_t_, ph_t_, s_, i_kh_, work_, k_r_;
  Eigen::LLT<Eigen::MatrixXd> s_llt_;
};

struct LinearEstimates {
  Eigen::MatrixXd state;     // samples x n: x_{k|k} or x_{k|N}
  Eigen::MatrixXd variance;  // samples x n: diagonal of P_{k|k} or P_{k|N}
};

// z: samples x p.
LinearEstimates filter(const Eigen::MatrixXd& z, const LinearModel& model, const Eigen::VectorXd& x0,
                       const Eigen::MatrixXd& p0);
LinearEstimates smooth(const Eigen::MatrixXd& z, const LinearModel& model, const Eigen::VectorXd& x0,
                       const Eigen::MatrixXd& p0);

}  // namespace driftlab::kalman
