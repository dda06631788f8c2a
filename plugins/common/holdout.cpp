#include "plugins/common/holdout.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "framework/seeded_random.hpp"

namespace driftlab::holdout {

Split blocked_holdout(Eigen::Index n, double fraction, std::size_t blocks, std::uint64_t seed) {
  if (!(fraction > 0 && fraction < 1)) throw std::invalid_argument("holdout fraction must lie in (0, 1)");
  if (blocks < 1) throw std::invalid_argument("holdout needs at least one block");
  SeededRandom rng(seed);
  std::vector<bool> held(static_cast<std::size_t>(n), false);
  const auto b = static_cast<Eigen::Index>(blocks);
  for (Eigen::Index s = 0; s < b; ++s) {
    const Eigen::Index begin = s * n / b;
    const Eigen::Index length = (s + 1) * n / b - begin;
    const auto run = static_cast<Eigen::Index>(std::llround(fraction * static_cast<double>(length)));
    if (run == 0) continue;
    const auto start = begin + static_cast<Eigen::Index>(rng.index(static_cast<std::size_t>(length - run + 1)));
    for (Eigen::Index i = start; i < start + run; ++i) held[static_cast<std::size_t>(i)] = true;
  }
  Split split;
  for (Eigen::Index i = 0; i < n; ++i) (held[static_cast<std::size_t>(i)] ? split.holdout : split.train).push_back(i);
  if (split.train.empty() || split.holdout.empty()) {
    throw std::invalid_argument("holdout of " + std::to_string(n) + " samples leaves an empty training or holdout set");
  }
  return split;
}

double rmse(const Eigen::VectorXd& predicted, const Eigen::VectorXd& actual) {
  return std::sqrt((predicted - actual).squaredNorm() / static_cast<double>(actual.size()));
}

}  // namespace driftlab::holdout
