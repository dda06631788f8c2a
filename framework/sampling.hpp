// The sampling facts of a record, the one home of what every analysis asks before it assumes even
// sampling (DESIGN.md §8): the median step, the mean rate, the gaps, the runs of samples between
// them and whether they form regular bursts (like the LSM6DSM thermal-vacuum run: 5 s of samples
// every 5 min).
//
//   gap             a time step longer than gap_factor x the median step (kGapFactor by default, the
//                   CSV reader's --max-gap default)
//   segment         a run of samples without a gap inside (one for an evenly sampled record)
//   regular bursts  at least 2 gaps, and the burst periods (burst start to burst start) within
//                   kRegularBurstSpread x of each other
//   irregular       any other record with gaps (one gap, or bursts of irregular period)
// An analysis that assumes even sampling (Allan family, decompositions, spectra) takes an evenly
// sampled record as it is; regular bursts only per burst (models/allan/bursts.hpp), never as one
// contiguous record; an irregular record not at all: uneven_sampling_error() names the first gap and
// the ways out. An analysis on block means (the discrepancy search) takes regular bursts as they are;
// an irregular record not: irregular_sampling_error().
// Cost O(n) (the median by selection). Time in s.
#pragma once

#include <Eigen/Core>

#include <string>
#include <string_view>
#include <vector>

#include "framework/error.hpp"

namespace driftlab::sampling {

inline constexpr double kGapFactor = 3.0;
inline constexpr double kRegularBurstSpread = 1.5;

enum class Layout { Even, RegularBursts, Irregular };

struct Segment {
  Eigen::Index first = 0;  // index of its first sample
  Eigen::Index samples = 0;
};

struct Facts {
  Eigen::Index samples = 0;
  double median_step_s = 0.0;      // 0 for fewer than 2 samples
  double mean_rate_hz = 0.0;       // (samples - 1) / span; 0 for fewer than 2 samples or a zero span
  double gap_factor = kGapFactor;  // a step longer than gap_factor x median_step_s is a gap
  int gaps = 0;
  double first_gap_time_s = 0.0;                           // time stamp before the first gap
  Eigen::Index first_gap_index = 0;                        // index of the sample before the first gap
  double first_gap_s = 0.0;                                // length of the first gap's time step
  double shortest_period_s = 0.0, longest_period_s = 0.0;  // burst start to burst start (with gaps)
  std::vector<Segment> segments;  // the runs between gaps, in time order (empty for no samples)
  bool evenly_sampled() const { return gaps == 0; }
  bool regular_bursts() const { return gaps >= 2 && longest_period_s <= kRegularBurstSpread * shortest_period_s; }
  Layout layout() const {
    return evenly_sampled() ? Layout::Even : regular_bursts() ? Layout::RegularBursts : Layout::Irregular;
  }
};

Facts facts_of(const Eigen::VectorXd& time_s, double gap_factor = kGapFactor);

// The samples of each block of block_s seconds, the one home of time blocking (residual-drift block
// means, the discrepancy search's blocks, calibration bins): block k holds the samples with
// t0 + k block_s <= t < t0 + (k+1) block_s, t0 = time_s[0]; the boundaries allow
// kBlockBoundaryTolerance x block_s, so that time stamps such as k x 0.1 s that do not add up exactly
// fall in the block they name. A block without samples (a gap) is left out. In time order; O(n).
// Throws std::invalid_argument unless block_s > 0.
inline constexpr double kBlockBoundaryTolerance = 1e-9;
struct TimeBlock {
  Eigen::Index first = 0;  // index of its first sample
  Eigen::Index samples = 0;
  long number = 0;  // k
};
std::vector<TimeBlock> time_blocks(const Eigen::VectorXd& time_s, double block_s);

// (n - 1) / (t_last - t_first): the mean sample rate, Hz; 0 for fewer than 2 samples or a zero span.
double mean_rate_hz(const Eigen::VectorXd& time_s);

// Mean sample rate inside the segments (steps across a gap left out), Hz: the rate of a burst record
// while it samples. Equals mean_rate_hz for an evenly sampled record; 0 when no segment has 2 samples.
double rate_within_segments_hz(const Eigen::VectorXd& time_s, const Facts& facts);

// One line for messages and reports: "evenly sampled at 10 Hz", "25 regular bursts of 250 samples
// at 50 Hz, one every 300 .. 305 s", "irregular: 12 gaps, not at a regular period (0.5 .. 1205 s from
// one segment's start to the next)".
std::string describe(const Facts& facts, const Eigen::VectorXd& time_s);

// The DataError for a record with gaps given to `analysis` ("an Allan analysis", "the pipeline"),
// which assumes even sampling: it names the first gap (time, length, the median step and the gap
// factor), says whether the gaps form regular bursts, and the ways out: resample onto an even grid
// with a stated method, split the record at its gaps, or analyse the segments one by one (`hint`
// adds the command that does, when there is one).
DataError uneven_sampling_error(const Facts& facts, const Eigen::VectorXd& time_s, const std::string& file,
                                std::string_view analysis, std::string_view hint = {});
// The same for an analysis that also takes regular bursts as they are (the discrepancy search: its
// block means never span a gap), given an irregular record.
DataError irregular_sampling_error(const Facts& facts, const Eigen::VectorXd& time_s, const std::string& file,
                                   std::string_view analysis, std::string_view hint = {});

}  // namespace driftlab::sampling
