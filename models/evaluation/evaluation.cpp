#include "models/evaluation/evaluation.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

#include "framework/error.hpp"
#include "framework/signal.hpp"

namespace driftlab::evaluation {

BlockMeans block_means(const Eigen::VectorXd& time_s, const Eigen::VectorXd& x, double block_s) {
  if (time_s.size() != x.size()) throw DataError({"", 0, "t_s"}, "time and values differ in length");
  BlockMeans out;
  const Eigen::Index n = x.size();
  if (n == 0 || !(block_s > 0)) return out;
  out.blocks = sampling::time_blocks(time_s, block_s);
  const double last_step = n > 1 ? time_s[n - 1] - time_s[n - 2] : 0.0;
  const double block_end = time_s[0] + static_cast<double>(out.blocks.back().number + 1) * block_s;
  const bool reaches_end =
      n > 1 && time_s[n - 1] + last_step >= block_end - sampling::kBlockBoundaryTolerance * block_s;
  if (!reaches_end && sampling::facts_of(time_s).evenly_sampled()) out.blocks.pop_back();
  out.means.resize(static_cast<Eigen::Index>(out.blocks.size()));
  for (std::size_t k = 0; k < out.blocks.size(); ++k)
    out.means[static_cast<Eigen::Index>(k)] = x.segment(out.blocks[k].first, out.blocks[k].samples).mean();
  return out;
}

double block_mean_rms(const Eigen::VectorXd& time_s, const Eigen::VectorXd& x, double block_s) {
  const Eigen::VectorXd means = block_means(time_s, x, block_s).means;
  if (means.size() == 0)
    throw DataError({"", 0, "rate"}, "the record is shorter than one " + std::to_string(block_s) + "-s block");
  return std::sqrt(means.squaredNorm() / static_cast<double>(means.size()));
}

StageScore score_stage(const std::string& stage, const Eigen::VectorXd& output_rad_s, const Eigen::VectorXd& time_s,
                       double sample_rate_hz, double reference_arw_rad_sqrt_s, const Truth* truth,
                       const allan::Analysis* estimated) {
  StageScore s;
  s.stage = stage;
  s.label = stage;
  s.bandwidth_hz =
      std::min(allan::noise_bandwidth_hz(output_rad_s, sample_rate_hz, reference_arw_rad_sqrt_s), sample_rate_hz / 2.0);
  s.correlation_time_s = allan::correlation_time_s(s.bandwidth_hz);
  allan::AnalysisOptions options;
  options.min_tau_s = s.correlation_time_s;
  s.analysis = estimated != nullptr ? allan::reread(*estimated, options)
                                    : allan::analyze_rate(output_rad_s, sample_rate_hz, options);
  if (truth != nullptr) {
    const Eigen::VectorXd error = output_rad_s - truth->true_rate_rad_s;
    s.residual_drift_rad_s = block_mean_rms(time_s, error);
    if (truth->intrinsic_noise_rad_s)
      s.systematic_error_rad_s = block_mean_rms(time_s, error - *truth->intrinsic_noise_rad_s);
    s.error = allan::analyze_rate(error, sample_rate_hz, options);
  }
  return s;
}

Eigen::VectorXd intrinsic_noise(const Eigen::VectorXd& measured_rad_s, const Eigen::VectorXd& systematic_rad_s) {
  if (measured_rad_s.size() != systematic_rad_s.size())
    throw DataError({"", 0, "systematic"}, "the systematic rate has " + std::to_string(systematic_rad_s.size()) +
                                               " samples, the measured rate " + std::to_string(measured_rad_s.size()));
  return measured_rad_s - systematic_rad_s;
}

allan::Analysis intrinsic_floor(const Eigen::VectorXd& intrinsic_noise_rad_s, double sample_rate_hz) {
  return allan::analyze_rate(intrinsic_noise_rad_s, sample_rate_hz);
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

}  // namespace driftlab::evaluation
