#include "models/discrepancy/views.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "framework/signal.hpp"
#include "models/allan/analysis.hpp"

namespace driftlab::discrepancy {
namespace {

constexpr double kNyquistFraction = 0.95;  // highest line: 95 % of the Nyquist frequency of the block spacing
constexpr double kConditionFloor = 1e-6;   // skip frequencies where sin and cos are nearly dependent (aliases)

struct Accumulator {
  double sum = 0.0, sum_sq = 0.0;
  std::size_t count = 0;
  void add(double x) {
    sum += x;
    sum_sq += x * x;
    ++count;
  }
  Bin bin(double center) const {
    Bin b{center, 0.0, 0.0, count};
    if (count == 0) return b;
    const double n = static_cast<double>(count);
    b.mean_rad_s = sum / n;
    if (count > 1)
      b.standard_error_rad_s = std::sqrt(std::max(0.0, (sum_sq - n * b.mean_rad_s * b.mean_rad_s) / (n - 1)) / n);
    return b;
  }
};

std::vector<Bin> binned(const Eigen::VectorXd& by, const Eigen::VectorXd& value, const std::vector<bool>& keep,
                        int bins, double lo, double hi) {
  std::vector<Accumulator> acc(static_cast<std::size_t>(bins));
  const double width = hi > lo ? (hi - lo) / bins : 1.0;
  for (Eigen::Index i = 0; i < by.size(); ++i) {
    if (!keep[static_cast<std::size_t>(i)]) continue;
    const int k = std::clamp(static_cast<int>((by[i] - lo) / width), 0, bins - 1);
    acc[static_cast<std::size_t>(k)].add(value[i]);
  }
  std::vector<Bin> out;
  for (int k = 0; k < bins; ++k)
    if (acc[static_cast<std::size_t>(k)].count > 0)
      out.push_back(acc[static_cast<std::size_t>(k)].bin(lo + (k + 0.5) * width));
  return out;
}

double sinusoid_amplitude(const Eigen::VectorXd& t, const Eigen::VectorXd& y, double frequency_hz) {
  Eigen::MatrixXd x(t.size(), 3);
  x.col(0).setOnes();
  const Eigen::ArrayXd phase = 2.0 * std::numbers::pi * frequency_hz * t.array();
  x.col(1) = phase.sin().matrix();
  x.col(2) = phase.cos().matrix();
  const Eigen::Matrix3d normal = x.transpose() * x;
  const Eigen::Vector3d eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(normal).eigenvalues();
  if (!(eigenvalues[0] > kConditionFloor * eigenvalues[2])) return std::numeric_limits<double>::quiet_NaN();
  const Eigen::Vector3d c = normal.ldlt().solve(x.transpose() * y);
  return std::hypot(c[1], c[2]);
}

}  // namespace

Views residual_views(const Blocks& blocks, const Eigen::VectorXd& block_temperature_c,
                     const Eigen::VectorXd& block_residual_rad_s, const Eigen::VectorXd& full_residual_rad_s,
                     const error_model::NoiseTerms& noise, int bins, int peak_count) {
  Views v;
  v.time_s = blocks.time_s;
  v.residual_rad_s = block_residual_rad_s;
  v.temperature_c = block_temperature_c;
  v.temperature_rate_k_s = signal::time_derivative(blocks.time_s, block_temperature_c);
  const Eigen::Index n = blocks.size();

  std::vector<bool> heating(static_cast<std::size_t>(n)), cooling(heating), all(heating.size(), true);
  Accumulator up, down, flat;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double rate = v.temperature_rate_k_s[i];
    heating[static_cast<std::size_t>(i)] = rate > kSoakRateKPerS;
    cooling[static_cast<std::size_t>(i)] = rate < -kSoakRateKPerS;
    (rate > kSoakRateKPerS ? up : rate < -kSoakRateKPerS ? down : flat).add(block_residual_rad_s[i]);
  }
  v.heating = up.bin(0.0);
  v.cooling = down.bin(0.0);
  v.soak = flat.bin(0.0);
  const double t_lo = block_temperature_c.minCoeff(), t_hi = block_temperature_c.maxCoeff();
  v.heating_by_temperature = binned(block_temperature_c, block_residual_rad_s, heating, bins, t_lo, t_hi);
  v.cooling_by_temperature = binned(block_temperature_c, block_residual_rad_s, cooling, bins, t_lo, t_hi);
  v.by_temperature_rate = binned(v.temperature_rate_k_s, block_residual_rad_s, all, bins,
                                 v.temperature_rate_k_s.minCoeff(), v.temperature_rate_k_s.maxCoeff());

  const double span = blocks.time_s[n - 1] - blocks.time_s[0];
  if (span > 0.0 && n >= 6) {
    const auto lines = static_cast<Eigen::Index>(kNyquistFraction * span / (2.0 * blocks.median_spacing_s()));
    for (Eigen::Index k = 1; k <= lines; ++k) {
      const double amplitude = sinusoid_amplitude(blocks.time_s, block_residual_rad_s, static_cast<double>(k) / span);
      if (std::isfinite(amplitude)) v.spectrum.push_back({span / static_cast<double>(k), amplitude});
    }
    for (std::size_t k = 0; k < v.spectrum.size(); ++k) {
      const double a = v.spectrum[k].amplitude_rad_s;
      if ((k == 0 || a > v.spectrum[k - 1].amplitude_rad_s) &&
          (k + 1 == v.spectrum.size() || a >= v.spectrum[k + 1].amplitude_rad_s))
        v.peaks.push_back(v.spectrum[k]);
    }
    std::sort(v.peaks.begin(), v.peaks.end(),
              [](const SpectrumLine& a, const SpectrumLine& b) { return a.amplitude_rad_s > b.amplitude_rad_s; });
    if (v.peaks.size() > static_cast<std::size_t>(peak_count)) v.peaks.resize(static_cast<std::size_t>(peak_count));
  }

  if (full_residual_rad_s.size() >= 8) {
    const auto analysis =
        allan::analyze_rate(full_residual_rad_s, 1.0 / blocks.sample_interval_s, {.fit_terms = false});
    for (const auto& d : analysis.curve) v.allan.push_back({d.tau, d.dev, model_allan_deviation(noise, d.tau)});
  }
  return v;
}

}  // namespace driftlab::discrepancy
