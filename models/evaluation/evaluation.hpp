// Scoring a compensated rate the way Table 2 of Li et al. 2023 does, plus the honest columns the
// paper leaves out (DESIGN.md §1). One home for `driftlab run`'s report and `driftlab compare`.
//
// Per output ("stage"), from allan::analyze_rate (models/allan/analysis.hpp):
//   - B read as the flat floor of the OADEV beyond the output's correlation time, with its interval,
//     and N read from the -1/2 line at tau = 1 s;
//   - the output's noise bandwidth relative to the white level N of the original record (N is only
//     comparable at equal bandwidth);
//   - with a truth (simulated records): the residual drift, the rms of 60-s block means of
//     (output - true rate), and the Allan curve of (output - true rate) against the intrinsic floor.
// Intrinsic floor: the same analysis of (measured - true systematic rate), i.e. the gyro's own noise,
// which no compensation can remove.
// Baseline: the PX4-style thermal calibration, a third-order polynomial in (T - T0) fitted by least
// squares on the first heating leg only (from the coldest point before the hottest to the hottest),
// evaluated with T clipped to that leg's range, subtracted from the rate.
// Units: rates rad/s, temperatures degC, times s.
#pragma once

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

#include "models/allan/analysis.hpp"

namespace driftlab::evaluation {

inline constexpr double kResidualBlockS = 60.0;  // block length of the residual-drift metric

struct Truth {
  Eigen::VectorXd true_rate_rad_s;                 // the table's rate
  std::optional<Eigen::VectorXd> systematic_rad_s;  // everything but noise (simulator), for the floor
};

struct StageScore {
  std::string stage;
  allan::Analysis analysis;          // B, N, curve of the output
  double bandwidth_hz = 0.0;         // noise bandwidth relative to the original record's N
  double correlation_time_s = 0.0;   // 1 / bandwidth: B is read beyond it
  std::optional<double> residual_drift_rad_s;   // rms of 60-s block means of output - true rate
  std::optional<allan::Analysis> error;         // Allan analysis of output - true rate
};

// Means of x over consecutive whole blocks of block_s seconds (a partial block at the end is left
// out); empty when the record is shorter than one block.
Eigen::VectorXd block_means(const Eigen::VectorXd& x, double sample_rate_hz, double block_s = kResidualBlockS);

// rms of block_means(x) (rad/s). Throws DataError when the record is shorter than one block.
double block_mean_rms(const Eigen::VectorXd& x, double sample_rate_hz, double block_s = kResidualBlockS);

// Scores one output. reference_arw_rad_sqrt_s: N of the original record (for the bandwidth).
StageScore score_stage(const std::string& stage, const Eigen::VectorXd& output_rad_s, double sample_rate_hz,
                       double reference_arw_rad_sqrt_s, const Truth* truth);

// Allan analysis of measured - systematic (read like the original record: full bandwidth).
allan::Analysis intrinsic_floor(const Eigen::VectorXd& measured_rad_s, const Eigen::VectorXd& systematic_rad_s,
                                double sample_rate_hz);

// The largest ratio over tau of the error curve to the intrinsic curve, and whether every tau is
// within `factor` of it once both intervals are allowed for (error.dev_lo <= factor * floor.dev_hi).
struct FloorComparison {
  double max_ratio = 0.0;
  double tau_of_max_s = 0.0;
  bool within = true;
};
FloorComparison compare_to_floor(const allan::Analysis& error, const allan::Analysis& floor, double factor);

struct PolynomialBaseline {
  std::vector<double> coefficients_rad_s;  // c0 + c1 dT + c2 dT^2 + c3 dT^3, dT = T - T0
  double reference_temp_c = 25.0;
  double fit_min_c = 0.0, fit_max_c = 0.0;  // the heating leg's range; T is clipped to it
  Eigen::Index fit_first = 0, fit_last = 0;  // samples of the heating leg used
  Eigen::VectorXd compensated_rad_s;
};
// Throws DataError when the record has no heating leg of at least 10 samples.
PolynomialBaseline px4_style_baseline(const Eigen::VectorXd& rate_rad_s, const Eigen::VectorXd& temp_c,
                                      double reference_temp_c = 25.0);

}  // namespace driftlab::evaluation
