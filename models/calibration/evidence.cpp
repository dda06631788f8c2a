#include "models/calibration/evidence.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "framework/error.hpp"
#include "models/allan/confidence.hpp"
#include "models/allan/deviation.hpp"
#include "models/allan/noise_fit.hpp"
#include "models/allan/tau_grid.hpp"

namespace driftlab::calibration {

double residual_drift_rad_s(const Eigen::VectorXd& time_s, const Eigen::VectorXd& output, const Eigen::VectorXd& truth,
                            double block_s) {
  double sum = 0.0, ss = 0.0, count = 0.0;
  long current = -1;
  std::size_t blocks = 0;
  const auto close = [&] {
    if (count > 0) {
      const double m = sum / count;
      ss += m * m;
      ++blocks;
    }
    sum = count = 0.0;
  };
  for (Eigen::Index i = 0; i < time_s.size(); ++i) {
    const long k = static_cast<long>(std::floor((time_s[i] - time_s[0]) / block_s));
    if (k != current) {
      close();
      current = k;
    }
    sum += output[i] - (truth.size() ? truth[i] : 0.0);
    count += 1.0;
  }
  close();
  return blocks ? std::sqrt(ss / static_cast<double>(blocks)) : 0.0;
}

namespace {
std::vector<allan::Estimate> curve(const Eigen::VectorXd& error, double fs) {
  const double tau0 = 1.0 / fs;
  const Eigen::VectorXd angle = allan::angle_from_rate(error, tau0);
  const auto n = static_cast<std::size_t>(angle.size());
  const auto factors = allan::averaging_factors(allan::TauGrid{}, allan::Kind::Oadev, n, tau0);
  return allan::estimate(allan::Kind::Oadev, angle, tau0, allan::InputType::Rate, factors, allan::kDefaultConfidence);
}
}  // namespace

std::optional<AllanFigures> allan_figures(const Eigen::VectorXd& error, double fs) {
  if (!(fs > 0) || static_cast<double>(error.size()) / fs < 3.0) return std::nullopt;
  try {
    const auto c = curve(error, fs);
    if (c.empty()) return std::nullopt;
    AllanFigures f;
    const auto best = std::min_element(c.begin(), c.end(), [](const auto& a, const auto& b) { return a.dev < b.dev; });
    f.bias_instability_rad_s = best->dev / std::sqrt(2.0 * std::numbers::ln2 / std::numbers::pi);
    f.min_adev_tau_s = best->tau;
    // N: the deviation at tau = 1 s, interpolated in log-log between the neighbouring points.
    for (std::size_t i = 0; i + 1 < c.size(); ++i) {
      if (c[i].tau <= 1.0 && c[i + 1].tau >= 1.0) {
        const double w = std::log(1.0 / c[i].tau) / std::log(c[i + 1].tau / c[i].tau);
        f.arw_rad_sqrt_s = std::exp((1 - w) * std::log(c[i].dev) + w * std::log(c[i + 1].dev));
      }
    }
    if (f.arw_rad_sqrt_s == 0.0) f.arw_rad_sqrt_s = c.front().dev * std::sqrt(c.front().tau);
    return f;
  } catch (const Error&) {
    return std::nullopt;
  }
}

std::optional<FittedNoise> fit_noise(const Eigen::VectorXd& error, double fs) {
  if (!(fs > 0) || static_cast<double>(error.size()) / fs < 3.0) return std::nullopt;
  try {
    const auto fit = allan::fit_noise_terms(curve(error, fs));
    FittedNoise out;
    out.arw_rad_sqrt_s = fit[allan::Term::N].value;
    out.arw_sigma = fit[allan::Term::N].sigma;
    out.bias_instability_rad_s = fit[allan::Term::B].value;
    out.rate_random_walk_rad_s_sqrt_s = fit[allan::Term::K].value;
    out.rate_random_walk_sigma = fit[allan::Term::K].sigma;
    return out;
  } catch (const Error&) {
    return std::nullopt;
  }
}

}  // namespace driftlab::calibration
