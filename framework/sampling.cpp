#include "framework/sampling.hpp"

#include <algorithm>
#include <vector>

#include "framework/signal.hpp"

namespace driftlab::sampling {

double mean_rate_hz(const Eigen::VectorXd& time_s) {
  const Eigen::Index n = time_s.size();
  if (n < 2) return 0.0;
  const double span = time_s[n - 1] - time_s[0];
  return span > 0.0 ? static_cast<double>(n - 1) / span : 0.0;
}

Facts facts_of(const Eigen::VectorXd& time_s, double gap_factor) {
  Facts f;
  f.samples = time_s.size();
  f.mean_rate_hz = mean_rate_hz(time_s);
  if (time_s.size() < 2) return f;
  f.median_step_s = signal::median_step(time_s);
  if (time_s.size() < 3) return f;
  const double limit = gap_factor * f.median_step_s;
  std::vector<double> starts{time_s[0]};
  for (Eigen::Index k = 0; k + 1 < time_s.size(); ++k) {
    if (time_s[k + 1] - time_s[k] <= limit) continue;
    if (f.gaps++ == 0) f.first_gap_time_s = time_s[k];
    starts.push_back(time_s[k + 1]);
  }
  for (std::size_t i = 1; i < starts.size(); ++i) {
    const double period = starts[i] - starts[i - 1];
    f.shortest_period_s = i == 1 ? period : std::min(f.shortest_period_s, period);
    f.longest_period_s = std::max(f.longest_period_s, period);
  }
  return f;
}

}  // namespace driftlab::sampling
