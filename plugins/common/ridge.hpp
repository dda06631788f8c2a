// Shared by the regressor kernels (rbf, elm, svr): feature standardization and ridge least
// squares over a design matrix built in row blocks. Eigen/std only.
#pragma once

#include <Eigen/Core>
#include <functional>

namespace driftlab::ridge {

// Rows per block when a design matrix is built piecewise (memory O(block x columns)).
inline constexpr Eigen::Index kBlockRows = 4096;

// Per-feature mean and population standard deviation (a constant feature keeps scale 1).
struct Standardizer {
  Eigen::RowVectorXd mean, scale;
  static Standardizer fit(const Eigen::MatrixXd& X);
  Eigen::MatrixXd apply(const Eigen::MatrixXd& X) const {
    return (X.rowwise() - mean).array().rowwise() / scale.array();
  }
};

// Solves (A^T A / N + lambda I') w = A^T y / N by LDLT, where A = [design | 1] (a constant column
// appended last) and design(start, len) returns rows start..start+len-1 of the design (len x
// columns). I' is the identity on the first `penalized` columns (all columns when negative): the
// constant and any later columns are not penalized. Blocks of kBlockRows rows are formed on
// `threads` threads (framework/parallel.hpp) and their Gram matrices summed in block order, so the
// result does not depend on the thread count; an exception thrown by `design` reaches the caller.
// Returns w (columns + 1 values, the constant's weight last). Throws std::invalid_argument when the
// system cannot be factorized or the weights are not finite.
Eigen::VectorXd solve(Eigen::Index rows, Eigen::Index columns,
                      const std::function<Eigen::MatrixXd(Eigen::Index start, Eigen::Index len)>& design,
                      const Eigen::VectorXd& y, double lambda, Eigen::Index penalized = -1, unsigned threads = 1);

}  // namespace driftlab::ridge
