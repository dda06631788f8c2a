// Variational mode decomposition (VMD), as a pure numerical kernel (Eigen/std + FFTW).
//
// Dragomiretskiy & Zosso 2014, "Variational Mode Decomposition", IEEE Trans. Signal Process. 62(3),
// 531-544, Algorithm 2 (ADMM in the Fourier domain), with the conventions of the authors' reference
// code (VMD.m, also followed by vmdpy):
//
//   minimize  sum_k || d/dt[(delta(t) + j/(pi t)) * u_k(t)] e^{-j omega_k t} ||^2
//   subject to sum_k u_k = f
//
// 1. Mirror extension: the N samples are extended to M = 2N by reflecting the first floor(N/2)
//    samples before and the last N - floor(N/2) samples after the signal (half-sample symmetric:
//    the end samples repeat), which removes the jump of the periodic DFT at the ends.
// 2. f_hat = DFT of the extended signal, kept on the M/2 + 1 non-negative frequencies
//    omega = m / M, m = 0 .. M/2, in cycles per sample (the analytic half; FFTW r2c).
// 3. ADMM, for n = 0, 1, ... (Gauss-Seidel over the modes k = 1 .. K):
//      u_hat_k <- (f_hat - sum_{i != k} u_hat_i - lambda_hat / 2) / (1 + alpha (omega - omega_k)^2)
//      omega_k <- sum_omega omega |u_hat_k|^2 / sum_omega |u_hat_k|^2         (non-negative half)
//      lambda_hat <- lambda_hat + tau (sum_k u_hat_k - f_hat)
//    (the paper's eq. 27 writes 2 alpha and +lambda/2 with the opposite sign convention for
//    lambda; the reference code's 1 + alpha (omega - omega_k)^2 is what the family's alpha values,
//    e.g. 2000, refer to, so alpha here is the reference code's alpha.) The Wiener-filter half
//    width of a mode is 1 / sqrt(alpha) cycles per sample (0.022 for alpha = 2000).
//    tau = 0 drops the dual ascent (the paper's recommendation for noisy signals: no exact
//    reconstruction is enforced); tau > 0 enforces sum_k u_k = f as the iterations converge.
// 4. Stop when sum_k ||u_hat_k^{n+1} - u_hat_k^n||^2 / ||f_hat||^2 < tolerance, or after
//    max_iterations. (The reference code compares the unnormalized sum, scaled by 1/M, with the
//    tolerance, so its stopping point depends on the signal's units; normalizing by the signal's
//    spectral energy makes the criterion scale-free and equal to the reference code's for a
//    signal of unit mean-square value.)
// 5. u_k = inverse DFT of u_hat_k (Hermitian completion, FFTW c2r), restricted to the original N
//    samples.
//
// Centre-frequency initialisation (Init): Uniform omega_k = 0.5 (k - 1) / K (the reference code's
// init = 1), Zero (init = 0), Random (init = 2: omega_k = exp(ln(1/N) + (ln 0.5 - ln(1/N)) U),
// U uniform from the seeded generator, sorted). With dc = true the first mode's centre frequency is
// held at 0 (a trend mode).
//
// Output: modes sorted by centre frequency, HIGHEST first (the order of EMD's IMFs); the residue is
// x - sum_k u_k, so x = sum modes + residue holds to rounding. With tau > 0 and convergence the
// residue is small; with tau = 0 it holds what no mode's band captured.
//
// Progress (Config::progress): after an iteration that does not stop the loop, the fraction
//   p_n = max(n / max_iterations, log(c_1 / c_n) / log(c_1 / tolerance))
// of the way to the stopping rule, with c_n the stopping statistic of iteration n: the share of the
// iteration cap used, or of the decades the change has to fall by (it falls about geometrically),
// whichever is further. Reported on the calling thread when it has grown by at least 0.01 since the
// last report (at most 100 calls), in [0, 1), increasing; it jumps when the decomposition converges
// (the caller reports the end). Empty: not called. It never changes the result.
//
// Cost: O(K M) per iteration plus 2 FFTs of size M at the start and K inverse FFTs at the end.
// The per-bin update runs on separate real and imaginary arrays in an AVX2 clone
// (framework/simd.hpp); its sums are kept in four fixed lanes, so both clones give the same bits.
// Errors: std::invalid_argument for a bad configuration, std::domain_error for bad data (too
// short, non-finite).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>

namespace driftlab::vmd {

enum class Init { Uniform, Zero, Random };

struct Config {
  int modes = 4;          // K >= 1
  double alpha = 2000.0;  // bandwidth penalty (reference-code convention), > 0
  double tau = 0.0;       // dual ascent step, >= 0 (0: no exact-reconstruction constraint)
  bool dc = false;        // hold the first centre frequency at 0
  Init init = Init::Uniform;
  double tolerance = 1e-7;                        // relative change of the mode spectra, > 0
  int max_iterations = 500;                       // >= 1
  std::uint64_t seed = 1;                         // Init::Random only
  std::function<void(double fraction)> progress;  // see "Progress" above
};

struct Result {
  Eigen::MatrixXd modes;               // N x K, highest centre frequency first
  Eigen::VectorXd centre_frequencies;  // K, cycles per sample, same order as the columns
  Eigen::VectorXd residue;             // x - sum of the modes
  int iterations = 0;
  bool converged = false;
  double final_change = 0.0;  // the stopping statistic at the last iteration
};

// Needs N >= 4 finite samples.
Result decompose(const Eigen::VectorXd& x, const Config& config);

}  // namespace driftlab::vmd
