#include "models/allan/analysis.hpp"

#include <unsupported/Eigen/FFT>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>

#include "framework/error.hpp"
#include "models/allan/deviation.hpp"
#include "models/allan/tau_grid.hpp"

namespace driftlab::allan {
namespace {

constexpr double kBandwidthFloorHz = 0.01;
constexpr std::size_t kWelchSegment = std::size_t{1} << 14;

double arw_at_one_second(const std::vector<Estimate>& curve) {
  const auto above = std::find_if(curve.begin(), curve.end(), [](const Estimate& e) { return e.tau >= 1.0; });
  if (above == curve.begin()) return above->dev * std::sqrt(above->tau);
  if (above == curve.end()) return curve.back().dev * std::sqrt(curve.back().tau);
  const auto below = std::prev(above);
  const double f = std::log(1.0 / below->tau) / std::log(above->tau / below->tau);
  return std::exp(std::log(below->dev) + f * (std::log(above->dev) - std::log(below->dev)));
}

FloorReading flat_floor(const std::vector<Estimate>& curve, double min_tau_s) {
  std::size_t best = curve.size();
  for (std::size_t i = 0; i < curve.size(); ++i) {
    if (curve[i].tau + 1e-12 < min_tau_s) continue;
    if (best == curve.size() || curve[i].dev < curve[best].dev) best = i;
  }
  if (best == curve.size()) {
    throw DataError({"", 0, "tau"}, "no averaging time at or beyond the output's correlation time (" +
                                        std::to_string(min_tau_s) + " s): the record is too short");
  }
  const Estimate& e = curve[best];
  const auto rising_or_flat = [&](const Estimate& neighbour) { return neighbour.dev_hi >= e.dev_lo; };
  const bool resolved =
      best > 0 && best + 1 < curve.size() && rising_or_flat(curve[best - 1]) && rising_or_flat(curve[best + 1]);
  return {resolved,
          e.dev / kFlickerFloorFactor,
          e.dev_lo / kFlickerFloorFactor,
          e.dev_hi / kFlickerFloorFactor,
          e.tau,
          curve.back().tau};
}

// The readings and the fit of a curve already estimated.
void read_curve(Analysis& a, const AnalysisOptions& options) {
  a.bias_instability = flat_floor(a.curve, options.min_tau_s);
  a.arw_rad_sqrt_s = arw_at_one_second(a.curve);
  if (options.fit_terms) {
    try {
      a.fit = fit_noise_terms(a.curve);
    } catch (const DataError&) {
      a.fit.reset();
    }
  }
}

}  // namespace

Analysis analyze_rate(const Eigen::Ref<const Eigen::VectorXd>& rate_rad_s, double sample_rate_hz,
                      const AnalysisOptions& options) {
  if (rate_rad_s.size() < 9) throw DataError({"", 0, "rate"}, "an Allan analysis needs at least 9 samples");
  return analyze_angle(angle_from_rate(rate_rad_s, 1.0 / sample_rate_hz), 1.0 / sample_rate_hz, options);
}

Analysis analyze_angle(const Eigen::Ref<const Eigen::VectorXd>& angle, double tau0, const AnalysisOptions& options) {
  const auto n = static_cast<std::size_t>(angle.size());
  if (n < 10) throw DataError({"", 0, "rate"}, "an Allan analysis needs at least 9 samples");
  const auto factors = averaging_factors(TauGrid{}, Kind::Oadev, n, tau0);
  Analysis a;
  a.sample_rate_hz = 1.0 / tau0;
  a.samples = n - 1;
  a.curve = estimate(Kind::Oadev, angle, tau0, InputType::Rate, factors, options.confidence);
  read_curve(a, options);
  return a;
}

Analysis reread(const Analysis& estimated, const AnalysisOptions& options) {
  Analysis a = estimated;
  a.fit.reset();
  read_curve(a, options);
  return a;
}

Analysis analyze_segments(const Eigen::Ref<const Eigen::VectorXd>& rate, std::span<const sampling::Segment> segments,
                          double sample_rate_hz, const AnalysisOptions& options) {
  const double tau0 = 1.0 / sample_rate_hz;
  std::vector<Eigen::VectorXd> angles;
  std::vector<std::size_t> lengths;
  Analysis a;
  a.sample_rate_hz = sample_rate_hz;
  for (const auto& s : segments) {
    angles.push_back(angle_from_rate(Eigen::Ref<const Eigen::VectorXd>(rate.segment(s.first, s.samples)), tau0));
    lengths.push_back(static_cast<std::size_t>(s.samples) + 1);
    a.samples += static_cast<std::size_t>(s.samples);
  }
  a.segments = segments.size();
  if (lengths.empty()) throw DataError({"", 0, "rate"}, "an Allan analysis needs at least 9 samples per burst");
  const auto middle = lengths.begin() + static_cast<std::ptrdiff_t>(lengths.size() / 2);
  std::nth_element(lengths.begin(), middle, lengths.end());
  if (*middle < 10) throw DataError({"", 0, "rate"}, "an Allan analysis needs at least 9 samples per burst");
  const auto factors = averaging_factors(TauGrid{}, Kind::Oadev, *middle, tau0);
  a.curve = estimate_bursts(Kind::Oadev, angles, tau0, InputType::Rate, factors, options.confidence);
  read_curve(a, options);
  return a;
}

double noise_bandwidth_hz(const Eigen::Ref<const Eigen::VectorXd>& output_rad_s, double sample_rate_hz,
                          double reference_arw_rad_sqrt_s) {
  const auto n = static_cast<std::size_t>(output_rad_s.size());
  if (n < 64) throw DataError({"", 0, "rate"}, "a noise bandwidth needs at least 64 samples");
  const std::size_t length = std::min(kWelchSegment, n);
  const std::size_t step = length / 2;
  std::vector<double> window(length), segment(length);
  double window_power = 0.0;
  for (std::size_t i = 0; i < length; ++i) {
    window[i] = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(length));
    window_power += window[i] * window[i];
  }
  const double df = sample_rate_hz / static_cast<double>(length);
  const auto first_bin = static_cast<std::size_t>(std::ceil(kBandwidthFloorHz / df));

  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> spectrum;
  double band_power = 0.0;  // integral of the one-sided PSD over [f_lo, fs/2], averaged over segments
  std::size_t segments = 0;
  for (std::size_t start = 0; start + length <= n; start += step, ++segments) {
    const auto block = output_rad_s.segment(static_cast<Eigen::Index>(start), static_cast<Eigen::Index>(length));
    const double mean = block.mean();
    for (std::size_t i = 0; i < length; ++i) segment[i] = (block[static_cast<Eigen::Index>(i)] - mean) * window[i];
    fft.fwd(spectrum, segment);
    for (std::size_t k = std::max<std::size_t>(first_bin, 1); k <= length / 2; ++k) {
      const double weight = k == length / 2 ? 1.0 : 2.0;
      band_power += weight * std::norm(spectrum[k]) / (static_cast<double>(length) * window_power);
    }
  }
  band_power /= static_cast<double>(segments);
  const double reference_one_sided = 2.0 * reference_arw_rad_sqrt_s * reference_arw_rad_sqrt_s;
  return band_power / reference_one_sided + std::max<std::size_t>(first_bin, 1) * df;
}

}  // namespace driftlab::allan
