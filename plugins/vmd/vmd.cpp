#include "plugins/vmd/vmd.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "framework/seeded_random.hpp"
#include "framework/simd.hpp"
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

struct SpectrumView {
  const double* freq;  // cycles per sample, per bin
  const double* f_re;
  const double* f_im;
  const double* lambda_re;
  const double* lambda_im;
  std::size_t bins;
};

struct ModeSums {
  double change = 0.0;    // sum |u_new - u_old|^2
  double energy = 0.0;    // sum |u_new|^2
  double weighted = 0.0;  // sum f |u_new|^2
};

// One mode's Wiener-filter update (step 3) over all bins; updates the running sum of the modes.
// The three sums are accumulated in four lanes (bin b into lane b mod 4) and added as
// (l0 + l1) + (l2 + l3), so the AVX2 and the baseline clone give the same bits.
DRIFTLAB_SIMD_CLONES
ModeSums update_mode(const SpectrumView& s, double alpha, double centre, double* __restrict u_re,
                     double* __restrict u_im, double* __restrict sum_re, double* __restrict sum_im) {
  constexpr std::size_t kLanes = 4;
  double change[kLanes] = {}, energy[kLanes] = {}, weighted[kLanes] = {};
  const std::size_t full = s.bins - s.bins % kLanes;
  auto step = [&](std::size_t b, std::size_t lane) {
    const double d = s.freq[b] - centre;
    const double gain = 1.0 / (1.0 + alpha * d * d);
    const double new_re = (s.f_re[b] - (sum_re[b] - u_re[b]) - 0.5 * s.lambda_re[b]) * gain;
    const double new_im = (s.f_im[b] - (sum_im[b] - u_im[b]) - 0.5 * s.lambda_im[b]) * gain;
    const double delta_re = new_re - u_re[b], delta_im = new_im - u_im[b];
    u_re[b] = new_re;
    u_im[b] = new_im;
    sum_re[b] += delta_re;
    sum_im[b] += delta_im;
    change[lane] += delta_re * delta_re + delta_im * delta_im;
    const double p = new_re * new_re + new_im * new_im;
    energy[lane] += p;
    weighted[lane] += s.freq[b] * p;
  };
  for (std::size_t b = 0; b < full; b += kLanes) {
    for (std::size_t lane = 0; lane < kLanes; ++lane) step(b + lane, lane);
  }
  for (std::size_t b = full; b < s.bins; ++b) step(b, b - full);
  return {(change[0] + change[1]) + (change[2] + change[3]), (energy[0] + energy[1]) + (energy[2] + energy[3]),
          (weighted[0] + weighted[1]) + (weighted[2] + weighted[3])};
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

// The progress fraction of the header ("Progress") after iteration n with stopping statistic
// `change`, given the first iteration's statistic `first`.
double progress_fraction(const Config& c, int n, double first, double change) {
  double fraction = static_cast<double>(n) / c.max_iterations;
  if (first > c.tolerance && change < first) {
    const double decades = change > 0.0 ? std::log(first / change) / std::log(first / c.tolerance) : 1.0;
    fraction = std::max(fraction, decades);
  }
  return std::min(fraction, 1.0);
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

  // Spectra as separate real and imaginary arrays (vectorizable update, step 3).
  std::vector<double> f_re(nb), f_im(nb);
  double f_energy = 0.0;
  for (std::size_t b = 0; b < nb; ++b) {
    f_re[b] = f_hat[b].real();
    f_im[b] = f_hat[b].imag();
    f_energy += std::norm(f_hat[b]);
  }

  std::vector<double> omega = initial_centres(config, n);
  std::vector<double> u_re(k_count * nb, 0.0), u_im(k_count * nb, 0.0);
  std::vector<double> sum_re(nb, 0.0), sum_im(nb, 0.0);        // sum of all current modes
  std::vector<double> lambda_re(nb, 0.0), lambda_im(nb, 0.0);  // dual variable
  const SpectrumView spectrum{freq.data(), f_re.data(), f_im.data(), lambda_re.data(), lambda_im.data(), nb};

  Result result;
  double first_change = 0.0, reported = 0.0;
  for (int iteration = 1; iteration <= config.max_iterations; ++iteration) {
    double change = 0.0;
    for (std::size_t k = 0; k < k_count; ++k) {
      const ModeSums sums = update_mode(spectrum, config.alpha, omega[k], u_re.data() + k * nb, u_im.data() + k * nb,
                                        sum_re.data(), sum_im.data());
      change += sums.change;
      if (!(config.dc && k == 0) && sums.energy > 0.0) omega[k] = sums.weighted / sums.energy;
    }
    if (config.tau > 0.0) {
      for (std::size_t b = 0; b < nb; ++b) {
        lambda_re[b] += config.tau * (sum_re[b] - f_re[b]);
        lambda_im[b] += config.tau * (sum_im[b] - f_im[b]);
      }
    }
    result.iterations = iteration;
    result.final_change = f_energy > 0.0 ? change / f_energy : 0.0;
    if (result.final_change < config.tolerance) {
      result.converged = true;
      break;
    }
    if (iteration == 1) first_change = result.final_change;
    if (config.progress) {
      const double fraction = progress_fraction(config, iteration, first_change, result.final_change);
      if (fraction < 1.0 && fraction >= reported + 0.01) config.progress(reported = fraction);
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
    for (std::size_t b = 0; b < nb; ++b) spectrum_buffer[b] = Complex(u_re[k * nb + b], u_im[k * nb + b]);
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
