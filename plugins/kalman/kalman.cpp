#include "plugins/kalman/kalman.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace driftlab::kalman {
namespace {

void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument("kalman: " + message);
}

void validate(const ScalarModel& model, double x0, double p0) {
  require(std::isfinite(model.q) && model.q >= 0.0, "process variance q must be finite and >= 0");
  require(std::isfinite(model.r) && model.r > 0.0, "measurement variance r must be finite and > 0");
  require(std::isfinite(x0), "initial state must be finite");
  require(std::isfinite(p0) && p0 >= 0.0, "initial variance must be finite and >= 0");
}

// One predict + update of the scalar random-walk model (eqs. 10-14 with F = H = 1); returns K.
inline double scalar_step(double& x, double& p, double z, const ScalarModel& model) {
  const double p_pred = p + model.q;
  const double gain = p_pred / (p_pred + model.r);
  x += gain * (z - x);
  const double keep = 1.0 - gain;
  p = keep * keep * p_pred + gain * gain * model.r;
  return gain;
}

void require_finite_measurements(const Eigen::Ref<const Eigen::MatrixXd>& z) {
  for (Eigen::Index k = 0; k < z.rows(); ++k) {
    if (!z.row(k).allFinite())
      throw std::invalid_argument("kalman: measurement " + std::to_string(k) + " is not finite");
  }
}

void require_symmetric_psd(const Eigen::MatrixXd& m, const std::string& name) {
  constexpr double kRelativeTolerance = 1e-12;  // rounding in matrices given as decimal text
  require(m.allFinite(), name + " must be finite");
  const double scale = m.cwiseAbs().maxCoeff();
  require((m - m.transpose()).cwiseAbs().maxCoeff() <= kRelativeTolerance * scale, name + " must be symmetric");
  if (scale == 0.0) return;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(m, Eigen::EigenvaluesOnly);
  require(eigen.eigenvalues().minCoeff() >= -kRelativeTolerance * scale, name + " must be positive semi-definite");
}

void symmetrize(Eigen::MatrixXd& p, Eigen::MatrixXd& work) {
  work = p.transpose();
  p = 0.5 * (p + work);
}

}  // namespace

double steady_state_prior_variance(const ScalarModel& model) {
  validate(model, 0.0, 0.0);
  return 0.5 * (model.q + std::sqrt(model.q * model.q + 4.0 * model.q * model.r));
}

double steady_state_gain(const ScalarModel& model) {
  const double p = steady_state_prior_variance(model);
  return p / (p + model.r);
}

ScalarFilter::ScalarFilter(const ScalarModel& model, double x0, double p0) : model_(model), x_(x0), p_(p0) {
  validate(model, x0, p0);
}

double ScalarFilter::step(double z) {
  if (!std::isfinite(z)) throw std::invalid_argument("kalman: measurement is not finite");
  gain_ = scalar_step(x_, p_, z, model_);
  return x_;
}

namespace {

// Scalar recursion over n samples; `variance` may be null.
void run_scalar(const Eigen::VectorXd& z, const ScalarModel& model, double x0, double p0, double* state,
                double* variance) {
  validate(model, x0, p0);
  const Eigen::Index n = z.size();
  const double* in = z.data();
  double x = x0;
  double p = p0;
  double gain = 0.0;
  Eigen::Index k = 0;
  while (k < n) {
    const double previous = p;
    gain = scalar_step(x, p, in[k], model);
    state[k] = x;
    if (variance) variance[k] = p;
    ++k;
    if (p == previous) break;
  }
  if (variance) std::fill(variance + k, variance + n, p);
  for (; k < n; ++k) {
    x += gain * (in[k] - x);
    state[k] = x;
  }
  if (!std::isfinite(x)) require_finite_measurements(z);
}

}  // namespace

ScalarEstimates filter(const Eigen::VectorXd& z, const ScalarModel& model, double x0, double p0) {
  ScalarEstimates out{Eigen::VectorXd(z.size()), Eigen::VectorXd(z.size())};
  run_scalar(z, model, x0, p0, out.state.data(), out.variance.data());
  return out;
}

Eigen::VectorXd filter_states(const Eigen::VectorXd& z, const ScalarModel& model, double x0, double p0) {
  Eigen::VectorXd state(z.size());
  run_scalar(z, model, x0, p0, state.data(), nullptr);
  return state;
}

ScalarEstimates smooth(const Eigen::VectorXd& z, const ScalarModel& model, double x0, double p0) {
  const ScalarEstimates filtered = filter(z, model, x0, p0);
  ScalarEstimates out = filtered;
  for (Eigen::Index k = z.size() - 2; k >= 0; --k) {
    const double p_filtered = filtered.variance[k];
    const double p_pred = p_filtered + model.q;
    const double c = p_pred > 0.0 ? p_filtered / p_pred : 0.0;
    out.state[k] = filtered.state[k] + c * (out.state[k + 1] - filtered.state[k]);
    out.variance[k] = p_filtered + c * c * (out.variance[k + 1] - p_pred);
  }
  return out;
}

void validate(const LinearModel& model) {
  const Eigen::Index n = model.F.rows();
  const Eigen::Index p = model.H.rows();
  require(n >= 1 && model.F.cols() == n, "F must be square and non-empty");
  require(model.F.allFinite(), "F must be finite");
  require(p >= 1 && model.H.cols() == n, "H must have one column per state (" + std::to_string(n) + ")");
  require(model.H.allFinite(), "H must be finite");
  require(model.Q.rows() == n && model.Q.cols() == n, "Q must be " + std::to_string(n) + " x " + std::to_string(n));
  require(model.R.rows() == p && model.R.cols() == p, "R must be " + std::to_string(p) + " x " + std::to_string(p));
  require_symmetric_psd(model.Q, "Q");
  require_symmetric_psd(model.R, "R");
  require(Eigen::LLT<Eigen::MatrixXd>(model.R).info() == Eigen::Success, "R must be positive definite");
}

LinearModel random_walk_model(double q, double r) {
  LinearModel model{Eigen::MatrixXd::Ones(1, 1), Eigen::MatrixXd::Ones(1, 1), Eigen::MatrixXd::Constant(1, 1, q),
                    Eigen::MatrixXd::Constant(1, 1, r)};
  validate(model);
  return model;
}

LinearModel random_walk_gauss_markov_model(double q, double sigma, double tau_s, double dt_s, double r) {
  require(std::isfinite(sigma) && sigma >= 0.0, "Gauss-Markov sigma must be finite and >= 0");
  require(std::isfinite(tau_s) && tau_s > 0.0, "Gauss-Markov time constant must be finite and > 0");
  require(std::isfinite(dt_s) && dt_s > 0.0, "sample interval must be finite and > 0");
  const double phi = std::exp(-dt_s / tau_s);
  LinearModel model;
  model.F = Eigen::Matrix2d{{1.0, 0.0}, {0.0, phi}};
  model.H = Eigen::RowVector2d{1.0, 1.0};
  model.Q = Eigen::Matrix2d{{q, 0.0}, {0.0, -sigma * sigma * std::expm1(-2.0 * dt_s / tau_s)}};
  model.R = Eigen::MatrixXd::Constant(1, 1, r);
  validate(model);
  return model;
}

double measurement_variance_from_arw(double arw, double sample_rate_hz) {
  require(std::isfinite(arw) && arw >= 0.0, "angle random walk must be finite and >= 0");
  require(std::isfinite(sample_rate_hz) && sample_rate_hz > 0.0, "sample rate must be finite and > 0");
  return arw * arw * sample_rate_hz;
}

double process_variance_from_rrw(double rrw, double sample_rate_hz) {
  require(std::isfinite(rrw) && rrw >= 0.0, "rate random walk must be finite and >= 0");
  require(std::isfinite(sample_rate_hz) && sample_rate_hz > 0.0, "sample rate must be finite and > 0");
  return rrw * rrw / sample_rate_hz;
}

LinearFilter::LinearFilter(LinearModel model, Eigen::VectorXd x0, Eigen::MatrixXd p0)
    : model_(std::move(model)), x_(std::move(x0)), p_(std::move(p0)) {
  validate(model_);
  const Eigen::Index n = model_.states();
  const Eigen::Index m = model_.measurements();
  require(x_.size() == n, "initial state must have " + std::to_string(n) + " entries");
  require(x_.allFinite(), "initial state must be finite");
  require(p_.rows() == n && p_.cols() == n,
          "initial covariance must be " + std::to_string(n) + " x " + std::to_string(n));
  require_symmetric_psd(p_, "initial covariance");
  x_pred_ = x_;
  innovation_.resize(m);
  p_pred_ = p_;
  gain_.resize(n, m);
  gain_t_.resize(m, n);
  ph_t_.resize(n, m);
  s_.resize(m, m);
  i_kh_.resize(n, n);
  work_.resize(n, n);
  k_r_.resize(n, m);
  s_llt_ = Eigen::LLT<Eigen::MatrixXd>(m);
}

void LinearFilter::predict() {
  x_pred_.noalias() = model_.F.lazyProduct(x_);
  work_.noalias() = model_.F.lazyProduct(p_);
  p_pred_.noalias() = work_.lazyProduct(model_.F.transpose());
  p_pred_ += model_.Q;
}

void LinearFilter::update(const Eigen::Ref<const Eigen::VectorXd>& z) {
  if (z.size() != model_.measurements()) {
    throw std::invalid_argument("kalman: measurement must have " + std::to_string(model_.measurements()) + " entries");
  }
  if (!z.allFinite()) throw std::invalid_argument("kalman: measurement is not finite");
  innovation_ = z;
  innovation_.noalias() -= model_.H.lazyProduct(x_pred_);
  ph_t_.noalias() = p_pred_.lazyProduct(model_.H.transpose());
  s_.noalias() = model_.H.lazyProduct(ph_t_);
  s_ += model_.R;
  gain_t_ = ph_t_.transpose();
  if (s_.rows() == 1) {
    if (!(s_(0, 0) > 0.0)) throw std::domain_error("kalman: innovation variance is not positive");
    gain_t_ /= s_(0, 0);
  } else {
    s_llt_.compute(s_);
    if (s_llt_.info() != Eigen::Success)
      throw std::domain_error("kalman: innovation covariance is not positive definite");
    s_llt_.solveInPlace(gain_t_);
  }
  gain_ = gain_t_.transpose();
  x_ = x_pred_;
  x_.noalias() += gain_.lazyProduct(innovation_);
  i_kh_.setIdentity();
  i_kh_.noalias() -= gain_.lazyProduct(model_.H);
  work_.noalias() = i_kh_.lazyProduct(p_pred_);
  p_.noalias() = work_.lazyProduct(i_kh_.transpose());
  k_r_.noalias() = gain_.lazyProduct(model_.R);
  p_.noalias() += k_r_.lazyProduct(gain_t_);
  symmetrize(p_, work_);
}

const Eigen::VectorXd& LinearFilter::step(const Eigen::Ref<const Eigen::VectorXd>& z) {
  predict();
  update(z);
  return x_;
}

namespace {

// Runs the filter; when `covariances` is given, stores every P_{k|k} as one column (n*n rows).
LinearEstimates run_filter(const Eigen::MatrixXd& z, const LinearModel& model, const Eigen::VectorXd& x0,
                           const Eigen::MatrixXd& p0, Eigen::MatrixXd* covariances) {
  LinearFilter f(model, x0, p0);
  const Eigen::Index n = model.states();
  require(z.cols() == model.measurements(),
          "measurements must have " + std::to_string(model.measurements()) + " columns");
  require_finite_measurements(z);
  LinearEstimates out{Eigen::MatrixXd(z.rows(), n), Eigen::MatrixXd(z.rows(), n)};
  if (covariances) covariances->resize(n * n, z.rows());
  Eigen::VectorXd zk(z.cols());
  for (Eigen::Index k = 0; k < z.rows(); ++k) {
    zk = z.row(k).transpose();
    f.step(zk);
    out.state.row(k) = f.state().transpose();
    out.variance.row(k) = f.covariance().diagonal().transpose();
    if (covariances) covariances->col(k) = f.covariance().reshaped();
  }
  return out;
}

}  // namespace

LinearEstimates filter(const Eigen::MatrixXd& z, const LinearModel& model, const Eigen::VectorXd& x0,
                       const Eigen::MatrixXd& p0) {
  return run_filter(z, model, x0, p0, nullptr);
}

LinearEstimates smooth(const Eigen::MatrixXd& z, const LinearModel& model, const Eigen::VectorXd& x0,
                       const Eigen::MatrixXd& p0) {
  Eigen::MatrixXd covariances;
  const LinearEstimates filtered = run_filter(z, model, x0, p0, &covariances);
  LinearEstimates out = filtered;
  const Eigen::Index n = model.states();
  if (z.rows() == 0) return out;
  Eigen::MatrixXd p_next = covariances.col(z.rows() - 1).reshaped(n, n);
  Eigen::MatrixXd work(n, n);
  for (Eigen::Index k = z.rows() - 2; k >= 0; --k) {
    const Eigen::MatrixXd p_filtered = covariances.col(k).reshaped(n, n);
    const Eigen::VectorXd x_filtered = filtered.state.row(k).transpose();
    const Eigen::VectorXd x_pred = model.F * x_filtered;
    const Eigen::MatrixXd p_pred = model.F * p_filtered * model.F.transpose() + model.Q;
    const Eigen::LLT<Eigen::MatrixXd> llt(p_pred);
    if (llt.info() != Eigen::Success) {
      throw std::domain_error("kalman: predicted covariance at sample " + std::to_string(k + 1) +
                              " is not positive definite; the RTS smoother needs it inverted");
    }
    const Eigen::MatrixXd c_t = llt.solve(model.F * p_filtered);
    const Eigen::VectorXd x_next = out.state.row(k + 1).transpose();
    out.state.row(k) = (x_filtered + c_t.transpose() * (x_next - x_pred)).transpose();
    Eigen::MatrixXd p_smoothed = p_filtered + c_t.transpose() * (p_next - p_pred) * c_t;
    symmetrize(p_smoothed, work);
    out.variance.row(k) = p_smoothed.diagonal().transpose();
    p_next = std::move(p_smoothed);
  }
  return out;
}

}  // namespace driftlab::kalman
