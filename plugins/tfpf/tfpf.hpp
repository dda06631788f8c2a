// Time-frequency peak filtering (TFPF), as a pure numerical kernel (Eigen/std + FFTW).
//
// Boashash & Mesbah 2004, "Signal enhancement by time-frequency peak filtering", IEEE Trans. Signal
// Process. 52(4), 929-937: the noisy signal is encoded as the instantaneous frequency (IF) of a
// unit-amplitude FM signal; the peak of the pseudo Wigner-Ville distribution (PWVD) of that FM
// signal is an unbiased IF estimate for a signal that is linear over the window, so the peak
// recovers the signal while the noise, integrated into the phase, is averaged out.
//
// Steps:
// 1. Scaling: x_s = a + (b - a) (x - min x) / (max x - min x), with [a, b] = [0.05, 0.45] cycles
//    per sample (the IF must stay inside (0, 0.5) for the doubled-lag kernel not to alias).
// 2. Edges: x_s is extended by h = (L - 1) / 2 samples at each end by half-sample symmetric
//    reflection, so every output sample has a full window (L = the odd window length).
// 3. FM encoding: z[n] = exp(j phi[n]), phi[n] = phi[n-1] + pi (x_s[n-1] + x_s[n]) (trapezoidal
//    integration of 2 pi x_s): phi[n+m] - phi[n-m] = 2 pi * 2m * x_s[n] exactly when x_s is
//    linear over the window.
// 4. PWVD over the lag window w (rectangular, or Hann), at time n:
//      W_n(f) = sum_{m=-h..h} w[m] z[n+m] conj(z[n-m]) e^{-j 2 pi f m}
//             = w[0] + 2 sum_{m=1..h} w[m] cos(phi[n+m] - phi[n-m] - 2 pi f m)      (real)
//    with f in cycles per lag step; its peak sits at f = 2 IF.
// 5. Peak: coarse search on the grid f = k / F (F = the FFT size, the next power of two >= 4 (h+1),
//    at least 64; one FFTW transform per sample of the one-sided lag sequence), then Newton steps
//    on W_n'(f) = 0 with analytic derivatives, kept within one grid step of the coarse peak.
// 6. Estimate: x_hat[n] = min x + (f_peak / 2 - a) (max x - min x) / (b - a).
// A constant signal is returned unchanged.
//
// Window length and the noise level. Short windows keep the signal's amplitude (the estimate is
// exact for signals linear over the window; curvature biases it by ~ x'' L^2 / 24) but remove
// little noise; long windows remove more noise and flatten peaks (Sensors 2016, 16(6), 796,
// SEEMD-TFPF; Micromachines 2024, 15(5), 609, ICEEMDAN-TFPF). The family therefore filters
// signal-dominated (mixed) components with a short window and noise-dominated ones with a long
// window. WindowRule::NoiseLevel makes that choice continuous in the component's estimated noise
// share rho = sigma^2 / var(x), where sigma = median(|x[n+1] - x[n]| - median) / 0.6745 / sqrt(2)
// (MAD of the first differences: white noise of variance sigma^2 gives differences of variance
// 2 sigma^2, while a signal smooth at the sample scale contributes little to them):
//      rho <= 0.1  -> L = short_window
//      rho >= 0.9  -> L = long_window
//      otherwise   -> L = short_window (long_window / short_window)^((rho - 0.1) / 0.8),
// rounded to the nearest odd integer and capped at the largest odd number <= N.
//
// Progress (Config::progress): the fraction of the output samples estimated, reported on the
// calling thread after each block of ceil(N / 100) samples but the last (at most 99 calls), in
// (0, 1), increasing (the caller reports the end). Empty: not called. It never changes the result.
//
// Cost: O(N F log F) for the coarse search plus O(N h) per Newton step (complex rotations, no
// trigonometric calls inside the Newton loop).
// Errors: std::invalid_argument for a bad configuration, std::domain_error for bad data (fewer than
// 3 samples, non-finite samples).
#pragma once

#include <Eigen/Core>
#include <functional>

namespace driftlab::tfpf {

enum class WindowRule { Fixed, NoiseLevel };
enum class LagWindow { Rectangular, Hann };

struct Config {
  WindowRule rule = WindowRule::NoiseLevel;
  int window = 31;       // odd, >= 3: the window length for WindowRule::Fixed
  int short_window = 9;  // odd, >= 3: NoiseLevel, signal-dominated input
  int long_window = 65;  // odd, >= short_window: NoiseLevel, noise-dominated input
  LagWindow lag_window = LagWindow::Rectangular;
  std::function<void(double fraction)> progress;  // see "Progress" above
};

struct Result {
  Eigen::VectorXd filtered;
  int window = 0;            // the window length used, samples
  double noise_sigma = 0.0;  // MAD estimate from the first differences, signal units
  double noise_share = 0.0;  // noise_sigma^2 / var(x), clamped to [0, 1]
};

// The noise estimate of the window rule (see above): {sigma, share}.
struct NoiseEstimate {
  double sigma = 0.0;
  double share = 0.0;
};
NoiseEstimate estimate_noise(const Eigen::VectorXd& x);

// The window length the rule picks for a given noise share and record length.
int window_for_noise_share(double share, int short_window, int long_window, Eigen::Index n);

Result filter(const Eigen::VectorXd& x, const Config& config);

}  // namespace driftlab::tfpf
