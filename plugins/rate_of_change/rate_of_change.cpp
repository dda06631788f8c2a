#include "plugins/rate_of_change/rate_of_change.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace driftlab::rate_of_change {

Eigen::VectorXd centred_slope(const Eigen::VectorXd& time_s, const Eigen::VectorXd& x, double window_s) {
  const Eigen::Index n = x.size();
  if (n < 2 || time_s.size() != n) throw std::invalid_argument("needs at least 2 samples with one time stamp each");
  std::vector<double> steps(static_cast<std::size_t>(n - 1));
  for (Eigen::Index k = 0; k + 1 < n; ++k) steps[static_cast<std::size_t>(k)] = time_s[k + 1] - time_s[k];
  std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
  const double dt = steps[steps.size() / 2];
  if (!(dt > 0.0)) throw std::invalid_argument("time stamps must increase");
  const auto h = std::max<Eigen::Index>(1, std::llround(window_s / (2.0 * dt)));
  Eigen::VectorXd slope(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const Eigen::Index lo = std::max<Eigen::Index>(0, k - h), hi = std::min<Eigen::Index>(n - 1, k + h);
    slope[k] = (x[hi] - x[lo]) / (time_s[hi] - time_s[lo]);
  }
  return slope;
}

}  // namespace driftlab::rate_of_change
