#include "models/calibration/calibration_model.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <random>

#include "framework/error.hpp"
#include "models/calibration/fit.hpp"
#include "models/evaluation/evaluation.hpp"
#include "tests/models/calibration_fixtures.hpp"

namespace driftlab::calibration {
namespace {

constexpr double kRounding = 1e-12;  // double evaluation of the same expression
// A fitted coefficient against its truth: kSigmas of its own standard error, plus a floor (rad/s,
// rad/s/K, rad/s/K^2) that keeps the bound open should a standard error come out 0.
constexpr double kSigmas = 5.0, kSigmaFloor = 1e-12;

std::filesystem::path scratch(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("driftlab_calmodel_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir / name;
}

CalibrationModel poly_model() { return testing::example_polynomial_model(); }
CalibrationModel full_model() { return testing::example_full_model(); }

TEST(CalibrationModelJson, RoundTripsEveryFieldOfEveryChannel) {
  const auto path = scratch("full.json");
  ImuCalibration imu_model = testing::one_channel(full_model());
  imu_model.channels.push_back(
      {{imu::Sensor::Accel, 'z', 1}, "accel1_z", "az1", "mg", "temp1", "2490378", false, poly_model()});
  std::ofstream(path) << to_json_text(imu_model);
  const ImuCalibration back = read_calibration(path);
  ASSERT_EQ(back.channels.size(), 2u);
  const CalibrationModel& m = imu_model.channels[0].model;
  const CalibrationModel& r = back.channels[0].model;
  EXPECT_EQ(back.channels[0].id, (imu::ChannelId{imu::Sensor::Gyro, 'z', 0}));
  EXPECT_EQ(r.kind, ModelKind::Rbf);
  EXPECT_EQ(r.extrapolation, Extrapolation::Linear);
  EXPECT_EQ(r.bias_rad_s, m.bias_rad_s);
  EXPECT_EQ(r.bias_sigma_rad_s, m.bias_sigma_rad_s);
  EXPECT_EQ(r.lag_tau_s, m.lag_tau_s);
  EXPECT_EQ(r.hysteresis_width_k, m.hysteresis_width_k);
  ASSERT_TRUE(r.rbf);
  EXPECT_EQ(r.rbf->centres, m.rbf->centres);
  EXPECT_EQ(r.rbf->weights_rad_s, m.rbf->weights_rad_s);
  EXPECT_EQ(r.scale_factor_per_k, m.scale_factor_per_k);
  EXPECT_EQ(r.noise.arw_rad_sqrt_s, m.noise.arw_rad_sqrt_s);
  EXPECT_EQ(r.fit.records, m.fit.records);
  const auto& accel = back.channels[1];
  EXPECT_EQ(accel.id, (imu::ChannelId{imu::Sensor::Accel, 'z', 1}));
  EXPECT_EQ(accel.column, "az1");
  EXPECT_EQ(accel.read_unit, "mg");
  EXPECT_EQ(accel.temperature_column, "temp1");
  EXPECT_EQ(accel.device_id, "2490378");
  EXPECT_FALSE(accel.offset_observable);
  const std::string text = to_json_text(imu_model);
  EXPECT_NE(text.find("polynomial_m_s2_per_k_i"), std::string::npos) << "accelerometer keys carry m/s^2";
  EXPECT_EQ(to_json_text(back), text) << "a read-back model writes the same file";
}

TEST(CalibrationModelJson, AVersion1SingleAxisFileStillReadsAndCompensatesIdentically) {
  const auto v1 = std::filesystem::path(DRIFTLAB_TEST_DATA) / "calibration" / "v1_rbf_ranged.json";
  const ImuCalibration read = read_calibration(v1);
  ASSERT_EQ(read.channels.size(), 1u);
  const auto& c = read.channels.front();
  EXPECT_EQ(c.role, "rate") << "a version-1 model applies to the record's single-axis rate column";
  EXPECT_EQ(c.id.sensor, imu::Sensor::Gyro);
  // The numbers are the file's, read independently.
  nlohmann::json j;
  std::ifstream(v1) >> j;
  EXPECT_EQ(c.id.axis, j["axis"].get<std::string>()[0]);
  EXPECT_EQ(c.model.bias_rad_s, j["bias"]["polynomial_rad_s_per_k_i"].get<std::vector<double>>());
  EXPECT_EQ(c.model.rbf->weights_rad_s, j["rbf"]["weights_rad_s"].get<std::vector<double>>());
  EXPECT_EQ(c.model.lag_tau_s, j["physical"]["lag_tau_s"].get<double>());
  // Rewritten as version 2 and read back, it compensates bit for bit as the version-1 file does.
  const auto v2 = scratch("v2_of_v1.json");
  std::ofstream(v2) << to_json_text(read);
  const ImuCalibration again = read_calibration(v2);
  CausalCompensator a(c.model), b(again.channels.front().model);
  for (int i = 0; i < 2000; ++i) {
    const double t = 0.1 * i, temp = 20.0 + 10.0 * std::sin(0.003 * i), rate = 1e-3 * std::cos(0.01 * i);
    ASSERT_EQ(a.step(t, rate, temp), b.step(t, rate, temp)) << "sample " << i;
  }
}

std::string error_of(const std::string& text) {
  const auto path = scratch("bad.json");
  std::ofstream(path) << text;
  try {
    read_calibration(path);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "no error";
}

TEST(CalibrationModelJson, BadFilesNameTheFileAndTheKey) {
  const std::string good = to_json_text(testing::one_channel(poly_model()));
  EXPECT_NE(error_of("{ not json").find("not valid JSON"), std::string::npos);
  // A number beyond double (found by the fuzzer, tests/fuzz/corpus/calibration/number_overflow.json).
  EXPECT_NE(error_of("{\"format\": 2.3e905}").find("not valid JSON"), std::string::npos);
  EXPECT_NE(error_of("{\"format\": \"other/1\"}").find("format"), std::string::npos);
  // A count beyond std::size_t (found by the fuzzer in CI, corpus/calibration/count_overflow.json).
  std::string huge_count = good;
  huge_count = std::regex_replace(huge_count, std::regex("\"samples\": [0-9]+"), "\"samples\": 1e300");
  const std::string c = error_of(huge_count);
  EXPECT_NE(c.find("fit.samples"), std::string::npos) << c;
  EXPECT_NE(c.find("whole number"), std::string::npos) << c;
  std::string missing = good;
  missing.replace(missing.find("\"reference_temp_c\""), 18, "\"reference_temp\"");
  const std::string e = error_of(missing);
  EXPECT_NE(e.find("reference_temp_c"), std::string::npos) << e;
  EXPECT_NE(e.find("bad.json"), std::string::npos) << e;
  std::string mistyped = good;
  mistyped.replace(mistyped.find("\"clamp\""), 7, "\"wild\"");
  EXPECT_NE(error_of(mistyped).find("extrapolation"), std::string::npos);
  EXPECT_THROW(read_calibration(scratch("absent.json")), ConfigError);
  std::string wrong_role = good;
  wrong_role = std::regex_replace(wrong_role, std::regex("\"role\": \"gyro_z\""), "\"role\": \"gyro_y\"");
  EXPECT_NE(error_of(wrong_role).find("channels[0].role"), std::string::npos) << error_of(wrong_role);
}

// The hostile models of issue 28: each passed validate() and gave inf/nan on every compensated row.
TEST(CalibrationModelValidation, ModelsAreCheckedAsPhysicsNotOnlyAsSyntax) {
  const auto refused = [](const CalibrationModel& m, const std::string& key, const std::string& expected) {
    try {
      m.validate();
      ADD_FAILURE() << key << ": accepted";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(key + ": "), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  EXPECT_NO_THROW(full_model().validate());
  CalibrationModel m = poly_model();
  m.scale_factor_per_k = {-2.0};  // sf = -1
  refused(m, "scale_factor.polynomial_per_k_j", "expected 0.1 to 10 over the valid range");
  m.scale_factor_per_k = {0.0, 0.1};  // sf = 1 + 0.1 (T - 25): 0 at 15 degC, inside [-10, 50]
  refused(m, "scale_factor.polynomial_per_k_j", "the scale factor is");
  m.scale_factor_per_k = {-1.0};  // what calibrate wrote for an all-zero rate with a moving truth
  refused(m, "scale_factor.polynomial_per_k_j", "the scale factor is 0");
  m = poly_model();
  m.reference_temp_c = 1e300;
  refused(m, "reference_temp_c", "expected a temperature within [-273.15, 1000] degC");
  m = poly_model();
  m.bias_rad_s.assign(100000, 1e-3);
  m.bias_sigma_rad_s.clear();
  refused(m, "bias.polynomial_rad_s_per_k_i", "expected at most 16 coefficients");
  m = testing::example_polynomial_model({1e-3, 1e307, 1e307}, -10.0, 50.0);  // finite coefficients, an infinite bias
  refused(m, "bias.polynomial_rad_s_per_k_i", "the bias is not finite");
  m = testing::example_polynomial_model(
      {1e-3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1e282}, -10.0, 50.0);
  m.bias_sigma_rad_s.clear();
  EXPECT_NO_THROW(m.validate()) << "finite over the range when clamped: 1e282 * 35^15 ~ 1e305";
  m.extrapolation = Extrapolation::Evaluate;
  refused(m, "bias.polynomial_rad_s_per_k_i", "and 50 K beyond it (extrapolation evaluate)");
  m = full_model();
  m.rbf->sigma = 1e-200;
  refused(m, "rbf.sigma", "expected a width within [0.001, 1000]");
  m = full_model();
  m.rbf->weights_rad_s = {1e308, 1e308, 1e308};
  refused(m, "rbf.weights_rad_s", "overflows");
  m = full_model();
  m.noise.sample_rate_hz = -1.0;
  refused(m, "noise", "must be finite and >= 0");
}

TEST(CalibrationModelJson, ARepeatedKeyAFifoAndAnUnphysicalModelAreRefusedWithFileAndKey) {
  const std::string good = to_json_text(testing::one_channel(poly_model()));
  std::string repeated = good;
  repeated.replace(repeated.find("\"kind\""), 6, "\"kind\": \"rbf\", \"kind\"");
  const std::string r = error_of(repeated);
  EXPECT_NE(r.find("bad.json: channels[0].model.kind: the key appears twice in one object"), std::string::npos) << r;
  std::string nested = good;  // repeated inside a list element
  nested.replace(nested.find("\"axis\""), 6, "\"axis\": \"x\", \"axis\"");
  EXPECT_NE(error_of(nested).find("channels[0].axis: the key appears twice"), std::string::npos) << error_of(nested);
  std::string negative_sf = good;
  negative_sf =
      std::regex_replace(negative_sf, std::regex("\"polynomial_per_k_j\": \\[\\]"), "\"polynomial_per_k_j\": [-2.0]");
  const std::string n = error_of(negative_sf);
  EXPECT_NE(n.find("bad.json: channels[0].model.scale_factor.polynomial_per_k_j: the scale factor is -1"),
            std::string::npos)
      << n;
  ImuCalibration accel =
      testing::one_channel(testing::example_polynomial_model({1e-3, 1e307, 1e307}), {imu::Sensor::Accel, 'z', 0});
  const std::string a = error_of(to_json_text(accel));  // the key as the accelerometer's file spells it
  EXPECT_NE(a.find("bad.json: channels[0].model.bias.polynomial_m_s2_per_k_i: the bias is not finite"),
            std::string::npos)
      << a;
  const auto fifo = scratch("model_fifo.json");
  std::filesystem::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  try {
    read_calibration(fifo);  // blocked forever before
    ADD_FAILURE() << "a FIFO was read";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(fifo.string() + ": cannot read the calibration model file: it is a FIFO"),
              std::string::npos)
        << e.what();
  }
}

TEST(CausalCompensator, SubtractsThePolynomialAndFlagsAndClampsOutsideTheRange) {
  const CalibrationModel m = poly_model();
  CausalCompensator c(m);
  const auto p = [&](double t) {
    return m.bias_rad_s[0] + m.bias_rad_s[1] * (t - 25) + m.bias_rad_s[2] * (t - 25) * (t - 25);
  };
  EXPECT_NEAR(c.step(0.0, 0.01, 30.0), 0.01 - p(30.0), kRounding);
  EXPECT_EQ(c.last_outside(), 0u);
  EXPECT_NEAR(c.step(1.0, 0.01, 70.0), 0.01 - p(50.0), kRounding) << "clamp holds the edge value";
  EXPECT_EQ(c.last_outside(), kOutsideTemperature);
  CalibrationModel lin = m;
  lin.extrapolation = Extrapolation::Linear;
  const double slope = m.bias_rad_s[1] + 2 * m.bias_rad_s[2] * (50.0 - 25.0);
  EXPECT_NEAR(lin.polynomial_bias_rad_s(60.0), p(50.0) + 10.0 * slope, kRounding);
  CalibrationModel ev = m;
  ev.extrapolation = Extrapolation::Evaluate;
  EXPECT_NEAR(ev.polynomial_bias_rad_s(60.0), p(60.0), kRounding);
}

// The compensated rate (input 0) at 30 degC after a 1200-s ramp at rate_c_per_min, at 10 Hz (long
// enough for the dT/dt estimate and the hysteresis state to settle).
double after_ramp(const CalibrationModel& m, double rate_c_per_min) {
  CausalCompensator c(m);
  double out = 0.0;
  for (int k = 0; k <= 12000; ++k) out = c.step(0.1 * k, 0.0, 30.0 - rate_c_per_min * (12000 - k) / 600.0);
  return out;
}

TEST(CausalCompensator, EvaluatesTheRbfNetworkInsideTheRangeOfItsFittingData) {
  // rad/s: the network sees the same clamped dT/dt; only the hysteresis term's remainder differs,
  // 2e-5 rad/s x exp(-30 K / 1.5 K) = 4e-14 (measured 6e-14).
  constexpr double kSameEdge = 1e-12;
  CalibrationModel m = testing::example_full_model();  // dT/dt range +-0.02 K/s = +-1.2 degC/min
  m.temperature_rate_rad_s_per_k_s = 0.0;              // only the network sees dT/dt
  m.lag_tau_s = 0.0;                                   // the same model temperature on both ramps
  // 1.5 and 2.4 degC/min are both beyond the range: the network sees its edge both times.
  EXPECT_NEAR(after_ramp(m, 1.5), after_ramp(m, 2.4), kSameEdge);
  m.rbf->input_min.clear();
  m.rbf->input_max.clear();
  EXPECT_GT(std::abs(after_ramp(m, 1.5) - after_ramp(m, 2.4)), 1e-10) << "without the range the network extrapolates";
}

TEST(CausalCompensator, LimitsDTdtAndTheBranchStateToTheirFittedRangesAndSaysWhichInputWasOutside) {
  // rad/s: after 20 min the 20-s derivative filter and the 1.5-K branch have settled (60 widths).
  constexpr double kSettled = 1e-12;
  CalibrationModel m = testing::example_polynomial_model();
  m.kind = ModelKind::Physical;
  m.derivative_tau_s = 20.0;
  m.temperature_rate_rad_s_per_k_s = 3e-3;
  m.temperature_rate_range_k_s = InputRange{-0.01, 0.01};  // fitted on ramps of up to 0.6 degC/min
  m.hysteresis_rad_s = -2e-5;
  m.hysteresis_width_k = 1.5;
  m.hysteresis_state_range = InputRange{-1.0, -0.5};  // fitted on cooling only
  CausalCompensator c(m);
  // Heating at 1.2 degC/min from 20 to 44 degC: inside the valid temperature range, outside both others.
  for (int k = 0; k <= 12000; ++k) c.step(0.1 * k, 0.0, 20.0 + 0.002 * k);
  EXPECT_NEAR(c.last_bias_rad_s(), m.polynomial_bias_rad_s(44.0) + 3e-3 * 0.01 + -2e-5 * -0.5, kSettled)
      << "dT/dt and the branch state held at the edges of their ranges";
  EXPECT_EQ(c.last_outside(), kOutsideTemperatureRate | kOutsideBranchState);
  EXPECT_EQ(outside_inputs_text(c.last_outside()), "dT/dt, branch state");
  m.temperature_rate_range_k_s.reset();
  m.hysteresis_state_range.reset();
  CausalCompensator unlimited(m);
  for (int k = 0; k <= 12000; ++k) unlimited.step(0.1 * k, 0.0, 20.0 + 0.002 * k);
  EXPECT_NEAR(unlimited.last_bias_rad_s(), m.polynomial_bias_rad_s(44.0) + 3e-3 * 0.02 + -2e-5 * 1.0, 1e-9)
      << "a file without the ranges: no limit";
  EXPECT_EQ(unlimited.last_outside(), 0u);
}

TEST(CausalCompensator, RejectsTimeThatDoesNotIncrease) {
  CausalCompensator c(poly_model());
  c.step(1.0, 0.0, 20.0);
  EXPECT_THROW(c.step(1.0, 0.0, 20.0), DataError);
}

TEST(CausalState, TracksARampWithTheLagAndEstimatesItsRate) {
  constexpr double kRamp = 0.02;  // K/s
  // K/s: the 10-s derivative filter has run 200 time constants; rounding of 0.1-s differences of
  // ~60-degC values remains (measured 3e-14).
  constexpr double kRateSettled = 1e-9;
  // 40 K of heating is 40 widths (exp(-40)), but with 0.002-K steps the update stalls where a step
  // moves the state by less than half an ulp: 2^-54 / (0.002 K / 1 K) = 2.8e-14 from the branch.
  constexpr double kOnTheBranch = 1e-9;
  CausalState s(100.0, 10.0, 1.0);
  for (int i = 0; i <= 20000; ++i) s.step(0.1 * i, 20.0 + kRamp * 0.1 * i);
  const double t = 2000.0;
  constexpr double kSettled = 1e-7;  // the 2 K start transient decays to 2 K x exp(-20) = 4e-9 K
  EXPECT_NEAR(s.model_temp_c(), 20.0 + kRamp * (t - 100.0), kSettled) << "a first-order lag delays a ramp by tau";
  EXPECT_NEAR(s.temp_rate_k_s(), kRamp, kRateSettled);
  EXPECT_NEAR(s.hysteresis_state(), 1.0, kOnTheBranch) << "heating branch";
}

TEST(CausalCompensator, BatchEqualsStepByStep) {
  const CalibrationModel m = full_model();
  Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(500, 0, 499);
  Eigen::VectorXd temp = (20.0 + 10.0 * (t.array() / 80.0).sin()).matrix();
  Eigen::VectorXd rate = Eigen::VectorXd::Constant(500, 0.01);
  const auto batch = compensate(m, t, rate, temp);
  CausalCompensator c(m);
  for (int i = 0; i < 500; ++i) ASSERT_EQ(c.step(t[i], rate[i], temp[i]), batch.rate_rad_s[i]);
}

// A synthetic oven record: bias truth[0] + truth[1] dT + truth[2] dT^2 (dT = T - 25 degC) plus
// white noise, temperature swinging 15 +- 35 degC (heating and cooling).
Record synthetic_record(std::uint64_t seed, const std::vector<double>& truth, double phase) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1e-3);
  Record r;
  r.name = "synthetic " + std::to_string(seed);
  const Eigen::Index n = 20000;
  r.time_s = Eigen::VectorXd::LinSpaced(n, 0, (n - 1) * 0.5);
  r.temp_c = (15.0 + 35.0 * (r.time_s.array() * (2 * M_PI / 10000.0) + phase).sin()).matrix();
  r.rate_rad_s.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double d = r.temp_c[i] - 25.0;
    r.rate_rad_s[i] = truth[0] + truth[1] * d + truth[2] * d * d + noise(rng);
  }
  return r;
}

const std::vector<double> kTruth{2e-3, -4e-5, 6e-7};

TEST(FitCalibration, RecoversAPolynomialBiasFromANoisyRecordOfBothDirections) {
  // degC: the valid range is the extremes of the 10-s bin means, just inside the sine's -20 / 50
  // peaks (measured 2e-4).
  constexpr double kRangeEdge = 0.01;
  const CalibrationModel m = fit_calibration({synthetic_record(11, kTruth, 0.0)}, FitOptions{});
  EXPECT_GE(m.order(), 2);
  for (int i = 0; i <= 2; ++i)
    EXPECT_NEAR(m.bias_rad_s[i], kTruth[i], kSigmas * m.bias_sigma_rad_s[i] + kSigmaFloor) << i;
  EXPECT_NEAR(m.valid_min_c, -20.0, kRangeEdge);
  EXPECT_NEAR(m.valid_max_c, 50.0, kRangeEdge);
}

TEST(FitCalibration, CombinesSeveralRecordsOfOneGyro) {
  const CalibrationModel one = fit_calibration({synthetic_record(11, kTruth, 0.0)}, FitOptions{});
  const CalibrationModel two =
      fit_calibration({synthetic_record(11, kTruth, 0.0), synthetic_record(12, kTruth, 1.0)}, FitOptions{});
  EXPECT_EQ(two.fit.records.size(), 2u);
  EXPECT_EQ(two.fit.samples, 2 * one.fit.samples);
  for (int i = 0; i <= 2; ++i)
    EXPECT_NEAR(two.bias_rad_s[i], kTruth[i], kSigmas * two.bias_sigma_rad_s[i] + kSigmaFloor) << i;
  EXPECT_EQ(two.fit.holdout_blocks, one.fit.holdout_blocks) << "each record is cut into its own held-out blocks";
}

TEST(FitCalibration, FitsTheScaleFactorWhenTheTrueRateVaries) {
  // Rate table: +-0.5 rad/s square steps; scale factor 1 + 2e-3 + 5e-5 (T - 25).
  Record r = synthetic_record(13, kTruth, 0.0);
  r.true_rate_rad_s.resize(r.time_s.size());
  for (Eigen::Index i = 0; i < r.time_s.size(); ++i) {
    const double w = (static_cast<long>(r.time_s[i] / 37.0) % 2 ? 0.5 : -0.5);
    r.true_rate_rad_s[i] = w;
    r.rate_rad_s[i] += w * (1.0 + 2e-3 + 5e-5 * (r.temp_c[i] - 25.0));
  }
  const CalibrationModel m = fit_calibration({r}, FitOptions{});
  ASSERT_TRUE(m.fit.scale_factor_fitted);
  ASSERT_GE(m.scale_factor_per_k.size(), 2u);
  constexpr double kNoise = 2e-5;  // 1/K: 1e-3 rad/s noise on +-0.5 rad/s over 20 000 samples
  EXPECT_NEAR(m.scale_factor_per_k[0], 2e-3, 10 * kNoise);
  EXPECT_NEAR(m.scale_factor_per_k[1], 5e-5, kNoise);
  const auto out = compensate(m, r.time_s, r.rate_rad_s, r.temp_c);
  EXPECT_LT(evaluation::block_mean_rms(r.time_s, out.rate_rad_s - r.true_rate_rad_s), 1e-4);
}

}  // namespace
}  // namespace driftlab::calibration
