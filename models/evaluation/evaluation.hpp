// Scoring a compensated rate the way Table 2 of Li et al. 2023 does, plus the honest columns the
// paper leaves out (DESIGN.md §1). One home for `driftlab run`'s report and `driftlab compare`.
//
// Per output ("stage"), from allan::analyze_rate (models/allan/analysis.hpp):
//   - B read as the flat floor of the OADEV beyond the output's correlation time, with its interval,
//     and N read from the -1/2 line at tau = 1 s;
//   - the output's noise bandwidth relative to the white level N of the original record (N is only
//     comparable at equal bandwidth);
//   - with a truth (simulated records): the residual drift, the rms of 60-s block means of
//     (output - true rate), and the Allan curve of (output - true rate) against the intrinsic floor;
//   - with the true systematic rate as well: the systematic error, the rms of 60-s block means of
//     (output - true rate - intrinsic noise), what the stage left of the drift once the gyro's own
//     noise, which dominates the residual drift of a good stage, is taken out.
// Intrinsic floor: the same analysis of (measured - true systematic rate), i.e. the gyro's own noise,
// which no compensation can remove.
// The block means here are the one home of the residual-drift metric: `driftlab run`, `driftlab
// compare` and the held-out scores of `driftlab calibrate` (models/calibration) all use them.
// The PX4-style baseline is a calibration model (calibration::fit_px4_style), not a score.
// Units: rates rad/s, temperatures degC, times s.
#pragma once

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

#include "framework/sampling.hpp"
#include "models/allan/analysis.hpp"

namespace driftlab::evaluation {

inline constexpr double kResidualBlockS = 60.0;  // block length of the residual-drift metric

struct Truth {
  Eigen::VectorXd true_rate_rad_s;                       // the table's rate
  std::optional<Eigen::VectorXd> intrinsic_noise_rad_s;  // measured - systematic (simulator): intrinsic_noise
};

struct StageScore {
  enum class Source { Record, Pipeline, Baseline };  // the record itself, a pipeline stage, a reference model
  std::string stage;                                 // the output's name
  std::string label;                                 // what reports call it (the pipeline's stage label)
  Source source = Source::Pipeline;
  allan::Analysis analysis;                      // B, N, curve of the output
  double bandwidth_hz = 0.0;                     // noise bandwidth relative to the original record's N
  double correlation_time_s = 0.0;               // 1 / bandwidth: B is read beyond it
  std::optional<double> residual_drift_rad_s;    // rms of 60-s block means of output - true rate
  std::optional<double> systematic_error_rad_s;  // the same of output - true rate - intrinsic noise
  std::optional<allan::Analysis> error;          // Allan analysis of output - true rate
};

// Means of x over blocks of block_s seconds of time, for evenly sampled records and for records with
// gaps alike (bursts, like the LSM6DSM cooling run: 5 s of samples every ~5 min).
//   - Block k holds the samples with t0 + k block_s <= t < t0 + (k+1) block_s, t0 = time_s[0]; the
//     boundaries allow 1e-9 block_s for time stamps such as k * 0.1 s that do not add up exactly.
//   - A block without samples gives no mean (a gap, or the time between bursts).
//   - An evenly sampled record is scored on whole blocks: its last block is left out when the record
//     ends inside it (last time stamp + the record's last step < the block's end). A record with
//     gaps (a step longer than sampling::kGapFactor x the median step) keeps every non-empty block, the last
//     one too: its blocks are partial anyway (a burst record's last burst counts like the others).
// On an evenly sampled record with block_s x rate a whole number of samples this is exactly the
// sample-count blocking (whole blocks of block_s x rate samples, the remainder left out).
// Throws DataError when time_s and x differ in length.
struct BlockMeans {
  Eigen::VectorXd means;                    // one per kept block, unit of x
  std::vector<sampling::TimeBlock> blocks;  // the samples of each kept block
};
BlockMeans block_means(const Eigen::VectorXd& time_s, const Eigen::VectorXd& x, double block_s = kResidualBlockS);

// rms of block_means(time_s, x).means, unit of x. Throws DataError when no block is kept (a record
// shorter than one block).
double block_mean_rms(const Eigen::VectorXd& time_s, const Eigen::VectorXd& x, double block_s = kResidualBlockS);

// Scores one output. reference_arw_rad_sqrt_s: N of the original record (for the bandwidth);
// time_s: the record's time stamps (for the residual drift's blocks); estimated: the output's Allan
// analysis when one was already run (its curve is read again, not estimated again).
StageScore score_stage(const std::string& stage, const Eigen::VectorXd& output_rad_s, const Eigen::VectorXd& time_s,
                       double sample_rate_hz, double reference_arw_rad_sqrt_s, const Truth* truth,
                       const allan::Analysis* estimated = nullptr);

// measured - systematic: the gyro's own noise, rad/s, with the true systematic rate of a simulated
// record taken out (no compensation can do better). Throws DataError when the lengths differ.
Eigen::VectorXd intrinsic_noise(const Eigen::VectorXd& measured_rad_s, const Eigen::VectorXd& systematic_rad_s);

// Allan analysis of intrinsic_noise (read like the original record: full bandwidth).
allan::Analysis intrinsic_floor(const Eigen::VectorXd& intrinsic_noise_rad_s, double sample_rate_hz);

// The largest ratio over tau of the error curve to the intrinsic curve, and whether every tau is
// within `factor` of it once both intervals are allowed for (error.dev_lo <= factor * floor.dev_hi).
struct FloorComparison {
  double max_ratio = 0.0;
  double tau_of_max_s = 0.0;
  bool within = true;
};
FloorComparison compare_to_floor(const allan::Analysis& error, const allan::Analysis& floor, double factor);

}  // namespace driftlab::evaluation
