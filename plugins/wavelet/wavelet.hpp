// Wavelet-threshold denoising, as a pure numerical kernel (Eigen/std + GSL's discrete wavelet
// transform).
//
//   Donoho & Johnstone 1994, "Ideal spatial adaptation by wavelet shrinkage", Biometrika 81(3),
//     425-455 (VisuShrink: the universal threshold sigma sqrt(2 ln n), hard and soft rules);
//   Donoho 1995, "De-noising by soft-thresholding", IEEE Trans. Inf. Theory 41(3), 613-627;
//   Donoho & Johnstone 1995, "Adapting to unknown smoothness via wavelet shrinkage", JASA 90(432),
//     1200-1224 (SureShrink: per-level SURE threshold, and the hybrid rule for sparse levels);
//   Johnstone & Silverman 1997, "Wavelet threshold estimators for data with correlated noise",
//     JRSS B 59(2) (level-dependent noise estimates).
//
// Steps:
// 1. The N samples are extended to M = the next power of two >= N (GSL transforms powers of two
//    only), by half-sample symmetric reflection split between both ends (floor((M - N) / 2) before,
//    the rest after; reflected again if the padding is longer than the signal). GSL's transform is
//    periodic: with N a power of two the signal is wrapped as it is, end to start.
// 2. Forward DWT (gsl_wavelet_transform_forward) over all log2 M levels. Detail level l = 1 is the
//    finest (M/2 coefficients, GSL level J - 1), l = 2 the next, ...
// 3. The details of levels 1 .. L (L = `levels`, at most log2 M) are thresholded; coarser details
//    and the scaling coefficient are kept. For an orthogonal wavelet this equals an L-level
//    transform whose approximation is kept. L is lowered to log2 M when the record is too short
//    (reported in Result::levels).
// 4. Noise level sigma (in signal units): FinestLevel: sigma = median(|d_1|) / 0.6745 for every
//    level (Donoho & Johnstone 1994, white noise); PerLevel: sigma_l = median(|d_l|) / 0.6745
//    (Johnstone & Silverman 1997, coloured noise such as a gyro's flicker). 0.6745 is the median of
//    |Z| for a standard normal Z.
// 5. Threshold per level, lambda_l = sigma_l t_l, with t_l on the coefficients normalized by sigma:
//      Universal:  t = sqrt(2 ln N)                    (N = the number of samples)
//      Sure:       t = argmin_{0 <= t <= sqrt(2 ln n_l)} SURE(t), over the level's n_l coefficients
//                  y = d / sigma:  SURE(t) = n_l - 2 #{i : |y_i| <= t} + sum_i min(|y_i|, t)^2
//                  (Stein's unbiased risk estimate of soft thresholding; the minimum lies at 0 or at
//                  one of the |y_i|; ties go to the smallest t)
//      SureHybrid: Universal with n = n_l when the level is sparse,
//                  s^2 = (sum_i y_i^2 - n_l) / n_l <= (log2 n_l)^(3/2) / sqrt(n_l), else Sure
//                  (Donoho & Johnstone 1995 Sec. 2.3; MATLAB's 'heursure').
// 6. Rule: soft  eta(d) = sign(d) max(|d| - lambda, 0);  hard  eta(d) = d 1{|d| > lambda}.
// 7. Inverse DWT; the N original samples are returned.
//
// Progress (Config::progress): the share of the work done, counted in coefficients: the forward
// transform M, each thresholded level its n_l, the inverse transform M. Reported on the calling
// thread after the forward transform and after each thresholded level (at most 1 + log2 M calls),
// in (0, 1), increasing (the caller reports the end). Empty: not called. It never changes the
// result.
//
// Wavelet families (GSL): Daubechies (maximum phase, k/2 vanishing moments, k = 4, 6, ..., 20;
// k = 8 is MATLAB's 'db4'), Haar (k = 2), biorthogonal B-spline (k = 100 i + j: 103, 105, 202,
// 204, 206, 208, 301, 303, 305, 307, 309), each also "centered" (coefficients aligned on the
// sub-band edges). Daubechies and Haar are orthonormal (white noise stays white, sigma equal on
// every level); B-splines are biorthogonal, so the thresholds' white-noise calibration is
// approximate there.
//
// Errors: std::invalid_argument for a bad configuration (including an order the family does not
// have), std::domain_error for bad data (fewer than 8 samples, non-finite samples).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <vector>

namespace driftlab::wavelet {

enum class Family { Daubechies, DaubechiesCentered, Haar, HaarCentered, Bspline, BsplineCentered };
enum class ThresholdRule { Universal, Sure, SureHybrid };
enum class Shrink { Soft, Hard };
enum class NoiseEstimate { FinestLevel, PerLevel };

struct Config {
  Family family = Family::Daubechies;
  int order = 8;   // GSL's k
  int levels = 5;  // detail levels thresholded, >= 1
  ThresholdRule rule = ThresholdRule::Universal;
  Shrink shrink = Shrink::Soft;
  NoiseEstimate noise = NoiseEstimate::FinestLevel;
  std::function<void(double fraction)> progress;  // see "Progress" above
};

struct Result {
  Eigen::VectorXd denoised;
  int levels = 0;                  // levels actually thresholded (finest first below)
  std::vector<double> sigma;       // noise level per thresholded level, signal units
  std::vector<double> thresholds;  // lambda per thresholded level, signal units
  std::vector<std::size_t> kept;   // coefficients above the threshold, per level
};

// True when GSL implements order k for the family.
bool valid_order(Family family, int order);

Result denoise(const Eigen::VectorXd& x, const Config& config);

// Building blocks (exposed for tests).
double mad_sigma(std::vector<double> coefficients);        // median(|c|) / 0.6745
double universal_threshold(std::size_t n);                 // sqrt(2 ln n), in units of sigma
double sure_risk(const std::vector<double>& y, double t);  // SURE(t) for normalized y
double sure_threshold(const std::vector<double>& y);       // argmin over [0, sqrt(2 ln n)]
double hybrid_sure_threshold(const std::vector<double>& y);
double soft(double d, double lambda);
double hard(double d, double lambda);

}  // namespace driftlab::wavelet
