// Seeded white Gaussian noise for the signal-processing plugin tests (vmd, tfpf, wavelet):
// Box-Muller on framework/seeded_random.hpp's portable uniforms, so the same seed gives the same
// samples on every platform.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>

#include "framework/seeded_random.hpp"

namespace driftlab::testing_noise {

inline constexpr double kPi = 3.14159265358979323846;

inline Eigen::VectorXd standard_normal(Eigen::Index n, std::uint64_t seed) {
  SeededRandom random(seed);
  Eigen::VectorXd out(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double u1 = 1.0 - random.uniform(), u2 = random.uniform();
    out[i] = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
  }
  return out;
}

}  // namespace driftlab::testing_noise
