// Where a model misses: views of the residual (measured - modelled systematic rate) of the
// discrepancy workflow, computed on block means (blocks.hpp).
//
//   over time             the block residual itself
//   by temperature        mean per temperature bin, separately for heating and cooling blocks
//                         (|dT/dt| > kSoakRate counts as moving); a gap between the two curves is
//                         direction-dependent (hysteresis, lag), a common shape is a missing T term
//   by dT/dt              mean per temperature-rate bin (rate-dependent terms: lag, dT/dt bias)
//   heating/cooling/soak  mean over each regime
//   spectrum              least-squares sinusoid amplitude at frequencies k / span up to 95 % of the
//                         Nyquist frequency of the median block spacing (Lomb 1976; Scargle 1982;
//                         gapped records included), and its largest local maxima
//   Allan deviation       overlapping ADEV of the full-rate residual (models/allan) against the
//                         model's noise terms (blocks.hpp); residual above the model curve at long
//                         tau is structure the model lacks. Only for records without gaps.
// Standard errors are s / sqrt(count) of the block means in a bin: they assume independent blocks
// and are optimistic under flicker and random-walk noise; they show scatter, not significance
// (the workflow's test uses the full noise covariance).
// Cost: O(B) bins, O(B^2) spectrum, O(n log n) Allan deviation (octave grid).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "models/discrepancy/blocks.hpp"
#include "models/error_model/error_model.hpp"

namespace driftlab::discrepancy {

inline constexpr double kSoakRateKPerS = 0.05 / 60.0;  // below 0.05 degC/min the block is soaking

struct Bin {
  double center = 0.0;  // bin centre in the binned variable's unit (degC or K/s)
  double mean_rad_s = 0.0;
  double standard_error_rad_s = 0.0;
  std::size_t count = 0;
};

struct SpectrumLine {
  double period_s = 0.0;
  double amplitude_rad_s = 0.0;
};

struct AllanPoint {
  double tau_s = 0.0;
  double residual_rad_s = 0.0;  // OADEV of the residual
  double model_rad_s = 0.0;     // the noise terms' Allan deviation
};

struct Views {
  Eigen::VectorXd time_s, residual_rad_s, temperature_c, temperature_rate_k_s;  // per block
  std::vector<Bin> heating_by_temperature, cooling_by_temperature, by_temperature_rate;
  Bin heating, cooling, soak;
  std::vector<SpectrumLine> spectrum, peaks;
  std::vector<AllanPoint> allan;
};

// `full_residual` is the residual at every sample (for the Allan deviation); pass an empty vector
// when the record has gaps. `bins` temperature / rate bins (>= 1), `peak_count` peaks kept.
Views residual_views(const Blocks& blocks, const Eigen::VectorXd& block_temperature_c,
                     const Eigen::VectorXd& block_residual_rad_s, const Eigen::VectorXd& full_residual_rad_s,
                     const error_model::NoiseTerms& noise, int bins = 12, int peak_count = 3);

}  // namespace driftlab::discrepancy
