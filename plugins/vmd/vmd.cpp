#include "plugins/vmd/vmd.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "framework/seeded_random.hpp"
#include "plugins/signal/fftw_plan.hpp"
#include "plugins/signal/robust.hpp"

namespace driftlab::vmd {
namespace {

using Complex = std::complex<double>;

void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument("vmd: " + message);
}

void validate(const Config& c) {
  require(c.modes >= 1, "modes must be >= 1");
  require(std::isfinite(c.alpha) && c.alpha > 0.0, "alpha must be finite and > 0");
  require(std::isfinite(c.tau) && c.tau >= 0.0, "tau must be finite and >= 0");
  require(std::isfinite(c.tolerance) && c.tolerance > 0.0, "tolerance must be finite and > 0");
  require(c.max_iterations >= 1, "max_iterations must be >= 1");
}

fftw_complex* as_fftw(Complex* p) { return reinterpret_cast<fftw_complex*>(p); }

// Half-sample symmetric extension to 2N samples (step 1 of the header).
std::vector<double> mirror(const Eigen::VectorXd& x) {
  const Eigen::Index n = x.size();
  std::vector<double> out(static_cast<std::size_t>(2 * n));
  for (Eigen::Index i = 0; i < 2 * n; ++i) out[static_cast<std::size_t>(i)] = x[signal::reflect(i - n / 2, n)];
  return out;
}

std::vector<double> initial_centres(const Config& c, Eigen::Index n) {
  const auto k_count = static_cast<std::size_t>(c.modes);
  std::vector<double> omega(k_count, 0.0);
  if (c.init == Init::Uniform) {
    for (std::size_t k = 0; k < k_count; ++k) omega[k] = 0.5 * static_cast<double>(k) / c.modes;
  } else if (c.init == Init::Random) {
    SeededRandom random(c.seed);
    const double low = std::log(1.0 / static_cast<double>(n));
    const double high = std::log(0.5);
    for (auto& w : omega) w = std::exp(low + (high - low) * random.uniform());
    std::sort(omega.begin(), omega.end());
  }
  if (c.dc) omega[0] = 0.0;
  return omega;
}

}  // namespace

Result decompose(const Eigen::VectorXd& x, const Config& config) {
  validate(config);
  const Eigen::Index n = x.size();
  signal::require_finite_samples(x, 4, "vmd");

  const Eigen::Index m = 2 * n;         // extended length
  const Eigen::Index bins = m / 2 + 1;  // non-negative frequencies
  const auto nb = static_cast<std::size_t>(bins);
  const auto k_count = static_cast<std::size_t>(config.modes);

  std::vector<double> extended = mirror(x);
  std::vector<Complex> f_hat(nb);
  std::vector<double> time_buffer(static_cast<std::size_t>(m));
  std::vector<Complex> spectrum_buffer(nb);
  const fftw::Plan forward([&] {
    return fftw_plan_dft_r2c_1d(static_cast<int>(m), time_buffer.data(), as_fftw(spectrum_buffer.data()),
                                FFTW_ESTIMATE);
  });
  const fftw::Plan backward([&] {
    return fftw_plan_dft_c2r_1d(static_cast<int>(m), as_fftw(spectrum_buffer.data()), time_buffer.data(),
                                FFTW_ESTIMATE);
  });
  fftw_execute_dft_r2c(forward.get(), extended.data(), as_fftw(f_hat.data()));

  std::vector<double> freq(nb);
  for (std::size_t b = 0; b < nb; ++b) freq[b] = static_cast<double>(b) / static_cast<double>(m);

  double f_energy = 0.0;
  for (const Complex& v : f_hat) f_energy += std::norm(v);

  std::vector<double> omega = initial_centres(config, n);
  std::vector<Complex> u_hat(k_count * nb, Complex(0.0, 0.0));
  std::vector<Complex> sum(nb, Complex(0.0, 0.0));     // sum of all current modes
  std::vector<Complex> lambda(nb, Complex(0.0, 0.0));  // dual variable

  Result result;
  const double alpha = config.alpha;
  for (int iteration = 1; iteration <= config.max_iterations; ++iteration) {
    double change = 0.0;
    for (std::size_t k = 0; k < k_count; ++k) {
      Complex* u = u_hat.data() + k * nb;
      const double wk = omega[k];
      double weighted = 0.0, energy = 0.0;
      for (std::size_t b = 0; b < nb; ++b) {
        const Complex old = u[b];
        const double d = freq[b] - wk;
        const Complex updated = (f_hat[b] - (sum[b] - old) - 0.5 * lambda[b]) / (1.0 + alpha * d * d);
        u[b] = updated;
        sum[b] += updated - old;
        change += std::norm(updated - old);
        const double p = std::norm(updated);
        energy += p;
        weighted += freq[b] * p;
      }
      if (!(config.dc && k == 0) && energy > 0.0) omega[k] = weighted / energy;
    }
    if (config.tau > 0.0) {
      for (std::size_t b = 0; b < nb; ++b) lambda[b] += config.tau * (sum[b] - f_hat[b]);
    }
    result.iterations = iteration;
    result.final_change = f_energy > 0.0 ? change / f_energy : 0.0;
    if (result.final_change < config.tolerance) {
      result.converged = true;
      break;
    }
  }

  // Highest centre frequency first.
  std::vector<std::size_t> order(k_count);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return omega[a] > omega[b]; });

  const Eigen::Index half = n / 2;
  result.modes.resize(n, config.modes);
  result.centre_frequencies.resize(config.modes);
  const double scale = 1.0 / static_cast<double>(m);
  for (std::size_t column = 0; column < k_count; ++column) {
    const std::size_t k = order[column];
    std::copy_n(u_hat.data() + k * nb, nb, spectrum_buffer.data());
    // The DC and Nyquist bins of a real signal's spectrum are real; c2r uses their real parts.
    fftw_execute_dft_c2r(backward.get(), as_fftw(spectrum_buffer.data()), time_buffer.data());
    const auto col = static_cast<Eigen::Index>(column);
    for (Eigen::Index i = 0; i < n; ++i) result.modes(i, col) = time_buffer[static_cast<std::size_t>(half + i)] * scale;
    result.centre_frequencies[col] = omega[k];
  }
  result.residue = x - result.modes.rowwise().sum();
  return result;
}

}  // namespace driftlab::vmd
