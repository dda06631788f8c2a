// Fitting a CalibrationModel from one or more oven records (`driftlab calibrate`).
//
// Every candidate model is scored the way it will be used: the causal filters of the compensator
// (calibration_model.hpp: model temperature lag, dT/dt estimate, hysteresis state) are run over the
// full-rate record, the features and the target are averaged over bins of bin_s seconds (noise
// down, rows few), and the linear coefficients are fitted by least squares on the bins
// (regressor/polynomial's kernel). The model terms are linear in their coefficients, so bin means
// of the features give the exact bin means of the fitted bias.
//
// Selection: terms are kept only where they transfer (issue: calibration that holds on real IMUs).
//   Before fitting, the oven runs are analysed (oven_run.hpp: legs, soaks, span) and the quality
//   gate's errors (a span below kMinFitSpanK) stop the fit. A history term is only scored when the
//   runs can determine it: lag (up to the longest soak) and dT/dt / hysteresis (span of at least
//   kMinHistorySpanK and both directions).
//   poly      order in [min_order, max_order] by the held-out error on contiguous time blocks of
//             each record (holdout_blocks per record)
//   physical  order x lag_tau_s (lag_grid_s up to the longest soak) x with/without dT/dt x
//             hysteresis width (hysteresis_width_grid_k) on the same blocks; a candidate with a
//             dT/dt or hysteresis term counts only when each coefficient is beyond 3 standard
//             errors (the larger of the least-squares ones, inflated for lag-1 correlation, and
//             the delete-one-block jackknife) and no larger than the bias swing it explains. The
//             best cell's lag and width are refined between their grid neighbours by golden
//             section (refine_iterations, framework/golden_section.hpp). The history terms are then
//             kept only when they lower the block error of the best polynomial by 10 % and, where
//             whole runs (several records) or whole legs (a record with two legs of every
//             direction it holds) can be held out, the error on those too, scored with the
//             extrapolation policy; otherwise the polynomial is the model and fit.selection says why
//   rbf       the physical model, plus a Gaussian RBF network on (T_c, D, s) fitted to the physical
//             residual when the runs hold both directions; its width, ridge and number of centres
//             are tuned by the GA (plugins/ga) on a blocked holdout, kept when it lowers that
//             holdout's error by 10 %
// The model's kind is what was kept (a physical fit without history terms is a poly model), its
// valid range is the range of the fitted bins' model temperature, and fit.holdout_rms_rad_s (the
// block error of the kept model) is its stated accuracy, fit.holdout_design how it was held out.
// Target: rate - true_rate when a true-rate column exists; when the true rate varies (a rate
// table, std > 1e-3 rad/s), the scale factor (1 + sum_j k_j (T - T0)^j, j = 0..2) is fitted jointly.
// Heating only (PX4 practice): only bins whose dT/dt estimate is > 0 are used.
// Coefficient uncertainties: least-squares standard errors on the bins, inflated by
// sqrt((1 + rho) / (1 - rho)) for the lag-1 autocorrelation rho of the bin residuals.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "models/calibration/calibration_model.hpp"

namespace driftlab::calibration {

struct Record {
  std::string name;  // file name, for the model's fit summary and messages
  Eigen::VectorXd time_s, rate_rad_s, temp_c;
  Eigen::VectorXd true_rate_rad_s;   // empty when unknown (static: 0)
  Eigen::VectorXd systematic_rad_s;  // empty, or the simulator's true systematic rate (evidence only)
};

// The samples of `r` with t in [from_s, to_s) (for calibrating on the first part of a record and
// testing on the rest).
Record slice(const Record& r, double from_s, double to_s);

struct FitOptions {
  ModelKind kind = ModelKind::Polynomial;

  double reference_temp_c = 25.0;  // T0, degC
  Extrapolation extrapolation = Extrapolation::Clamp;
  int min_order = 1, max_order = 5;  // polynomial orders scored
  std::size_t holdout_blocks = 8;    // contiguous held-out blocks per record
  double bin_s = 10.0;               // fitting bins, s
  bool heating_only = false;
  double derivative_tau_s = 30.0;  // smoothing of dT/dt and of the hysteresis path, s
  std::vector<double> lag_grid_s{0, 15, 30, 60, 120, 240, 480, 960};
  std::vector<double> hysteresis_width_grid_k{0, 0.5, 1, 2, 4, 8};
  int refine_iterations = 12;                           // golden-section steps per refined parameter (0: grid only)
  std::size_t ga_population = 16, ga_generations = 10;  // RBF tuning
  std::uint64_t seed = 1;
  // Progress: (stage label, fraction in [0, 1]).
  std::function<void(const std::string&, double)> progress = [](const std::string&, double) {};
};

// Throws DataError (naming the record) for records too short for the bins and blocks or giving a
// model CalibrationModel::validate() refuses (a scale factor of 0, ...), and ConfigError for
// inconsistent options.
CalibrationModel fit_calibration(const std::vector<Record>& records, const FitOptions& options);

// The two simple cubics every report sets beside a richer model, fitted with `base`'s records, bins,
// blocks and reference temperature as kind poly, order 3 (no selection), clamped outside the range of
// the bins they were fitted on:
//   fit_px4_style         the PX4/ArduPilot thermal calibration practice, the one home of every
//                         "PX4-style" figure (the baseline of `driftlab calibrate --report` and the
//                         px4_polynomial row of `driftlab run`'s Table 2): heating bins only (dT/dt
//                         estimate > 0: every heating leg of every record). When the records hold too
//                         few heating bins (a cooling-only run), the same cubic is fitted on all bins
//                         instead; the model says which in fit.heating_only.
//   fit_cubic_all_bins    every bin of every record, both directions (the cubic_whole_record row of
//                         Table 2: the strongest simple in-sample peer of a pipeline fitted on the
//                         same record).
// Both throw what fit_calibration throws when the cubic cannot be fitted.
CalibrationModel fit_px4_style(const std::vector<Record>& records, const FitOptions& base);
CalibrationModel fit_cubic_all_bins(const std::vector<Record>& records, const FitOptions& base);

// Whether several records of one channel can be one device: each record's bias (60-s bin means of
// signal - truth) gets a least-squares cubic in temperature; for every pair, the rms difference of
// the two cubics over the other record's bins inside the first one's temperature range, divided by
// the larger in-record rms of bin residuals about its own cubic. Repeated runs of one unit give a
// ratio near 1 (the noise of the bin means); two units differ by their bias, tens to thousands of
// times that. Pairs whose ranges overlap in fewer than 3 bins compare the mean levels instead.
struct Disagreement {
  double ratio = 0.0;           // largest over all pairs
  double difference_rms = 0.0;  // channel unit (rad/s gyro, m/s^2 accel)
  std::string first, second;    // the records of that pair
};
Disagreement largest_disagreement(const std::vector<Record>& records);
// Records whose disagreement ratio exceeds this are refused as one device (driftlab calibrate
// --same-device overrides): a bias difference 10x the noise of 60-s means is not one unit.
inline constexpr double kSameDeviceRatio = 10.0;

}  // namespace driftlab::calibration
