// Generalized method of wavelet moments (GMWM; Guerrier, Skaloud, Stebler & Victoria-Feser 2013,
// "Wavelet-variance-based estimation for composite stochastic processes", J. Am. Stat. Assoc.
// 108(503):1021-1030) for the noise of a rate record, beside the IEEE-952 slope fit (noise_fit.hpp).
//
// Moments: the Haar wavelet variance of the MODWT at scale 2m is half the Allan variance at
// averaging time tau = m dt (Percival & Walden 2000, sec. 8.6), so the moments are the variances of
// an OADEV curve (confidence.hpp: one point per averaging time, with its edf). The estimate is
//   theta = argmin sum_j w_j (a_j - A_j(theta))^2,  a_j = dev_j^2, w_j = edf_j / (2 A_j(theta)^2),
// the inverse of each point's chi-square variance 2 A^2 / edf (a diagonal Omega: the overlap of the
// points is not modelled), recomputed from the model three times after the first fit so that points
// that came out low are not favoured (as noise_fit.hpp does).
//
// Processes: closed forms of the Allan variance of the *sampled* process, exact at every m >= 1
// (dt = 1 / fs, tau = m dt; a rate in rad/s):
//   wn  white rate noise, N (rad/sqrt(s)):          N^2 / tau
//   qn  angle quantization, Q (rad):                3 Q^2 / tau^2
//   rw  rate random walk, K (rad/s/sqrt(s)):        K^2 (2 tau^2 + dt^2) / (6 tau)     (-> K^2 tau / 3)
//   dr  rate ramp, R (rad/s^2):                     R^2 tau^2 / 2
//   gm  first-order Gauss-Markov of stationary std sigma (rad/s) and correlation time T (s), sampled
//       as AR(1) with phi = exp(-dt / T):           (V_m - C_m) / m^2,
//       V_m = sigma^2 [m (1 + phi) / (1 - phi) - 2 phi (1 - phi^m) / (1 - phi)^2],
//       C_m = sigma^2 phi (1 - phi^m)^2 / (1 - phi)^2   (variance of a block sum, covariance of two
//       adjacent ones)
// A model is a sum of them, written "wn+rw+gm" (gm may repeat; the others at most once).
//
// Fit: Levenberg-Marquardt (Eigen's unsupported module) on the logarithms of N^2, Q^2, K^2, R^2,
// sigma^2 and T, from a fixed set of starts (the terms' asymptotes read off the curve, each scaled
// by 1e-2 in turn, the Gauss-Markov times spread over the curve's taus); the least objective wins.
// Deterministic: no random start. Gauss-Markov times are kept within [dt, 10 x longest tau] and
// listed in increasing order.
// Intervals, two ways; a parameter's one-sigma interval is value * exp(+-s) for a standard deviation
// s of its logarithm, and it is resolved when s < 0.5 (its value exceeds twice its delta-method
// sigma, the rule noise_fit.hpp uses) and its component is observable: its Allan variance exceeds
// the one-sigma half width A sqrt(2 / edf) of at least one point, and a Gauss-Markov time is not at
// its bound. Otherwise it is reported only as "< high"; for a component that is not observable,
// high is the level at which it would become visible (its time T has no bound: infinite), and the
// bootstrap leaves it so.
//   asymptotic  s from (J^T J)^-1 at the solution (J the Jacobian of the weighted residuals), scaled
//               by chi2/dof when that exceeds 1. Fast, but the overlapping Allan estimates are
//               correlated and the diagonal weights ignore it: optimistic (below).
//   bootstrap   (parametric) s the standard deviation over `replicates`
//               records of the same length simulated from the fit (simulate(), seeds derived from
//               (seed, replicate)), each analysed on the same octave grid and refitted as the
//               estimate was. Replicates run in parallel; the result does not depend on the
//               thread count.
// Measured (tests/models/allan_gmwm_test.cpp, 10 seeded 5-h records of white + random walk +
// Gauss-Markov noise at 10 Hz): the one-sigma intervals held the truth for 55 % (asymptotic) and
// 62 % (bootstrap, 20 replicates) of the parameters, 68.3 % nominal. Against the IEEE-952 slope fit
// of the same curves: N within 0.20 % rms (slope fit 1.3 %), K within 39 % rms (slope fit 20 %: a
// random walk and the tail of a Gauss-Markov bump trade against each other in 5 h), and sigma, T of
// the Gauss-Markov term, which the slope fit cannot express (it reads the bump as B).
//
// Cost: O(points x components) per residual evaluation; at most 400 evaluations per LM run, four
// runs (the fit and three reweightings) per start, 2 + components + 2 per gm starts: some
// milliseconds for an octave curve. The bootstrap costs `replicates` x (a
// simulation and an Allan curve of the record's length + one fit).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "models/allan/confidence.hpp"

namespace driftlab::allan::gmwm {

enum class Process { WhiteNoise, Quantization, RandomWalk, Drift, GaussMarkov };

std::string to_string(Process p);  // "wn", "qn", "rw", "dr", "gm"

// The processes of a composite model, in the order written. Throws ConfigError (field `field`)
// for an unknown name, a repeated non-gm process or an empty model, listing the names.
std::vector<Process> parse_model(const std::string& text, const std::string& field = "gmwm");
std::string to_string(const std::vector<Process>& model);  // "wn+rw+gm"

struct Parameter {
  std::string name;  // "N", "Q", "K", "R", "sigma", "T"
  std::string unit;  // SI: "rad/sqrt(s)", "rad", "rad/s/sqrt(s)", "rad/s^2", "rad/s", "s"
  double value = 0.0;
  double low = 0.0, high = 0.0;  // one-sigma interval (68.3 %)
  bool resolved = false;
};

struct Component {
  Process process = Process::WhiteNoise;
  std::vector<Parameter> parameters;  // one (two for gm: sigma, T)
  bool observable = true;             // see "resolved" above
};

struct Fit {
  std::vector<Component> components;  // in the model's order (gm components by increasing T)
  double chi2 = 0.0;                  // weighted residual sum at the solution
  std::size_t points = 0, dof = 0;
  double scale = 1.0;  // max(1, chi2 / dof), applied to the covariance
  double sample_rate_hz = 0.0;
  std::string intervals = "asymptotic";  // or "bootstrap, R replicates"
  double reduced_chi2() const { return dof > 0 ? chi2 / static_cast<double>(dof) : 0.0; }
  // Allan variance of the fitted model at averaging time tau (s), rad^2/s^2.
  double model_variance(double tau_s) const;
};

// Allan variance of one process at m samples of dt seconds, for its parameters in SI (one value, or
// sigma and T for gm).
double process_variance(Process p, std::span<const double> parameters, double m, double dt_s);

// Fits `model` to the OADEV points of a rate record sampled at sample_rate_hz (points with a
// positive deviation and edf). Throws DataError when there are fewer usable points than parameters
// + 1, ConfigError for a non-positive sample rate.
Fit fit(std::span<const Estimate> curve, double sample_rate_hz, const std::vector<Process>& model);

// A record of `samples` samples of the components' sum at sample_rate_hz (rad/s), seeded:
// white noise N sqrt(fs) e_k; quantization (theta_k - theta_{k-1}) fs with theta_k = Q e'_k; a
// random walk from 0 with increments K sqrt(dt) e''_k; the ramp R k dt; each Gauss-Markov component
// an AR(1) started in its stationary distribution. O(samples x components).
Eigen::VectorXd simulate(const std::vector<Component>& components, double sample_rate_hz, Eigen::Index samples,
                         std::uint64_t seed);

// `estimate` (a fit of a record of `samples` samples) with bootstrap intervals (above). Throws
// ConfigError for fewer than 2 replicates; a replicate whose fit fails counts against the interval
// (it is left out and the number kept is stated in Fit::intervals).
Fit bootstrap(const Fit& estimate, Eigen::Index samples, std::size_t replicates, std::uint64_t seed, unsigned threads);

}  // namespace driftlab::allan::gmwm
