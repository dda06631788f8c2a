// Exports of a whole-IMU calibration (ImuCalibration, driftlab-calibration/2; a /1 single-axis file
// reads as one gyro channel): every channel of every instance goes into one file. Numbers are in the
// channels' internal units: gyro rad/s, accelerometer m/s^2 (N in rad/s/sqrt(Hz) or m/s^2/sqrt(Hz),
// K in rad/s^2/sqrt(Hz) or m/s^3/sqrt(Hz)); temperatures degC. The axes are the record's axes: the
// firmware applies its thermal correction to the sensor's own x/y/z as it logs them (PX4: board frame
// before the vehicle rotation; ArduPilot: after INS orientation, before AHRS_ORIENTATION).
//
//   c_header   self-contained C99 (<math.h> only, static inline, no allocation): one P_model per
//              channel and P_step(&P_gyro1_x, &state, t, x, T, ...) running the same causal step as
//              CausalCompensator (every term, the extrapolation policy, the scale factor), plus
//              P_imu_step for all channels at once. Exact up to libm's exp. Inputs in the channel's
//              internal unit, not the column's read unit.
//   px4        QGroundControl .params (tab-separated "vehicle component name value type", type 6 INT32,
//              9 REAL32). Per sensor s in {G gyro, A accel} and instance i (0..3): TC_s{i}_ID,
//              TC_s{i}_TREF, TC_s{i}_TMIN, TC_s{i}_TMAX, TC_s{i}_X{k}_{a} (k = 0..3, a = 0 x, 1 y, 2 z),
//              and TC_G_ENABLE / TC_A_ENABLE = 1 for each sensor the model has. PX4's correction
//              (TemperatureCompensation::calc_thermal_offsets_3D, float arithmetic):
//                dT = clamp(T, TMIN, TMAX) - TREF;  offset = X0 + X1 dT + X2 dT^2 + X3 dT^3
//                corrected = raw - offset - CAL_* offset            (rad/s; m/s^2)
//              TREF is the T0 of the block's first channel, so an accelerometer without a reference
//              (offset not observable, a0 = 0) gets X0 = 0 when its axes share T0; PX4's accelerometer
//              calibration (run after loading, TC_A_ENABLE = 1: it adjusts X0) supplies the constant. TC_s{i}_ID is the
//              channel's device_id when it is a PX4 integer device id, else 0 with a comment asking to set it (PX4
//              matches sensors by that id).
//   ardupilot  Mission Planner .parm (NAME,VALUE). Per instance i (n = i + 1, 1..3): INS_TCAL{n}_ENABLE,
//              _TMIN, _TMAX, _GYR{k}_{X,Y,Z}, _ACC{k}_{X,Y,Z} (k = 1..3). ArduPilot's correction
//              (AP_InertialSensor_TCal::correct_sensor, float arithmetic; 35 degC TEMP_REFERENCE,
//              SCALE_FACTOR 1e6, no constant term):
//                p(d) = (C1 + (C2 + C3 d) d) d * 1e-6,  Ck = INS_TCAL{n}_GYRk_* or _ACCk_*
//                T' = clamp(T, TMIN, TMAX), Tc = clamp(CALTEMP, TMIN, TMAX)
//                corrected = raw - p(T' - 35) + p(Tc - 35) - offset
//              with CALTEMP / offset = INS_GYR{n}_CALTEMP / INS_GYROFFS_* (INS_GYR{n}OFFS_* for n > 1)
//              for the gyro and INS_ACC{n}_CALTEMP / INS_ACCOFFS_* (INS_ACC{n}OFFS_*) for the
//              accelerometer. The gyro constant goes into the offset: the export writes INS_GYR*OFFS_* =
//              the model at CALTEMP = clamp(35, TMIN, TMAX) and that CALTEMP (the boot-time gyro
//              calibration, INS_GYR_CAL = 1, replaces both with a fresh measurement, which is as good).
//              The accelerometer constant is left to ArduPilot's own accelerometer calibration (it
//              measures INS_ACC*OFFS_* and records INS_ACC{n}_CALTEMP): the export writes ACC1..3 only.
//   kalibr     imu.yaml of one instance (ExportOptions::kalibr_instance): gyroscope_noise_density = N
//              and gyroscope_random_walk = K of its gyro axes, accelerometer_noise_density and
//              accelerometer_random_walk of its accelerometer axes (continuous-time, Kalibr's names);
//              several axes are combined by taking the largest (the file lists every axis). Refused
//              (ConfigError) when the instance lacks gyro or accelerometer channels or a term is not
//              measured (0): no placeholders. A term the records only bound (ResidualNoise::*_upper) counts
//              with its bound; when that is the largest, the value is refused too, unless
//              kalibr_allow_bounds: then the bound is written, its line saying "UPPER BOUND, not a
//              measured value" and naming the axes.
//   json       the driftlab-calibration/2 file itself: to_json_text (calibration_model.hpp).
//
// PX4 and ArduPilot hold, per channel, a cubic in temperature with one [TMIN, TMAX] per block (PX4:
// sensor and instance; ArduPilot: instance, gyro and accelerometer together): the intersection of the
// block's valid ranges. A channel they cannot represent (order > 3, lag, dT/dt, hysteresis, RBF terms,
// a scale factor, the linear or evaluate extrapolation policy, a valid range wider than the block's) is exported as the
// least-squares cubic in T over its valid range (201 points) of the model's polynomial part, and the export states per
// channel the approximation's maximum error and every dropped term (ExportResult::losses and comments in the file);
// with `strict` it is refused (ConfigError naming the channel) instead. Every value written is checked to be a finite
// REAL32 number (ConfigError naming the channel and parameter otherwise); the text carries 9 significant digits, which
// round-trips a float.
#pragma once

#include <string>
#include <vector>

#include "framework/imu.hpp"
#include "models/calibration/calibration_model.hpp"

namespace driftlab::calibration {

struct ExportOptions {
  bool strict = false;                         // refuse instead of approximating
  std::string symbol_prefix = "driftlab_cal";  // C identifiers: [A-Za-z][A-Za-z0-9_]*, no "__", no trailing "_", <= 32
  int kalibr_instance = 0;                     // the IMU instance of the Kalibr file
  double kalibr_update_rate_hz = 0.0;          // 0: the channels' noise sample rate
  std::string kalibr_topic = "/imu0";
  bool kalibr_allow_bounds = false;  // write a noise value the records only bound as that bound, marked
};

// What the firmware's form drops for one channel.
struct ChannelLoss {
  imu::ChannelId id;
  // Largest |firmware polynomial - model polynomial part| over the channel's valid range, in the
  // channel's internal unit (cubic approximation and clipping to the block's [TMIN, TMAX]; 0 when
  // exact), before REAL32 rounding. The approximation's own error is the maximum on a 201-point grid;
  // it counts twice for an ArduPilot accelerometer, whose correction is the difference to the
  // temperature of ArduPilot's own accelerometer calibration (and so for a gyro whose offset a
  // boot-time calibration replaced).
  double max_error = 0.0;
  std::vector<std::string> dropped;  // terms the form does not carry (empty when none)
};

struct ExportResult {
  std::string text;
  std::vector<std::string> notes;   // approximations and dropped terms, also written into the text
  std::vector<ChannelLoss> losses;  // PX4 and ArduPilot: one per channel exported
};

// Cubic a_0..a_3 in powers of (T - t_ref) that best matches the model's polynomial part over the
// valid range; `max_error` receives the largest deviation on the grid (internal unit). Exact
// re-expansion when the polynomial has order <= 3.
std::vector<double> cubic_about(const CalibrationModel& model, double t_ref, double& max_error);
// Terms a temperature-only polynomial cannot carry (empty when none), in the sensor's unit.
std::vector<std::string> unrepresentable_terms(const CalibrationModel& model, imu::Sensor sensor = imu::Sensor::Gyro);

ExportResult export_c_header(const ImuCalibration& model, const ExportOptions& options = {});
ExportResult export_px4_params(const ImuCalibration& model, const ExportOptions& options = {});
ExportResult export_ardupilot_params(const ImuCalibration& model, const ExportOptions& options = {});
ExportResult export_kalibr_imu_yaml(const ImuCalibration& model, const ExportOptions& options = {});

}  // namespace driftlab::calibration
