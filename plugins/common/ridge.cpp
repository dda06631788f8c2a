#include "plugins/common/ridge.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <stdexcept>
#include <vector>

#include "framework/parallel.hpp"

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
                      const Eigen::VectorXd& y, double lambda, Eigen::Index penalized, unsigned threads) {
  const Eigen::Index k = columns + 1;
  const Eigen::Index blocks = (rows + kBlockRows - 1) / kBlockRows;
  std::vector<Eigen::MatrixXd> grams(static_cast<std::size_t>(blocks));
  std::vector<Eigen::VectorXd> rhss(static_cast<std::size_t>(blocks));
  parallel_for(static_cast<std::size_t>(blocks), threads, [&](std::size_t block) {
    const auto b = static_cast<Eigen::Index>(block);
    const Eigen::Index start = b * kBlockRows, len = std::min(kBlockRows, rows - start);
    Eigen::MatrixXd B(len, k);
    B.leftCols(columns) = design(start, len);
    B.col(columns).setOnes();
    auto& g = grams[block] = Eigen::MatrixXd::Zero(k, k);
    g.selfadjointView<Eigen::Lower>().rankUpdate(B.transpose());
    rhss[block] = B.transpose() * y.segment(start, len);
  });
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(k, k);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(k);
  for (Eigen::Index b = 0; b < blocks; ++b) {
    gram += grams[static_cast<std::size_t>(b)];
    rhs += rhss[static_cast<std::size_t>(b)];
  }
  const double n = static_cast<double>(rows);
  gram = gram.selfadjointView<Eigen::Lower>();
  gram /= n;
  rhs /= n;
  gram.diagonal().head(penalized < 0 ? columns : std::min(penalized, columns)).array() += lambda;
  Eigen::LDLT<Eigen::MatrixXd> ldlt(gram);
  if (ldlt.info() != Eigen::Success) throw std::invalid_argument("normal equations could not be factorized");
  Eigen::VectorXd w = ldlt.solve(rhs);
  if (!w.allFinite()) throw std::invalid_argument("least-squares weights are not finite; raise regularization");
  return w;
}

}  // namespace driftlab::ridge
