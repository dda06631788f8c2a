// Every export of a whole-IMU model is parsed back (or compiled and run) and evaluated the way its
// consumer does: PX4 and ArduPilot through their own correction equations (re-implemented here, float
// arithmetic, clamping and reference rules included), the C header by a C99 compiler, Kalibr's file
// by a YAML parser; each is compared with the model within the loss the export states.
#include "models/calibration/exports.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>
#include <unistd.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "framework/error.hpp"
#include "tests/models/calibration_fixtures.hpp"

namespace driftlab::calibration {
namespace {

using imu::Sensor;

// The cubic's stated error is its maximum on a 201-point grid; between grid points it can be a
// little larger (the test grid is 0.05 K).
constexpr double kGridSlack = 1.05;
// Float rounding of the firmware's evaluation, in units of FLT_EPSILON times the largest magnitude
// involved (sum_k |X_k| (|T| + |T_ref|)^k): the coefficients, T and T_ref rounded to float (0.5 ulp
// each), the subtraction, three products and three sums (<= 1 ulp each), for ArduPilot twice (the
// difference to CALTEMP) and the 1e-6 rescaling; 16 covers that with margin.
constexpr double kReal32Ulps = 16.0;
constexpr double kStep = 0.05;  // K, the comparison grid over each channel's valid range

ChannelCalibration channel(Sensor sensor, char axis, int instance, std::vector<double> a, double t0, double lo,
                           double hi, std::string device_id = "") {
  const imu::ChannelId id{sensor, axis, instance};
  CalibrationModel m = testing::example_polynomial_model(std::move(a), lo, hi);
  m.reference_temp_c = t0;
  return {id,
          id.role(),
          id.role() + (sensor == Sensor::Gyro ? "_dps" : "_mps2"),
          sensor == Sensor::Gyro ? "deg/s" : "m/s^2",
          instance == 0 ? "temp_c" : "temp1_c",
          std::move(device_id),
          true,
          std::move(m)};
}

// Two instances x (gyro + accelerometer) x 3 axes. Instance 0: cubics and lower orders, device ids,
// one range. Instance 1: gyro1_x of order 5 (approximated), accelerometers without a reference
// (a0 = 0) about 20 degC, and accel1_z valid over a narrower range than the rest of its instance.
ImuCalibration two_instance_imu() {
  ImuCalibration m;
  m.device = "imu3";
  const std::string g0 = "2490378", a0 = "2621450";
  m.channels = {
      channel(Sensor::Gyro, 'x', 0, {4e-4, -1.1e-5, -1.4e-8, 3e-10}, 25, -25, 60, g0),
      channel(Sensor::Gyro, 'y', 0, {-2e-3, 5e-6, 1e-7}, 25, -25, 60, g0),
      channel(Sensor::Gyro, 'z', 0, {1e-3, 2e-6}, 25, -25, 60, g0),
      channel(Sensor::Gyro, 'x', 1, {3e-4, -1e-5, 2e-8, 3e-10, 2e-11, -1e-13}, 25, -10, 50),
      channel(Sensor::Gyro, 'y', 1, {-1e-3, 4e-6, -2e-8, 1e-10}, 25, -10, 50),
      channel(Sensor::Gyro, 'z', 1, {5e-4, -3e-6}, 25, -10, 50),
      channel(Sensor::Accel, 'x', 0, {0.05, 1e-3, -2e-5, 1e-7}, 25, -25, 60, a0),
      channel(Sensor::Accel, 'y', 0, {-0.03, -8e-4, 1e-5}, 25, -25, 60, a0),
      channel(Sensor::Accel, 'z', 0, {0.1, 2.7e-3, -9.7e-6, 2e-8}, 25, -25, 60, a0),
      channel(Sensor::Accel, 'x', 1, {0.0, 1.7e-3, 1e-5}, 20, -10, 50),
      channel(Sensor::Accel, 'y', 1, {0.0, -1.8e-3, 1.5e-5, -4e-8}, 20, -10, 50),
      channel(Sensor::Accel, 'z', 1, {0.0, 2.5e-3, -9.7e-6}, 20, -5, 50),
  };
  for (std::size_t k = 0; k < m.channels.size(); ++k) {
    auto& c = m.channels[k];
    if (c.id.sensor == Sensor::Accel && c.id.instance == 1) c.offset_observable = false;
    const double g = c.id.sensor == Sensor::Gyro ? 1.0 : 10.0;  // accelerometer terms in m/s^2 units
    c.model.noise = {g * (7e-5 + 1e-6 * static_cast<double>(k)), g * 3e-5, g * (1e-6 + 1e-7 * static_cast<double>(k)),
                     200.0};
  }
  return m;
}

// Name -> value text of a PX4 .params (QGC: vehicle component name value type) or ArduPilot .parm
// (NAME,VALUE) file; comment lines start with '#'.
std::map<std::string, std::string> read_params(const std::string& text, bool qgc) {
  std::map<std::string, std::string> p;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::string name, value;
    if (qgc) {
      std::istringstream f(line);
      int vehicle = 0, component = 0, type = 0;
      EXPECT_TRUE(f >> vehicle >> component >> name >> value >> type) << line;
      EXPECT_TRUE(type == 6 || type == 9) << line;
      if (type == 6) {
        EXPECT_EQ(value.find_first_not_of("-0123456789"), std::string::npos) << "INT32: " << line;
      }
    } else {
      const auto comma = line.find(',');
      EXPECT_NE(comma, std::string::npos) << line;
      name = line.substr(0, comma);
      value = line.substr(comma + 1);
    }
    EXPECT_FALSE(p.count(name)) << name << " twice";
    p[name] = value;
  }
  return p;
}

// A REAL32 parameter as the firmware holds it.
float real32(const std::map<std::string, std::string>& p, const std::string& name) {
  const auto it = p.find(name);
  if (it == p.end()) {
    ADD_FAILURE() << name << " missing";
    return NAN;
  }
  char* end = nullptr;
  const float v = std::strtof(it->second.c_str(), &end);
  EXPECT_EQ(*end, '\0') << name << " = " << it->second;
  EXPECT_TRUE(std::isfinite(v)) << name;
  return v;
}

// PX4's TemperatureCompensation::calc_thermal_offsets_3D for one axis, in float: the offset that
// PX4 subtracts from the raw value.
float px4_offset(const std::map<std::string, std::string>& p, const std::string& block, int axis, float temp) {
  const float tmin = real32(p, block + "TMIN"), tmax = real32(p, block + "TMAX"), tref = real32(p, block + "TREF");
  float dt;
  if (temp > tmax) {
    dt = tmax - tref;
  } else if (temp < tmin) {
    dt = tmin - tref;
  } else {
    dt = temp - tref;
  }
  const float dt2 = dt * dt, dt3 = dt2 * dt;
  const std::string a = "_" + std::to_string(axis);
  return real32(p, block + "X0" + a) + real32(p, block + "X1" + a) * dt + real32(p, block + "X2" + a) * dt2 +
         real32(p, block + "X3" + a) * dt3;
}

// ArduPilot's AP_InertialSensor_TCal::correct_sensor followed by the offset subtraction of
// _rotate_and_correct_gyro / _accel, in float: raw - corrected.
float ardupilot_correction(const std::map<std::string, std::string>& p, int n, Sensor sensor, char axis, float temp,
                           float caltemp, float offset) {
  constexpr float kReference = 35.0f;   // TEMP_REFERENCE
  constexpr float kInvScale = 1.0e-6f;  // INV_SCALE_FACTOR
  const std::string tcal = "INS_TCAL" + std::to_string(n) + "_";
  const std::string c = tcal + (sensor == Sensor::Gyro ? "GYR" : "ACC");
  const std::string a = std::string("_") + static_cast<char>(axis - 'x' + 'X');
  const float c1 = real32(p, c + "1" + a), c2 = real32(p, c + "2" + a), c3 = real32(p, c + "3" + a);
  const auto poly = [&](float d) { return (c1 + (c2 + c3 * d) * d) * d * kInvScale; };
  const float tmin = real32(p, tcal + "TMIN"), tmax = real32(p, tcal + "TMAX");
  temp = std::clamp(temp, tmin, tmax);
  caltemp = std::clamp(caltemp, tmin, tmax);
  return poly(temp - kReference) - poly(caltemp - kReference) + offset;
}

// The float-rounding allowance of a cubic with coefficients x about t_ref at temperature t.
double real32_allowance(const double (&x)[4], double t, double t_ref) {
  double scale = 0.0;
  for (int k = 0; k < 4; ++k) scale += std::abs(x[k]) * std::pow(std::abs(t) + std::abs(t_ref), k);
  return kReal32Ulps * FLT_EPSILON * scale;
}

const ChannelLoss& loss_of(const ExportResult& r, const imu::ChannelId& id) {
  const auto it = std::find_if(r.losses.begin(), r.losses.end(), [&](const auto& l) { return l.id == id; });
  EXPECT_NE(it, r.losses.end()) << id.role();
  return *it;
}

TEST(CalibrationExports, Px4ParamsHoldEveryAxisAndInstanceAndPx4sEquationReproducesTheModel) {
  const ImuCalibration imu = two_instance_imu();
  const ExportResult r = export_px4_params(imu);
  const auto p = read_params(r.text, true);
  EXPECT_EQ(p.at("TC_G_ENABLE"), "1");
  EXPECT_EQ(p.at("TC_A_ENABLE"), "1");
  for (const std::string s : {"G", "A"}) {
    for (int i = 0; i < 2; ++i) {
      const std::string b = "TC_" + s + std::to_string(i) + "_";
      for (const std::string name : {"ID", "TREF", "TMIN", "TMAX"}) EXPECT_TRUE(p.count(b + name)) << b + name;
      for (int k = 0; k < 4; ++k) {
        for (int a = 0; a < 3; ++a) EXPECT_TRUE(p.count(b + "X" + std::to_string(k) + "_" + std::to_string(a)));
      }
    }
  }
  EXPECT_EQ(p.size(), 2u + 4u * (4u + 12u)) << "nothing else";
  EXPECT_EQ(p.at("TC_G0_ID"), "2490378") << "the channels' device id";
  EXPECT_EQ(p.at("TC_A0_ID"), "2621450");
  EXPECT_EQ(p.at("TC_G1_ID"), "0");
  EXPECT_NE(r.text.find("set TC_G1_ID"), std::string::npos) << "an unknown id is written as 0 with a comment";
  EXPECT_EQ(real32(p, "TC_A1_X0_0"), 0.0f) << "an accelerometer without a reference: X0 = a0 = 0 about its T0";

  for (const auto& c : imu.channels) {
    const std::string b =
        std::string("TC_") + (c.id.sensor == Sensor::Gyro ? "G" : "A") + std::to_string(c.id.instance) + "_";
    const int axis = c.id.axis - 'x';
    double x[4];
    for (int k = 0; k < 4; ++k) x[k] = real32(p, b + "X" + std::to_string(k) + "_" + std::to_string(axis));
    const double stated = kGridSlack * loss_of(r, c.id).max_error;
    for (double t = c.model.valid_min_c; t <= c.model.valid_max_c; t += kStep) {
      const double firmware = px4_offset(p, b, axis, static_cast<float>(t));
      const double tolerance = stated + real32_allowance(x, t, real32(p, b + "TREF"));
      ASSERT_NEAR(firmware, c.model.polynomial_bias_rad_s(t), tolerance) << c.id.role() << " at " << t << " degC";
    }
  }
  EXPECT_GT(loss_of(r, {Sensor::Gyro, 'x', 1}).max_error, 0.0) << "order 5: approximated";
  EXPECT_EQ(loss_of(r, {Sensor::Gyro, 'x', 0}).max_error, 0.0) << "a cubic is exact";
  EXPECT_GT(loss_of(r, {Sensor::Accel, 'x', 1}).max_error, 0.0) << "held at accel1_z's narrower range";
  EXPECT_NE(r.text.find("# NOTE: gyro1_x: order-5 polynomial"), std::string::npos)
      << "the file states the loss per channel";
}

TEST(CalibrationExports, ArduPilotParmHoldsEveryInstanceAndArduPilotsEquationReproducesTheModel) {
  const ImuCalibration imu = two_instance_imu();
  const ExportResult r = export_ardupilot_params(imu);
  const auto p = read_params(r.text, false);
  for (int n = 1; n <= 2; ++n) {
    const std::string b = "INS_TCAL" + std::to_string(n) + "_";
    EXPECT_EQ(p.at(b + "ENABLE"), "1");
    for (const std::string s : {"GYR", "ACC"}) {
      for (int k = 1; k <= 3; ++k) {
        for (const char a : {'X', 'Y', 'Z'}) EXPECT_TRUE(p.count(b + s + std::to_string(k) + "_" + a)) << b + s;
      }
    }
  }
  for (const char a : {'X', 'Y', 'Z'}) {
    EXPECT_TRUE(p.count(std::string("INS_GYROFFS_") + a));
    EXPECT_TRUE(p.count(std::string("INS_GYR2OFFS_") + a));
    EXPECT_FALSE(p.count(std::string("INS_ACCOFFS_") + a))
        << "the accelerometer constant is ArduPilot's own calibration's";
  }
  EXPECT_EQ(p.size(), 2u * (3u + 18u + 4u)) << "nothing else";
  EXPECT_EQ(p.at("INS_TCAL2_TMIN"), "-5") << "one range per instance: the intersection (accel1_z from -5 degC)";

  constexpr float kAccelCalTemp = 20.0f;       // where the emulated ArduPilot accelerometer calibration runs
  constexpr double kUnobservedConstant = 0.3;  // m/s^2: the accelerometer offset the model does not know
  for (const auto& c : imu.channels) {
    const int n = c.id.instance + 1;
    const bool gyro = c.id.sensor == Sensor::Gyro;
    const std::string a = std::string("_") + static_cast<char>(c.id.axis - 'x' + 'X');
    const std::string s = std::string("INS_TCAL") + std::to_string(n) + (gyro ? "_GYR" : "_ACC");
    double x[4] = {0.0, 1e-6 * real32(p, s + "1" + a), 1e-6 * real32(p, s + "2" + a), 1e-6 * real32(p, s + "3" + a)};
    float caltemp = kAccelCalTemp, offset = 0.0f;
    double constant = 0.0;  // what the firmware's correction holds beyond the model
    if (gyro) {
      caltemp = real32(p, "INS_GYR" + std::to_string(n) + "_CALTEMP");
      offset = real32(p, (n == 1 ? std::string("INS_GYROFFS") : "INS_GYR" + std::to_string(n) + "OFFS") + a);
    } else {  // ArduPilot's accelerometer calibration measures the whole raw bias at its temperature
      constant = c.offset_observable ? 0.0 : kUnobservedConstant;
      offset = static_cast<float>(c.model.polynomial_bias_rad_s(kAccelCalTemp) + constant);
    }
    x[0] = offset;
    const double stated = kGridSlack * loss_of(r, c.id).max_error;
    for (double t = c.model.valid_min_c; t <= c.model.valid_max_c; t += kStep) {
      const double firmware =
          ardupilot_correction(p, n, c.id.sensor, c.id.axis, static_cast<float>(t), caltemp, offset);
      const double tolerance = stated + 2.0 * real32_allowance(x, t, 35.0);
      ASSERT_NEAR(firmware - constant, c.model.polynomial_bias_rad_s(t), tolerance) << c.id.role() << " at " << t;
    }
  }
  EXPECT_GT(loss_of(r, {Sensor::Gyro, 'z', 1}).max_error, 0.0) << "gyro1 is held at the instance's -5 degC";
  EXPECT_NE(r.text.find("# NOTE: gyro1_z: valid range -10 .. 50 degC held at [TMIN, TMAX] = -5 .. 50"),
            std::string::npos)
      << r.text;
}

TEST(CalibrationExports, KalibrYamlCarriesTheMeasuredNoiseOfOneInstanceLargestAxisFirst) {
  ImuCalibration imu = two_instance_imu();
  for (const int instance : {0, 1}) {
    const auto text = export_kalibr_imu_yaml(imu, {.kalibr_instance = instance}).text;
    const YAML::Node y = YAML::Load(text);
    double gn = 0, gk = 0, an = 0, ak = 0;
    for (const auto& c : imu.channels) {
      if (c.id.instance != instance) continue;
      double& n = c.id.sensor == Sensor::Gyro ? gn : an;
      double& k = c.id.sensor == Sensor::Gyro ? gk : ak;
      n = std::max(n, c.model.noise.arw_rad_sqrt_s);
      k = std::max(k, c.model.noise.rate_random_walk_rad_s_sqrt_s);
      EXPECT_NE(text.find(c.id.role() + " (column " + c.column + ")"), std::string::npos) << "every axis listed";
    }
    constexpr double kText = 1e-8;  // relative: 9 significant digits
    EXPECT_NEAR(y["accelerometer_noise_density"].as<double>(), an, an * kText);
    EXPECT_NEAR(y["accelerometer_random_walk"].as<double>(), ak, ak * kText);
    EXPECT_NEAR(y["gyroscope_noise_density"].as<double>(), gn, gn * kText);
    EXPECT_NEAR(y["gyroscope_random_walk"].as<double>(), gk, gk * kText);
    EXPECT_EQ(y["update_rate"].as<double>(), 200.0);
    EXPECT_EQ(text.find('<'), std::string::npos) << "no placeholders";
  }
  for (auto& c : imu.channels) {
    if (c.id == imu::ChannelId{Sensor::Accel, 'y', 0}) c.model.noise.rate_random_walk_rad_s_sqrt_s = 0.0;
  }
  EXPECT_NO_THROW(export_kalibr_imu_yaml(imu)) << "an axis without K: the others give the sensor's value";
  for (auto& c : imu.channels) {
    if (c.id.sensor == Sensor::Accel && c.id.instance == 0) c.model.noise.rate_random_walk_rad_s_sqrt_s = 0.0;
  }
  EXPECT_THROW(export_kalibr_imu_yaml(imu), ConfigError) << "K measured on no accelerometer axis: refused, not zeros";
  EXPECT_THROW(export_kalibr_imu_yaml(imu, {.kalibr_instance = 2}), ConfigError) << "no such instance";
}

// A term the calibration records only bound (allan: not resolved) is never written to Kalibr as if
// measured: when its bound is the largest of the sensor's axes, the export refuses; allowed, it writes
// the bound and says so on that line. Axes below a measured value change nothing. The bound survives
// the model file.
TEST(CalibrationExports, KalibrYamlWritesAnUnresolvedTermOnlyAsAMarkedBound) {
  ImuCalibration imu = two_instance_imu();
  for (auto& c : imu.channels)
    if (c.id == imu::ChannelId{Sensor::Gyro, 'x', 0}) {
      c.model.noise.rate_random_walk_rad_s_sqrt_s = 0.0;  // the fit set K to 0 ...
      c.model.noise.rate_random_walk_upper = 1e-3;        // ... and bounds it far above the other axes
    }
  try {
    export_kalibr_imu_yaml(imu);
    ADD_FAILURE() << "an unresolved K written as a value";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("not resolved"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("gyro_x"), std::string::npos) << e.what();
  }
  const auto text = export_kalibr_imu_yaml(imu, {.kalibr_allow_bounds = true}).text;
  const YAML::Node y = YAML::Load(text);
  EXPECT_EQ(y["gyroscope_random_walk"].as<double>(), 1e-3);
  const auto line = text.substr(text.find("gyroscope_random_walk:"));
  EXPECT_NE(line.substr(0, line.find('\n')).find("UPPER BOUND"), std::string::npos) << text;
  EXPECT_NE(text.find("K < 0.001 (not resolved)"), std::string::npos) << text;
  // A bound below another axis' measured value: that value is written, measured, unmarked.
  for (auto& c : imu.channels)
    if (c.id == imu::ChannelId{Sensor::Gyro, 'x', 0}) c.model.noise.rate_random_walk_upper = 1e-12;
  EXPECT_EQ(export_kalibr_imu_yaml(imu).text.find("UPPER BOUND"), std::string::npos);
  // The model file keeps the bound.
  const auto dir = std::filesystem::temp_directory_path() / ("driftlab_exports_bound_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "m.json") << to_json_text(imu);
  const ImuCalibration back = read_calibration(dir / "m.json");
  std::filesystem::remove_all(dir);
  for (const auto& c : back.channels) {
    const bool bounded = c.id == imu::ChannelId{Sensor::Gyro, 'x', 0};
    EXPECT_EQ(c.model.noise.rate_random_walk_upper.has_value(), bounded) << c.id.role();
    if (bounded) {
      EXPECT_EQ(*c.model.noise.rate_random_walk_upper, 1e-12);
    }
  }
}

std::filesystem::path scratch(const std::string& name) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("driftlab_exports_" + std::to_string(::getpid()) + "_" + name);
  std::filesystem::create_directories(dir);
  return dir;
}

// Compiles `main_c` against the header `h` with the strictest C99 flags; "" when it worked.
std::string compile_c99(const std::filesystem::path& dir, const std::string& h, const std::string& main_c) {
  std::ofstream(dir / "cal.h") << h;
  std::ofstream(dir / "main.c") << main_c;
  const std::string cc = DRIFTLAB_C_COMPILER;
  const std::string build = cc + " -std=c99 -pedantic -Wall -Wextra -Werror -O2 -o " + (dir / "run").string() + " " +
                            (dir / "main.c").string() + " -lm 2>" + (dir / "cc.log").string();
  if (std::system(build.c_str()) == 0) return "";
  std::ifstream log(dir / "cc.log");
  std::stringstream s;
  s << log.rdbuf();
  return "compile failed:\n" + s.str();
}

TEST(CalibrationExports, TheCHeaderCompilesAsC99AndRunsEveryChannelLikeTheCompensator) {
  ImuCalibration imu = two_instance_imu();
  // Every term on two channels: lag, dT/dt, hysteresis, RBF, scale factor, 'linear' extrapolation.
  for (auto& c : imu.channels) {
    if (c.id == imu::ChannelId{Sensor::Gyro, 'y', 1} || c.id == imu::ChannelId{Sensor::Accel, 'z', 0}) {
      c.model = testing::example_full_model();
    }
  }
  const auto dir = scratch("c_header");
  // "P_x": a prefix that starts like the generator's placeholders did.
  const std::string error = compile_c99(dir, export_c_header(imu, {.symbol_prefix = "P_x"}).text, R"(#include <stdio.h>
#include "cal.h"
int main(void) {
  P_x_imu_state st;
  int i, k;
  P_x_imu_init(&st);
  for (i = 0; i < 3000; ++i) {
    const double t = 0.5 * i;
    double temps[P_x_TEMPERATURES], in[P_x_CHANNELS], out[P_x_CHANNELS], bias[P_x_CHANNELS];
    int outside[P_x_CHANNELS];
    temps[0] = 15.0 + 50.0 * sin(t / 200.0);
    temps[1] = 10.0 + 45.0 * sin(t / 170.0 + 0.3);
    for (k = 0; k < P_x_CHANNELS; ++k) in[k] = (k >= 6 ? 9.8 : 0.0) + 0.01 + 0.02 * cos(t / 7.0 + k);
    printf("%d", P_x_imu_step(&st, t, in, temps, out, bias, outside));
    for (k = 0; k < P_x_CHANNELS; ++k) printf(" %.17g %.17g %d", out[k], bias[k], outside[k]);
    printf("\n");
  }
  return P_x_ch_accel1_z == 11 ? 0 : 1;
})");
  ASSERT_EQ(error, "");
  ASSERT_EQ(std::system(((dir / "run").string() + " > " + (dir / "out.txt").string()).c_str()), 0);
  std::ifstream in(dir / "out.txt");
  std::vector<CausalCompensator> reference;
  for (const auto& c : imu.channels) reference.emplace_back(c.model);
  // The same formulas in C and C++; libm's exp may differ in the last bit: a few ulps of the value.
  constexpr double kLibmUlps = 8.0;
  unsigned seen_outside = 0;
  for (int i = 0; i < 3000; ++i) {
    const double t = 0.5 * i;
    const double temps[2] = {15.0 + 50.0 * std::sin(t / 200.0), 10.0 + 45.0 * std::sin(t / 170.0 + 0.3)};
    int channels_outside = 0, expected_channels_outside = 0;
    ASSERT_TRUE(in >> channels_outside);
    for (std::size_t k = 0; k < imu.channels.size(); ++k) {
      const double x = (k >= 6 ? 9.8 : 0.0) + 0.01 + 0.02 * std::cos(t / 7.0 + static_cast<double>(k));
      double out = 0, bias = 0;
      unsigned outside = 0;
      ASSERT_TRUE(in >> out >> bias >> outside);
      const double expected = reference[k].step(t, x, temps[imu.channels[k].id.instance]);
      const double tolerance = kLibmUlps * DBL_EPSILON * (1.0 + std::abs(expected));
      ASSERT_NEAR(out, expected, tolerance) << imu.channels[k].id.role() << " sample " << i;
      ASSERT_NEAR(bias, reference[k].last_bias_rad_s(), tolerance) << imu.channels[k].id.role() << " sample " << i;
      ASSERT_EQ(outside, reference[k].last_outside()) << imu.channels[k].id.role() << " sample " << i;
      expected_channels_outside += reference[k].last_outside() != 0 ? 1 : 0;
      seen_outside |= reference[k].last_outside();
    }
    ASSERT_EQ(channels_outside, expected_channels_outside) << i;
  }
  EXPECT_EQ(seen_outside, kOutsideTemperature | kOutsideTemperatureRate | kOutsideBranchState | kOutsideRbfInputs)
      << "the records leave every input's range at some sample";
}

TEST(CalibrationExports, PrefixesThatAreNoSafeCIdentifierStartAreRefused) {
  const ImuCalibration imu = testing::one_channel(testing::example_polynomial_model());
  for (const std::string& bad :
       std::vector<std::string>{"", "_cal", "1cal", "cal_", "my__cal", "cal-x", std::string(33, 'a')}) {
    EXPECT_THROW(export_c_header(imu, {.symbol_prefix = bad}), ConfigError) << "'" << bad << "'";
  }
  EXPECT_NO_THROW(export_c_header(imu, {.symbol_prefix = std::string(32, 'a')}));
}

TEST(CalibrationExports, StrictRefusesNamingTheChannelAndTheDefaultStatesWhatIsDropped) {
  ImuCalibration imu = two_instance_imu();
  EXPECT_THROW(export_px4_params(imu, {.strict = true}), ConfigError) << "gyro1_x is of order 5";
  for (auto& c : imu.channels) {
    if (c.id == imu::ChannelId{Sensor::Gyro, 'x', 1}) c.model = testing::example_full_model();
  }
  try {
    export_ardupilot_params(imu, {.strict = true});
    ADD_FAILURE() << "not refused";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("gyro1_x"), std::string::npos) << e.what();
  }
  const auto r = export_px4_params(imu);
  EXPECT_NE(r.text.find("# NOTE: gyro1_x: dropped (not representable in PX4 TC_G1_*): hysteresis"), std::string::npos)
      << r.text;
  EXPECT_NE(r.text.find("# NOTE: gyro1_x: dropped (not representable in PX4 TC_G1_*): scale-factor"),
            std::string::npos);
  EXPECT_EQ(loss_of(r, {Sensor::Gyro, 'x', 1}).dropped.size(), 6u)
      << "lag, dT/dt, hysteresis, RBF, scale factor, linear extrapolation";
  // A cubic under the linear policy is exact inside the range but not outside it: strict refuses it.
  ImuCalibration linear = two_instance_imu();
  linear.channels = {linear.channels[2]};  // gyro_z: a line, one channel to its block
  EXPECT_NO_THROW(export_px4_params(linear, {.strict = true}));
  linear.channels[0].model.extrapolation = Extrapolation::Linear;
  try {
    export_px4_params(linear, {.strict = true});
    ADD_FAILURE() << "the linear policy was exported as exact";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("the 'linear' extrapolation outside the valid range"), std::string::npos)
        << e.what();
  }
}

TEST(CalibrationExports, ValuesThatAreNoFiniteReal32AreRefusedNamingChannelAndParameter) {
  ImuCalibration imu = two_instance_imu();
  imu.channels[0].model.bias_rad_s = {0.0, 0.0, 0.0, 1e39};  // gyro_x: beyond FLT_MAX
  try {
    export_px4_params(imu);
    ADD_FAILURE() << "not refused";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("gyro_x"), std::string::npos) << what;
    EXPECT_NE(what.find("TC_G0_X3_0"), std::string::npos) << what;
  }
  imu.channels[0].model.bias_rad_s = {0.0, 0.0, 0.0, 1e31};  // fits a float, not after ArduPilot's x1e6
  try {
    export_ardupilot_params(imu);
    ADD_FAILURE() << "not refused";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("gyro_x: INS_TCAL1_GYR1_X"), std::string::npos)
        << what;  // 3e39: re-expanded about 35 degC, x1e6
    EXPECT_EQ(what.find("accel_x"), std::string::npos) << "names the one channel: " << what;
  }
}

TEST(CalibrationExports, TheSingleAxisV1FileStillExportsToItsAxisOfInstanceZero) {
  // rad/s: the firmware's float evaluation at one temperature, ~16 float ulps (kReal32Ulps) of the
  // file's ~5e-4 rad/s bias (6e-11 each).
  constexpr double kFloatEvaluation = 1e-9;
  const ImuCalibration v1 = read_calibration(std::string(DRIFTLAB_TEST_DATA) + "/calibration/v1_rbf_ranged.json");
  ASSERT_EQ(v1.channels.size(), 1u);
  const auto& c = v1.channels.front();
  const auto px4 = export_px4_params(v1);
  const auto p = read_params(px4.text, true);
  EXPECT_EQ(p.count("TC_A_ENABLE"), 0u) << "no accelerometer in the model";
  EXPECT_EQ(real32(p, "TC_G0_X1_0"), 0.0f) << "axes other than z: no correction";
  EXPECT_NE(real32(p, "TC_G0_X1_2"), 0.0f);
  EXPECT_NEAR(px4_offset(p, "TC_G0_", 2, 20.0f), c.model.polynomial_bias_rad_s(20.0),
              kGridSlack * loss_of(px4, c.id).max_error + kFloatEvaluation);
  EXPECT_FALSE(px4.notes.empty()) << "lag and dT/dt dropped, order 4 approximated";
  const auto ap = read_params(export_ardupilot_params(v1).text, false);
  EXPECT_NE(real32(ap, "INS_TCAL1_GYR1_Z"), 0.0f);
  EXPECT_EQ(real32(ap, "INS_TCAL1_ACC1_Z"), 0.0f);
  EXPECT_EQ(compile_c99(scratch("v1"), export_c_header(v1).text, "#include \"cal.h\"\nint main(void) { return 0; }\n"),
            "");
  EXPECT_THROW(export_kalibr_imu_yaml(v1), ConfigError) << "no accelerometer and no noise terms: refused";
}

}  // namespace
}  // namespace driftlab::calibration
