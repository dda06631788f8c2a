// Allan figures of a compensated record against its truth (issue 13 evidence):
//   B, N  from the overlapping Allan deviation of (output - truth) on an octave grid, read by
//         allan::analyze_rate (models/allan/analysis.hpp) like every other report:
//         B = min ADEV / sqrt(2 ln 2 / pi) (IEEE-952 flicker floor, the paper's reading), a value only
//         where the deviation has a floor, otherwise a bound (FloorReading::resolved);
//         N = ADEV at tau = 1 s (white rate noise: sigma(tau) = N / sqrt(tau)).
// Units: rad/s (B), rad/sqrt(s) (N). The residual drift (rms of 60-s block means of output - truth)
// is evaluation::block_mean_rms (models/evaluation/evaluation.hpp).
#pragma once

#include <Eigen/Core>
#include <optional>

#include "models/allan/analysis.hpp"

namespace driftlab::calibration {

// The analysis B and N are read from (its curve: the OADEV on the octave grid, with intervals; no
// term fit). Empty when the record is too short (< 3 s) or not evenly sampled enough for an Allan
// analysis.
std::optional<allan::Analysis> allan_figures(const Eigen::VectorXd& error_rad_s, double sample_rate_hz);

// N and K (rate random walk) fitted to the Allan curve (IEEE-952 five-term fit), for the model's
// noise terms (Kalman stage, Kalibr export). Empty when the fit is impossible. A term the fit does
// not resolve (allan::TermEstimate::resolved) has its bound in *_upper (models/allan/noise_fit.hpp).
struct FittedNoise {
  double arw_rad_sqrt_s = 0.0, arw_sigma = 0.0;
  double bias_instability_rad_s = 0.0;
  double rate_random_walk_rad_s_sqrt_s = 0.0, rate_random_walk_sigma = 0.0;
  std::optional<double> arw_upper, bias_instability_upper, rate_random_walk_upper;  // not resolved: value < this
};
std::optional<FittedNoise> fit_noise(const Eigen::VectorXd& error_rad_s, double sample_rate_hz);

}  // namespace driftlab::calibration
