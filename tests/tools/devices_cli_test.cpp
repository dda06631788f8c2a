// End-to-end: `driftlab devices list|describe` and `driftlab simulate`.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "framework/csv.hpp"
#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

using ::testing::HasSubstr;
using namespace testing_cli;

const std::string kSource = DRIFTLAB_SOURCE_DIR;

TEST(DevicesCli, ListsTheShippedDevices) {
  const auto r = run_driftlab("devices list");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("fmvmg.yaml"));
  EXPECT_THAT(r.out, HasSubstr("lsm6dsm.yaml"));
}

TEST(DevicesCli, ListsADirectoryGivenByTheEnvironment) {
  const auto r = run_driftlab("devices list", "DRIFTLAB_DEVICES_DIR=" + kSource + "/tests/data/devices");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("valid_minimal.yaml"));
  EXPECT_THAT(r.out, HasSubstr("INVALID"));
}

TEST(DevicesCli, DescribesADeviceByNameWithItsTemperatureTable) {
  const auto r = run_driftlab("devices describe fmvmg");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("30740"));
  EXPECT_THAT(r.out, HasSubstr("split 146 Hz"));
  EXPECT_THAT(r.out, HasSubstr("versus die temperature"));
}

TEST(DevicesCli, AMalformedDeviceExitsTwoNamingFileLineAndKey) {
  const auto r = run_driftlab("devices describe " + kSource + "/tests/data/devices/negative_frequency.yaml");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("negative_frequency.yaml:18: modes.sense.frequency_hz"));
}

TEST(DevicesCli, SimulatesTheContractColumnsReproduciblyWithEffects) {
  const auto dir = scratch_dir("simulate");
  const std::string common = "simulate --device " + kSource + "/devices/fmvmg.yaml --fs 10 --duration 120 --seed 5";
  const auto a = run_driftlab(common + " --out " + (dir / "a.csv").string());
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const auto b = run_driftlab(common + " --out " + (dir / "b.csv").string());
  ASSERT_EQ(b.exit_code, 0) << b.err;
  EXPECT_EQ(read_text(dir / "a.csv"), read_text(dir / "b.csv"));
  const std::string header = read_text(dir / "a.csv").substr(0, 80);
  EXPECT_THAT(header, HasSubstr("t_s,rate_dps,temp_c,true_rate_dps,systematic_dps,die_temp_c,drive_freq_hz"));
  const TimeSeries record = read_csv(dir / "a.csv");
  EXPECT_EQ(record.size(), 1200);
  EXPECT_TRUE(record.has("drive_frequency"));

  const auto c = run_driftlab(common + " --effect thermal_lag:tau_s=400 --out " + (dir / "c.csv").string());
  ASSERT_EQ(c.exit_code, 0) << c.err;
  EXPECT_THAT(c.out, HasSubstr("thermal_lag{tau_s=400}"));
  const auto bad = run_driftlab(common + " --effect thermal_lag:tau_s=-1 --out " + (dir / "d.csv").string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_THAT(bad.err, HasSubstr("tau_s"));
}

TEST(DevicesCli, SimulatesAWholeImuWithEveryChannelInTheImuNames) {
  const auto dir = scratch_dir("simulate_imu");
  const auto r = run_driftlab("simulate --device " + kSource +
                              "/devices/imu3.yaml --profile oven --fs 10 --duration 600 "
                              "--seed 1 --out " +
                              (dir / "x.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::string instance[2];
  for (const std::string i : {"", "1"}) {
    std::string& h = instance[i.empty() ? 0 : 1];
    for (const std::string prefix : {"", "true_", "systematic_"}) {
      for (const char* axis : {"x", "y", "z"}) h += "," + prefix + "gyro" + i + "_" + axis + "_dps";
      for (const char* axis : {"x", "y", "z"}) h += "," + prefix + "accel" + i + "_" + axis + "_mps2";
      if (prefix.empty()) h += ",temp" + i + "_c";
    }
  }
  const std::string text = read_text(dir / "x.csv");
  EXPECT_EQ(text.substr(0, text.find('\n')), "t_s" + instance[0] + instance[1]);
  EXPECT_TRUE(
      text.starts_with("t_s,gyro_x_dps,gyro_y_dps,gyro_z_dps,accel_x_mps2,accel_y_mps2,accel_z_mps2,temp_c,"
                       "true_gyro_x_dps,"));

  // The CSV reader knows every column by its default names.
  const TimeSeries record = read_csv(dir / "x.csv", {.required_roles = {}});
  EXPECT_EQ(record.size(), 6000);
  for (const char* role :
       {"gyro_x", "accel_z", "temperature", "true_gyro_x", "true_accel_z", "systematic_gyro_y", "systematic_accel_z",
        "gyro1_z", "accel1_x", "temperature1", "true_accel1_z", "systematic_accel1_y"})
    EXPECT_TRUE(record.has(role)) << role;
  EXPECT_DOUBLE_EQ(record.channel("true_accel_z").values[0], 9.80665);
  EXPECT_EQ(record.channel("true_accel_x").values[0], 0.0);

  const auto described = run_driftlab("devices describe imu3");
  ASSERT_EQ(described.exit_code, 0) << described.err;
  EXPECT_THAT(described.out, HasSubstr("whole IMU: 2 instance(s)"));
  EXPECT_THAT(described.out, HasSubstr("accel1_z"));
  const auto listed = run_driftlab("devices list");
  EXPECT_THAT(listed.out, HasSubstr("imu3.yaml"));
  EXPECT_THAT(listed.out, ::testing::Not(HasSubstr("INVALID")));
  const auto with_effect = run_driftlab("simulate --device imu3 --duration 60 --effect thermal_lag:tau_s=400 --out " +
                                        (dir / "y.csv").string());
  EXPECT_EQ(with_effect.exit_code, 2);
  EXPECT_THAT(with_effect.err, HasSubstr("whole IMU"));
}

TEST(DevicesCli, SimulatesAProfileFile) {
  // rad/s: through the CSV's deg/s text (shortest round trip) and back, against a 15-digit pi.
  constexpr double kCsvRoundTrip = 1e-9;
  const auto dir = scratch_dir("simulate_profile");
  {
    std::ofstream profile(dir / "table.yaml");
    profile << "format: driftlab-profile/1\nchamber: {start_c: 20, segments: [{to_c: 30, duration_s: 60}]}\n"
               "rate: {start_dps: 0, segments: [{hold_s: 30}, {to_dps: 50, duration_s: 0}, {hold_s: 30}]}\n";
  }
  const auto r = run_driftlab("simulate --device fmvmg --fs 5 --profile " + (dir / "table.yaml").string() + " --out " +
                              (dir / "sim.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const TimeSeries record = read_csv(dir / "sim.csv", {.required_roles = {"rate", "true_rate"}});
  EXPECT_EQ(record.size(), 300);
  EXPECT_NEAR(record.channel("true_rate").values[250], 50.0 * 3.14159265358979 / 180.0, kCsvRoundTrip);
}

}  // namespace
}  // namespace driftlab
