// Exports of a CalibrationModel (issue 13), each stating its order, reference temperature and units.
//
//   c_header   a self-contained C99 evaluator (static inline functions, <math.h> only) that runs the
//              same causal step as CausalCompensator: every term, the extrapolation policy, the
//              scale factor. Exact (up to libm's exp).
//   px4        PX4 thermal-compensation parameters TC_G0_* in QGroundControl .params format
//              (tab-separated "vehicle component name value type"): offset = X0 + X1 dT + X2 dT^2
//              + X3 dT^3, dT = clamp(T, TMIN, TMAX) - TREF, rad/s; corrected = raw - offset.
//   ardupilot  ArduPilot INS_TCAL1_* parameters (NAME,VALUE lines): GYRk = 1e6 x the coefficient of
//              (T - 35 degC)^k, k = 1..3, rad/s, T clamped to [TMIN, TMAX]; the constant term is the
//              gyro offset INS_GYROFFS_* at INS_GYR1_CALTEMP (ArduPilot subtracts
//              p(T - 35) - p(CALTEMP - 35) and then the offset).
//   kalibr     Kalibr imu.yaml noise terms from the model's Allan analysis (gyroscope_noise_density
//              = N rad/s/sqrt(Hz), gyroscope_random_walk = K rad/s^2/sqrt(Hz)).
//   json       the driftlab-calibration/1 file (what the MRPT bridge reads).
//
// PX4 and ArduPilot hold a cubic in temperature only. A model they cannot represent (order > 3,
// lag, dT/dt, hysteresis, RBF terms) is exported as the least-squares cubic in T over the valid
// range (201 points) of the model's polynomial part, and the export states the approximation's
// maximum error and every dropped term; with `strict` it is refused (ConfigError) instead.
#pragma once

#include <string>
#include <vector>

#include "models/calibration/calibration_model.hpp"

namespace driftlab::calibration {

struct ExportOptions {
  bool strict = false;                 // refuse instead of approximating
  std::string symbol_prefix = "driftlab_cal";  // C identifiers
  int px4_sensor_index = 0;            // TC_G<i>
  int ardupilot_imu = 1;               // INS_TCAL<i>
  double kalibr_update_rate_hz = 0.0;  // 0: the model's noise sample rate
  std::string kalibr_topic = "/imu0";
};

struct ExportResult {
  std::string text;
  std::vector<std::string> notes;  // approximations and dropped terms, also written into the text
};

// Cubic a_0..a_3 in powers of (T - t_ref) that best matches the model's polynomial part over the
// valid range; `max_error_rad_s` receives the largest deviation on the grid. Exact re-expansion
// when the polynomial has order <= 3.
std::vector<double> cubic_about(const CalibrationModel& model, double t_ref, double& max_error_rad_s);
// Terms a temperature-only polynomial cannot carry (empty when none).
std::vector<std::string> unrepresentable_terms(const CalibrationModel& model);

ExportResult export_c_header(const ChannelCalibration& channel, const ExportOptions& options = {});
ExportResult export_px4_params(const ChannelCalibration& channel, const ExportOptions& options = {});
ExportResult export_ardupilot_params(const ChannelCalibration& channel, const ExportOptions& options = {});
ExportResult export_kalibr_imu_yaml(const ChannelCalibration& channel, const ExportOptions& options = {});

}  // namespace driftlab::calibration
