// Confidence intervals of the Allan-family deviations: power-law noise identification per tau,
// equivalent degrees of freedom (edf) and chi-square bounds.
//
// Noise type alpha: the rate (frequency) PSD goes as f^alpha; +2 white angle (phase) noise,
// +1 flicker angle, 0 white rate (angle random walk), -1 flicker rate (bias instability), -2 random
// walk of rate (rate random walk); -3, -4 only for the Hadamard kinds.
//
// Identification (identify_noise), per averaging factor m:
//  * at least 30 points after decimation: lag-1 autocorrelation method of W. J. Riley and
//    C. A. Greenhall, "Power law noise identification using the lag 1 autocorrelation", Proc.
//    18th EFTF 2004 (also NIST SP 1065 sec. 5.5.6). Angle input: the angle decimated by m; rate
//    input: the rate averaged over m (one difference of the decimated angle). The series is
//    differenced until delta = r1/(1+r1) < 0.25 (r1 = lag-1 autocorrelation about the mean) or the
//    number of differences of the angle, d, reaches dmax (2 Allan kinds, 3 Hadamard); then
//    alpha = round(2 - 2 delta - 2 d). No polynomial is removed first: with one, agreement with
//    Stable32's alpha column drops (2200 vs 2490 of 2664 rows with >= 30 points).
//  * fewer points: B1 ratio (standard over Allan variance of the m-averages, Barnes' B1(N, mu)
//    function, boundaries at geometric means of adjacent types), and R(n) = MVAR/AVAR to tell
//    white from flicker angle noise (SP1065 sec. 5.5.3, 5.5.4; f_h = 1/(2 tau0) assumed).
//  The result is clamped to the range the kind's edf supports (-2..2, Hadamard -4..2).
//  estimate() also holds the type from rising with tau: the variance is a sum of power laws, and the
//  longer tau, the more the redder terms (lower alpha) dominate, so the type at a tau is at most the
//  type found at any shorter tau of the same grid. Without it, the few averages at the longest taus
//  called white rate noise flicker angle noise (alpha = 1) in 5 of 20 seeded records of 2^16
//  samples, with an edf of 60-440 where white rate noise has 3-36: intervals far too narrow exactly
//  where the curve is least certain. identify_noise() itself reads one tau alone (Stable32's column).
//
// Equivalent degrees of freedom (edf):
//  * ADEV, OADEV, MDEV, HDEV, OHDEV: C. A. Greenhall and W. J. Riley, "Uncertainty of stability
//    variances based on finite differences", Proc. 35th PTTI 2003: eqs. (7)-(10) (sw, sx, sz, basic
//    sum), the cases of sec. 4 with J_max = 100, Tables 1-3. d = 2 (Allan) or 3 (Hadamard); filter
//    factor F = m (unmodified) or 1 (modified); stride S = 1 (non-overlapping) or m (overlapping).
//    For white angle noise with fewer than d+1 strides of data the exact basic sum is used.
//  * TOTDEV: SP1065 Table 7 (Howe): edf = b n/m - c, (b, c) = (1.50, 0) white rate,
//    (1.17, 0.22) flicker rate, (0.93, 0.36) random-walk rate; for angle noises (alpha = 1, 2)
//    the simple approximations of SP1065 Table 5 (Howe, Allan, Barnes 1981). This is what Stable32
//    prints.
// n is always the number of angle samples (rate samples + 1).
//
// Bounds (SP1065 eq. 45): sigma_lo^2 = edf sigma^2 / chi2(p_hi, edf), sigma_hi^2 = edf sigma^2 /
// chi2(p_lo, edf), p_lo = (1 - confidence)/2, p_hi = 1 - p_lo; chi-square quantiles from
// Boost.Math. Default confidence 0.683 (Stable32's "1 sigma").
//
// Cost: identify_noise O(n/m) (the B1 branch O(n) for the R(n) ratio); edf O(J_max) at most;
// interval O(1).
#pragma once

#include "models/allan/deviation.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <span>
#include <vector>

namespace driftlab::allan {

enum class InputType { Rate, Angle };

enum class NoiseMethod { Lag1Autocorrelation, B1Ratio };

struct NoiseEstimate {
  int alpha = 0;                // clamped integer noise type
  double alpha_estimate = 0.0;  // continuous estimate 2 - 2(delta + d) (lag-1 method only)
  NoiseMethod method = NoiseMethod::Lag1Autocorrelation;
};

// Dominant power-law noise at averaging factor m of the angle series (see above). `input` says
// whether the angle was integrated from a rate (rate-domain identification) or measured directly.
NoiseEstimate identify_noise(const Eigen::Ref<const Eigen::VectorXd>& angle, std::size_t m, Kind kind, InputType input);

// Lag-1 autocorrelation sum (z_i - mean)(z_{i+1} - mean) / sum (z_i - mean)^2 (Riley & Greenhall
// eq. 2).
double lag1_autocorrelation(const Eigen::Ref<const Eigen::VectorXd>& z);

// Range of alpha the kind's edf supports.
int min_alpha(Kind kind);
constexpr int kMaxAlpha = 2;

// Equivalent degrees of freedom of `kind` at factor m for n angle samples and noise type alpha.
double equivalent_dof(Kind kind, int alpha, std::size_t n_angle, std::size_t m);

// Greenhall & Riley's edf for a d-th difference variance with filter factor F (m or 1) and
// stride S (1 or m).
double greenhall_edf(int alpha, int d, std::size_t m, std::size_t n_angle, bool overlapping, bool modified);

// Simple edf approximations of SP1065 Table 5 for alpha in -2..2.
double simple_edf(int alpha, std::size_t n_angle, std::size_t m);

struct Interval {
  double lo = 0.0;
  double hi = 0.0;
};

constexpr double kDefaultConfidence = 0.683;

// Chi-square confidence interval of a deviation with `edf` degrees of freedom; 0 < confidence < 1.
Interval chi_square_interval(double dev, double edf, double confidence = kDefaultConfidence);

struct Estimate {
  std::size_t m = 0;
  double tau = 0.0;  // s
  double dev = 0.0;  // unit of the rate
  double dev_lo = 0.0;
  double dev_hi = 0.0;
  std::size_t terms = 0;
  int alpha = 0;  // identified noise type
  double edf = 0.0;
};

// Deviations with identified noise type (at most the type of any shorter tau, see above), edf and
// interval at each factor.
std::vector<Estimate> estimate(Kind kind, const Eigen::Ref<const Eigen::VectorXd>& angle, double tau0, InputType input,
                               std::span<const std::size_t> factors, double confidence = kDefaultConfidence);

// The same for a record of bursts (framework/sampling.hpp), each burst's angle integrated on its own
// and spaced tau0 like the others. No difference spans a gap: at each factor the kind's squared
// differences of every burst long enough for a term are summed and divided by their total number,
// sigma^2 = sum_b T_b sigma_b^2 / sum_b T_b (T_b the terms of burst b), which is the one-record
// estimator with the differences across gaps left out. The noise type at each factor is the median
// of the types identified on those bursts (then held from rising with tau as above); the bursts are
// taken as independent, so their chi-square variables add: edf = sum_b edf(kind, alpha, n_b, m).
// `terms` is sum_b T_b. Throws DataError when no burst has a term at a factor.
std::vector<Estimate> estimate_bursts(Kind kind, std::span<const Eigen::VectorXd> angles, double tau0, InputType input,
                                      std::span<const std::size_t> factors, double confidence = kDefaultConfidence);

}  // namespace driftlab::allan
