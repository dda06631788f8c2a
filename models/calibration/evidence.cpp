#include "models/calibration/evidence.hpp"

#include "framework/error.hpp"
#include "models/allan/analysis.hpp"

namespace driftlab::calibration {

std::optional<allan::Analysis> allan_figures(const Eigen::VectorXd& error, double fs) {
  if (!(fs > 0) || static_cast<double>(error.size()) / fs < 3.0) return std::nullopt;
  try {
    return allan::analyze_rate(error, fs, {.fit_terms = false});
  } catch (const Error&) {
    return std::nullopt;
  }
}

std::optional<FittedNoise> fit_noise(const Eigen::VectorXd& error, double fs) {
  if (!(fs > 0) || static_cast<double>(error.size()) / fs < 3.0) return std::nullopt;
  try {
    const auto analysis = allan::analyze_rate(error, fs);
    if (!analysis.fit) return std::nullopt;
    const auto& fit = *analysis.fit;
    FittedNoise out;
    out.arw_rad_sqrt_s = fit[allan::Term::N].value;
    out.arw_sigma = fit[allan::Term::N].sigma;
    out.bias_instability_rad_s = fit[allan::Term::B].value;
    out.rate_random_walk_rad_s_sqrt_s = fit[allan::Term::K].value;
    out.rate_random_walk_sigma = fit[allan::Term::K].sigma;
    const auto bound = [&](allan::Term t) {
      return fit[t].resolved ? std::nullopt : std::optional<double>(fit[t].high);
    };
    out.arw_upper = bound(allan::Term::N);
    out.bias_instability_upper = bound(allan::Term::B);
    out.rate_random_walk_upper = bound(allan::Term::K);
    return out;
  } catch (const Error&) {
    return std::nullopt;
  }
}

}  // namespace driftlab::calibration
