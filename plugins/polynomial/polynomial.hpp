// Polynomial regression with the order chosen on held-out time blocks (the PX4 / ArduPilot
// thermal-calibration baseline, and the linear core of driftlab's calibration models).
//
// Model: y = sum_{i=0..p} a_i (x - x0)^i. The fit is done in the scaled variable u = (x - x0) / s
// (s = half the range of x, so |u| <= ~1 and the normal equations stay well conditioned) and the
// coefficients are converted back to powers of (x - x0): a_i = b_i / s^i.
//
// Order selection ("held-out time blocks"): the rows, in time order, are cut into `blocks`
// contiguous blocks of equal length. For each candidate order every block is predicted by the fit
// to all other blocks; the order with the smallest pooled held-out RMSE wins. Contiguous blocks
// (not random rows) keep autocorrelated noise out of the score and make the score include the
// interpolation / extrapolation error a deployed model meets.
//
// General linear least squares with the same block cross-validation is exposed too (the physical
// calibration model uses it with extra columns). Everything works from per-block Gram matrices,
// so cross-validation costs O(N c^2 + blocks c^3) for N rows and c columns.
//
// Standard errors: sqrt(diag((A^T A)^-1) * s2), s2 = residual sum of squares / (N - c). They hold
// for independent residuals; with correlated residuals they are too small (callers that know the
// correlation time pass block means as rows).
//
// Pure kernel: Eigen and std only. Errors: std::invalid_argument (sizes, non-finite data, too few
// rows, a singular system).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

namespace driftlab::polynomial {

// ---- general linear least squares -------------------------------------------------------------

struct LinearFit {
  Eigen::VectorXd coefficients;
  Eigen::VectorXd standard_errors;
  double rms_residual = 0.0;  // in-sample RMS of y - A c
};

// Least squares by column-scaled normal equations (LDLT), with a tiny ridge only if singular.
LinearFit least_squares(const Eigen::MatrixXd& A, const Eigen::VectorXd& y);

// Pooled RMSE of each contiguous block predicted by the fit on all other blocks (rows in order).
// `group_ends`: optional row indices where independent records end (blocks never straddle them;
// each record is cut into `blocks` blocks). Empty: one record.
double blocked_cv_rmse(const Eigen::MatrixXd& A, const Eigen::VectorXd& y, std::size_t blocks,
                       const std::vector<Eigen::Index>& group_ends = {});

// Pooled RMSE of each group of rows (label 0 .. G-1, any order) predicted by the fit on all other
// groups: leave-one-group-out, e.g. whole legs of an oven run. Throws std::invalid_argument for
// fewer than 2 groups or a label count that differs from the rows.
double labelled_cv_rmse(const Eigen::MatrixXd& A, const Eigen::VectorXd& y, const std::vector<int>& labels);

// Delete-one-group jackknife standard errors of the least-squares coefficients (labels as for
// labelled_cv_rmse): sqrt((G-1)/G sum_g (c_(g) - mean c)^2). Unlike the textbook standard errors
// they hold when residuals are correlated within a group (a slow wander over a leg of an oven
// run). Throws std::invalid_argument as labelled_cv_rmse, or for a singular fold.
Eigen::VectorXd jackknife_standard_errors(const Eigen::MatrixXd& A, const Eigen::VectorXd& y,
                                          const std::vector<int>& labels);

// Block index of every row (0 .. total blocks - 1) as used by blocked_cv_rmse.
std::vector<int> block_labels(Eigen::Index rows, std::size_t blocks, const std::vector<Eigen::Index>& group_ends);

// ---- polynomials --------------------------------------------------------------------------------

// Columns (x - x0)^i / s^i, i = 0..order.
Eigen::MatrixXd scaled_powers(const Eigen::VectorXd& x, double x0, double s, int order);

struct Config {
  int min_order = 1;
  int max_order = 5;       // orders min..max are scored; a fixed order: min = max
  std::size_t blocks = 8;  // held-out time blocks per record, >= 2
  double x0 = 0.0;         // expansion point (e.g. the reference temperature, degC)
};

struct Fit {
  int order = 0;
  double x0 = 0.0;
  std::vector<double> coefficients;     // a_i per (x - x0)^i, unit of y per unit of x^i
  std::vector<double> standard_errors;  // of a_i
  std::vector<double> cv_rmse;          // held-out RMSE for order min_order + k
  double rms_residual = 0.0;            // in-sample
};

Fit fit(const Eigen::VectorXd& x, const Eigen::VectorXd& y, const Config& config,
        const std::vector<Eigen::Index>& group_ends = {});

// Horner evaluation of sum a_i (x - x0)^i.
inline double evaluate(const std::vector<double>& a, double x0, double x) {
  const double u = x - x0;
  double v = 0.0;
  for (std::size_t i = a.size(); i-- > 0;) v = v * u + a[i];
  return v;
}

}  // namespace driftlab::polynomial
