#include "plugins/wavelet/wavelet.hpp"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_wavelet.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "plugins/signal/robust.hpp"

namespace driftlab::wavelet {
namespace {

void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument("wavelet: " + message);
}

const gsl_wavelet_type* gsl_type(Family family) {
  switch (family) {
    case Family::Daubechies:
      return gsl_wavelet_daubechies;
    case Family::DaubechiesCentered:
      return gsl_wavelet_daubechies_centered;
    case Family::Haar:
      return gsl_wavelet_haar;
    case Family::HaarCentered:
      return gsl_wavelet_haar_centered;
    case Family::Bspline:
      return gsl_wavelet_bspline;
    case Family::BsplineCentered:
      return gsl_wavelet_bspline_centered;
  }
  return gsl_wavelet_daubechies;
}

struct WaveletDeleter {
  void operator()(gsl_wavelet* w) const { gsl_wavelet_free(w); }
};
struct WorkspaceDeleter {
  void operator()(gsl_wavelet_workspace* w) const { gsl_wavelet_workspace_free(w); }
};

}  // namespace

bool valid_order(Family family, int order) {
  switch (family) {
    case Family::Daubechies:
    case Family::DaubechiesCentered:
      return order >= 4 && order <= 20 && order % 2 == 0;
    case Family::Haar:
    case Family::HaarCentered:
      return order == 2;
    case Family::Bspline:
    case Family::BsplineCentered:
      for (const int k : {103, 105, 202, 204, 206, 208, 301, 303, 305, 307, 309}) {
        if (order == k) return true;
      }
      return false;
  }
  return false;
}

double mad_sigma(std::vector<double> coefficients) {
  if (coefficients.empty()) return 0.0;
  for (double& c : coefficients) c = std::abs(c);
  return signal::median(std::move(coefficients)) / signal::kMadToSigma;
}

double universal_threshold(std::size_t n) { return n < 2 ? 0.0 : std::sqrt(2.0 * std::log(static_cast<double>(n))); }

double sure_risk(const std::vector<double>& y, double t) {
  double risk = static_cast<double>(y.size());
  for (const double v : y) {
    const double a = std::abs(v);
    if (a <= t) risk -= 2.0;
    const double m = std::min(a, t);
    risk += m * m;
  }
  return risk;
}

double sure_threshold(const std::vector<double>& y) {
  const std::size_t n = y.size();
  if (n == 0) return 0.0;
  const double cap = universal_threshold(n);
  std::vector<double> a(n);
  for (std::size_t i = 0; i < n; ++i) a[i] = std::abs(y[i]);
  std::sort(a.begin(), a.end());
  // SURE(t) at t = a[k-1] (k smallest at or below t): n - 2k + sum_{i<k} a_i^2 + (n - k) t^2.
  // Equal magnitudes: evaluated at the last of a run, where the count includes the whole run.
  double best_t = 0.0, best_risk = static_cast<double>(n);  // t = 0
  double cumulative = 0.0;
  for (std::size_t k = 1; k <= n; ++k) {
    const double t = a[k - 1];
    cumulative += t * t;
    if (t > cap) break;
    if (k < n && a[k] == t) continue;
    const auto kd = static_cast<double>(k);
    const double risk = static_cast<double>(n) - 2.0 * kd + cumulative + (static_cast<double>(n) - kd) * t * t;
    if (risk < best_risk) {
      best_risk = risk;
      best_t = t;
    }
  }
  // The cap itself, when it lies between two magnitudes.
  if (sure_risk(y, cap) < best_risk) best_t = cap;
  return best_t;
}

double hybrid_sure_threshold(const std::vector<double>& y) {
  const std::size_t n = y.size();
  if (n == 0) return 0.0;
  const auto nd = static_cast<double>(n);
  double energy = 0.0;
  for (const double v : y) energy += v * v;
  const double s2 = (energy - nd) / nd;
  const double sparse_bound = std::pow(std::log2(nd), 1.5) / std::sqrt(nd);
  return s2 <= sparse_bound ? universal_threshold(n) : sure_threshold(y);
}

double soft(double d, double lambda) {
  const double a = std::abs(d) - lambda;
  return a > 0.0 ? std::copysign(a, d) : 0.0;
}

double hard(double d, double lambda) { return std::abs(d) > lambda ? d : 0.0; }

Result denoise(const Eigen::VectorXd& x, const Config& config) {
  require(valid_order(config.family, config.order),
          "order " + std::to_string(config.order) + " is not implemented for this wavelet family");
  require(config.levels >= 1, "levels must be >= 1");
  const Eigen::Index n = x.size();
  signal::require_finite_samples(x, 8, "wavelet");

  Eigen::Index m = 1;
  int total_levels = 0;
  while (m < n) {
    m *= 2;
    ++total_levels;
  }
  const Eigen::Index before = (m - n) / 2;
  std::vector<double> data(static_cast<std::size_t>(m));
  for (Eigen::Index i = 0; i < m; ++i) data[static_cast<std::size_t>(i)] = x[signal::reflect(i - before, n)];

  // Orders are validated above, so GSL's allocation cannot fail on them; a null means no memory.
  std::unique_ptr<gsl_wavelet, WaveletDeleter> w(
      gsl_wavelet_alloc(gsl_type(config.family), static_cast<std::size_t>(config.order)));
  std::unique_ptr<gsl_wavelet_workspace, WorkspaceDeleter> work(
      gsl_wavelet_workspace_alloc(static_cast<std::size_t>(m)));
  if (!w || !work) throw std::runtime_error("wavelet: GSL could not allocate the transform");
  if (gsl_wavelet_transform_forward(w.get(), data.data(), 1, static_cast<std::size_t>(m), work.get()) != GSL_SUCCESS) {
    throw std::runtime_error("wavelet: GSL forward transform failed");
  }

  Result result;
  result.levels = std::min(config.levels, total_levels);
  // Level l (1 = finest) holds GSL indices [2^(J - l), 2^(J - l + 1)).
  auto level_range = [&](int l) {
    const Eigen::Index begin = Eigen::Index{1} << (total_levels - l);
    return std::pair<std::size_t, std::size_t>(static_cast<std::size_t>(begin), static_cast<std::size_t>(2 * begin));
  };
  auto level_coefficients = [&](int l) {
    const auto [b, e] = level_range(l);
    return std::vector<double>(data.begin() + static_cast<std::ptrdiff_t>(b),
                               data.begin() + static_cast<std::ptrdiff_t>(e));
  };
  // Work in coefficients (header, "Progress"): levels 1 .. L hold M - M / 2^L of them.
  const double total_work = static_cast<double>(2 * m + m - (m >> result.levels));
  double done = static_cast<double>(m);
  if (config.progress) config.progress(done / total_work);
  const double finest_sigma = mad_sigma(level_coefficients(1));
  for (int l = 1; l <= result.levels; ++l) {
    std::vector<double> d = level_coefficients(l);
    const double sigma = config.noise == NoiseEstimate::FinestLevel ? finest_sigma : mad_sigma(d);
    double t = 0.0;
    if (sigma > 0.0) {
      if (config.rule == ThresholdRule::Universal) {
        t = universal_threshold(static_cast<std::size_t>(n));
      } else {
        for (double& v : d) v /= sigma;
        t = config.rule == ThresholdRule::Sure ? sure_threshold(d) : hybrid_sure_threshold(d);
      }
    }
    const double lambda = sigma * t;
    const auto [b, e] = level_range(l);
    std::size_t kept = 0;
    for (std::size_t i = b; i < e; ++i) {
      data[i] = config.shrink == Shrink::Soft ? soft(data[i], lambda) : hard(data[i], lambda);
      if (data[i] != 0.0) ++kept;
    }
    result.sigma.push_back(sigma);
    result.thresholds.push_back(lambda);
    result.kept.push_back(kept);
    done += static_cast<double>(e - b);
    if (config.progress) config.progress(done / total_work);
  }

  if (gsl_wavelet_transform_inverse(w.get(), data.data(), 1, static_cast<std::size_t>(m), work.get()) != GSL_SUCCESS) {
    throw std::runtime_error("wavelet: GSL inverse transform failed");
  }
  result.denoised = Eigen::Map<const Eigen::VectorXd>(data.data() + before, n);
  return result;
}

}  // namespace driftlab::wavelet
