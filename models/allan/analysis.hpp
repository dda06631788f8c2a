// One Allan analysis of a rate record, the entry point for every caller (`driftlab allan`, the run
// report's Table 2, the discrepancy views, the benchmarks): rate -> octave taus -> overlapping
// Allan deviation -> chi-square intervals -> two readings side by side.
//
// 1. The reading of the paper and of data sheets (IEEE Std 952-1997 Annex C):
//    - B, bias instability: the flat floor of the OADEV, min sigma(tau) / sqrt(2 ln 2 / pi)
//      (= sigma / 0.664), with the tau of the minimum and the point's interval scaled the same way.
//      The minimum is taken only at tau >= min_tau_s: a low-passed output's deviation falls toward
//      short tau because its bandwidth is narrow, not because its bias is stable, so callers pass
//      the output's correlation time (correlation_time_s() below) as min_tau_s.
//      It is a B only where the curve has a floor: the minimum has a neighbour on both sides, each
//      rising or flat within the intervals (neighbour's dev_hi >= the minimum's dev_lo). A minimum at
//      the longest tau (the curve still falling where the record ends), at the shortest, or beside a
//      neighbour clearly below it (a low-passed output inside its correlation time) resolves no floor:
//      the reading is then only a bound, B < dev_hi / 0.664 at the minimum (the flicker floor lies
//      below the whole curve), "not resolved within tau <= the longest tau". Every caller reports B
//      this way (FloorReading::resolved), never the bound as a value.
//    - N, angle random walk: the -1/2 slope line through the curve at tau = 1 s, i.e.
//      N = sigma(1 s) * sqrt(1 s), the curve interpolated log-log between the neighbouring taus.
//      N of a low-passed output is only comparable with the same bandwidth (noise_bandwidth_hz()).
// 2. The least-squares Q/N/B/K/R fit of noise_fit.hpp on the same curve (labelled as a fit).
//
// Noise bandwidth: the one-sided equivalent noise bandwidth B_n (Hz) of a processed output, relative
// to the white level N of the record it came from (two-sided PSD N^2, IEEE 952): the output's
// one-sided PSD (Welch: Hann windows of 2^14 samples, or the record length if shorter, 50 % overlap)
// integrated from f_lo = 0.01 Hz to fs/2, divided by 2 N^2, plus f_lo (unit gain assumed below
// f_lo, where residual drift rather than noise would dominate the estimate). A raw white-noise
// record sampled at fs gives fs/2. The correlation time is 1 / B_n: four time constants of a
// one-pole low-pass of that noise bandwidth, after which its deviation is within a few per cent of
// the white-noise line.
// Records of regular bursts (framework/sampling.hpp) are analysed per burst, never across a gap:
// analyze_segments() pools the bursts' OADEV (confidence.hpp, estimate_bursts) on the octave grid of
// the median burst, so tau reaches only a quarter of a burst; the readings and the fit are read from
// that pooled curve the same way.
// Units: rates in rad/s, taus and times in s, deviations in rad/s, N in rad/sqrt(s).
// Cost: O(n) per tau (22 taus for 1e7 samples) plus O(n log 2^14) for the bandwidth.
#pragma once

#include <Eigen/Core>

#include <optional>
#include <span>
#include <vector>

#include "framework/sampling.hpp"
#include "models/allan/confidence.hpp"
#include "models/allan/noise_fit.hpp"

namespace driftlab::allan {

// sqrt(2 ln 2 / pi): the flat floor of the Allan deviation of flicker noise of bias instability B.
inline constexpr double kFlickerFloorFactor = 0.6642824702679600;

struct FloorReading {
  bool resolved = false;  // the minimum is a floor (see above): value is B; otherwise B < high
  double value = 0.0;     // min sigma / 0.664, rad/s
  double low = 0.0;       // interval of the point at the minimum, scaled by 1 / 0.664
  double high = 0.0;
  double tau_s = 0.0;          // tau of the minimum
  double longest_tau_s = 0.0;  // the curve's longest tau: an unresolved B is bounded within tau <= this
};

struct AnalysisOptions {
  double min_tau_s = 0.0;  // B is read at tau >= this (the output's correlation time)
  double confidence = kDefaultConfidence;
  bool fit_terms = true;  // also run the least-squares Q/N/B/K/R fit
};

struct Analysis {
  std::vector<Estimate> curve;    // OADEV on the octave grid, rad/s
  FloorReading bias_instability;  // B read as the flat floor
  double arw_rad_sqrt_s = 0.0;    // N read from the -1/2 line at tau = 1 s
  std::optional<NoiseFit> fit;    // the least-squares terms (absent when the fit failed)
  double sample_rate_hz = 0.0;
  std::size_t samples = 0;
  std::size_t segments = 1;  // bursts pooled (analyze_segments); 1 for one contiguous record
};

// Throws DataError when the record is too short for an Allan curve (fewer than 9 samples) or has
// no tau >= min_tau_s.
Analysis analyze_rate(const Eigen::Ref<const Eigen::VectorXd>& rate_rad_s, double sample_rate_hz,
                      const AnalysisOptions& options = {});
// The same from the integrated angle (rad) spaced tau0 s (an angle record, or a rate already
// integrated by angle_from_rate).
Analysis analyze_angle(const Eigen::Ref<const Eigen::VectorXd>& angle_rad, double tau0_s,
                       const AnalysisOptions& options = {});

// The readings (B, N, the fit) of a curve already estimated, read again with other options: what
// analyze_rate with `options` would give on the same data (the curve's confidence must be the same
// as options.confidence). Throws DataError like analyze_rate.
Analysis reread(const Analysis& estimated, const AnalysisOptions& options);

// The same for a record of bursts: rate_rad_s holds every burst's samples, `segments` says where each
// burst is (framework/sampling.hpp), all sampled at sample_rate_hz. Throws DataError when the median
// burst has fewer than 9 samples.
Analysis analyze_segments(const Eigen::Ref<const Eigen::VectorXd>& rate_rad_s,
                          std::span<const sampling::Segment> segments, double sample_rate_hz,
                          const AnalysisOptions& options = {});

// One-sided equivalent noise bandwidth (Hz) of `output` relative to white noise of level
// reference_arw_rad_sqrt_s (see above). Throws DataError for fewer than 64 samples.
double noise_bandwidth_hz(const Eigen::Ref<const Eigen::VectorXd>& output_rad_s, double sample_rate_hz,
                          double reference_arw_rad_sqrt_s);

inline double correlation_time_s(double noise_bandwidth_hz) { return 1.0 / noise_bandwidth_hz; }

}  // namespace driftlab::allan
