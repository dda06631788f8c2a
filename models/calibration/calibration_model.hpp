// Deployable temperature calibration of an IMU: the per-channel model, the whole-IMU model (one
// model per gyro / accelerometer channel of every instance), its JSON file and the causal,
// constant-memory compensator.
//
// Files: "driftlab-calibration/2" holds the whole IMU (ImuCalibration: per channel its identity,
// source column and units, and the model); "driftlab-calibration/1", the single-axis gyro file of
// earlier versions, still reads (as an ImuCalibration with one gyro channel whose column is the
// record's "rate"). Keys carry their units: a gyro channel's in rad/s, an accelerometer's in m/s^2
// (e.g. bias.polynomial_rad_s_per_k_i / bias.polynomial_m_s2_per_k_i).
//
// The model of one channel. Its numbers are in the channel's internal unit: rad/s for a gyro,
// m/s^2 for an accelerometer (the C++ field names say rad_s after the gyro; for an accelerometer
// channel read them as m/s^2).
//
// The model, for a measured rate w_m (rad/s) and a case temperature T (degC) at time t (s):
//
//   T_m   = first-order lag of T with time constant lag_tau_s (T itself when 0)   model temperature
//   y1    = lag(T, derivative_tau_s), y2 = lag(y1, derivative_tau_s)
//   D     = (y1 - y2) / derivative_tau_s        causal dT/dt estimate, K/s (exact for a ramp after
//                                               the filter settles; delayed by ~2 derivative_tau_s)
//   s     : hysteresis branch state in [-1, 1] driven by the increments dT of y1:
//           s <- sgn(dT) + (s - sgn(dT)) exp(-|dT| / hysteresis_width_k)   (+1 heating, -1 cooling)
//   T_c   = T_m limited by the extrapolation policy to the valid range [valid_min_c, valid_max_c]
//   D_c   = D limited to temperature_rate_range_k_s, s_c = s limited to hysteresis_state_range
//           (the ranges the fitted bins cover, when the term was fitted)
//   bias  = sum_i bias_rad_s[i] (T_c - T0)^i  + temperature_rate_rad_s_per_k_s * D_c
//           + hysteresis_rad_s * s_c  + rbf(T_c, D, s)                                     (rad/s)
//   sf    = 1 + sum_j scale_factor_per_k[j] (T_c - T0)^j      (j from 0: constant scale error)
//   w     = (w_m - bias) / sf                                  compensated rate, rad/s
//
// A "poly" model has only the polynomial (and optionally the scale factor); "physical" adds the
// lag, dT/dt and hysteresis terms; "rbf" adds a Gaussian RBF network on (T_c, D, s) fitted to what
// the physical terms leave. Every filter is causal and needs O(1) state: the compensator can run
// sample by sample in firmware. All the filters start at the first sample's temperature.
//
// Extrapolation (outside [valid_min_c, valid_max_c] of the model temperature):
//   clamp     the polynomial, scale factor and RBF are evaluated at the nearest range edge (PX4)
//   linear    the polynomial continues along its tangent at the edge (scale factor and RBF clamp)
//   evaluate  the polynomial is evaluated as is (scale factor and RBF clamp)
// Every model input is limited to the range it was fitted on: T_m as above, D and s to their fitted
// ranges, the RBF's inputs to theirs. CausalCompensator::last_outside() says which input was outside
// at each step (the kOutside* bits), and `driftlab compensate` writes them per row.
//
// Validation (CalibrationModel::validate, issue 28): a model is checked as physics, not only as
// syntax, by the same rules where calibrate writes it and where compensate / export / mrpt / nav
// read it: temperatures within [kMinTemperatureC, kMaxTemperatureC] (framework/units.hpp); at most kMaxPolynomialTerms
// bias and scale-factor coefficients and kMaxRbfCentres RBF centres; every number finite; the
// scale factor within [kMinScaleFactor, kMaxScaleFactor] over the valid range (positive: it
// divides); the bias finite over the valid range and, under the linear or evaluate policy, over
// kExtrapolationMarginK beyond it; the RBF width within [kMinRbfSigma, kMaxRbfSigma].
//
// Errors: read_calibration throws ConfigError naming the file and the JSON key (a missing
// file, one that is not a regular file or larger than kMaxTextInputBytes, bad JSON, wrong format
// tag, a key repeated in one object, missing or mistyped key, inconsistent sizes, a model
// validate() refuses);
// CausalCompensator::step throws DataError on a non-increasing time stamp or a non-finite input.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "framework/imu.hpp"
#include "framework/units.hpp"

namespace driftlab::calibration {

inline constexpr const char* kFormat = "driftlab-calibration/1";     // single-axis gyro (read only)
inline constexpr const char* kImuFormat = "driftlab-calibration/2";  // whole IMU

// The bounds validate() checks (see above).
inline constexpr std::size_t kMaxPolynomialTerms = 16;  // bias and scale-factor coefficients, each
inline constexpr std::size_t kMaxRbfCentres = 10000;
inline constexpr double kMinRbfSigma = 1e-3, kMaxRbfSigma = 1e3;  // standardized units
// 1 + sum_j k_j dT^j: a MEMS scale error is percent-sized; 0 or below would divide by 0 or flip the sign.
inline constexpr double kMinScaleFactor = 0.1, kMaxScaleFactor = 10.0;
inline constexpr double kExtrapolationMarginK = 50.0;  // beyond the valid range, where a policy evaluates

// Which model inputs a compensator step found outside their fitted range (bits, ORed; 0: none):
inline constexpr unsigned kOutsideTemperature = 1;      // T_m outside [valid_min_c, valid_max_c]
inline constexpr unsigned kOutsideTemperatureRate = 2;  // D outside temperature_rate_range_k_s
inline constexpr unsigned kOutsideBranchState = 4;      // s outside hysteresis_state_range
inline constexpr unsigned kOutsideRbfInputs = 8;        // an RBF input outside [input_min, input_max]
// "model temperature, dT/dt": the inputs named by `flags`, for messages ("" for 0).
std::string outside_inputs_text(unsigned flags);

// Steps with a model input outside its fitted range, and which inputs (the bits of any of them).
struct OutsideCount {
  std::size_t samples = 0;
  unsigned inputs = 0;
  void add(unsigned flags) {
    if (flags == 0) return;
    ++samples;
    inputs |= flags;
  }
  // "12 samples had a model input outside its fitted range (model temperature, dT/dt)": `what`
  // names the samples ("drive samples", "observations").
  std::string text(const std::string& what) const;
};

// A closed range of one model input, in its unit.
struct InputRange {
  double min = 0.0, max = 0.0;
  bool contains(double x) const { return x >= min && x <= max; }
};

enum class ModelKind { Polynomial, Physical, Rbf };
std::string to_string(ModelKind kind);                               // "poly", "physical", "rbf"
std::optional<ModelKind> parse_model_kind(const std::string& text);  // inverse of to_string

enum class Extrapolation { Clamp, Linear, Evaluate };
std::string to_string(Extrapolation policy);                                // "clamp", "linear", "evaluate"
std::optional<Extrapolation> parse_extrapolation(const std::string& text);  // inverse of to_string

// Gaussian RBF network on standardized inputs u = (x - mean) / scale, x = (T_c degC, D K/s, s 1):
// rbf(x) = bias_rad_s + sum_k weights_rad_s[k] exp(-|u - centres.row(k)|^2 / (2 sigma^2)).
// Each input is first clamped to [input_min, input_max], the range of the data the network was
// fitted on: far from its data a Gaussian network returns its bias, not the physics (measured: a
// held-out profile ramping twice as fast as the calibration made an unclamped network worse than
// none). Empty ranges (files written before they existed): no clamp.
struct RbfTerm {
  std::vector<double> mean, scale;           // per input (3)
  std::vector<double> input_min, input_max;  // per input (3), x units; or both empty
  Eigen::MatrixXd centres;                   // K x 3, standardized units
  double sigma = 1.0;                        // standardized units
  std::vector<double> weights_rad_s;
  double bias_rad_s = 0.0;
};

// Allan noise terms of the compensated calibration residual (IEEE-952 names; what the records show,
// unlike the simulated truth of error_model::NoiseTerms), for the Kalman stage
// and the Kalibr export. 0 = not estimated.
// A term the residual's Allan curve did not resolve (models/allan/noise_fit.hpp: set to 0 by the
// fit, or within one sigma of 0) has its bound in *_upper: its value above is then the fit's (0 when
// set to 0) and means nothing, and no export writes it as measured. The model file lists them under
// noise.unresolved_upper; a file without that entry (written before it existed) has none.
struct ResidualNoise {
  double arw_rad_sqrt_s = 0.0;                 // N, rad/s/sqrt(Hz) = rad/sqrt(s)
  double bias_instability_rad_s = 0.0;         // B, rad/s
  double rate_random_walk_rad_s_sqrt_s = 0.0;  // K, rad/s^2/sqrt(Hz) = rad/s/sqrt(s)
  double sample_rate_hz = 0.0;                 // of the calibration records
  std::optional<double> arw_upper, bias_instability_upper, rate_random_walk_upper;  // not resolved: value < this
};

// How the model was obtained and how well it did on data it was not fitted to.
struct FitSummary {
  std::vector<std::string> records;      // calibration files
  std::size_t samples = 0;               // rows used
  double bin_s = 0.0;                    // fitting rows are means over bins of this length, s
  std::string selection;                 // how order / time constants were chosen
  std::size_t holdout_blocks = 0;        // contiguous time blocks per record
  std::string holdout_design;            // how bins were held out: whole legs, or time blocks (and why)
  double holdout_rms_rad_s = 0.0;        // pooled RMS of held-out bin residuals: the model's stated accuracy
  double uncompensated_rms_rad_s = 0.0;  // RMS of the fitted bins' bias itself (what no compensation leaves)
  double train_rms_rad_s = 0.0;          // in-sample RMS of bin residuals
  bool heating_only = false;             // fitted on heating samples only (PX4 practice)
  bool scale_factor_fitted = false;      // a true-rate column was present and varied
};

struct CalibrationModel {
  ModelKind kind = ModelKind::Polynomial;
  double reference_temp_c = 25.0;               // T0, degC
  double valid_min_c = 0.0, valid_max_c = 0.0;  // range of the calibration model temperature, degC
  Extrapolation extrapolation = Extrapolation::Clamp;

  std::vector<double> bias_rad_s;        // a_i, rad/s per K^i, i = 0..order
  std::vector<double> bias_sigma_rad_s;  // 1-sigma of a_i (same units)

  double lag_tau_s = 0.0;                       // 0: T_m = T
  double derivative_tau_s = 30.0;               // smoothing of D and of the hysteresis path, s, > 0
  double temperature_rate_rad_s_per_k_s = 0.0;  // coefficient of D, rad/s per K/s
  double temperature_rate_sigma = 0.0;
  double hysteresis_rad_s = 0.0;  // coefficient of s (cooling branch: -s), rad/s
  double hysteresis_sigma_rad_s = 0.0;
  double hysteresis_width_k = 0.0;  // 0: no hysteresis term
  // The range of D (K/s) and of s over the fitted bins, present when the term was fitted; files
  // without them (written before they existed): no limit.
  std::optional<InputRange> temperature_rate_range_k_s, hysteresis_state_range;
  std::optional<RbfTerm> rbf;

  std::vector<double> scale_factor_per_k;  // k_j, 1/K^j, j = 0..; empty: no scale-factor model

  ResidualNoise noise;
  FitSummary fit;

  int order() const { return static_cast<int>(bias_rad_s.size()) - 1; }
  bool uses_state() const {
    return lag_tau_s > 0 || temperature_rate_rad_s_per_k_s != 0.0 || hysteresis_width_k > 0 || rbf.has_value();
  }
  // The hysteresis as every report states it, the effect catalogue's convention (framework/
  // effect_catalogue.cpp, hysteresis height_dph, which `driftlab discrepancy` reports): the full gap
  // between the saturated branches, cooling minus heating, = -2 hysteresis_rad_s (bias h s with
  // s = +1 heating, -1 cooling); positive: the cooling branch above. Its 1-sigma is
  // 2 hysteresis_sigma_rad_s. Channel unit (rad/s for a gyro); 0 without a hysteresis term.
  double hysteresis_height() const { return -2.0 * hysteresis_rad_s; }
  double hysteresis_height_sigma() const { return 2.0 * hysteresis_sigma_rad_s; }
  // Polynomial part of the bias at model temperature T (degC), with the extrapolation policy.
  double polynomial_bias_rad_s(double temp_c) const;
  // Scale factor sf at T (clamped to the valid range); 1 without a scale-factor model.
  double scale_factor(double temp_c) const;
  // Throws ConfigError (no file; field = the JSON key of the channel's model) with every problem
  // found: inconsistent (empty polynomial, bad range, ...) or not physical (the rules above).
  void validate() const;
};

// One channel of a whole-IMU model: what it was fitted on, and its model.
struct ChannelCalibration {
  imu::ChannelId id;
  std::string role;                // the record role it applies to: id.role(), or "rate" (single-axis record)
  std::string column;              // the source column the model was fitted on (and applies to)
  std::string read_unit;           // the unit that column holds ("deg/s", "0.061*mdeg/s"), units.hpp
  std::string temperature_column;  // the temperature the model is a function of
  std::string device_id;           // of the instance that recorded it; empty when the source has none
  // false for an accelerometer without a reference (a static record holds gravity along the axis):
  // the constant term is not observable and is 0, the model corrects bias(T) - bias(T0).
  bool offset_observable = true;
  CalibrationModel model;
  std::string unit() const { return imu::internal_unit(id.sensor); }
};

struct ImuCalibration {
  std::string device;                        // free text (device name or file)
  std::vector<ChannelCalibration> channels;  // in the order gyro before accel, instance, axis
  const ChannelCalibration* find(const imu::ChannelId& id) const;
  void validate() const;  // every channel's model, and no channel twice (ConfigError)
};

// The model of a single-axis gyro record: one gyro channel (axis `axis`, instance 0) applied to the
// record's "rate" column and its "temperature" (what a driftlab-calibration/1 file reads as).
ImuCalibration single_axis(CalibrationModel model, char axis = 'z', std::string device = "");

// Reads a driftlab-calibration/2 file, or a /1 file as a one-channel model. ConfigError naming the
// file and the JSON key for anything wrong.
ImuCalibration read_calibration(const std::filesystem::path& json);
std::string to_json_text(const ImuCalibration& model);  // driftlab-calibration/2

// The causal filters of the model: model temperature, dT/dt estimate, hysteresis state.
class CausalState {
 public:
  CausalState(double lag_tau_s, double derivative_tau_s, double hysteresis_width_k);
  void step(double t_s, double temp_c);  // throws DataError on non-increasing time
  double model_temp_c() const { return tm_; }
  double temp_rate_k_s() const { return rate_; }
  double hysteresis_state() const { return s_; }
  bool started() const { return started_; }

 private:
  double lag_tau_, deriv_tau_, width_;
  bool started_ = false;
  double t_prev_ = 0.0, x_prev_ = 0.0, tm_ = 0.0, y1_ = 0.0, y2_ = 0.0, rate_ = 0.0, s_ = 0.0;
  double dt_cached_ = -1.0, a_lag_ = 0.0, a_der_ = 0.0;
};

class CausalCompensator {
 public:
  explicit CausalCompensator(const CalibrationModel& model);
  // time (s), measured rate (rad/s), case temperature (degC) -> compensated rate (rad/s)
  double step(double t_s, double rate_rad_s, double temp_c);
  double last_bias_rad_s() const { return bias_; }    // the correction subtracted at the last step
  unsigned last_outside() const { return outside_; }  // kOutside* bits of the last step

 private:
  double rbf_value(double tc);

  CalibrationModel model_;
  CausalState state_;
  bool stateful_;
  bool started_ = false;  // stateless models still check the time order
  double t_prev_ = 0.0;
  double bias_ = 0.0;
  unsigned outside_ = 0;
};

// Batch form: the same compensator run over a whole record (equal to streaming by construction).
struct Compensated {
  Eigen::VectorXd rate_rad_s, bias_rad_s;
  std::vector<unsigned char> outside;  // kOutside* bits per sample
};
Compensated compensate(const CalibrationModel& model, const Eigen::VectorXd& time_s, const Eigen::VectorXd& rate_rad_s,
                       const Eigen::VectorXd& temp_c);

}  // namespace driftlab::calibration
