// The kernels' progress contract (plugins/emd/emd.hpp's Progress, and the kernels that follow it):
// fractions in [0, 1), increasing, the end left to the caller. A listener that records them.
#pragma once

#include <gtest/gtest.h>

#include <functional>
#include <vector>

namespace driftlab::testing_progress {

struct Recorder {
  std::vector<double> fractions;
  std::function<void(double)> listener() {
    return [this](double f) { fractions.push_back(f); };
  }
};

// Expects the contract of `fractions` and returns them.
inline std::vector<double> checked_fractions(const std::vector<double>& fractions) {
  for (std::size_t i = 0; i < fractions.size(); ++i) {
    EXPECT_GE(fractions[i], 0.0);
    EXPECT_LT(fractions[i], 1.0);
    if (i > 0) {
      EXPECT_GT(fractions[i], fractions[i - 1]);
    }
  }
  return fractions;
}

}  // namespace driftlab::testing_progress
