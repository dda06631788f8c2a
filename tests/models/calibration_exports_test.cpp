// Every export is parsed back (or compiled and run) and evaluates to the model's bias.
#include "models/calibration/exports.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "framework/error.hpp"
#include "tests/models/calibration_fixtures.hpp"

namespace driftlab::calibration {
namespace {

constexpr double kFloatText = 1e-8;  // relative: the .params files carry 9 significant digits
const std::vector<double> kTemperatures{-40.0, -20.0, 0.0, 12.5, 25.0, 35.0, 48.0, 70.0};

CalibrationModel cubic_model() { return testing::example_polynomial_model({4e-4, -1.1e-5, -1.4e-8, 3e-10}, -25.0, 60.0); }
CalibrationModel stateful_model() { return testing::example_full_model(); }

std::filesystem::path scratch() {
  const auto dir = std::filesystem::temp_directory_path() / ("driftlab_exports_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

TEST(CalibrationExports, TheCHeaderCompilesAsC99AndRunsTheCompensatorSampleForSample) {
  for (const auto& model : {cubic_model(), stateful_model()}) {
    const auto dir = scratch();
    std::ofstream(dir / "cal.h") << export_c_header(testing::one_channel(model).channels.front(), {.symbol_prefix = "gyro_cal"}).text;
    std::ofstream(dir / "main.c") << R"(#include <stdio.h>
#include "cal.h"
int main(void) {
  gyro_cal_state st;
  int i;
  gyro_cal_init(&st);
  for (i = 0; i < 3000; ++i) {
    const double t = 0.5 * i, temp = 15.0 + 50.0 * sin(t / 200.0), rate = 0.01 + 0.02 * cos(t / 7.0);
    double bias; int ex;
    const double w = gyro_cal_step(&st, t, rate, temp, &bias, &ex);
    printf("%.17g %.17g %d\n", w, bias, ex);
  }
  return 0;
})";
    const std::string cc = DRIFTLAB_C_COMPILER;
    const std::string build = cc + " -std=c99 -pedantic -Wall -Wextra -Werror -O2 -o " + (dir / "run").string() + " " +
                              (dir / "main.c").string() + " -lm 2>" + (dir / "cc.log").string();
    ASSERT_EQ(std::system(build.c_str()), 0) << std::ifstream(dir / "cc.log").rdbuf();
    ASSERT_EQ(std::system(((dir / "run").string() + " > " + (dir / "out.txt").string()).c_str()), 0);
    std::ifstream in(dir / "out.txt");
    CausalCompensator ref(model);
    for (int i = 0; i < 3000; ++i) {
      const double t = 0.5 * i, temp = 15.0 + 50.0 * std::sin(t / 200.0), rate = 0.01 + 0.02 * std::cos(t / 7.0);
      double w = 0, bias = 0;
      int ex = 0;
      ASSERT_TRUE(in >> w >> bias >> ex);
      const double expected = ref.step(t, rate, temp);
      constexpr double kLibm = 1e-15;  // rad/s: the same formulas, C and C++ libm calls
      ASSERT_NEAR(w, expected, kLibm) << i;
      ASSERT_NEAR(bias, ref.last_bias_rad_s(), kLibm) << i;
      ASSERT_EQ(ex != 0, ref.last_extrapolated()) << i;
    }
  }
}

std::map<std::string, double> read_params(const std::string& text, bool qgc) {
  std::map<std::string, double> p;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (qgc) {
      std::istringstream f(line);
      int vehicle, component, type;
      std::string name;
      double value;
      EXPECT_TRUE(f >> vehicle >> component >> name >> value >> type) << line;
      EXPECT_TRUE(type == 6 || type == 9) << line;
      p[name] = value;
    } else {
      const auto comma = line.find(',');
      p[line.substr(0, comma)] = std::stod(line.substr(comma + 1));
    }
  }
  return p;
}

TEST(CalibrationExports, Px4ParamsEvaluateToTheModelBiasWithPx4sClamp) {
  const CalibrationModel m = cubic_model();
  const auto p = read_params(export_px4_params(testing::one_channel(m).channels.front()).text, true);
  EXPECT_EQ(p.at("TC_G_ENABLE"), 1);
  for (double t : kTemperatures) {
    const double dt = std::clamp(t, p.at("TC_G0_TMIN"), p.at("TC_G0_TMAX")) - p.at("TC_G0_TREF");
    const double offset = p.at("TC_G0_X0_2") + p.at("TC_G0_X1_2") * dt + p.at("TC_G0_X2_2") * dt * dt +
                          p.at("TC_G0_X3_2") * dt * dt * dt;
    EXPECT_NEAR(offset, m.polynomial_bias_rad_s(t), kFloatText * 1e-3) << t;
    EXPECT_EQ(p.at("TC_G0_X1_0"), 0.0) << "other axes untouched";
  }
}

TEST(CalibrationExports, ArduPilotParamsUseThe35DegreeReferenceAndMillionScaling) {
  const CalibrationModel m = cubic_model();
  const auto p = read_params(export_ardupilot_params(testing::one_channel(m).channels.front()).text, false);
  const auto poly = [&](double tdiff) {  // ArduPilot's polynomial_eval, without the constant term
    return (p.at("INS_TCAL1_GYR1_Z") + (p.at("INS_TCAL1_GYR2_Z") + p.at("INS_TCAL1_GYR3_Z") * tdiff) * tdiff) * tdiff *
           1e-6;
  };
  for (double t : kTemperatures) {
    const double tc = std::clamp(t, p.at("INS_TCAL1_TMIN"), p.at("INS_TCAL1_TMAX"));
    const double cal = std::clamp(p.at("INS_GYR1_CALTEMP"), p.at("INS_TCAL1_TMIN"), p.at("INS_TCAL1_TMAX"));
    const double correction = poly(tc - 35.0) - poly(cal - 35.0) + p.at("INS_GYROFFS_Z");
    EXPECT_NEAR(correction, m.polynomial_bias_rad_s(t), kFloatText * 1e-3) << t;
  }
}

TEST(CalibrationExports, KalibrYamlCarriesTheAllanTermsInSiUnits) {
  CalibrationModel m = cubic_model();
  m.noise = {2.9e-4, 5e-6, 3e-7, 100.0};
  const YAML::Node y = YAML::Load(export_kalibr_imu_yaml(testing::one_channel(m).channels.front()).text);
  EXPECT_NEAR(y["gyroscope_noise_density"].as<double>(), 2.9e-4, 2.9e-4 * kFloatText);
  EXPECT_NEAR(y["gyroscope_random_walk"].as<double>(), 3e-7, 3e-7 * kFloatText);
  EXPECT_EQ(y["update_rate"].as<double>(), 100.0);
  m.noise = {};
  EXPECT_THROW(export_kalibr_imu_yaml(testing::one_channel(m).channels.front()), ConfigError) << "no noise terms: refused, not zeros";
}

TEST(CalibrationExports, UnrepresentableModelsAreRefusedWhenStrictAndApproximatedWithNotesOtherwise) {
  const CalibrationModel m = stateful_model();
  EXPECT_THROW(export_px4_params(testing::one_channel(m).channels.front(), {.strict = true}), ConfigError);
  EXPECT_THROW(export_ardupilot_params(testing::one_channel(m).channels.front(), {.strict = true}), ConfigError);
  const auto r = export_px4_params(testing::one_channel(m).channels.front());
  EXPECT_GE(r.notes.size(), 4u);
  EXPECT_NE(r.text.find("hysteresis"), std::string::npos) << "the file itself says what was dropped";

  CalibrationModel quintic = cubic_model();
  quintic.bias_rad_s = {4e-4, -1.1e-5, -1.4e-8, 3e-10, 2e-11, -1e-13};
  double stated = 0.0;
  const auto c = cubic_about(quintic, 25.0, stated);
  double worst = 0.0;
  for (double t = quintic.valid_min_c; t <= quintic.valid_max_c; t += 0.25) {
    const double d = t - 25.0;
    worst = std::max(worst, std::abs(c[0] + c[1] * d + c[2] * d * d + c[3] * d * d * d - quintic.polynomial_bias_rad_s(t)));
  }
  constexpr double kGridSlack = 1.05;  // the stated error is the maximum on a 201-point grid
  EXPECT_LE(worst, kGridSlack * stated);
  EXPECT_GT(stated, 0.0);
  EXPECT_NE(export_px4_params(testing::one_channel(quintic).channels.front()).text.find("max error"), std::string::npos);
}

}  // namespace
}  // namespace driftlab::calibration
