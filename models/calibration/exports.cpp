#include "models/calibration/exports.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include "framework/error.hpp"
#include "framework/units.hpp"

namespace driftlab::calibration {
namespace {

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string short_num(double v) {  // 9 significant digits: round-trips a REAL32
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

// User text (device names, columns) on one comment line.
std::string one_line(std::string text) {
  for (auto& ch : text) {
    if (ch == '\n' || ch == '\r') ch = ' ';
  }
  return text;
}

// "value unit", with deg/h beside a gyro value.
std::string with_unit(double value, imu::Sensor sensor) {
  if (sensor == imu::Sensor::Accel) return short_num(value) + " m/s^2";
  return short_num(value) + " rad/s (" + short_num(value * kDphPerRadPerSec) + " deg/h)";
}

// A value the firmware stores as REAL32: finite and within float's range, written with 9 digits.
std::string real32(double value, const std::string& channels, const std::string& parameter) {
  if (!std::isfinite(value) || std::abs(value) > static_cast<double>(std::numeric_limits<float>::max())) {
    throw ConfigError({"", 0, parameter}, channels + ": " + parameter + " = " + num(value) +
                                              " is not a finite REAL32 number (|value| <= 3.4e38)");
  }
  return short_num(value);
}

using Channels = std::vector<const ChannelCalibration*>;

std::string roles(const Channels& channels) {
  std::string out;
  for (const auto* c : channels) out += (out.empty() ? "" : ", ") + c->id.role();
  return out;
}

// Channels sharing one firmware temperature range, with that range: the intersection of theirs.
struct Block {
  Channels channels;  // sorted by sensor, axis
  double tmin_c = 0.0, tmax_c = 0.0;
};

Block make_block(Channels channels, const std::string& format) {
  std::sort(channels.begin(), channels.end(), [](const auto* a, const auto* b) { return a->id < b->id; });
  Block b{channels, -std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  for (const auto* c : channels) {
    b.tmin_c = std::max(b.tmin_c, c->model.valid_min_c);
    b.tmax_c = std::min(b.tmax_c, c->model.valid_max_c);
  }
  if (!(b.tmin_c < b.tmax_c)) {
    std::string ranges;
    for (const auto* c : channels) {
      ranges += (ranges.empty() ? "" : ", ") + c->id.role() + " " + short_num(c->model.valid_min_c) + " .. " +
                short_num(c->model.valid_max_c) + " degC";
    }
    throw ConfigError({"", 0, "valid_range_c"}, format + " holds one [TMIN, TMAX] for " + roles(channels) +
                                                    "; their valid ranges do not overlap (" + ranges + ")");
  }
  return b;
}

// Groups of channels by a key (sensor / instance), in key order.
template <typename Key, typename KeyOf>
std::map<Key, Channels> group(const ImuCalibration& model, KeyOf key_of) {
  std::map<Key, Channels> out;
  for (const auto& c : model.channels) out[key_of(c)].push_back(&c);
  return out;
}

// The cubic about t_ref that the firmware evaluates for `c` on [tmin, tmax], with what it loses
// (appended to r.losses and r.notes); refused in strict mode when it is not exact. `difference_form`:
// the firmware corrects p(T) - p(T_cal) and takes the constant from its own calibration at T_cal, so
// the cubic's error enters twice.
std::vector<double> firmware_cubic(const ChannelCalibration& c, double t_ref, const Block& block,
                                   const std::string& format, bool difference_form, const ExportOptions& o,
                                   ExportResult& r) {
  const CalibrationModel& m = c.model;
  const std::string who = c.id.role();
  double cubic_error = 0.0;
  auto cubic = cubic_about(m, t_ref, cubic_error);
  ChannelLoss loss{c.id, 0.0, unrepresentable_terms(m, c.id.sensor)};
  if (!m.scale_factor_per_k.empty()) loss.dropped.push_back("scale-factor model (" + format + " carries offsets only)");
  if (m.extrapolation != Extrapolation::Clamp)
    loss.dropped.push_back("the '" + to_string(m.extrapolation) + "' extrapolation outside the valid range (" + format +
                           " clamps the temperature to [TMIN, TMAX])");
  // Held at the block's edges where the channel's own range extends beyond them.
  double clip_error = 0.0;
  if (block.tmin_c > m.valid_min_c || block.tmax_c < m.valid_max_c) {
    constexpr int kGrid = 201;
    for (int g = 0; g < kGrid; ++g) {
      const double t = m.valid_min_c + (m.valid_max_c - m.valid_min_c) * g / (kGrid - 1);
      clip_error = std::max(clip_error, std::abs(m.polynomial_bias_rad_s(t) -
                                                 m.polynomial_bias_rad_s(std::clamp(t, block.tmin_c, block.tmax_c))));
    }
  }
  loss.max_error = (difference_form ? 2.0 : 1.0) * cubic_error + clip_error;
  const bool exact = m.order() <= 3 && clip_error == 0.0 && loss.dropped.empty();
  if (!exact && o.strict) {
    std::string why = m.order() > 3 ? "polynomial order " + std::to_string(m.order()) + " > 3" : "";
    if (clip_error > 0)
      why += std::string(why.empty() ? "" : "; ") + "a valid range wider than the shared [TMIN, TMAX]";
    for (const auto& d : loss.dropped) why += (why.empty() ? "" : "; ") + d;
    throw ConfigError({"", 0, who}, format + " holds a cubic in temperature only; channel " + who + " has " + why +
                                        " (export without --strict for the best cubic with its stated error)");
  }
  const auto note = [&](const std::string& text) { r.notes.push_back(who + ": " + text); };
  if (m.order() > 3) {
    note("order-" + std::to_string(m.order()) + " polynomial approximated by the least-squares cubic over " +
         short_num(m.valid_min_c) + " .. " + short_num(m.valid_max_c) + " degC: max error " +
         with_unit(cubic_error, c.id.sensor) +
         (difference_form ? " (twice that on the correction, a difference to the firmware's calibration temperature)"
                          : ""));
  }
  if (clip_error > 0) {
    note("valid range " + short_num(m.valid_min_c) + " .. " + short_num(m.valid_max_c) +
         " degC held at [TMIN, TMAX] = " + short_num(block.tmin_c) + " .. " + short_num(block.tmax_c) +
         " degC (shared with " + roles(block.channels) + "): up to " + with_unit(clip_error, c.id.sensor));
  }
  for (const auto& d : loss.dropped) note("dropped (not representable in " + format + "): " + d);
  r.losses.push_back(std::move(loss));
  return cubic;
}

void write_notes(std::ostringstream& s, const std::vector<std::string>& notes, std::size_t from) {
  for (std::size_t i = from; i < notes.size(); ++i) s << "# NOTE: " << one_line(notes[i]) << "\n";
}

int axis_index(char axis) { return axis - 'x'; }

// The PX4 device id of a block: the channels' device_id when it is a decimal integer PX4 can hold.
struct DeviceId {
  long long value = 0;
  std::string comment;  // why 0, when it is
};

DeviceId px4_device_id(const Channels& channels, const std::string& parameter) {
  std::string id;
  for (const auto* c : channels) {
    if (c->device_id.empty()) continue;
    if (!id.empty() && c->device_id != id) {
      throw ConfigError({"", 0, parameter}, roles(channels) + " share " + parameter +
                                                " but their device ids differ (\"" + id + "\", \"" + c->device_id +
                                                "\")");
    }
    id = c->device_id;
  }
  if (id.empty()) return {0, "no device id in the model: set " + parameter + " to the sensor's device id"};
  const bool digits =
      id.size() <= 10 && std::all_of(id.begin(), id.end(), [](char ch) { return ch >= '0' && ch <= '9'; });
  if (digits && std::stoll(id) <= std::numeric_limits<std::int32_t>::max()) return {std::stoll(id), ""};
  return {0, "device id \"" + one_line(id) + "\" is not a PX4 integer device id: set " + parameter +
                 " to the sensor's device id"};
}

}  // namespace

std::vector<double> cubic_about(const CalibrationModel& m, double t_ref, double& max_error) {
  max_error = 0.0;
  std::vector<double> c(4, 0.0);
  if (m.order() <= 3) {  // exact: re-expand sum a_i (T - T0)^i about t_ref (binomial)
    const double d = t_ref - m.reference_temp_c;
    for (int i = 0; i <= m.order(); ++i) {
      double binom = 1.0;
      for (int k = 0; k <= i; ++k) {
        c[static_cast<std::size_t>(k)] += m.bias_rad_s[static_cast<std::size_t>(i)] * binom * std::pow(d, i - k);
        binom = binom * (i - k) / (k + 1);
      }
    }
    return c;
  }
  constexpr int kGrid = 201;
  const double half = std::max(0.5 * (m.valid_max_c - m.valid_min_c), 1e-6);
  Eigen::MatrixXd A(kGrid, 4);
  Eigen::VectorXd y(kGrid);
  for (int g = 0; g < kGrid; ++g) {
    const double t = m.valid_min_c + (m.valid_max_c - m.valid_min_c) * g / (kGrid - 1);
    const double u = (t - t_ref) / half;
    for (int k = 0; k < 4; ++k) A(g, k) = std::pow(u, k);
    y[g] = m.polynomial_bias_rad_s(t);  // the grid lies inside the valid range
  }
  const Eigen::VectorXd b = A.colPivHouseholderQr().solve(y);
  max_error = (A * b - y).cwiseAbs().maxCoeff();
  for (int k = 0; k < 4; ++k) c[static_cast<std::size_t>(k)] = b[k] / std::pow(half, k);
  return c;
}

std::vector<std::string> unrepresentable_terms(const CalibrationModel& m, imu::Sensor sensor) {
  const bool gyro = sensor == imu::Sensor::Gyro;
  const std::string unit = gyro ? "rad/s" : "m/s^2";
  std::vector<std::string> out;
  if (m.lag_tau_s > 0)
    out.push_back("thermal lag tau = " + short_num(m.lag_tau_s) +
                  " s (the cubic is applied to the sensor temperature)");
  if (m.temperature_rate_rad_s_per_k_s != 0.0) {
    const double per_k_min = m.temperature_rate_rad_s_per_k_s / 60.0;
    out.push_back("dT/dt term " + short_num(m.temperature_rate_rad_s_per_k_s) + " " + unit + " per K/s (" +
                  (gyro ? short_num(per_k_min * kDphPerRadPerSec) + " deg/h" : short_num(per_k_min) + " m/s^2") +
                  " at 1 K/min)");
  }
  if (m.hysteresis_width_k > 0)
    out.push_back("hysteresis branch term +-" + with_unit(std::abs(m.hysteresis_rad_s), sensor));
  if (m.rbf && m.rbf->centres.rows() > 0) {
    out.push_back("RBF network of " + std::to_string(m.rbf->centres.rows()) + " centres on (T, dT/dt, branch)");
  }
  return out;
}

ExportResult export_px4_params(const ImuCalibration& model, const ExportOptions& o) {
  model.validate();
  constexpr int kMaxInstance = 3;  // TC_G0..3, TC_A0..3
  for (const auto& c : model.channels) {
    if (c.id.instance > kMaxInstance) {
      throw ConfigError({"", 0, c.id.role()}, "PX4 holds TC_G0..3 / TC_A0..3; channel " + c.id.role() +
                                                  " is of instance " + std::to_string(c.id.instance));
    }
  }
  const auto blocks = group<std::pair<imu::Sensor, int>>(model, [](const auto& c) {
    return std::pair{c.id.sensor, c.id.instance};
  });
  ExportResult r;
  std::ostringstream body;
  const auto line = [&](const std::string& name, const std::string& value, int type) {
    body << "1\t1\t" << name << "\t" << value << "\t" << type << "\n";
  };
  bool gyro = false, accel = false;
  for (const auto& [key, channels] : blocks) (key.first == imu::Sensor::Gyro ? gyro : accel) = true;
  if (gyro) line("TC_G_ENABLE", "1", 6);
  if (accel) line("TC_A_ENABLE", "1", 6);
  for (const auto& [key, channels] : blocks) {
    const auto [sensor, instance] = key;
    const bool is_gyro = sensor == imu::Sensor::Gyro;
    const std::string p = std::string("TC_") + (is_gyro ? "G" : "A") + std::to_string(instance) + "_";
    const Block block = make_block(channels, "PX4 " + p + "*");
    const double tref = block.channels.front()->model.reference_temp_c;
    const std::size_t first_note = r.notes.size();
    double x[4][3] = {};
    bool present[3] = {false, false, false};
    std::string axis_role[3];
    for (const auto* c : block.channels) {
      const auto cubic = firmware_cubic(*c, tref, block, "PX4 " + p + "*", false, o, r);
      const int a = axis_index(c->id.axis);
      present[a] = true;
      axis_role[a] = c->id.role();
      for (int k = 0; k < 4; ++k) x[k][a] = cubic[static_cast<std::size_t>(k)];
    }
    const DeviceId id = px4_device_id(block.channels, p + "ID");
    body << "# " << p << "*: " << (is_gyro ? "gyro" : "accelerometer") << " instance " << instance << " ("
         << roles(block.channels) << "; columns";
    for (const auto* c : block.channels) body << " " << one_line(c->column) << " [" << one_line(c->read_unit) << "]";
    body << "), " << (is_gyro ? "rad/s" : "m/s^2") << "\n";
    std::string absent;
    for (int a = 0; a < 3; ++a) absent += present[a] ? "" : std::string(absent.empty() ? "" : ", ") + char('x' + a);
    if (!absent.empty()) body << "# axes " << absent << " are not in the model: written as 0 (no correction)\n";
    if (!is_gyro) {
      for (const auto* c : block.channels) {
        if (!c->offset_observable) {
          body << "# " << c->id.role() << ": offset not observable (no reference): X0 is relative to "
               << short_num(c->model.reference_temp_c)
               << " degC; PX4's accelerometer calibration sets X0 (run it after loading, inside TMIN..TMAX)\n";
        }
      }
    }
    if (!id.comment.empty()) body << "# " << id.comment << "\n";
    write_notes(body, r.notes, first_note);
    const std::string who = roles(block.channels);
    line(p + "ID", std::to_string(id.value), 6);
    line(p + "TMAX", real32(block.tmax_c, who, p + "TMAX"), 9);
    line(p + "TMIN", real32(block.tmin_c, who, p + "TMIN"), 9);
    line(p + "TREF", real32(tref, who, p + "TREF"), 9);
    for (int k = 0; k < 4; ++k) {
      for (int a = 0; a < 3; ++a) {
        const std::string name = p + "X" + std::to_string(k) + "_" + std::to_string(a);
        line(name, real32(x[k][a], present[a] ? axis_role[a] : who, name), 9);
      }
    }
  }
  std::ostringstream s;
  s << "# Onboard parameters for Vehicle 1\n"
    << "# PX4 thermal compensation from driftlab (" << kImuFormat << ", device \"" << one_line(model.device) << "\")\n"
    << "# offset = X0 + X1*dT + X2*dT^2 + X3*dT^3, dT = clamp(T, TMIN, TMAX) - TREF [degC]; corrected = raw - offset\n"
    << "# (gyro rad/s, accelerometer m/s^2; axis suffix 0 x, 1 y, 2 z). PX4 applies a TC_*{i} block to the\n"
    << "# sensor whose device id equals TC_*{i}_ID, and subtracts its CAL_GYRO*/CAL_ACC* offsets as well: the record\n"
    << "# must hold raw values (PX4's offboard procedure resets those to defaults before logging).\n"
    << "#\n# Vehicle-Id Component-Id Name Value Type\n"
    << body.str();
  r.text = s.str();
  return r;
}

ExportResult export_ardupilot_params(const ImuCalibration& model, const ExportOptions& o) {
  model.validate();
  constexpr double kReference = 35.0;  // ArduPilot's fixed TEMP_REFERENCE, degC
  constexpr double kScale = 1e6;       // ArduPilot's SCALE_FACTOR of the coefficients
  constexpr int kMaxInstance = 2;      // INS_TCAL1..3
  for (const auto& c : model.channels) {
    if (c.id.instance > kMaxInstance) {
      throw ConfigError({"", 0, c.id.role()}, "ArduPilot holds INS_TCAL1..3; channel " + c.id.role() +
                                                  " is of instance " + std::to_string(c.id.instance));
    }
  }
  const auto instances = group<int>(model, [](const auto& c) { return c.id.instance; });
  ExportResult r;
  std::ostringstream s;
  s << "# ArduPilot IMU temperature calibration from driftlab (" << kImuFormat << ", device \""
    << one_line(model.device) << "\")\n"
    << "# INS_TCALn_GYRk_* / _ACCk_* = 1e6 x the coefficient of (T - 35 degC)^k, k = 1..3 (rad/s, m/s^2); T clamped "
       "to\n"
    << "# [TMIN, TMAX]. ArduPilot subtracts p(T - 35) - p(CALTEMP - 35) and then the sensor offset. Gyro: the offset\n"
    << "# INS_GYROFFS_* (INS_GYRnOFFS_*) is the model at INS_GYRn_CALTEMP (a boot-time gyro calibration replaces "
       "both).\n"
    << "# Accelerometer: no constant term is written; ArduPilot's accelerometer calibration measures INS_ACC*OFFS_* "
       "and\n"
    << "# INS_ACCn_CALTEMP: run it after loading, inside [TMIN, TMAX].\n";
  for (const auto& [instance, channels] : instances) {
    const int n = instance + 1;
    const std::string p = "INS_TCAL" + std::to_string(n) + "_";
    const Block block = make_block(channels, "ArduPilot " + p + "*");
    const std::size_t first_note = r.notes.size();
    double coef[2][3][4] = {};  // [gyro, accel][axis][k]
    bool present[2][3] = {};
    std::string axis_role[2][3];
    for (const auto* c : block.channels) {
      const auto cubic =
          firmware_cubic(*c, kReference, block, "ArduPilot " + p + "*", c->id.sensor == imu::Sensor::Accel, o, r);
      const int sidx = c->id.sensor == imu::Sensor::Gyro ? 0 : 1;
      present[sidx][axis_index(c->id.axis)] = true;
      axis_role[sidx][axis_index(c->id.axis)] = c->id.role();
      for (int k = 0; k < 4; ++k) coef[sidx][axis_index(c->id.axis)][k] = cubic[static_cast<std::size_t>(k)];
    }
    s << "# " << p << "*: instance " << instance << " (" << roles(block.channels) << "; columns";
    for (const auto* c : block.channels) s << " " << one_line(c->column) << " [" << one_line(c->read_unit) << "]";
    s << ")\n";
    std::string absent;
    for (int sidx = 0; sidx < 2; ++sidx) {
      for (int a = 0; a < 3; ++a) {
        if (!present[sidx][a]) {
          absent += (absent.empty() ? "" : ", ") + imu::ChannelId{sidx == 0 ? imu::Sensor::Gyro : imu::Sensor::Accel,
                                                                  static_cast<char>('x' + a), instance}
                                                       .role();
        }
      }
    }
    if (!absent.empty()) s << "# " << absent << ": not in the model, written as 0 (no correction)\n";
    write_notes(s, r.notes, first_note);
    const std::string who = roles(block.channels);
    s << p << "ENABLE,1\n";
    s << p << "TMIN," << real32(block.tmin_c, who, p + "TMIN") << "\n";
    s << p << "TMAX," << real32(block.tmax_c, who, p + "TMAX") << "\n";
    for (int sidx = 0; sidx < 2; ++sidx) {
      for (int k = 1; k <= 3; ++k) {
        for (int a = 0; a < 3; ++a) {
          const std::string name = p + (sidx == 0 ? "GYR" : "ACC") + std::to_string(k) + "_" + char('X' + a);
          s << name << "," << real32(kScale * coef[sidx][a][k], present[sidx][a] ? axis_role[sidx][a] : who, name)
            << "\n";
        }
      }
    }
    if (present[0][0] || present[0][1] || present[0][2]) {
      const double caltemp = std::clamp(kReference, block.tmin_c, block.tmax_c);
      const std::string offs = n == 1 ? "INS_GYROFFS_" : "INS_GYR" + std::to_string(n) + "OFFS_";
      for (int a = 0; a < 3; ++a) {
        if (!present[0][a]) continue;
        double offset = 0.0;  // the cubic at CALTEMP, constant term included
        for (int k = 3; k >= 0; --k) offset = offset * (caltemp - kReference) + coef[0][a][k];
        const std::string name = offs + char('X' + a);
        s << name << "," << real32(offset, axis_role[0][a], name) << "\n";
      }
      const std::string name = "INS_GYR" + std::to_string(n) + "_CALTEMP";
      s << name << "," << real32(caltemp, who, name) << "\n";
    }
  }
  r.text = s.str();
  return r;
}

ExportResult export_kalibr_imu_yaml(const ImuCalibration& model, const ExportOptions& o) {
  model.validate();
  Channels gyro, accel;
  for (const auto& c : model.channels) {
    if (c.id.instance == o.kalibr_instance) (c.id.sensor == imu::Sensor::Gyro ? gyro : accel).push_back(&c);
  }
  const std::string which = "instance " + std::to_string(o.kalibr_instance);
  if (gyro.empty() || accel.empty()) {
    throw ConfigError({"", 0, "channels"},
                      "Kalibr's imu.yaml needs gyroscope and accelerometer noise terms; the model has " +
                          std::string(gyro.empty() ? "no gyro" : "no accelerometer") + " channel of " + which +
                          " (calibrate with --channels gyro,accel; choose the instance with --instance)");
  }
  Channels all = gyro;
  all.insert(all.end(), accel.begin(), accel.end());
  double rate = o.kalibr_update_rate_hz > 0 ? o.kalibr_update_rate_hz : 0.0;
  for (const auto* c : all) {
    const double fs = c->model.noise.sample_rate_hz;
    if (o.kalibr_update_rate_hz > 0) continue;
    if (!(fs > 0))
      throw ConfigError({"", 0, "noise.sample_rate_hz"},
                        c->id.role() + ": no sample rate in the model: give the update rate");
    if (rate > 0 && std::abs(fs - rate) > 1e-9 * rate) {
      throw ConfigError({"", 0, "noise.sample_rate_hz"}, "the channels of " + which + " were sampled at " +
                                                             short_num(rate) + " and " + short_num(fs) +
                                                             " Hz: give the update rate");
    }
    rate = fs;
  }
  // One value per sensor: the largest of the axes that measured it (0 = not measured). An axis whose
  // term the records did not resolve counts with its bound; when a bound is the largest, the value is
  // only a bound: refused, or with kalibr_allow_bounds written and marked as one.
  struct Written {
    double value = 0.0;
    std::string bound_of;  // the axes whose bound it is; empty for a measured value
  };
  const auto largest = [&](const Channels& cs, double ResidualNoise::*term, std::optional<double> ResidualNoise::*upper,
                           const std::string& key, const std::string& what) {
    Written w;
    for (const auto* c : cs) {
      const auto& bound = c->model.noise.*upper;
      const double v = bound ? *bound : c->model.noise.*term;
      if (v > w.value) w = {v, bound ? c->id.role() : std::string()};
    }
    if (!(w.value > 0) || !std::isfinite(w.value)) {
      throw ConfigError({"", 0, key},
                        roles(cs) + ": " + what + " is not measured on any axis (0; " +
                            (term == &ResidualNoise::arw_rad_sqrt_s
                                 ? "recalibrate with driftlab calibrate, which fits it)"
                                 : "the records are too short for the Allan deviation to reach its +1/2 slope)"));
    }
    if (!w.bound_of.empty() && !o.kalibr_allow_bounds) {
      throw ConfigError({"", 0, key},
                        w.bound_of + ": " + what + " is not resolved by the calibration records, only bounded (< " +
                            short_num(w.value) +
                            "; its Allan deviation does not show the term within the "
                            "record): Kalibr would take the bound as a measured value. Calibrate on longer "
                            "records, or allow the bound to be written (marked as one)");
    }
    return w;
  };
  const Written accel_n = largest(accel, &ResidualNoise::arw_rad_sqrt_s, &ResidualNoise::arw_upper,
                                  "accelerometer_noise_density", "the noise density N");
  const Written accel_k =
      largest(accel, &ResidualNoise::rate_random_walk_rad_s_sqrt_s, &ResidualNoise::rate_random_walk_upper,
              "accelerometer_random_walk", "the random walk K");
  const Written gyro_n = largest(gyro, &ResidualNoise::arw_rad_sqrt_s, &ResidualNoise::arw_upper,
                                 "gyroscope_noise_density", "the noise density N");
  const Written gyro_k = largest(gyro, &ResidualNoise::rate_random_walk_rad_s_sqrt_s,
                                 &ResidualNoise::rate_random_walk_upper, "gyroscope_random_walk", "the random walk K");
  const auto line = [](const std::string& key, const Written& w, const std::string& unit) {
    return key + ": " + short_num(w.value) + "  # " + unit +
           (w.bound_of.empty()
                ? std::string()
                : "; UPPER BOUND, not a measured value: not resolved by the calibration records (" + w.bound_of + ")") +
           "\n";
  };
  // "N = 1e-4" for a resolved term, "N < 1e-4 (not resolved)" for a bound.
  const auto term_text = [](const std::string& name, double value, const std::optional<double>& upper) {
    return upper ? name + " < " + short_num(*upper) + " (not resolved)" : name + " = " + short_num(value);
  };
  ExportResult r;
  std::ostringstream s;
  s << "# Kalibr IMU noise model from driftlab (" << kImuFormat << ", device \"" << one_line(model.device) << "\", "
    << which << "): Allan analysis of each channel's compensated calibration residual, continuous-time values.\n"
    << "# Kalibr takes one value per sensor: each is the largest of the axes below (conservative; 0 = not measured).\n";
  for (const auto* c : all) {
    const bool g = c->id.sensor == imu::Sensor::Gyro;
    const auto& n = c->model.noise;
    s << "#   " << c->id.role() << " (column " << one_line(c->column)
      << "): " << term_text("N", n.arw_rad_sqrt_s, n.arw_upper) << (g ? " rad/s/sqrt(Hz)" : " m/s^2/sqrt(Hz)") << ", "
      << term_text("K", n.rate_random_walk_rad_s_sqrt_s, n.rate_random_walk_upper)
      << (g ? " rad/s^2/sqrt(Hz)" : " m/s^3/sqrt(Hz)") << ", "
      << term_text("B", n.bias_instability_rad_s, n.bias_instability_upper) << (g ? " rad/s" : " m/s^2")
      << " (B is not a Kalibr parameter)\n";
  }
  s << line("accelerometer_noise_density", accel_n, "m/s^2/sqrt(Hz)");
  s << line("accelerometer_random_walk", accel_k, "m/s^3/sqrt(Hz)");
  s << line("gyroscope_noise_density", gyro_n, "rad/s/sqrt(Hz)");
  s << line("gyroscope_random_walk", gyro_k, "rad/s^2/sqrt(Hz)");
  s << "rostopic: " << o.kalibr_topic << "\n";
  s << "update_rate: " << short_num(rate) << "  # Hz\n";
  r.text = s.str();
  return r;
}

namespace {

// The C identifier prefix: an identifier start, no "__" (reserved in C++) and no trailing "_" (it
// would make one), at most 32 characters so every generated name stays within the 63 significant
// characters C99 guarantees for internal identifiers and macros. A leading "_" is reserved at file scope.
void check_prefix(const std::string& p) {
  constexpr std::size_t kMaxPrefix = 32;
  bool ok = !p.empty() && p.size() <= kMaxPrefix && std::isalpha(static_cast<unsigned char>(p[0])) && p.back() != '_' &&
            p.find("__") == std::string::npos;
  for (const char ch : p) ok = ok && (std::isalnum(static_cast<unsigned char>(ch)) || ch == '_');
  if (!ok) {
    throw ConfigError({"", 0, "--prefix"},
                      "'" + p +
                          "' is not a usable C identifier prefix (a letter, then letters, "
                          "digits and single underscores, not ending in '_', at most 32 characters)");
  }
}

// `text` as the body of a C string literal.
std::string c_string(const std::string& text) {
  std::string out;
  for (const char ch : text) {
    const auto u = static_cast<unsigned char>(ch);
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += ch;
    } else if (u < 0x20 || u >= 0x7f || ch == '?') {  // '?': no trigraphs
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\%03o", u);
      out += buf;
    } else {
      out += ch;
    }
  }
  return out;
}

// `text` inside a C comment.
std::string c_comment(std::string text) {
  text = one_line(std::move(text));
  for (std::size_t at = text.find("*/"); at != std::string::npos; at = text.find("*/")) text.replace(at, 2, "* /");
  return text;
}

std::string c_array(const std::string& name, const std::vector<double>& v) {
  std::string out = "static const double " + name + "[" + std::to_string(std::max<std::size_t>(v.size(), 1)) + "] = {";
  for (std::size_t i = 0; i < v.size(); ++i) out += (i ? ", " : "") + num(v[i]);
  return out + "};\n";
}

// The model-independent part of the header; "@P@" stands for the prefix.
constexpr const char* kCTypes = R"(
/* One channel's model (calibration_model.hpp); units: the channel's internal unit (u = rad/s or m/s^2). */
typedef struct {
  int order;                  /* polynomial order */
  const double* bias;         /* a_0..a_order, u / K^i about t0_c */
  double t0_c, tmin_c, tmax_c;
  int policy;                 /* outside [tmin_c, tmax_c]: 0 clamp, 1 linear, 2 evaluate */
  double lag_tau_s, deriv_tau_s;
  double rate_coef;           /* u per K/s */
  double hyst_coef;           /* u */
  double hyst_width_k;        /* 0: no hysteresis term */
  int rate_ranged;            /* dT/dt limited to [rate_min, rate_max] (K/s) in the dT/dt term */
  double rate_min, rate_max;
  int state_ranged;           /* branch state limited to [state_min, state_max] in the hysteresis term */
  double state_min, state_max;
  int stateful;               /* lag, dT/dt, hysteresis or RBF in use */
  int sf_terms;               /* 0: no scale-factor model */
  const double* sf;           /* k_j, 1/K^j */
  int rbf_centres;            /* 0: no RBF network */
  int rbf_ranged;             /* inputs clamped to [rbf_input_min, rbf_input_max] */
  const double *rbf_mean, *rbf_scale, *rbf_input_min, *rbf_input_max, *rbf_centre, *rbf_weight;
  double rbf_sigma, rbf_bias;
} @P@_model;

typedef struct {
  int started;
  double t_prev, x_prev, tm, y1, y2, rate, s, dt_cached, a_lag, a_der;
} @P@_state;

static inline void @P@_init(@P@_state* st) {
  st->started = 0;
  st->t_prev = st->x_prev = st->tm = st->y1 = st->y2 = st->rate = st->s = 0.0;
  st->dt_cached = -1.0;
  st->a_lag = st->a_der = 0.0;
}

/* Exact step of y' = (x - y)/tau for x linear between samples, a = exp(-dt/tau). */
static inline double @P@_lag(double y, double x_prev, double x, double dt, double tau, double a) {
  return a * y + (1.0 - a) * x_prev + (x - x_prev) * (1.0 - tau * (1.0 - a) / dt);
}

static inline double @P@_horner(const double* a, int n, double u) {
  double v = 0.0;
  int i;
  for (i = n - 1; i >= 0; --i) v = v * u + a[i];
  return v;
}

static inline double @P@_poly(const @P@_model* m, double t) {
  const int n = m->order + 1;
  if (t < m->tmin_c || t > m->tmax_c) {
    const double edge = t < m->tmin_c ? m->tmin_c : m->tmax_c;
    if (m->policy == 0) return @P@_horner(m->bias, n, edge - m->t0_c);
    if (m->policy == 1) {
      double d = 0.0;
      int i;
      for (i = n - 1; i >= 1; --i) d = d * (edge - m->t0_c) + (double)i * m->bias[i];
      return @P@_horner(m->bias, n, edge - m->t0_c) + d * (t - edge);
    }
  }
  return @P@_horner(m->bias, n, t - m->t0_c);
}

/* Which inputs were outside their fitted range (bits of *outside_out in @P@_step). */
enum { @P@_OUTSIDE_TEMPERATURE = 1, @P@_OUTSIDE_TEMPERATURE_RATE = 2, @P@_OUTSIDE_BRANCH_STATE = 4, @P@_OUTSIDE_RBF_INPUTS = 8 };

static inline double @P@_limit(double x, int ranged, double lo, double hi, int bit, int* flags) {
  if (!ranged || (x >= lo && x <= hi)) return x;
  *flags |= bit;
  return x < lo ? lo : hi;
}

static inline double @P@_rbf(const @P@_model* m, double tc, double rate, double s, int* flags) {
  double x[3], u[3], y, g;
  int i, k;
  x[0] = tc;
  x[1] = rate;
  x[2] = s;
  for (i = 0; i < 3; ++i)
    x[i] = @P@_limit(x[i], m->rbf_ranged, m->rbf_ranged ? m->rbf_input_min[i] : 0.0,
                     m->rbf_ranged ? m->rbf_input_max[i] : 0.0, @P@_OUTSIDE_RBF_INPUTS, flags);
  for (i = 0; i < 3; ++i) u[i] = (x[i] - m->rbf_mean[i]) / m->rbf_scale[i];
  g = -0.5 / (m->rbf_sigma * m->rbf_sigma);
  y = m->rbf_bias;
  for (k = 0; k < m->rbf_centres; ++k) {
    const double d0 = u[0] - m->rbf_centre[3 * k], d1 = u[1] - m->rbf_centre[3 * k + 1], d2 = u[2] - m->rbf_centre[3 * k + 2];
    y += m->rbf_weight[k] * exp(g * (d0 * d0 + d1 * d1 + d2 * d2));
  }
  return y;
}

/* One sample of one channel: time t_s (s, increasing), measured value x and case temperature temp_c
   (degC) -> compensated value (the channel's internal unit); *bias_out = the correction subtracted,
   *outside_out = the @P@_OUTSIDE_* bits of the inputs outside their fitted range, 0 for none (either
   pointer may be 0). */
static inline double @P@_step(const @P@_model* m, @P@_state* st, double t_s, double x, double temp_c, double* bias_out,
                              int* outside_out) {
  double tm = temp_c, b, tc;
  int flags;
  if (m->stateful) {
    if (!st->started) {
      st->started = 1;
      st->t_prev = t_s;
      st->x_prev = st->tm = st->y1 = st->y2 = temp_c;
      st->rate = st->s = 0.0;
    } else {
      const double dt = t_s - st->t_prev;
      double y1_prev, y1;
      if (dt != st->dt_cached) {
        st->dt_cached = dt;
        st->a_lag = m->lag_tau_s > 0 ? exp(-dt / m->lag_tau_s) : 0.0;
        st->a_der = exp(-dt / m->deriv_tau_s);
      }
      st->tm = m->lag_tau_s > 0 ? @P@_lag(st->tm, st->x_prev, temp_c, dt, m->lag_tau_s, st->a_lag) : temp_c;
      y1_prev = st->y1;
      y1 = @P@_lag(st->y1, st->x_prev, temp_c, dt, m->deriv_tau_s, st->a_der);
      st->y2 = @P@_lag(st->y2, y1_prev, y1, dt, m->deriv_tau_s, st->a_der);
      st->y1 = y1;
      st->rate = (st->y1 - st->y2) / m->deriv_tau_s;
      if (m->hyst_width_k > 0) {
        const double d = st->y1 - y1_prev;
        if (d != 0.0) {
          const double sg = d > 0 ? 1.0 : -1.0;
          st->s = sg + (st->s - sg) * exp(-fabs(d) / m->hyst_width_k);
        }
      }
      st->t_prev = t_s;
      st->x_prev = temp_c;
    }
    tm = st->tm;
  }
  flags = (tm < m->tmin_c || tm > m->tmax_c) ? @P@_OUTSIDE_TEMPERATURE : 0;
  b = @P@_poly(m, tm);
  tc = tm < m->tmin_c ? m->tmin_c : (tm > m->tmax_c ? m->tmax_c : tm);
  if (m->stateful) {
    b += m->rate_coef * @P@_limit(st->rate, m->rate_ranged, m->rate_min, m->rate_max, @P@_OUTSIDE_TEMPERATURE_RATE, &flags) +
         m->hyst_coef * @P@_limit(st->s, m->state_ranged, m->state_min, m->state_max, @P@_OUTSIDE_BRANCH_STATE, &flags);
    if (m->rbf_centres > 0) b += @P@_rbf(m, tc, st->rate, st->s, &flags);
  }
  if (bias_out) *bias_out = b;
  if (outside_out) *outside_out = flags;
  if (m->sf_terms > 0) return (x - b) / (1.0 + @P@_horner(m->sf, m->sf_terms, tc - m->t0_c));
  return x - b;
}
)";

constexpr const char* kCImu = R"(
typedef struct {
  @P@_state ch[@P@_CHANNELS];
} @P@_imu_state;

static inline void @P@_imu_init(@P@_imu_state* st) {
  int k;
  for (k = 0; k < @P@_CHANNELS; ++k) @P@_init(&st->ch[k]);
}

/* One sample of every channel: in[k] / out[k] / bias[k] in channel k's internal unit (order of
   @P@_roles), temp_c[j] the temperature @P@_temperature_columns[j] (degC), outside[k] channel k's
   @P@_OUTSIDE_* bits (bias and outside may be 0). Returns the number of channels with a model input
   outside its fitted range. */
static inline int @P@_imu_step(@P@_imu_state* st, double t_s, const double* in, const double* temp_c, double* out,
                               double* bias, int* outside) {
  int k, n = 0;
  for (k = 0; k < @P@_CHANNELS; ++k) {
    int flags = 0;
    out[k] = @P@_step(@P@_models[k], &st->ch[k], t_s, in[k], temp_c[@P@_temperature_of[k]], bias ? &bias[k] : 0, &flags);
    if (outside) outside[k] = flags;
    n += flags != 0;
  }
  return n;
}
)";

std::string with_prefix(std::string text, const std::string& prefix) {
  for (std::size_t at = text.find("@P@"); at != std::string::npos; at = text.find("@P@", at + prefix.size())) {
    text.replace(at, 3, prefix);
  }
  return text;
}

}  // namespace

ExportResult export_c_header(const ImuCalibration& model, const ExportOptions& o) {
  model.validate();
  const std::string& P = o.symbol_prefix;
  check_prefix(P);
  std::string guard = P + "_H";
  for (auto& ch : guard) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  std::vector<std::string> temperatures;  // distinct temperature columns, in channel order
  std::vector<std::size_t> temperature_of;
  for (const auto& c : model.channels) {
    auto it = std::find(temperatures.begin(), temperatures.end(), c.temperature_column);
    if (it == temperatures.end()) it = temperatures.insert(temperatures.end(), c.temperature_column);
    temperature_of.push_back(static_cast<std::size_t>(it - temperatures.begin()));
  }
  std::ostringstream s;
  s << "/* Generated by driftlab from a " << kImuFormat << " model (device \"" << c_comment(model.device) << "\").\n"
    << " * Self-contained C99 (<math.h> only): causal temperature compensation of every channel, one call per\n"
    << " * sample, O(1) state. Units: time s, temperature degC, values in each channel's internal unit\n"
    << " * (gyro rad/s, accelerometer m/s^2: convert from the column's read unit first).\n"
    << " *   bias = sum_i a_i (T_c - T0)^i + dT/dt and hysteresis terms + RBF; T_c = model temperature limited by\n"
    << " *   the channel's extrapolation policy to its valid range, dT/dt, branch state and RBF inputs limited to\n"
    << " *   their fitted ranges (flagged in *outside); out = (x - bias) / sf.\n"
    << " * Usage: " << P << "_state st; " << P << "_init(&st); y = " << P << "_step(&" << P
    << "_<role>, &st, t, x, temp, &bias, &outside);\n"
    << " *    or " << P << "_imu_state st; " << P << "_imu_init(&st); " << P
    << "_imu_step(&st, t, in, temps, out, bias, outside);\n"
    << " * Channels (role: column [read unit] -> internal unit, temperature column, model):\n";
  for (std::size_t k = 0; k < model.channels.size(); ++k) {
    const auto& c = model.channels[k];
    const auto& m = c.model;
    s << " *   " << c.id.role() << ": " << c_comment(c.column) << " [" << c_comment(c.read_unit) << "] -> " << c.unit()
      << ", " << c_comment(c.temperature_column) << ", " << to_string(m.kind) << " order " << m.order() << ", T0 "
      << short_num(m.reference_temp_c) << " degC, valid " << short_num(m.valid_min_c) << " .. "
      << short_num(m.valid_max_c) << " degC, '" << to_string(m.extrapolation) << "'"
      << (c.device_id.empty() ? "" : ", device id " + c_comment(c.device_id)) << "\n";
  }
  s << " */\n#ifndef " << guard << "\n#define " << guard << "\n\n#include <math.h>\n";
  s << with_prefix(kCTypes, P) << "\n";
  for (const auto& c : model.channels) {
    const auto& m = c.model;
    const std::string name = P + "_" + c.id.role();
    s << "/* " << c.id.role() << " (" << c.unit() << ") */\n";
    s << c_array(name + "_bias", m.bias_rad_s);
    if (!m.scale_factor_per_k.empty()) s << c_array(name + "_sf", m.scale_factor_per_k);
    const bool rbf = m.rbf && m.rbf->centres.rows() > 0;
    const bool ranged = rbf && !m.rbf->input_min.empty();
    if (rbf) {
      std::vector<double> centres;
      for (Eigen::Index k = 0; k < m.rbf->centres.rows(); ++k) {
        for (int col = 0; col < 3; ++col) centres.push_back(m.rbf->centres(k, col));
      }
      s << c_array(name + "_rbf_mean", m.rbf->mean) << c_array(name + "_rbf_scale", m.rbf->scale);
      if (ranged)
        s << c_array(name + "_rbf_input_min", m.rbf->input_min) << c_array(name + "_rbf_input_max", m.rbf->input_max);
      s << c_array(name + "_rbf_centre", centres) << c_array(name + "_rbf_weight", m.rbf->weights_rad_s);
    }
    s << "static const " << P << "_model " << name << " = {\n"
      << "    .order = " << m.order() << ", .bias = " << name << "_bias,\n"
      << "    .t0_c = " << num(m.reference_temp_c) << ", .tmin_c = " << num(m.valid_min_c)
      << ", .tmax_c = " << num(m.valid_max_c) << ", .policy = " << static_cast<int>(m.extrapolation) << ",\n"
      << "    .lag_tau_s = " << num(m.lag_tau_s) << ", .deriv_tau_s = " << num(m.derivative_tau_s) << ",\n"
      << "    .rate_coef = " << num(m.temperature_rate_rad_s_per_k_s) << ", .hyst_coef = " << num(m.hysteresis_rad_s)
      << ", .hyst_width_k = " << num(m.hysteresis_width_k) << ",\n";
    if (const auto& r = m.temperature_rate_range_k_s)
      s << "    .rate_ranged = 1, .rate_min = " << num(r->min) << ", .rate_max = " << num(r->max) << ",\n";
    if (const auto& r = m.hysteresis_state_range)
      s << "    .state_ranged = 1, .state_min = " << num(r->min) << ", .state_max = " << num(r->max) << ",\n";
    s << "    .stateful = " << (m.uses_state() ? 1 : 0);
    if (!m.scale_factor_per_k.empty())
      s << ",\n    .sf_terms = " << m.scale_factor_per_k.size() << ", .sf = " << name << "_sf";
    if (rbf) {
      s << ",\n    .rbf_centres = " << m.rbf->centres.rows() << ", .rbf_ranged = " << (ranged ? 1 : 0) << ",\n"
        << "    .rbf_mean = " << name << "_rbf_mean, .rbf_scale = " << name << "_rbf_scale,\n";
      if (ranged)
        s << "    .rbf_input_min = " << name << "_rbf_input_min, .rbf_input_max = " << name << "_rbf_input_max,\n";
      s << "    .rbf_centre = " << name << "_rbf_centre, .rbf_weight = " << name << "_rbf_weight,\n"
        << "    .rbf_sigma = " << num(m.rbf->sigma) << ", .rbf_bias = " << num(m.rbf->bias_rad_s);
    }
    s << "};\n\n";
  }
  s << "/* The whole IMU: channel k of " << P << "_models is " << P << "_roles[k], read from " << P
    << "_columns[k]. */\n";
  s << "enum { " << P << "_CHANNELS = " << model.channels.size() << ", " << P
    << "_TEMPERATURES = " << temperatures.size() << " };\n";
  s << "enum {";
  for (std::size_t k = 0; k < model.channels.size(); ++k) {
    s << (k ? "," : "") << "\n  " << P << "_ch_" << model.channels[k].id.role() << " = " << k;
  }
  s << "\n};\n";
  const auto strings = [&](const std::string& name, std::size_t n, const auto& text_of) {
    s << "static const char* const " << P << "_" << name << "[" << n << "] = {";
    for (std::size_t k = 0; k < n; ++k) s << (k ? ", " : "") << "\"" << c_string(text_of(k)) << "\"";
    s << "};\n";
  };
  const std::size_t n = model.channels.size();
  s << "static const " << P << "_model* const " << P << "_models[" << n << "] = {";
  for (std::size_t k = 0; k < n; ++k) s << (k ? ", " : "") << "&" << P << "_" << model.channels[k].id.role();
  s << "};\n";
  strings("roles", n, [&](std::size_t k) { return model.channels[k].id.role(); });
  strings("columns", n, [&](std::size_t k) { return model.channels[k].column; });
  strings("read_units", n, [&](std::size_t k) { return model.channels[k].read_unit; });
  strings("temperature_columns", temperatures.size(), [&](std::size_t k) { return temperatures[k]; });
  s << "static const int " << P << "_temperature_of[" << n << "] = {";
  for (std::size_t k = 0; k < n; ++k) s << (k ? ", " : "") << temperature_of[k];
  s << "};\n";
  s << with_prefix(kCImu, P) << "\n#endif\n";
  return {s.str(), {}, {}};
}

}  // namespace driftlab::calibration
