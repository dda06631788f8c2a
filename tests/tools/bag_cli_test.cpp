// `driftlab log info / export` and `driftlab calibrate` on ROS bags, end to end: the listing of
// each fixture (tests/data/logs), the export read back by the CSV reader, calibrate on a bag equal
// to calibrate on the CSV it was written from (by python3-rosbag), exit code 3 for bad bags.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "framework/csv.hpp"
#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;
using namespace testing_cli;

// The same float64 values reach the fit through the CSV reader (deg/s -> rad/s by units.hpp) and
// through python's math.pi / 180: they differ in the last bit, and so may the coefficients.
constexpr double kSameFitTolerance = 1e-9;  // relative

fs::path logs() { return fs::path(DRIFTLAB_TEST_DATA) / "logs"; }
std::string fixture(const std::string& name) { return (logs() / name).string(); }

TEST(BagCli, InfoListsTopicsInstancesAndTemperatureOfEachFixture) {
  const auto ros1 = run_driftlab("log info " + fixture("ros1-robot-localization/test2.bag"));
  ASSERT_EQ(ros1.exit_code, 0) << ros1.err;
  EXPECT_THAT(
      ros1.out,
      AllOf(HasSubstr("ROS 1 bag v2.0, 533743 bytes"), HasSubstr("messages: 6121, 47.580 to 108.781 s"),
            HasSubstr("/imu/data                            sensor_msgs/Imu"), HasSubstr("instance 0: /imu/data"),
            HasSubstr("gyro:  3061 samples at 50.0 Hz, 47.580 to 108.780 s"),
            HasSubstr("temperature: no topic pairs with it")));

  const auto mcap = run_driftlab("log info " + fixture("ros2-robot-localization/imu_zstd.mcap"));
  ASSERT_EQ(mcap.exit_code, 0) << mcap.err;
  EXPECT_THAT(
      mcap.out,
      AllOf(
          HasSubstr("MCAP (profile ros2, zstd chunks, summary)"), HasSubstr("sensor_msgs/msg/Imu"),
          HasSubstr("cdr           3061      50.0"),
          HasSubstr("temperature: /imu/temperature, 307 samples at 5.0 Hz, 47.580 to 108.780 s, 20.00 to 35.30 degC")));

  const auto db3 = run_driftlab("log info " + fixture("ros2-robot-localization/imu_db3"));
  ASSERT_EQ(db3.exit_code, 0) << db3.err;
  EXPECT_THAT(db3.out,
              AllOf(HasSubstr("rosbag2 directory, sqlite3 storage (1 file)"), HasSubstr("20.00 to 22.45 degC")));

  const auto talker = run_driftlab("log info " + fixture("ros2-rosbag2/talker-mcap"));
  ASSERT_EQ(talker.exit_code, 0) << talker.err;
  EXPECT_THAT(talker.out, AllOf(HasSubstr("/parameter_events"), HasSubstr("std_msgs/msg/String"),
                                HasSubstr("IMU: no sensor_msgs/Imu topic")));
}

// rosbag2's own bags sit in a directory named after the bag: "cdr_test_0.db3" -> "cdr_test-sqlite3".
std::string bag_directory(const std::string& file, const std::string& storage) {
  std::string stem = fs::path(file).stem().string();
  if (stem.ends_with("_0")) stem.resize(stem.size() - 2);
  return stem + "-" + storage;
}

// Every ROS 2 bag fixture is listed, with the message total the independent readers counted
// (@mcap/core for the MCAP files, the sqlite3 CLI for the db3 files: reference_*.json).
TEST(BagCli, InfoListsEveryRos2FixtureWithTheIndependentReadersMessageTotal) {
  int listed = 0;
  for (const char* folder : {"ros2-robot-localization", "ros2-rosbag2"}) {
    const auto mcap = nlohmann::json::parse(read_text(logs() / folder / "reference_mcap.json"));
    for (const auto& [file, entry] : mcap.items()) {
      std::size_t total = 0;
      for (const auto& [topic, t] : entry["topics"].items()) total += t["count"].get<std::size_t>();
      fs::path path = logs() / folder / file;
      if (!fs::exists(path)) path = logs() / folder / bag_directory(file, "mcap") / file;
      SCOPED_TRACE(path.string());
      const auto r = run_driftlab("log info " + path.string());
      ASSERT_EQ(r.exit_code, 0) << r.err;
      EXPECT_THAT(r.out, AllOf(HasSubstr("MCAP"), HasSubstr("messages: " + std::to_string(total) + ",")));
      ++listed;
    }
  }
  const auto rl_db3 = nlohmann::json::parse(read_text(logs() / "ros2-robot-localization" / "reference_db3.json"));
  std::size_t total = 0;
  for (const auto& t : rl_db3) total += t["count"].get<std::size_t>();
  const auto db3 = run_driftlab("log info " + fixture("ros2-robot-localization/imu_db3"));
  ASSERT_EQ(db3.exit_code, 0) << db3.err;
  EXPECT_THAT(db3.out, HasSubstr("messages: " + std::to_string(total) + ","));
  const auto rosbag2_db3 = nlohmann::json::parse(read_text(logs() / "ros2-rosbag2" / "reference_db3.json"));
  for (const auto& [file, topics] : rosbag2_db3.items()) {
    std::size_t n = 0;
    for (const auto& t : topics) n += t["count"].get<std::size_t>();
    const std::string dir = bag_directory(file, "sqlite3");
    SCOPED_TRACE(dir);
    const auto r = run_driftlab("log info " + fixture("ros2-rosbag2/" + dir));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_THAT(r.out, AllOf(HasSubstr("sqlite3 storage"), HasSubstr("messages: " + std::to_string(n) + ",")));
    ++listed;
  }
  const auto zstd_messages = run_driftlab("log info " + fixture("ros2-robot-localization/imu_db3_zstd_messages"));
  ASSERT_EQ(zstd_messages.exit_code, 0) << zstd_messages.err;
  EXPECT_THAT(zstd_messages.out, HasSubstr("messages zstd-compressed"));
  EXPECT_EQ(listed, 10);  // 6 Jackal MCAP files, rosbag2's talker and cdr_test in MCAP and in sqlite3
}

TEST(BagCli, ExportWritesTheImuRecordTheCsvReaderReadsBack) {
  const auto dir = scratch_dir("bag_export");
  const auto r = run_driftlab("log export " + fixture("ros2-robot-localization/imu_zstd.mcap") + " --out " +
                              (dir / "imu.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("3061 samples, 7 channels"));
  CsvReadOptions options;
  options.required_roles = {"gyro_z", "accel_z", "temperature"};
  const auto record = read_csv(dir / "imu.csv", options);
  ASSERT_EQ(record.size(), 3061);
  EXPECT_EQ(record.time()[0], 47.58);
  EXPECT_EQ(record.channel("gyro_z").values[0], 0.04275138193045083);
  EXPECT_EQ(record.channel("accel_z").values[3060], 9.806229082013386);
  EXPECT_DOUBLE_EQ(record.channel("temperature").values[3060], 35.3);
}

TEST(BagCli, CalibrateOnABagFitsWhatCalibrateOnItsCsvFits) {
  const auto dir = scratch_dir("bag_calibrate");
  const std::string csv = (dir / "imu3.csv").string(), bag = (dir / "imu3.bag").string();
  const auto s = run_driftlab("simulate --device " + std::string(DRIFTLAB_SOURCE_DIR) +
                              "/devices/imu3.yaml --fs 1 --seed 1 --out " + csv);
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const int status = std::system(("/usr/bin/python3 " + std::string(DRIFTLAB_SOURCE_DIR) +
                                  "/tests/framework/write_ros1_bags.py from-csv " + csv + " " + bag + " 2>/dev/null")
                                     .c_str());
  if (WIFEXITED(status) && WEXITSTATUS(status) == 77)
    GTEST_SKIP() << "python3-rosbag or python3-sensor-msgs is not installed";
  ASSERT_EQ(status, 0);

  const auto from_csv =
      run_driftlab("-q calibrate --data " + csv + " --channels gyro --out " + (dir / "csv.json").string());
  ASSERT_EQ(from_csv.exit_code, 0) << from_csv.err;
  const auto from_bag =
      run_driftlab("-q calibrate --data " + bag + " --channels gyro --out " + (dir / "bag.json").string());
  ASSERT_EQ(from_bag.exit_code, 0) << from_bag.err;
  const auto a = nlohmann::json::parse(read_text(dir / "csv.json"));
  const auto b = nlohmann::json::parse(read_text(dir / "bag.json"));
  ASSERT_EQ(a["channels"].size(), 6u);
  ASSERT_EQ(b["channels"].size(), 6u);
  for (std::size_t i = 0; i < 6; ++i) {
    const auto& ca = a["channels"][i];
    const auto& cb = b["channels"][i];
    SCOPED_TRACE(ca["role"].get<std::string>());
    EXPECT_EQ(ca["role"], cb["role"]);
    EXPECT_EQ(cb["temperature_column"], cb["instance"] == 0 ? "/imu0/temperature" : "/imu1/temperature");
    const auto& pa = ca["model"]["bias"]["polynomial_rad_s_per_k_i"];
    const auto& pb = cb["model"]["bias"]["polynomial_rad_s_per_k_i"];
    ASSERT_EQ(pa.size(), pb.size());
    for (std::size_t k = 0; k < pa.size(); ++k)
      EXPECT_NEAR(pb[k].get<double>(), pa[k].get<double>(), kSameFitTolerance * std::abs(pa[k].get<double>())) << k;
  }

  // A ROS 2 bag too (61 s of a driving robot with a synthetic temperature: the path, not the fit;
  // --force, since a driving robot's model need not beat no model on held-out blocks).
  const auto ros2 = run_driftlab("-q calibrate --data " + fixture("ros2-robot-localization/imu_zstd.mcap") +
                                 " --channels gyro --bin 1 --blocks 4 --force --out " + (dir / "ros2.json").string());
  ASSERT_EQ(ros2.exit_code, 0) << ros2.err;
  EXPECT_EQ(nlohmann::json::parse(read_text(dir / "ros2.json"))["channels"].size(), 3u);
}

TEST(BagCli, BadBagsExitWithThreeNamingFileAndPlace) {
  const auto dir = scratch_dir("bag_bad");
  const std::string good = read_text(logs() / "ros2-robot-localization" / "imu_lz4.mcap");
  std::ofstream(dir / "cut.mcap", std::ios::binary) << good.substr(0, good.size() / 2);
  fs::create_directories(dir / "empty_dir");
  for (const auto& args :
       {"log info " + (dir / "cut.mcap").string(),
        "log export " + (dir / "cut.mcap").string() + " --out " + (dir / "x.csv").string(),
        "allan --data " + (dir / "cut.mcap").string() + " --column rate=gyro_z --out " + (dir / "x.csv").string()}) {
    SCOPED_TRACE(args);
    const auto r = run_driftlab(args);
    EXPECT_EQ(r.exit_code, 3);
    EXPECT_THAT(r.err, AllOf(HasSubstr("cut.mcap: byte "), Not(HasSubstr("failed"))));
    EXPECT_FALSE(fs::exists(dir / "x.csv"));
  }
  const auto topic = run_driftlab("log export " + fixture("ros1-robot-localization/test2.bag") +
                                  " --topic /imu --out " + (dir / "x.csv").string());
  EXPECT_EQ(topic.exit_code, 3);
  EXPECT_THAT(topic.err, HasSubstr("topic '/imu' is not in the bag (IMU topics it has: /imu/data)"));
  const auto not_a_bag = run_driftlab("log info " + (dir / "empty_dir").string());
  EXPECT_EQ(not_a_bag.exit_code, 3);
  EXPECT_THAT(not_a_bag.err, HasSubstr("is a directory; expected a regular file"));
}

}  // namespace
}  // namespace driftlab
