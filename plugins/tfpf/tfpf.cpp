#include "plugins/tfpf/tfpf.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>
#include <vector>

#include "plugins/signal/fftw_plan.hpp"
#include "plugins/signal/robust.hpp"

namespace driftlab::tfpf {
namespace {

using Complex = std::complex<double>;
constexpr double kPi = 3.14159265358979323846;
constexpr double kLow = 0.05, kHigh = 0.45;  // scaled IF range, cycles per sample
constexpr double kShareShort = 0.1, kShareLong = 0.9;

void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument("tfpf: " + message);
}

bool odd_at_least_3(int v) { return v >= 3 && v % 2 == 1; }

void validate(const Config& c) {
  require(odd_at_least_3(c.window), "window must be odd and >= 3");
  require(odd_at_least_3(c.short_window), "short_window must be odd and >= 3");
  require(odd_at_least_3(c.long_window), "long_window must be odd and >= 3");
  require(c.long_window >= c.short_window, "long_window must be >= short_window");
}

}  // namespace

NoiseEstimate estimate_noise(const Eigen::VectorXd& x) {
  NoiseEstimate out;
  const Eigen::Index n = x.size();
  if (n < 3) return out;
  std::vector<double> d(static_cast<std::size_t>(n - 1));
  for (Eigen::Index i = 0; i + 1 < n; ++i) d[static_cast<std::size_t>(i)] = x[i + 1] - x[i];
  const double centre = signal::median(d);
  for (double& v : d) v = std::abs(v - centre);
  out.sigma = signal::median(d) / signal::kMadToSigma / std::sqrt(2.0);
  const double variance = (x.array() - x.mean()).square().mean();
  out.share = variance > 0.0 ? std::clamp(out.sigma * out.sigma / variance, 0.0, 1.0) : 0.0;
  return out;
}

int window_for_noise_share(double share, int short_window, int long_window, Eigen::Index n) {
  double length = 0.0;
  if (share <= kShareShort) {
    length = short_window;
  } else if (share >= kShareLong) {
    length = long_window;
  } else {
    const double t = (share - kShareShort) / (kShareLong - kShareShort);
    length = short_window * std::pow(static_cast<double>(long_window) / short_window, t);
  }
  int odd = 2 * static_cast<int>(std::lround((length - 1.0) / 2.0)) + 1;
  const auto largest = static_cast<int>(std::min<Eigen::Index>(n % 2 == 1 ? n : n - 1, 1 << 30));
  return std::max(3, std::min(odd, largest));
}

Result filter(const Eigen::VectorXd& x, const Config& config) {
  validate(config);
  const Eigen::Index n = x.size();
  signal::require_finite_samples(x, 3, "tfpf");
  Result result;
  const NoiseEstimate noise = estimate_noise(x);
  result.noise_sigma = noise.sigma;
  result.noise_share = noise.share;
  result.window = config.rule == WindowRule::Fixed
                      ? std::min(config.window, static_cast<int>(n % 2 == 1 ? n : n - 1))
                      : window_for_noise_share(noise.share, config.short_window, config.long_window, n);
  result.window = std::max(result.window, 3);

  const double lo = x.minCoeff(), hi = x.maxCoeff();
  if (!(hi > lo)) {
    result.filtered = x;
    return result;
  }
  const double range = hi - lo;
  const Eigen::Index h = (result.window - 1) / 2;

  // Scaled, reflected, FM phase (steps 1-3).
  const Eigen::Index total = n + 2 * h;
  std::vector<double> phase(static_cast<std::size_t>(total));
  double previous = 0.0, accumulated = 0.0;
  for (Eigen::Index i = 0; i < total; ++i) {
    const double scaled = kLow + (kHigh - kLow) * (x[signal::reflect(i - h, n)] - lo) / range;
    if (i > 0) accumulated += kPi * (previous + scaled);
    phase[static_cast<std::size_t>(i)] = accumulated;
    previous = scaled;
  }

  // Lag window.
  std::vector<double> w(static_cast<std::size_t>(h + 1));
  for (Eigen::Index m = 0; m <= h; ++m) {
    w[static_cast<std::size_t>(m)] =
        config.lag_window == LagWindow::Rectangular
            ? 1.0
            : 0.5 * (1.0 + std::cos(kPi * static_cast<double>(m) / static_cast<double>(h + 1)));
  }

  int fft_size = 64;
  while (fft_size < 4 * (h + 1)) fft_size *= 2;
  std::vector<Complex> in(static_cast<std::size_t>(fft_size), Complex(0.0, 0.0));
  std::vector<Complex> out(static_cast<std::size_t>(fft_size));
  const fftw::Plan plan([&] {
    return fftw_plan_dft_1d(fft_size, reinterpret_cast<fftw_complex*>(in.data()),
                            reinterpret_cast<fftw_complex*>(out.data()), FFTW_FORWARD,
                            FFTW_ESTIMATE | FFTW_PRESERVE_INPUT);
  });
  const double grid = 1.0 / fft_size;

  const Eigen::Index block = (n + 99) / 100;  // samples per progress report
  result.filtered.resize(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    if (config.progress && k > 0 && k % block == 0) config.progress(static_cast<double>(k) / static_cast<double>(n));
    const Eigen::Index centre = k + h;  // index into the extended phase
    for (Eigen::Index m = 0; m <= h; ++m) {
      const double d = phase[static_cast<std::size_t>(centre + m)] - phase[static_cast<std::size_t>(centre - m)];
      in[static_cast<std::size_t>(m)] = w[static_cast<std::size_t>(m)] * Complex(std::cos(d), std::sin(d));
    }
    fftw_execute(plan.get());
    // W(f_k) = 2 Re S(f_k) - w[0]: the maximum of Re S is the maximum of W.
    int best = 0;
    double best_value = out[0].real();
    for (int b = 1; b < fft_size; ++b) {
      if (out[static_cast<std::size_t>(b)].real() > best_value) {
        best_value = out[static_cast<std::size_t>(b)].real();
        best = b;
      }
    }
    // Newton on W'(f) = 0 within one grid step of the coarse peak (step 5). With
    // e_m = w[m] exp(j (dphi_m - 2 pi f m)) = in[m] r^m, r = exp(-j 2 pi f) (powers by repeated
    // multiplication: rounding grows like m ulps), W'(f) ~ sum 2 pi m Im e_m and
    // W''(f) ~ -sum (2 pi m)^2 Re e_m (the common factor 2 cancels in the step).
    const double f0 = best * grid;
    double f = f0;
    for (int iteration = 0; iteration < 8; ++iteration) {
      const Complex rotation = std::polar(1.0, -2.0 * kPi * f);
      Complex power(1.0, 0.0);
      double first = 0.0, second = 0.0;
      for (Eigen::Index m = 1; m <= h; ++m) {
        power *= rotation;
        const Complex e = in[static_cast<std::size_t>(m)] * power;
        const double omega = 2.0 * kPi * static_cast<double>(m);
        first += omega * e.imag();
        second -= omega * omega * e.real();
      }
      if (!(second < 0.0)) break;
      const double next = std::clamp(f - first / second, f0 - grid, f0 + grid);
      const bool done = std::abs(next - f) < 1e-13;
      f = next;
      if (done) break;
    }
    result.filtered[k] = lo + (0.5 * f - kLow) * range / (kHigh - kLow);
  }
  return result;
}

}  // namespace driftlab::tfpf
