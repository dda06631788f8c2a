#include "models/evaluation/evaluation.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

#include "framework/error.hpp"

namespace driftlab::evaluation {

Eigen::VectorXd block_means(const Eigen::VectorXd& x, double sample_rate_hz, double block_s) {
  const auto per_block = static_cast<Eigen::Index>(std::llround(block_s * sample_rate_hz));
  const Eigen::Index blocks = per_block > 0 ? x.size() / per_block : 0;
  Eigen::VectorXd means(blocks);
  for (Eigen::Index b = 0; b < blocks; ++b) means[b] = x.segment(b * per_block, per_block).mean();
  return means;
}

double block_mean_rms(const Eigen::VectorXd& x, double sample_rate_hz, double block_s) {
  const Eigen::VectorXd means = block_means(x, sample_rate_hz, block_s);
  if (means.size() == 0) throw DataError({"", 0, "rate"}, "the record is shorter than one " + std::to_string(block_s) + "-s block");
  return std::sqrt(means.squaredNorm() / static_cast<double>(means.size()));
}

StageScore score_stage(const std::string& stage, const Eigen::VectorXd& output_rad_s, double sample_rate_hz,
                       double reference_arw_rad_sqrt_s, const Truth* truth) {
  StageScore s;
  s.stage = stage;
  s.bandwidth_hz = std::min(allan::noise_bandwidth_hz(output_rad_s, sample_rate_hz, reference_arw_rad_sqrt_s),
                            sample_rate_hz / 2.0);
  s.correlation_time_s = allan::correlation_time_s(s.bandwidth_hz);
  allan::AnalysisOptions options;
  options.min_tau_s = s.correlation_time_s;
  s.analysis = allan::analyze_rate(output_rad_s, sample_rate_hz, options);
  if (truth != nullptr) {
    const Eigen::VectorXd error = output_rad_s - truth->true_rate_rad_s;
    s.residual_drift_rad_s = block_mean_rms(error, sample_rate_hz);
    s.error = allan::analyze_rate(error, sample_rate_hz, options);
  }
  return s;
}

allan::Analysis intrinsic_floor(const Eigen::VectorXd& measured_rad_s, const Eigen::VectorXd& systematic_rad_s,
                                double sample_rate_hz) {
  return allan::analyze_rate(measured_rad_s - systematic_rad_s, sample_rate_hz);
}

FloorComparison compare_to_floor(const allan::Analysis& error, const allan::Analysis& floor, double factor) {
  FloorComparison c;
  for (const auto& e : error.curve) {
    const auto f = std::find_if(floor.curve.begin(), floor.curve.end(),
                                [&](const allan::Estimate& p) { return std::abs(p.tau - e.tau) < 1e-9 * e.tau; });
    if (f == floor.curve.end()) continue;
    const double ratio = e.dev / f->dev;
    if (ratio > c.max_ratio) {
      c.max_ratio = ratio;
      c.tau_of_max_s = e.tau;
    }
    if (e.dev_lo > factor * f->dev_hi) c.within = false;
  }
  return c;
}

PolynomialBaseline px4_style_baseline(const Eigen::VectorXd& rate_rad_s, const Eigen::VectorXd& temp_c,
                                      double reference_temp_c) {
  PolynomialBaseline b;
  b.reference_temp_c = reference_temp_c;
  Eigen::Index hottest = 0, coldest = 0;
  temp_c.maxCoeff(&hottest);
  temp_c.head(hottest + 1).minCoeff(&coldest);
  if (hottest - coldest + 1 < 10)
    throw DataError({"", 0, "temperature"}, "no heating leg of at least 10 samples for the polynomial baseline");
  b.fit_first = coldest;
  b.fit_last = hottest;
  b.fit_min_c = temp_c[coldest];
  b.fit_max_c = temp_c[hottest];
  const Eigen::Index n = hottest - coldest + 1;
  const double scale = std::max(1.0, (b.fit_max_c - b.fit_min_c) / 2.0);  // conditioning only
  Eigen::MatrixXd A(n, 4);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double x = (temp_c[coldest + k] - reference_temp_c) / scale;
    A.row(k) << 1.0, x, x * x, x * x * x;
  }
  const Eigen::Vector4d c = A.colPivHouseholderQr().solve(rate_rad_s.segment(coldest, n));
  b.coefficients_rad_s = {c[0], c[1] / scale, c[2] / (scale * scale), c[3] / (scale * scale * scale)};
  b.compensated_rad_s.resize(rate_rad_s.size());
  for (Eigen::Index k = 0; k < rate_rad_s.size(); ++k) {
    const double x = std::clamp(temp_c[k], b.fit_min_c, b.fit_max_c) - reference_temp_c;
    const auto& p = b.coefficients_rad_s;
    b.compensated_rad_s[k] = rate_rad_s[k] - (p[0] + x * (p[1] + x * (p[2] + x * p[3])));
  }
  return b;
}

}  // namespace driftlab::evaluation
