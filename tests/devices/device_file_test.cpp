#include "devices/device_file.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "devices/device_file_update.hpp"
#include "framework/units.hpp"

namespace driftlab::devices {
namespace {

const std::string kDevices = std::string(DRIFTLAB_SOURCE_DIR) + "/devices/";
const std::string kFixtures = std::string(DRIFTLAB_TEST_DATA) + "/devices/";
constexpr double kDph = kRadPerSecPerDph;
// A decimal from the file through a unit factor (or the up direction normalised): rounding only.
// Absolute: a few ulps of the O(1) values (0.6, 0.8), many ulps of the 1e-5 .. 1e-2 ones (measured: 0
// or below 5e-19).
constexpr double kConverted = 1e-15;

TEST(DeviceFile, LoadsTheFmvmgWithThePapersNumbers) {
  constexpr double kRoundTrip = 1e-9;  // deg/h: converted to rad/s on loading and back here
  const DeviceDefinition d = load_device_file(kDevices + "fmvmg.yaml");
  EXPECT_EQ(d.name, "fmvmg");
  EXPECT_DOUBLE_EQ(d.physics.drive.frequency_hz, 30740.0);
  EXPECT_DOUBLE_EQ(d.physics.sense.frequency_hz, 30886.0);
  EXPECT_DOUBLE_EQ(d.physics.structure.youngs_modulus_pa, 169e9);
  EXPECT_DOUBLE_EQ(d.physics.structure.poisson_ratio, 0.27);
  EXPECT_DOUBLE_EQ(d.physics.structure.density_kg_m3, 2328.3);
  EXPECT_NEAR(d.physics.structure.length_m, 3015e-6, kConverted);
  EXPECT_NEAR(d.physics.structure.width_m, 2331e-6, kConverted);
  EXPECT_NEAR(d.physics.structure.thickness_m, 60e-6, kConverted);
  EXPECT_THAT(d.notes, ::testing::HasSubstr("5.8 Hz"));
  ASSERT_NE(d.find_channel("rate"), nullptr);
  ASSERT_NE(d.find_channel("temperature"), nullptr);
  ASSERT_NE(d.find_channel("drive_frequency"), nullptr);
  EXPECT_NEAR(d.error_model.noise.arw_rad_sqrt_s / kDph, 99.6, kRoundTrip);
  // The paper's raw B (34.66) is the temperature-driven bias; the intrinsic B stays well below the
  // compensated 3.589 (devices/fmvmg.yaml explains both).
  EXPECT_NEAR(d.error_model.noise.bias_instability_rad_s / kDph, 1.0, kRoundTrip);
  EXPECT_FALSE(d.error_model.effects.any());
}

TEST(DeviceFile, LoadsEveryShippedDevice) {
  const auto files = list_device_files(kDevices);
  ASSERT_GE(files.size(), 2u);
  for (const auto& f : files) EXPECT_NO_THROW(load_device_file(f)) << f;
}

TEST(DeviceFile, LoadsTheWholeImuWithBothInstancesInInternalUnits) {
  constexpr double kMilliG = 1e-3 * kStandardGravity, kMicroG = 1e-6 * kStandardGravity;
  constexpr double kPpm = 1e-18;  // 150 ppm from the file's ppm: the same roundings on a 1.5e-4 value
  const DeviceDefinition d = load_device_file(kDevices + "imu3.yaml");
  ASSERT_TRUE(d.imu.has_value());
  EXPECT_TRUE(d.channels.empty());
  const ImuDefinition& imu = *d.imu;
  EXPECT_EQ(imu.reference_temp_c, 25.0);
  EXPECT_EQ(imu.up, Eigen::Vector3d(0.0, 0.0, 1.0));
  ASSERT_EQ(imu.instances.size(), 2u);
  const ImuInstance& first = imu.instances[0];
  EXPECT_FALSE(first.device_id.has_value());
  EXPECT_EQ(first.die_time_constant_s, 240.0);
  EXPECT_NEAR(first.gyro.axes[0].bias_polynomial.at(1), 0.021 * kRadPerDeg, kConverted);
  EXPECT_NEAR(first.gyro.axes[1].noise.arw_rad_sqrt_s, 14.4 * kDph, kConverted);  // the sensor's noise
  EXPECT_EQ(first.gyro.axes[2].lag_s, 20.0);
  EXPECT_NEAR(first.accel.axes[2].bias_polynomial.at(1), 0.8 * kMilliG, kConverted);
  EXPECT_NEAR(first.accel.axes[0].noise.arw_rad_sqrt_s, 100 * kMicroG, kConverted);
  EXPECT_NEAR(first.accel.axes[0].noise.rate_random_walk_rad_s_sqrt_s, 100 * kMicroG / 60.0, kConverted);
  EXPECT_NEAR(first.accel.axes[0].scale_factor_polynomial.at(0), 150e-6, kPpm);
  EXPECT_EQ(imu.instances[1].temperature_resolution_c, 0.125);
}

TEST(DeviceFile, AnImuAxisMayReplaceItsSensorsNoiseAndAnInstanceMayNameItsDevice) {
  const std::string text = R"(format: driftlab-device/1
identity: {name: tilted}
imu:
  up_direction: [0, 3, 4]
  instances:
    - device_id: 2490378
      gyro:
        noise: {arw_dph_rthz: 10}
        x: {bias_polynomial_dps: [0]}
        y: {bias_polynomial_dps: [0], noise: {arw_dph_rthz: 2}}
        z: {bias_polynomial_dps: [0]}
      accel: {x: {bias_polynomial_mg: [0]}, y: {bias_polynomial_mg: [0]}, z: {bias_polynomial_mg: [0]}}
)";
  const DeviceDefinition d = parse_device(text, "inline.yaml");
  const ImuInstance& instance = d.imu->instances.at(0);
  EXPECT_EQ(instance.device_id, 2490378.0);
  EXPECT_NEAR(instance.gyro.axes[0].noise.arw_rad_sqrt_s, 10 * kDph, kConverted);
  EXPECT_NEAR(instance.gyro.axes[1].noise.arw_rad_sqrt_s, 2 * kDph, kConverted);
  EXPECT_NEAR(d.imu->up[1], 0.6, kConverted);  // normalized
  EXPECT_NEAR(d.imu->up[2], 0.8, kConverted);
}

TEST(DeviceFile, ConvertsChannelUnitsToInternalUnits) {
  constexpr double kRange = 1e-12;  // rad/s: 125 deg/s converted, the same roundings on a 2.2-rad/s value
  const DeviceDefinition d = load_device_file(kDevices + "lsm6dsm.yaml");
  const ChannelSpec* rate = d.find_channel("rate");
  ASSERT_NE(rate, nullptr);
  EXPECT_NEAR(rate->range_max, 125.0 * kRadPerDeg, kRange);
  EXPECT_NEAR(rate->resolution, 0.004375 * kRadPerDeg, kConverted);
  EXPECT_NEAR(d.error_model.bias_polynomial_rad_s.at(1), 0.0299 * kRadPerDeg, kConverted);
}

TEST(DeviceFile, Lsm6dsmBiasModelMatchesTheMeasuredCoolingRun) {
  // Real data: per-burst means of the PAN thermal-vacuum run (x axis, rad/s, on-die temperature).
  constexpr double kTolerance = 3e-4;  // rad/s: twice the worst burst off the best straight line (1.4e-4)
  const std::string path = std::string(DRIFTLAB_SHARED_DATA) + "/real/pan-lsm6dsm-tvac/tvac_lsm6dsm_burst_means.csv";
  std::ifstream in(path);
  if (!in) GTEST_SKIP() << "shared data not found: " << path;
  const DeviceDefinition d = load_device_file(kDevices + "lsm6dsm.yaml");
  const DeviceModel model(d.physics);
  std::string line;
  std::getline(in, line);
  int bursts = 0;
  while (std::getline(in, line)) {
    std::vector<double> cells;
    std::stringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) cells.push_back(std::stod(cell));
    const double temp = cells.at(4), measured = cells.at(5);
    const double predicted = error_model::systematic_rate(d.error_model, model.response(temp), temp, 0.0);
    EXPECT_NEAR(predicted, measured, kTolerance) << "burst " << cells.at(0) << " at " << temp << " degC";
    ++bursts;
  }
  EXPECT_EQ(bursts, 25);
}

TEST(DeviceFile, AcceptsTheMinimalFixture) {
  const DeviceDefinition d = load_device_file(kFixtures + "valid_minimal.yaml");
  EXPECT_EQ(d.name, "minimal");
  EXPECT_DOUBLE_EQ(d.physics.drive.frequency_tc_per_k, -30e-6);  // TCE / 2 by default
}

TEST(DeviceFile, ReadsTheEffectsSectionAndTheCommandLineFormAlike) {
  const std::string text =
      "format: driftlab-device/1\nidentity: {name: x}\n"
      "structure: {youngs_modulus_gpa: 169, poisson_ratio: 0.27, density_kg_m3: 2330, length_um: 3000,"
      " width_um: 2300, thickness_um: 60, proof_mass_area_fraction: 0.3}\n"
      "modes: {drive: {frequency_hz: 30740, quality_factor: 8000}, sense: {frequency_hz: 30886, quality_factor: "
      "2500}}\n"
      "electronics: {drive_amplitude_um: 5}\n"
      "channels: [{name: r, role: rate, unit: deg/s, range: [-10, 10]}, {name: t, role: temperature, unit: degC}]\n"
      "effects: {hysteresis: {height_dph: 30, width_c: 3}, scale_factor_temperature: {coefficients_ppm: [100, 2]}}\n";
  const DeviceDefinition d = parse_device(text, "inline.yaml");
  error_model::Effects from_option;
  apply_effect_option("hysteresis:height_dph=30,width_c=3", from_option);
  apply_effect_option("scale_factor_temperature:coefficients_ppm=[100, 2]", from_option);
  ASSERT_TRUE(d.error_model.effects.hysteresis && from_option.hysteresis);
  EXPECT_DOUBLE_EQ(d.error_model.effects.hysteresis->height_rad_s, 30 * kDph);
  EXPECT_DOUBLE_EQ(from_option.hysteresis->height_rad_s, 30 * kDph);
  EXPECT_DOUBLE_EQ(from_option.hysteresis->width_k, 3.0);
  ASSERT_TRUE(from_option.scale_factor_temperature);
  EXPECT_EQ(from_option.scale_factor_temperature->coefficients_per_k,
            d.error_model.effects.scale_factor_temperature->coefficients_per_k);
  EXPECT_EQ(describe_effects(from_option), describe_effects(d.error_model.effects));
}

TEST(DeviceFile, ReadsGaussMarkovNoiseTermsAndNamesABadOne) {
  const std::string head =
      "format: driftlab-device/1\nidentity: {name: x}\n"
      "structure: {youngs_modulus_gpa: 169, poisson_ratio: 0.27, density_kg_m3: 2330, length_um: 3000,"
      " width_um: 2300, thickness_um: 60, proof_mass_area_fraction: 0.3}\n"
      "modes: {drive: {frequency_hz: 30740, quality_factor: 8000}, sense: {frequency_hz: 30886, quality_factor: "
      "2500}}\n"
      "electronics: {drive_amplitude_um: 5}\n"
      "channels: [{name: r, role: rate, unit: deg/s, range: [-10, 10]}, {name: t, role: temperature, unit: degC}]\n";
  const DeviceDefinition d = parse_device(head +
                                              "error_model:\n  noise: {arw_dph_rthz: 10, gauss_markov: [{sigma_dph: "
                                              "20, tau_s: 200}, {sigma_dph: 5, tau_s: 30}]}\n",
                                          "inline.yaml");
  const auto& gm = d.error_model.noise.gauss_markov;
  ASSERT_EQ(gm.size(), 2u);
  EXPECT_DOUBLE_EQ(gm[0].sigma_rad_s, 20 * kDph);
  EXPECT_DOUBLE_EQ(gm[0].tau_s, 200.0);
  EXPECT_EQ(error_model::gauss_markov_components(d.error_model.noise).size(), 2u) << "no flicker: B is 0";
  try {
    parse_device(head + "error_model:\n  noise: {gauss_markov: [{sigma_dph: 20, tau_s: -1}]}\n", "bad.yaml");
    FAIL() << "a negative correlation time was accepted";
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("error_model.noise.gauss_markov[0].tau_s"));
  }
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

const std::vector<NamedEffect> kNamed{{"thermal_lag", {{"tau_s", "s", {300.25}}}},
                                      {"hysteresis", {{"height_dph", "deg/h", {214.5}}, {"width_c", "degC", {2.5}}}}};

TEST(DeviceFileUpdate, AppendsAnEffectsSectionAndKeepsEveryOriginalLine) {
  const std::string original = read_text(kFixtures + "valid_minimal.yaml") + "# a closing comment\n";
  const std::string updated = add_effects_to_device_text(original, "new.yaml", kNamed, "named by a test");
  EXPECT_EQ(updated.substr(0, original.size()), original);  // the original, byte for byte, then the section
  EXPECT_THAT(updated.substr(original.size()),
              ::testing::HasSubstr("# named by a test\neffects:\n  thermal_lag: {tau_s: 300.25}\n"
                                   "  hysteresis: {height_dph: 214.5, width_c: 2.5}\n"));
  const auto d = parse_device(updated, "new.yaml");
  ASSERT_TRUE(d.error_model.effects.thermal_lag && d.error_model.effects.hysteresis);
  EXPECT_DOUBLE_EQ(d.error_model.effects.hysteresis->height_rad_s, 214.5 * kDph);
}

TEST(DeviceFileUpdate, ReplacesAListedEffectInPlaceAndKeepsTheOthersAndTheComments) {
  const std::string original = read_text(kFixtures + "valid_minimal.yaml") +
                               "effects:   # measured in 2025\n"
                               "  # the lag of the old mount\n"
                               "  thermal_lag:\n"
                               "    tau_s: 100\n"
                               "  periodic_disturbance: {amplitude_dph: 50, period_s: 600, phase_deg: 0}\n"
                               "# trailer\n";
  const std::string updated = add_effects_to_device_text(original, "new.yaml", kNamed, "");
  EXPECT_THAT(updated, ::testing::HasSubstr("effects:   # measured in 2025\n  # the lag of the old mount\n"
                                            "  thermal_lag: {tau_s: 300.25}\n"
                                            "  periodic_disturbance: {amplitude_dph: 50, period_s: 600, phase_deg: 0}\n"
                                            "  hysteresis: {height_dph: 214.5, width_c: 2.5}\n# trailer\n"));
  const auto d = parse_device(updated, "new.yaml");
  EXPECT_DOUBLE_EQ(d.error_model.effects.thermal_lag->tau_s, 300.25);
  EXPECT_TRUE(d.error_model.effects.periodic_disturbance);

  const std::string flow = read_text(kFixtures + "valid_minimal.yaml") +
                           "effects: {thermal_lag: {tau_s: 100}, warmup_transient: {amplitude_dph: 20, tau_s: 50}}\n";
  const auto from_flow = parse_device(add_effects_to_device_text(flow, "new.yaml", kNamed, ""), "new.yaml");
  EXPECT_DOUBLE_EQ(from_flow.error_model.effects.thermal_lag->tau_s, 300.25);
  EXPECT_TRUE(from_flow.error_model.effects.warmup_transient && from_flow.error_model.effects.hysteresis);
}

TEST(DeviceFileUpdate, RefusesAnEffectADeviceFileCannotHold) {
  const std::string original = read_text(kFixtures + "valid_minimal.yaml");
  EXPECT_THROW(add_effects_to_device_text(original, "new.yaml", {{"mode_split_drift", {}}}, ""), ConfigError);
  EXPECT_THROW(add_effects_to_device_text(original, "new.yaml", {{"hysteresis", {{"height_dph", "deg/h", {1.0}}}}}, ""),
               ConfigError);
}

TEST(DeviceFile, RejectsAMalformedEffectOption) {
  error_model::Effects effects;
  EXPECT_THROW(apply_effect_option("thermal_lag:tau_s=-3", effects), ConfigError);
  EXPECT_THROW(apply_effect_option("thermal_lag:tau=3", effects), ConfigError);
  EXPECT_THROW(apply_effect_option("no_such_effect:x=1", effects), ConfigError);
  EXPECT_THROW(apply_effect_option("thermal_lag:tau_s", effects), ConfigError);
  EXPECT_FALSE(effects.any());
}

struct MalformedCase {
  std::string file;
  int line;
  std::string field;
  std::string message;
};

class MalformedDeviceFile : public ::testing::TestWithParam<MalformedCase> {};

TEST_P(MalformedDeviceFile, GetsAClearErrorWithFileLineAndKey) {
  const MalformedCase& c = GetParam();
  const std::string path = kFixtures + c.file;
  try {
    load_device_file(path);
    FAIL() << c.file << " was accepted";
  } catch (const ConfigError& e) {
    bool found = false;
    for (const auto& p : e.problems()) {
      EXPECT_EQ(p.where.file, path);
      found |= p.where.line == c.line && p.where.field == c.field && p.message.find(c.message) != std::string::npos;
    }
    EXPECT_TRUE(found) << "expected line " << c.line << ", key '" << c.field << "', message containing '" << c.message
                       << "'; got:\n"
                       << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Fixtures, MalformedDeviceFile,
    ::testing::Values(
        MalformedCase{"yaml_syntax_error.yaml", 23, "", "YAML syntax error"},
        MalformedCase{"wrong_format.yaml", 2, "format", "unsupported format"},
        MalformedCase{"missing_modes.yaml", 2, "modes", "missing required key"},
        MalformedCase{"negative_frequency.yaml", 18, "modes.sense.frequency_hz", "must be > 0"},
        MalformedCase{"density_not_a_number.yaml", 8, "structure.density_kg_m3", "expected a number"},
        MalformedCase{"misspelled_key.yaml", 15, "modes.drive.frequncy_hz", "unknown key"},
        MalformedCase{"misspelled_key.yaml", 15, "modes.drive.frequency_hz", "missing required key"},
        MalformedCase{"rate_channel_in_celsius.yaml", 23, "channels[0].unit", "does not fit role 'rate'"},
        MalformedCase{"missing_rate_channel.yaml", 23, "channels", "no channel with role 'rate'"},
        MalformedCase{"duplicate_role.yaml", 25, "channels[2].role", "already used"},
        MalformedCase{"unknown_effect.yaml", 26, "effects.thermal_lagg", "unknown key"},
        MalformedCase{"effect_missing_parameter.yaml", 26, "effects.hysteresis.width_c", "missing required key"},
        MalformedCase{"beams_longer_than_die.yaml", 13, "structure.suspension", "longer than the die"},
        MalformedCase{"equal_mode_frequencies.yaml", 18, "modes.sense.frequency_hz", "equals the drive frequency"},
        MalformedCase{"inverted_rate_range.yaml", 23, "channels[0].range", "min < max"},
        MalformedCase{"poisson_out_of_range.yaml", 7, "structure.poisson_ratio", "must be in [0, 0.5]"},
        MalformedCase{"imu_malformed.yaml", 6, "imu.up_direction", "expected [x, y, z]"},
        MalformedCase{"imu_malformed.yaml", 9, "imu.instances[0].gyro.noise.arw_dps_rthz", "unknown key"},
        MalformedCase{"imu_malformed.yaml", 15, "imu.instances[0].accel.y.bias_polynomial_mg", "missing required key"},
        MalformedCase{"imu_malformed.yaml", 16, "imu.instances[0].accel.z.lag_s", "must be >= 0"},
        MalformedCase{"imu_with_channels.yaml", 15, "channels", "not used by a whole-IMU device"}),
    [](const ::testing::TestParamInfo<MalformedCase>& param_info) {
      const std::string& file = param_info.param.file;
      std::string name = file.substr(0, file.find('.')) + "_" + std::to_string(param_info.index);
      for (char& ch : name)
        if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
      return name;
    });

TEST(DeviceFile, CollectsEveryProblemBeforeThrowing) {
  try {
    load_device_file(kFixtures + "misspelled_key.yaml");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.problems().size(), 2u);
  }
}

TEST(DeviceFile, NamesAMissingFile) {
  try {
    load_device_file(kFixtures + "no_such_device.yaml");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("no_such_device.yaml"));
  }
}

}  // namespace
}  // namespace driftlab::devices
