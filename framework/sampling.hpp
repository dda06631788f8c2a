// The sampling facts of a record, the one home of what every analysis asks before it assumes even
// sampling (DESIGN.md §8): the median step, the mean rate, the gaps and whether they form regular
// bursts (like the LSM6DSM thermal-vacuum run: 5 s of samples every 5 min).
//
//   gap             a time step longer than gap_factor x the median step (kGapFactor by default, the
//                   CSV reader's --max-gap default)
//   regular bursts  at least 2 gaps, and the burst periods (burst start to burst start) within
//                   kRegularBurstSpread x of each other
// Cost O(n) (the median by selection). Time in s.
#pragma once

#include <Eigen/Core>

namespace driftlab::sampling {

inline constexpr double kGapFactor = 3.0;
inline constexpr double kRegularBurstSpread = 1.5;

struct Facts {
  Eigen::Index samples = 0;
  double median_step_s = 0.0;      // 0 for fewer than 2 samples
  double mean_rate_hz = 0.0;       // (samples - 1) / span; 0 for fewer than 2 samples or a zero span
  int gaps = 0;
  double first_gap_time_s = 0.0;   // time stamp before the first gap
  double shortest_period_s = 0.0, longest_period_s = 0.0;  // burst start to burst start (with gaps)
  bool evenly_sampled() const { return gaps == 0; }
  bool regular_bursts() const { return gaps >= 2 && longest_period_s <= kRegularBurstSpread * shortest_period_s; }
};

Facts facts_of(const Eigen::VectorXd& time_s, double gap_factor = kGapFactor);

// (n - 1) / (t_last - t_first): the mean sample rate, Hz; 0 for fewer than 2 samples or a zero span.
double mean_rate_hz(const Eigen::VectorXd& time_s);

}  // namespace driftlab::sampling
