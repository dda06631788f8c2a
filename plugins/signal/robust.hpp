// Small helpers shared by the signal-processing kernels (vmd, tfpf, wavelet): medians for robust
// noise estimates and half-sample symmetric extension. Header only, std + Eigen.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace driftlab::signal {

// Median of |Z| for a standard normal Z: sigma = MAD / kMadToSigma for Gaussian noise.
inline constexpr double kMadToSigma = 0.6744897501960817;

// Median (mean of the two middle values for an even count); 0 for an empty vector.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  if (v.size() % 2 == 1) return *mid;
  return 0.5 * (*mid + *std::max_element(v.begin(), mid));
}

// Index i (any integer) mapped into [0, n) by half-sample symmetric reflection (period 2n: the end
// samples repeat, ... x1 x0 | x0 x1 ... x_{n-1} | x_{n-1} x_{n-2} ...).
inline Eigen::Index reflect(Eigen::Index i, Eigen::Index n) {
  Eigen::Index r = i % (2 * n);
  if (r < 0) r += 2 * n;
  return r < n ? r : 2 * n - 1 - r;
}

// Throws std::domain_error("<kernel>: ...") when x has fewer than `minimum` samples or a
// non-finite one (the kernels' shared data check).
inline void require_finite_samples(const Eigen::VectorXd& x, Eigen::Index minimum, const std::string& kernel) {
  if (x.size() < minimum) {
    throw std::domain_error(kernel + ": the signal needs at least " + std::to_string(minimum) + " samples, got " +
                            std::to_string(x.size()));
  }
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i])) throw std::domain_error(kernel + ": sample " + std::to_string(i) + " is not finite");
  }
}

}  // namespace driftlab::signal
