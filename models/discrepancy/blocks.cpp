#include "models/discrepancy/blocks.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "framework/sampling.hpp"
#include "framework/signal.hpp"

namespace driftlab::discrepancy {
namespace {

// x - (1 - e^{-x}) without cancellation for small x.
double lag_excess(double x) { return x + std::expm1(-x); }

double gauss_markov_variance(double sigma, double tau, double length) {
  const double x = length / tau;
  return 2.0 * sigma * sigma * tau * tau / (length * length) * lag_excess(x);
}

double gauss_markov_covariance(double sigma, double tau, double length_i, double length_j, double gap) {
  return sigma * sigma * tau * tau / (length_i * length_j) * -std::expm1(-length_i / tau) *
         -std::expm1(-length_j / tau) * std::exp(-gap / tau);
}

}  // namespace

Blocks make_blocks(const TimeSeries& record, double block_s) {
  const Eigen::VectorXd& time_s = record.time();
  Blocks b;
  b.sample_interval_s = record.sampling_facts().median_step_s;
  b.record_start_s = time_s.size() ? time_s[0] : 0.0;
  const auto blocks = sampling::time_blocks(time_s, block_s);
  const auto count = static_cast<Eigen::Index>(blocks.size());
  b.start_s.resize(count);
  b.end_s.resize(count);
  b.time_s.resize(count);
  for (Eigen::Index i = 0; i < count; ++i) {
    const auto& block = blocks[static_cast<std::size_t>(i)];
    b.first.push_back(block.first);
    b.count.push_back(block.samples);
    b.start_s[i] = time_s[block.first];
    b.end_s[i] = b.start_s[i] + static_cast<double>(block.samples) * b.sample_interval_s;
    b.time_s[i] = time_s.segment(block.first, block.samples).mean();
  }
  return b;
}

double Blocks::median_spacing_s() const { return size() < 2 ? duration_s() : signal::median_step(time_s); }

Eigen::VectorXd block_means(const Blocks& blocks, const Eigen::VectorXd& x) {
  Eigen::VectorXd means(blocks.size());
  for (Eigen::Index i = 0; i < blocks.size(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    means[i] = x.segment(blocks.first[k], blocks.count[k]).mean();
  }
  return means;
}

Eigen::VectorXd interpolate(const Blocks& blocks, const Eigen::VectorXd& block_values, const Eigen::VectorXd& time_s) {
  Eigen::VectorXd out(time_s.size());
  const Eigen::Index last = blocks.size() - 1;
  Eigen::Index i = 0;
  for (Eigen::Index k = 0; k < time_s.size(); ++k) {
    const double t = time_s[k];
    while (i < last && blocks.time_s[i + 1] <= t) ++i;
    if (t <= blocks.time_s[0] || last == 0)
      out[k] = block_values[0];
    else if (i >= last)
      out[k] = block_values[last];
    else {
      const double w = (t - blocks.time_s[i]) / (blocks.time_s[i + 1] - blocks.time_s[i]);
      out[k] = block_values[i] + w * (block_values[i + 1] - block_values[i]);
    }
  }
  return out;
}

Eigen::MatrixXd noise_covariance(const Blocks& blocks, const error_model::NoiseTerms& noise) {
  const Eigen::Index n = blocks.size();
  const Eigen::VectorXd length = blocks.end_s - blocks.start_s;
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(n, n);
  const double white = noise.arw_rad_sqrt_s * noise.arw_rad_sqrt_s;
  const double walk = noise.rate_random_walk_rad_s_sqrt_s * noise.rate_random_walk_rad_s_sqrt_s;
  const auto components = error_model::gauss_markov_components(noise);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double a = blocks.start_s[i] - blocks.record_start_s;
    c(i, i) = white / length[i] + walk * (a + length[i] / 3.0);
    for (const auto& g : components) c(i, i) += gauss_markov_variance(g.sigma_rad_s, g.tau_s, length[i]);
    const double walk_cov = walk * (a + 0.5 * length[i]);
    for (Eigen::Index j = i + 1; j < n; ++j) {
      double v = walk_cov;
      const double gap = blocks.start_s[j] - blocks.end_s[i];
      for (const auto& g : components)
        v += gauss_markov_covariance(g.sigma_rad_s, g.tau_s, length[i], length[j], std::max(0.0, gap));
      c(i, j) = c(j, i) = v;
    }
  }
  return c;
}

double model_allan_deviation(const error_model::NoiseTerms& noise, double tau_s) {
  double avar = noise.arw_rad_sqrt_s * noise.arw_rad_sqrt_s / tau_s +
                noise.rate_random_walk_rad_s_sqrt_s * noise.rate_random_walk_rad_s_sqrt_s * tau_s / 3.0;
  for (const auto& g : error_model::gauss_markov_components(noise))
    avar += gauss_markov_variance(g.sigma_rad_s, g.tau_s, tau_s) -
            gauss_markov_covariance(g.sigma_rad_s, g.tau_s, tau_s, tau_s, 0.0);
  return std::sqrt(avar);
}

}  // namespace driftlab::discrepancy
