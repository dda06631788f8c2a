// Noise-term fit of an Allan-variance curve (IEEE Std 952-1997 Annex C, eq. C.2):
//
//   sigma^2(tau) = 3 Q^2 / tau^2 + N^2 / tau + (2 ln 2 / pi) B^2 + K^2 tau / 3 + R^2 tau^2 / 2
//
// Q quantization (rad), N angle random walk (rad/s/sqrt(Hz) = rad/sqrt(s)), B bias instability
// (rad/s; the flat flicker floor of the Allan deviation is sqrt(2 ln 2 / pi) B = 0.664 B),
// K rate random walk (rad/s/sqrt(s) = rad/s^2/sqrt(Hz)), R rate ramp (rad/s^2); all for a rate in
// rad/s. The fit is linear in c = (Q^2, N^2, B^2, K^2, R^2) >= 0: weighted least squares over the
// curve's points with weight 1/s_i^2, s_i = (dev_hi^2 - dev_lo^2)/2 the half width of the point's
// variance interval (one standard deviation for a 68.3 % interval), combined in quadrature with a
// 5 % model tolerance (real sensors' filters and correlated noise bend the curve away from the five
// terms; without it the points with edf ~1e6 at short tau dictate every term). That width is proportional
// to the measured variance, which would favour points that came out low (a downward bias at long
// tau, where edf is small), so after the first fit the weights are recomputed from the model's
// variance with the same relative width, four times (iteratively reweighted). Constrained to c >= 0 by
// solving every subset of terms and keeping the feasible one with the least chi^2 (exact
// non-negative least squares for five unknowns). The covariance of c is (A^T W A)^-1 of the kept
// terms, scaled by chi^2/dof when that exceeds 1 (the points' overlap and model error make the
// interval weights optimistic). A term's value is sqrt(c) with sigma = sigma_c / (2 sqrt(c)); a term
// the fit sets to zero has value 0 and sigma = sqrt(sigma_c) of the fit that includes it, the level
// it could have at one sigma.
// Resolution: a term is resolved when the fit keeps it and its coefficient lies more than one sigma
// above zero (c > sigma_c, i.e. value > 2 sigma); its one-sigma interval is
// [sqrt(max(c - sigma_c, 0)), sqrt(c + sigma_c)]. An unresolved term is reported only as the bound
// value < high = sqrt(c + sigma_c) (sqrt(sigma_c) for a term set to zero), never as a value: a kept
// K of 27 +- 86 deg/h/sqrt(h) is "K < 91", and a term set to zero is not "0". chi2 / dof says how well
// the five terms describe the curve (much above 1: the curve holds something else, e.g. a bump).
//
// Unit conversions (exact): 1 rad = 180/pi deg, 1 s = 1/3600 h, 1/sqrt(s) = 60/sqrt(h).
//   Q  deg            = Q[rad]            * 180/pi
//   N  deg/sqrt(h)    = N[rad/sqrt(s)]    * 180/pi * 60
//   N  deg/h/sqrt(Hz) = N[rad/s/sqrt(Hz)] * 180/pi * 3600
//   B  deg/h          = B[rad/s]          * 180/pi * 3600
//   K  deg/h/sqrt(h)  = K[rad/s/sqrt(s)]  * 180/pi * 3600 * 60
//   R  deg/h/h        = R[rad/s^2]        * 180/pi * 3600^2
// Kalibr's continuous-time IMU noise parameters are the same quantities in SI:
//   gyroscope_noise_density [rad/s/sqrt(Hz)] = N,  gyroscope_random_walk [rad/s^2/sqrt(Hz)] = K.
//
// Cost: 32 weighted least-squares solves of at most 5 unknowns over the curve's points, O(points).
#pragma once

#include "framework/units.hpp"
#include "models/allan/confidence.hpp"

#include <array>
#include <cstddef>
#include <numbers>
#include <span>
#include <string_view>

namespace driftlab::allan {

enum class Term { Q, N, B, K, R };
constexpr std::size_t kTermCount = 5;

struct TermEstimate {
  double value = 0.0;  // SI (see above)
  double sigma = 0.0;
  bool fitted = false;    // false: the constrained fit set this term to zero
  bool resolved = false;  // fitted and c > sigma_c (see above)
  double low = 0.0;       // one-sigma interval of the value; an unresolved term is only "< high"
  double high = 0.0;
};

struct NoiseFit {
  std::array<TermEstimate, kTermCount> terms{};
  double chi2 = 0.0;  // weighted residual sum of the kept terms
  std::size_t points = 0;
  std::size_t dof = 0;  // points - kept terms
  double scale = 1.0;   // factor applied to the covariance, max(1, chi2/dof)
  double reduced_chi2() const { return dof > 0 ? chi2 / static_cast<double>(dof) : 0.0; }  // chi2/dof (0: no dof)

  const TermEstimate& operator[](Term t) const { return terms[static_cast<std::size_t>(t)]; }
  // Allan deviation of one term at tau (rad/s), and of the whole fitted model.
  double term_deviation(Term t, double tau) const;
  double model_deviation(double tau) const;
};

// Fits the five terms to the points (tau, dev, dev_lo, dev_hi) of an OADEV curve in rad/s. Throws
// driftlab::DataError with fewer than 2 usable points (positive dev and interval).
NoiseFit fit_noise_terms(std::span<const Estimate> curve);

// Basis function of a term: sigma^2(tau) contribution per unit c.
double term_basis(Term t, double tau);

struct UnitConversion {
  Term term;
  std::string_view key;
  std::string_view unit;
  double factor;  // reported = SI value * factor
};

// The usual gyro units for a rate input: Q deg, N deg/sqrt(h), B deg/h, K deg/h/sqrt(h), R deg/h/h.
constexpr std::array<UnitConversion, kTermCount> kIeee952Units{{
    {Term::Q, "Q", "deg", kDegPerRad},
    {Term::N, "N", "deg/sqrt(h)", kDegPerRad * 60.0},
    {Term::B, "B", "deg/h", kDegPerRad* kSecondsPerHour},
    {Term::K, "K", "deg/h/sqrt(h)", kDegPerRad* kSecondsPerHour * 60.0},
    {Term::R, "R", "deg/h/h", kDegPerRad* kSecondsPerHour* kSecondsPerHour},
}};

// N as a noise density in deg/h/sqrt(Hz) (the paper's Table 2 unit).
constexpr UnitConversion kNoiseDensityDegPerHour{Term::N, "N_density", "deg/h/sqrt(Hz)", kDegPerRad* kSecondsPerHour};

// Kalibr's names, SI.
constexpr std::array<UnitConversion, 2> kKalibrUnits{{
    {Term::N, "gyroscope_noise_density", "rad/s/sqrt(Hz)", 1.0},
    {Term::K, "gyroscope_random_walk", "rad/s^2/sqrt(Hz)", 1.0},
}};

}  // namespace driftlab::allan
