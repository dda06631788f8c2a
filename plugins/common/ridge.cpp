#include "plugins/common/ridge.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <stdexcept>

namespace driftlab::ridge {

Standardizer Standardizer::fit(const Eigen::MatrixXd& X) {
  Standardizer s;
  s.mean = X.colwise().mean();
  s.scale = ((X.rowwise() - s.mean).colwise().squaredNorm() / static_cast<double>(X.rows())).cwiseSqrt();
  for (Eigen::Index f = 0; f < s.scale.size(); ++f) {
    if (!(s.scale[f] > 0)) s.scale[f] = 1.0;
  }
  return s;
}

Eigen::VectorXd solve(Eigen::Index rows, Eigen::Index columns,
                      const std::function<Eigen::MatrixXd(Eigen::Index, Eigen::Index)>& design,
                      const Eigen::VectorXd& y, double lambda) {
  const Eigen::Index k = columns + 1;
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(k, k);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(k);
  Eigen::MatrixXd B;
  for (Eigen::Index start = 0; start < rows; start += kBlockRows) {
    const Eigen::Index len = std::min(kBlockRows, rows - start);
    B.resize(len, k);
    B.leftCols(columns) = design(start, len);
    B.col(columns).setOnes();
    gram.selfadjointView<Eigen::Lower>().rankUpdate(B.transpose());
    rhs.noalias() += B.transpose() * y.segment(start, len);
  }
  const double n = static_cast<double>(rows);
  gram = gram.selfadjointView<Eigen::Lower>();
  gram /= n;
  rhs /= n;
  gram.diagonal().head(columns).array() += lambda;
  Eigen::LDLT<Eigen::MatrixXd> ldlt(gram);
  if (ldlt.info() != Eigen::Success) throw std::invalid_argument("normal equations could not be factorized");
  Eigen::VectorXd w = ldlt.solve(rhs);
  if (!w.allFinite()) throw std::invalid_argument("least-squares weights are not finite; raise regularization");
  return w;
}

}  // namespace driftlab::ridge
