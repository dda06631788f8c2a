// Held-out scoring shared by the regressor kernels, their tuning (plugins/tuning) and the
// calibration fit: a blocked holdout split and the root-mean-square error. Eigen/std only.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace driftlab::holdout {

// Rows of a blocked holdout: the samples are cut into `blocks` equal segments and in each a
// contiguous run of round(fraction * segment length) samples, at a seeded position, is held out
// (contiguous runs limit the leakage of autocorrelated noise; spreading them over the record
// keeps the held-out inputs inside the training range). Returns sorted indices. Throws
// std::invalid_argument for a fraction outside (0, 1), no blocks, or an empty side.
struct Split {
  std::vector<Eigen::Index> train, holdout;
};
Split blocked_holdout(Eigen::Index n, double fraction, std::size_t blocks, std::uint64_t seed);

// sqrt(mean((predicted - actual)^2)), in the unit of the values; the sizes must agree.
double rmse(const Eigen::VectorXd& predicted, const Eigen::VectorXd& actual);

}  // namespace driftlab::holdout
