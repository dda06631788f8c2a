// The discrepancy workflow (issue 6): fit the device's current model to a measured record, show
// where it misses, and name the physical effect it lacks; add it, refit, repeat.
//
// Model of the measured rate y (rad/s) at the block means (blocks.hpp):
//
//   y = prior(t, T_m, w) + sum_{i=0..d} b_i (T_m - T0)^i + sum_effects sum_j c_j basis_j(theta) + noise
//
// prior: the device file's systematic rate (physics, polynomials, any effects it already lists),
// fixed; without a device, w (unit scale factor, corrected by the free scale-factor polynomial below). b_i: the model's
// free parameters, a correction polynomial in temperature. T_m, the model temperature: the die temperature the device
// file implies, T_d = T + tau_s dT/dt (first-order inverse of the case sensor's lag tau_s behind the die,
// Options::sensor_time_constant_s), or the one an effect moves it to (thermal lag of T_d, drive-frequency thermometer;
// at most one such effect). w: the true rate (0 when absent). Effects see T_m as the record's temperature. Candidate
// effects are Effect plugins (framework/plugin.hpp): basis columns with linear coefficients c and at most a few
// nonlinear parameters theta.
//
// Fit and criterion. Generalized least squares with the covariance C of the block means that the
// model's own noise terms predict (white N, flicker B as a Gauss-Markov sum, random walk K;
// blocks.hpp): chi2 = r' C^-1 r (Aitken 1935), via the Cholesky factor C = L L'. Adding an effect
// with q parameters (linear + nonlinear) is scored by the Schwarz criterion (Schwarz 1978)
//
//   delta_BIC = (chi2_current - chi2_with_effect) / s2 - q ln(B),   s2 = max(1, chi2_current / (B - p))
//
// and the best effect is named when delta_BIC > significance (default 10, "very strong" on the
// 2 ln(Bayes factor) scale of Kass & Raftery, JASA 90 (1995) 773). Why this criterion and not the
// alternatives: BIC on block means with independent errors reads the slow wander of flicker and
// random-walk noise as structure (block means of coloured noise are correlated, so B overstates
// the information in the record); blocked cross-validation cannot score effects that live in one
// time block (a warm-up transient) and is dominated by the polynomial's extrapolation to held-out
// temperatures. GLS puts the coloured noise into the likelihood: a wander of the size the noise
// terms predict costs nothing, a term that explains it gains nothing. s2 inflates C when the record
// is noisier than the device file says, so a wrong noise model costs power, not false alarms. The
// look-elsewhere effect of the searches stays small: a period search tries ~B/2 independent
// frequencies, and the chance that pure noise passes with q = 3 is about (B/2) exp(-(10 + 3 ln B)/2),
// 2e-4 for B = 400. Measured: none of 128 simulated noise-only FMVMG records named anything
// (largest delta_BIC 2.4; tests/models/discrepancy_test.cpp at DRIFTLAB_DISCREPANCY_SCALE=8).
//
// Nonlinear parameters are searched one at a time on the block means, linear coefficients solved
// inside (variable projection, Golub & Pereyra 1973): a grid (EffectParameter::Scale::Log: 8 points
// per decade; Period: uniform in frequency with step 1/(4 span), periods from 4 median block
// spacings to half the span), then golden-section refinement (Kiefer 1953) between the best grid
// point's neighbours. After an effect is added, every nonlinear parameter of the model is refined
// once more with the others held, and all coefficients refitted.
// Uncertainties: Gauss-Newton covariance s2 (J' J)^-1 of all parameters (J: derivatives of the
// whitened model, finite differences for theta), propagated to the reported values by finite
// differences of Effect::describe.
//
// Gap: root mean square of the block residual y - model (rad/s). For scale, the noise floor is the
// RMS the noise terms alone would leave after the initial fit, sqrt((tr C - tr((X'C^-1X)^-1 X'X)) / B).
//
// Noise terms: the device's (Options::noise). Without them they are estimated from the overlapping
// Allan deviation (models/allan noise fit: N, B, K) of the part of the full-rate residual that no
// candidate reaches: the model plus every applicable candidate at its best parameters, fitted by
// ordinary least squares on the blocks (one temperature-moving candidate, the best), and minus what
// the views that live in temperature take (the temperature step, heating_vs_cooling,
// temperature_rate; not the time bins, which would take the random walk itself). The initial
// residual alone still holds the structure being looked for (a 310-s lag read as K = 75 deg/h/sqrt(h)
// and hid itself); the candidates' extra freedom absorbs little noise (measured: no noise-only
// record names anything, tests/models/discrepancy_test.cpp, WithoutTheDeviceFile). A record with
// gaps needs the noise terms given.
// With Options::noise_gmwm the terms are read off the same residual's OADEV curve by GMWM
// (Guerrier et al. 2013) instead: a Gauss-Markov bias noise (the bump of a MEMS bias instability,
// correlation time 100-400 s) then enters the covariance as itself rather than as a flicker level,
// which spreads its power over every scale and leaves the slow wander to the candidates.
//
// Without a prior (no device file) and with a true-rate channel that moves, the model also has a
// free scale-factor polynomial w (T - T0)^i, i = 0..d: there is no device scale factor to differ
// from, so effect/scale_factor_temperature gains nothing then.
//
// Cost: O(n) for blocks and the full-rate model; O(B^3) once for the Cholesky factor; per search
// evaluation O(B^2 q) (whitening the effect's columns) or O(B^2 p) for effects that move the model
// temperature. A 5-h record at 5 Hz (90 000 samples, B = 400): about 0.3 s on one core
// (driftlab-bench BM_Discrepancy/90000).
#pragma once

#include <Eigen/Core>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "framework/plugin.hpp"
#include "framework/time_series.hpp"
#include "models/discrepancy/blocks.hpp"
#include "models/discrepancy/views.hpp"
#include "models/error_model/error_model.hpp"

namespace driftlab::discrepancy {

// The device's systematic rate (rad/s) at times t, model temperatures T (degC) and true rates w (rad/s).
using PriorFn = std::function<Eigen::VectorXd(const Eigen::VectorXd& time_s, const Eigen::VectorXd& temp_c,
                                              const Eigen::VectorXd& true_rate_rad_s)>;

struct Candidate {
  std::string name;                // reported name, e.g. "thermal_lag"
  const Effect* effect = nullptr;  // not owned
};

struct Options {
  double reference_temp_c = 25.0;                // T0
  int bias_degree = 2;                           // d, degree of the free correction polynomial
  PriorFn prior;                                 // empty: w (scale factor 1, no bias)
  double sensor_time_constant_s = 0.0;           // tau_s: the temperature channel lags the die by this
  double drive_frequency_at_reference_hz = 0.0;  // device's drive mode at T0 (for effects; 0 = unknown)
  double drive_frequency_slope_hz_per_k = 0.0;   // its df/dT at T0 (0 = unknown)
  std::optional<error_model::NoiseTerms> noise;  // empty: estimated (see above)
  // How estimated noise terms are read off the residual's OADEV curve: empty, the IEEE-952 slope
  // fit (N, B as flicker, K); or a GMWM composite model of wn, rw and gm terms (e.g. "wn+rw+gm",
  // models/allan/gmwm.hpp): N, K and each Gauss-Markov term (sigma, T) as fitted, no flicker.
  std::string noise_gmwm;
  double block_s = 0.0;        // 0: duration / 400, at least one sample interval
  double significance = 10.0;  // delta_BIC needed to name an effect
  int max_effects = 4;
  int grid_points_per_decade = 8;
  int golden_iterations = 20;
};

struct ReportedValue {
  std::string key, unit;
  std::vector<double> values;
  std::vector<double> sigmas;  // one standard deviation; NaN where the value is not a fitted parameter
};

struct Score {
  std::string effect;
  bool applicable = true;
  std::string note;  // why it is not applicable
  double delta_chi2 = 0.0;
  double delta_bic = -std::numeric_limits<double>::infinity();
  int added_parameters = 0;
  Eigen::VectorXd theta;  // best nonlinear parameters found
};

struct Step {
  std::string effect;
  std::vector<ReportedValue> parameters;
  double gap_before_rad_s = 0.0, gap_after_rad_s = 0.0;
  double delta_chi2 = 0.0, delta_bic = 0.0;
  double chi2_scale = 1.0;    // s2 of the criterion at this step
  std::vector<Score> scores;  // every candidate at this step, best first
};

// Structure left in the residual that no candidate explains, tested in generic views of it (the
// same GLS criterion as the candidates, q = the view's columns outside the model's span):
//   temperature         bias by temperature: indicators of 8 equal-count temperature bins, or a
//                       step at one temperature level (whichever scores higher; see below)
//   heating_vs_cooling  branch offset: sgn(dT/dt) and sgn(dT/dt) (T - T0)
//   temperature_rate    dT/dt times a quadratic in T - T0 (dT/dt, x dT/dt, x^2 dT/dt)
//   time                indicators of 8 equal time spans
// A candidate is named only when its delta_BIC is within `significance` of the best view's: when a
// view beats every candidate by more, the workflow stops and reports the residual as unexplained
// (in that view) instead of naming a candidate that does not fit. After the last named effect the
// views are tested once more.
struct StructureTest {
  std::string view;  // one of the names above
  double delta_chi2 = 0.0, delta_bic = -std::numeric_limits<double>::infinity();
  int parameters = 0;       // q
  double size_rad_s = 0.0;  // rms over the blocks of the view's fitted component
  std::string where;        // e.g. "largest at 14.2 .. 25.8 degC (+160 deg/h)"
  // The temperature view has a second form, a step in bias where the temperature crosses one
  // level (q = 2: size and level, the level searched); it replaces the bins when it scores higher.
  struct TemperatureStep {
    double level_c = 0.0;
    double size_rad_s = 0.0;  // from the joint fit with the model
  };
  std::optional<TemperatureStep> step;
};

struct Unexplained {
  bool found = false;                // a view's delta_BIC exceeds the significance
  std::vector<StructureTest> views;  // every view, best first
};

struct Result {
  Unexplained unexplained;          // after the last named effect (or instead of a wrong one)
  std::vector<Step> steps;          // the named effects, in order
  std::vector<Score> final_scores;  // the round that found nothing significant (empty if max_effects stopped it)
  double gap_initial_rad_s = 0.0, gap_final_rad_s = 0.0, noise_floor_rad_s = 0.0;
  double block_s = 0.0;
  Eigen::Index blocks = 0;
  double chi2_initial = 0.0, chi2_final = 0.0;
  error_model::NoiseTerms noise;  // the terms used
  bool noise_estimated = false;
  std::vector<double> bias_coefficients_initial, bias_coefficients_final;  // b_i, rad/s/K^i
  Eigen::VectorXd model_initial_rad_s, model_final_rad_s;                  // systematic rate at every sample
  Views initial_views, final_views;
};

// Runs the workflow. The record needs channels rate and temperature; true_rate and
// drive_frequency are used when present (die_temperature is never read: a real gyro does not
// report its resonator temperature). Throws DataError when a channel is missing or the record is
// too short for the model (fewer blocks than 3 x its parameters), ConfigError for bad options.
Result find_missing_effects(const TimeSeries& record, const std::vector<Candidate>& candidates, const Options& options);

}  // namespace driftlab::discrepancy
