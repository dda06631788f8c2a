// Block averaging of a record and the covariance of the block means under the gyro noise model.
//
// The discrepancy workflow (discrepancy.hpp) works on block means: the nonlinear searches then
// cost O(blocks) instead of O(samples) per evaluation, and sensor noise on the temperature is
// averaged out before derivatives and hysteresis states are taken. The blocks are the record's time
// blocks (sampling::time_blocks; empty blocks, gaps in the record, dropped). Block i spans
// [a_i, b_i] = [first sample time, last sample time + dt] with L_i = b_i - a_i = m_i dt, dt the
// median sample interval.
//
// Noise covariance of the block means (continuous-time averages of IEEE 952 terms, error_model.hpp):
//   white (N, rad/sqrt(s)):         Var = N^2 / L_i,  independent between blocks
//   Gauss-Markov (sigma, tau)       Var = 2 sigma^2 tau^2 / L^2 (L/tau - 1 + exp(-L/tau))
//   (each Gauss-Markov component: the flicker of B and the explicit terms):  Cov(i < j) = sigma^2 tau^2 / (L_i L_j) (1
//   - e^{-L_i/tau})
//                                                (1 - e^{-L_j/tau}) exp(-(a_j - b_i)/tau)
//   random walk (K, rad/s/sqrt(s)), W(t_first) = 0:
//                                   Var = K^2 (a_i - t_first + L_i/3),  Cov(i < j) = K^2 ((a_i + b_i)/2 - t_first)
// (Papoulis & Pillai, Probability, Random Variables and Stochastic Processes, 4th ed., sec. 9-5:
// variance of a time average, applied to R(s) = sigma^2 exp(-|s|/tau) and R(s,t) = K^2 min(s,t).)
// The same formulas give the Allan variance of each stationary term: AVAR(tau) = Var - Cov(adjacent
// blocks of length tau); white N^2/tau and random walk K^2 tau/3 (IEEE 952 Annex C).
//
// Cost: blocks O(n); covariance O(B^2 M) for B blocks and M Gauss-Markov components.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "framework/time_series.hpp"
#include "models/error_model/error_model.hpp"

namespace driftlab::discrepancy {

struct Blocks {
  std::vector<Eigen::Index> first;  // index of each block's first sample
  std::vector<Eigen::Index> count;  // samples in each block
  Eigen::VectorXd start_s, end_s;   // span [a_i, b_i]
  Eigen::VectorXd time_s;           // mean sample time of each block
  double sample_interval_s = 0.0;   // median dt
  double record_start_s = 0.0;

  Eigen::Index size() const { return static_cast<Eigen::Index>(first.size()); }
  double duration_s() const { return end_s[size() - 1] - start_s[0]; }
  // Median distance between consecutive block times (the effective sampling of a gapped record).
  double median_spacing_s() const;
};

// Gaps and regular bursts of a record: framework/sampling.hpp (block averaging handles regular
// bursts like evenly spaced data with fewer samples: blocks of at least one burst period).

// The blocks of `record` (its time and its sampling facts' median step). Throws
// std::invalid_argument when block_s <= 0.
Blocks make_blocks(const TimeSeries& record, double block_s);

// Mean of x over each block.
Eigen::VectorXd block_means(const Blocks& blocks, const Eigen::VectorXd& x);

// Linear interpolation of block values (at blocks.time_s) to the given times, constant beyond the ends.
Eigen::VectorXd interpolate(const Blocks& blocks, const Eigen::VectorXd& block_values, const Eigen::VectorXd& time_s);

// Covariance of the block means of noise with these terms, rad^2/s^2. O(B^2 M).
Eigen::MatrixXd noise_covariance(const Blocks& blocks, const error_model::NoiseTerms& noise);

// Allan deviation of the noise terms at averaging time tau_s (rad/s), from the block formulas.
double model_allan_deviation(const error_model::NoiseTerms& noise, double tau_s);

}  // namespace driftlab::discrepancy
