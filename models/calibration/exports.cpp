#include "models/calibration/exports.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "framework/error.hpp"

namespace driftlab::calibration {
namespace {

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string short_num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

int axis_index(const std::string& axis) { return axis == "x" ? 0 : axis == "y" ? 1 : 2; }


// The cubic for PX4/ArduPilot with its notes; throws in strict mode when it is not exact.
std::vector<double> cubic_for_export(const CalibrationModel& m, double t_ref, const ExportOptions& o,
                                     const std::string& format, std::vector<std::string>& notes) {
  double err = 0.0;
  auto c = cubic_about(m, t_ref, err);
  const auto dropped = unrepresentable_terms(m);
  const bool exact = m.order() <= 3 && dropped.empty();
  if (!exact && o.strict) {
    std::string why = m.order() > 3 ? "polynomial order " + std::to_string(m.order()) + " > 3" : "";
    for (const auto& d : dropped) why += (why.empty() ? "" : "; ") + d;
    throw ConfigError({"", 0, "kind"}, format + " holds a cubic in temperature only; this model has " + why +
                                           " (export without --strict for the best cubic with its stated error)");
  }
  if (m.order() > 3) {
    notes.push_back("order-" + std::to_string(m.order()) + " polynomial approximated by the least-squares cubic over " +
                    short_num(m.valid_min_c) + " .. " + short_num(m.valid_max_c) + " degC: max error " +
                    short_num(err) + " rad/s (" + short_num(err * 180.0 / M_PI * 3600.0) + " deg/h)");
  }
  for (const auto& d : dropped) notes.push_back("dropped (not representable in " + format + "): " + d);
  if (!m.scale_factor_per_k.empty()) notes.push_back("dropped: scale-factor model (" + format + " export carries offsets only)");
  if (m.extrapolation != Extrapolation::Clamp) {
    notes.push_back(format + " clamps the temperature to [TMIN, TMAX]; the model's policy '" +
                    to_string(m.extrapolation) + "' is not carried");
  }
  return c;
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

std::vector<std::string> unrepresentable_terms(const CalibrationModel& m) {
  std::vector<std::string> out;
  if (m.lag_tau_s > 0) out.push_back("thermal lag tau = " + short_num(m.lag_tau_s) + " s (the cubic is applied to the sensor temperature)");
  if (m.temperature_rate_rad_s_per_k_s != 0.0) {
    out.push_back("dT/dt term " + short_num(m.temperature_rate_rad_s_per_k_s) + " rad/s per K/s (" +
                  short_num(m.temperature_rate_rad_s_per_k_s / 60.0 * 180.0 / M_PI * 3600.0) + " deg/h at 1 K/min)");
  }
  if (m.hysteresis_width_k > 0) {
    out.push_back("hysteresis branch term +-" + short_num(std::abs(m.hysteresis_rad_s)) + " rad/s (" +
                  short_num(std::abs(m.hysteresis_rad_s) * 180.0 / M_PI * 3600.0) + " deg/h)");
  }
  if (m.rbf && m.rbf->centres.rows() > 0) {
    out.push_back("RBF network of " + std::to_string(m.rbf->centres.rows()) + " centres on (T, dT/dt, branch)");
  }
  return out;
}

ExportResult export_px4_params(const ChannelCalibration& channel, const ExportOptions& o) {
  const CalibrationModel& m = channel.model;
  const std::string axis_name(1, channel.id.axis);
  ExportResult r;
  const double tref = m.reference_temp_c;
  const auto c = cubic_for_export(m, tref, o, "PX4 TC_G*", r.notes);
  const int ax = axis_index(axis_name);
  const std::string g = "TC_G" + std::to_string(o.px4_sensor_index) + "_";
  std::ostringstream s;
  s << "# Onboard parameters for Vehicle 1\n"
    << "# PX4 gyro thermal compensation from driftlab (driftlab-calibration/1, kind " << to_string(m.kind) << ")\n"
    << "# offset = X0 + X1*dT + X2*dT^2 + X3*dT^3 [rad/s], dT = clamp(T, TMIN, TMAX) - TREF [degC]; "
       "corrected = raw - offset. Axis "
    << axis_name << " (index " << ax << "); the other axes are left at 0.\n"
    << "# Set " << g << "ID to the gyro's device id (unknown here, written as 0).\n";
  for (const auto& n : r.notes) s << "# NOTE: " << n << "\n";
  s << "#\n# Vehicle-Id Component-Id Name Value Type\n";
  const auto line = [&](const std::string& name, const std::string& value, int type) {
    s << "1\t1\t" << name << "\t" << value << "\t" << type << "\n";
  };
  line("TC_G_ENABLE", "1", 6);
  line(g + "ID", "0", 6);
  line(g + "TMAX", short_num(m.valid_max_c), 9);
  line(g + "TMIN", short_num(m.valid_min_c), 9);
  line(g + "TREF", short_num(tref), 9);
  for (int k = 0; k < 4; ++k) {
    for (int a = 0; a < 3; ++a) {
      line(g + "X" + std::to_string(k) + "_" + std::to_string(a), a == ax ? short_num(c[static_cast<std::size_t>(k)]) : "0", 9);
    }
  }
  r.text = s.str();
  return r;
}

ExportResult export_ardupilot_params(const ChannelCalibration& channel, const ExportOptions& o) {
  const CalibrationModel& m = channel.model;
  const std::string axis_name(1, channel.id.axis);
  ExportResult r;
  constexpr double kReference = 35.0;  // ArduPilot's fixed TEMP_REFERENCE, degC
  constexpr double kScale = 1e6;       // ArduPilot's SCALE_FACTOR of the coefficients
  const auto c = cubic_for_export(m, kReference, o, "ArduPilot INS_TCAL", r.notes);
  const double caltemp = std::clamp(kReference, m.valid_min_c, m.valid_max_c);
  double offset = 0.0;
  for (int k = 3; k >= 0; --k) offset = offset * (caltemp - kReference) + c[static_cast<std::size_t>(k)];
  const char axis = static_cast<char>(std::toupper(static_cast<unsigned char>(axis_name[0])));
  const std::string p = "INS_TCAL" + std::to_string(o.ardupilot_imu) + "_";
  const std::string imu_suffix = o.ardupilot_imu == 1 ? "" : std::to_string(o.ardupilot_imu);
  std::ostringstream s;
  s << "# ArduPilot IMU temperature calibration from driftlab (driftlab-calibration/1, kind " << to_string(m.kind) << ")\n"
    << "# GYRk_" << axis << " = 1e6 x coefficient of (T - 35 degC)^k in rad/s; T clamped to [TMIN, TMAX].\n"
    << "# The constant term is the gyro offset INS_GYROFFS" << imu_suffix << "_" << axis
    << " at INS_GYR" << o.ardupilot_imu << "_CALTEMP. Other axes are left at 0.\n";
  for (const auto& n : r.notes) s << "# NOTE: " << n << "\n";
  s << p << "ENABLE,1\n" << p << "TMIN," << short_num(m.valid_min_c) << "\n" << p << "TMAX," << short_num(m.valid_max_c) << "\n";
  for (int k = 1; k <= 3; ++k) {
    for (const char a : {'X', 'Y', 'Z'}) {
      s << p << "GYR" << k << "_" << a << "," << (a == axis ? short_num(kScale * c[static_cast<std::size_t>(k)]) : "0") << "\n";
    }
  }
  s << "INS_GYROFFS" << imu_suffix << "_" << axis << "," << short_num(offset) << "\n";
  s << "INS_GYR" << o.ardupilot_imu << "_CALTEMP," << short_num(caltemp) << "\n";
  r.text = s.str();
  return r;
}

ExportResult export_kalibr_imu_yaml(const ChannelCalibration& channel, const ExportOptions& o) {
  const CalibrationModel& m = channel.model;
  const std::string axis_name(1, channel.id.axis);
  ExportResult r;
  const double rate = o.kalibr_update_rate_hz > 0 ? o.kalibr_update_rate_hz : m.noise.sample_rate_hz;
  if (!(m.noise.arw_rad_sqrt_s > 0)) {
    throw ConfigError({"", 0, "noise.arw_rad_sqrt_s"},
                      "the model has no Allan noise terms (recalibrate with driftlab calibrate, which fits them)");
  }
  if (!(rate > 0)) throw ConfigError({"", 0, "noise.sample_rate_hz"}, "no sample rate: give the update rate");
  std::ostringstream s;
  s << "# Kalibr IMU noise model from driftlab: Allan analysis of the compensated calibration residual.\n"
    << "# gyroscope_noise_density = N [rad/s/sqrt(Hz)], gyroscope_random_walk = K [rad/s^2/sqrt(Hz)]\n"
    << "# (IEEE-952 names; continuous-time values). B (bias instability) = "
    << short_num(m.noise.bias_instability_rad_s) << " rad/s is not a Kalibr parameter.\n";
  s << "rostopic: " << o.kalibr_topic << "\n";
  s << "update_rate: " << short_num(rate) << "  # Hz\n";
  s << "gyroscope_noise_density: " << short_num(m.noise.arw_rad_sqrt_s) << "  # rad/s/sqrt(Hz)\n";
  s << "gyroscope_random_walk: " << short_num(m.noise.rate_random_walk_rad_s_sqrt_s) << "  # rad/s^2/sqrt(Hz)\n";
  r.notes.push_back("accelerometer terms are not measured by driftlab (gyro only): add accelerometer_noise_density "
                    "and accelerometer_random_walk before using this file with Kalibr");
  s << "# NOTE: " << r.notes.back() << "\n";
  s << "# accelerometer_noise_density: <not measured>\n# accelerometer_random_walk: <not measured>\n";
  r.text = s.str();
  return r;
}

ExportResult export_c_header(const ChannelCalibration& channel, const ExportOptions& o) {
  const CalibrationModel& m = channel.model;
  const std::string axis_name(1, channel.id.axis);
  m.validate();
  const std::string P = o.symbol_prefix;
  bool identifier = !P.empty() && !std::isdigit(static_cast<unsigned char>(P[0])) && P != "P";
  for (const char ch : P) identifier = identifier && (std::isalnum(static_cast<unsigned char>(ch)) || ch == '_');
  if (!identifier) throw ConfigError({"", 0, "--prefix"}, "'" + P + "' is not a usable C identifier prefix");
  std::string guard = P + "_H";
  for (auto& ch : guard) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  std::ostringstream s;
  s << "/* Generated by driftlab from a driftlab-calibration/1 model (kind " << to_string(m.kind) << ", axis " << axis_name
    << ").\n"
    << " * Self-contained C99: causal gyro temperature compensation, one call per sample, O(1) state.\n"
    << " * Units: time s, rate rad/s, temperature degC. bias = sum_i a_i (T_c - " << short_num(m.reference_temp_c)
    << " degC)^i\n"
    << " *   + dT/dt and hysteresis terms + RBF; T_c = model temperature limited by the '" << to_string(m.extrapolation)
    << "' policy\n"
    << " *   to the valid range " << short_num(m.valid_min_c) << " .. " << short_num(m.valid_max_c) << " degC.\n"
    << " * Usage: " << P << "_state st; " << P << "_init(&st); w = " << P << "_step(&st, t, rate, temp, &bias, &extrap);\n"
    << " */\n#ifndef " << guard << "\n#define " << guard << "\n\n#include <math.h>\n\n";
  const auto array = [&](const std::string& name, const std::vector<double>& v) {
    s << "static const double " << P << "_" << name << "[" << std::max<std::size_t>(v.size(), 1) << "] = {";
    for (std::size_t i = 0; i < v.size(); ++i) s << (i ? ", " : "") << num(v[i]);
    if (v.empty()) s << "0";
    s << "};\n";
  };
  s << "#define " << P << "_ORDER " << m.order() << "\n";
  s << "#define " << P << "_T0_C " << num(m.reference_temp_c) << "\n";
  s << "#define " << P << "_TMIN_C " << num(m.valid_min_c) << "\n";
  s << "#define " << P << "_TMAX_C " << num(m.valid_max_c) << "\n";
  s << "#define " << P << "_POLICY " << static_cast<int>(m.extrapolation) << " /* 0 clamp, 1 linear, 2 evaluate */\n";
  s << "#define " << P << "_LAG_TAU_S " << num(m.lag_tau_s) << "\n";
  s << "#define " << P << "_DERIV_TAU_S " << num(m.derivative_tau_s) << "\n";
  s << "#define " << P << "_RATE_COEF " << num(m.temperature_rate_rad_s_per_k_s) << " /* rad/s per K/s */\n";
  s << "#define " << P << "_HYST_COEF " << num(m.hysteresis_rad_s) << " /* rad/s */\n";
  s << "#define " << P << "_HYST_WIDTH_K " << num(m.hysteresis_width_k) << "\n";
  s << "#define " << P << "_STATEFUL " << (m.uses_state() ? 1 : 0) << "\n";
  array("bias", m.bias_rad_s);
  s << "#define " << P << "_SF_TERMS " << m.scale_factor_per_k.size() << "\n";
  array("sf", m.scale_factor_per_k);
  const bool rbf = m.rbf && m.rbf->centres.rows() > 0;
  s << "#define " << P << "_RBF_CENTRES " << (rbf ? m.rbf->centres.rows() : 0) << "\n";
  if (rbf) {
    std::vector<double> centres;
    for (Eigen::Index k = 0; k < m.rbf->centres.rows(); ++k) {
      for (int c = 0; c < 3; ++c) centres.push_back(m.rbf->centres(k, c));
    }
    array("rbf_mean", m.rbf->mean);
    if (!m.rbf->input_min.empty()) {
      array("rbf_input_min", m.rbf->input_min);
      array("rbf_input_max", m.rbf->input_max);
    }
    array("rbf_scale", m.rbf->scale);
    array("rbf_centres", centres);
    array("rbf_weights", m.rbf->weights_rad_s);
    s << "#define " << P << "_RBF_SIGMA " << num(m.rbf->sigma) << "\n";
    s << "#define " << P << "_RBF_BIAS " << num(m.rbf->bias_rad_s) << "\n";
  }
  s << R"(
typedef struct {
  int started;
  double t_prev, x_prev, tm, y1, y2, rate, s, dt_cached, a_lag, a_der;
} P_state;

static inline void P_init(P_state* st) {
  st->started = 0;
  st->t_prev = st->x_prev = st->tm = st->y1 = st->y2 = st->rate = st->s = 0.0;
  st->dt_cached = -1.0;
  st->a_lag = st->a_der = 0.0;
}

/* Exact step of y' = (x - y)/tau for x linear between samples, a = exp(-dt/tau). */
static inline double P_lag(double y, double x_prev, double x, double dt, double tau, double a) {
  return a * y + (1.0 - a) * x_prev + (x - x_prev) * (1.0 - tau * (1.0 - a) / dt);
}

static inline double P_horner(const double* a, int n, double u) {
  double v = 0.0;
  int i;
  for (i = n - 1; i >= 0; --i) v = v * u + a[i];
  return v;
}

static inline double P_poly(double t) {
  const int n = P_ORDER + 1;
  if (t < P_TMIN_C || t > P_TMAX_C) {
    const double edge = t < P_TMIN_C ? P_TMIN_C : P_TMAX_C;
    if (P_POLICY == 0) return P_horner(P_bias, n, edge - P_T0_C);
    if (P_POLICY == 1) {
      double d = 0.0;
      int i;
      for (i = n - 1; i >= 1; --i) d = d * (edge - P_T0_C) + (double)i * P_bias[i];
      return P_horner(P_bias, n, edge - P_T0_C) + d * (t - edge);
    }
  }
  return P_horner(P_bias, n, t - P_T0_C);
}

/* One sample: returns the compensated rate (rad/s); *bias_out = the correction subtracted (rad/s),
   *extrapolated_out = 1 outside the valid range. Time stamps must increase. */
static inline double P_step(P_state* st, double t_s, double rate_rad_s, double temp_c, double* bias_out,
                            int* extrapolated_out) {
  double tm = temp_c, b, tc;
  if (P_STATEFUL) {
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
        st->a_lag = P_LAG_TAU_S > 0 ? exp(-dt / P_LAG_TAU_S) : 0.0;
        st->a_der = exp(-dt / P_DERIV_TAU_S);
      }
      st->tm = P_LAG_TAU_S > 0 ? P_lag(st->tm, st->x_prev, temp_c, dt, P_LAG_TAU_S, st->a_lag) : temp_c;
      y1_prev = st->y1;
      y1 = P_lag(st->y1, st->x_prev, temp_c, dt, P_DERIV_TAU_S, st->a_der);
      st->y2 = P_lag(st->y2, y1_prev, y1, dt, P_DERIV_TAU_S, st->a_der);
      st->y1 = y1;
      st->rate = (st->y1 - st->y2) / P_DERIV_TAU_S;
      if (P_HYST_WIDTH_K > 0) {
        const double d = st->y1 - y1_prev;
        if (d != 0.0) {
          const double sg = d > 0 ? 1.0 : -1.0;
          st->s = sg + (st->s - sg) * exp(-fabs(d) / (P_HYST_WIDTH_K > 0 ? P_HYST_WIDTH_K : 1.0));
        }
      }
      st->t_prev = t_s;
      st->x_prev = temp_c;
    }
    tm = st->tm;
  }
  if (extrapolated_out) *extrapolated_out = (tm < P_TMIN_C || tm > P_TMAX_C);
  b = P_poly(tm);
  tc = tm < P_TMIN_C ? P_TMIN_C : (tm > P_TMAX_C ? P_TMAX_C : tm);
  if (P_STATEFUL) {
    b += P_RATE_COEF * st->rate + P_HYST_COEF * st->s;
)";
  if (rbf) {
    const bool ranged = !m.rbf->input_min.empty();
    s << R"(    {
      double x[3];
      x[0] = tc;
      x[1] = st->rate;
      x[2] = st->s;
)";
    if (ranged) {
      s << R"(      {
        int i;
        for (i = 0; i < 3; ++i) x[i] = x[i] < P_rbf_input_min[i] ? P_rbf_input_min[i] : (x[i] > P_rbf_input_max[i] ? P_rbf_input_max[i] : x[i]);
      }
)";
    }
    s << R"(      const double u0 = (x[0] - P_rbf_mean[0]) / P_rbf_scale[0];
      const double u1 = (x[1] - P_rbf_mean[1]) / P_rbf_scale[1];
      const double u2 = (x[2] - P_rbf_mean[2]) / P_rbf_scale[2];
      const double g = -0.5 / (P_RBF_SIGMA * P_RBF_SIGMA);
      double y = P_RBF_BIAS;
      int k;
      for (k = 0; k < P_RBF_CENTRES; ++k) {
        const double d0 = u0 - P_rbf_centres[3 * k], d1 = u1 - P_rbf_centres[3 * k + 1], d2 = u2 - P_rbf_centres[3 * k + 2];
        y += P_rbf_weights[k] * exp(g * (d0 * d0 + d1 * d1 + d2 * d2));
      }
      b += y;
    }
)";
  }
  s << R"(  }
  if (bias_out) *bias_out = b;
  if (P_SF_TERMS > 0) return (rate_rad_s - b) / (1.0 + P_horner(P_sf, P_SF_TERMS, tc - P_T0_C));
  (void)tc;
  return rate_rad_s - b;
}

#endif
)";
  std::string text = s.str();
  // Substitute the prefix placeholder "P_" in the template (only at identifier starts).
  std::string out;
  out.reserve(text.size() + 1024);
  for (std::size_t i = 0; i < text.size(); ++i) {
    const bool start = i == 0 || !(std::isalnum(static_cast<unsigned char>(text[i - 1])) || text[i - 1] == '_');
    if (start && text.compare(i, 2, "P_") == 0) {
      out += P + "_";
      ++i;
    } else {
      out += text[i];
    }
  }
  return {out, {}};
}

}  // namespace driftlab::calibration
