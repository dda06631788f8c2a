// `driftlab log info / export` and the record-reading commands on PX4 ULogs and ArduPilot DataFlash
// logs, end to end: exit codes (3 for a bad log), messages naming file and byte offset, the export
// read back by the CSV reader; calibrate, compensate and allan reading a .bin directly.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "framework/csv.hpp"
#include "tests/framework/dataflash_writer.hpp"
#include "tests/framework/ulog_writer.hpp"
#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;
using namespace testing_cli;
using testing_ulog::Writer;

fs::path pyulog_dir() { return fs::path(DRIFTLAB_SHARED_DATA) / "logs" / "px4-pyulog"; }

void write(const fs::path& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

// Two gyro instances at 100 Hz, instance 1 offset by 3 ms, temperatures 30 and 31 degC rising.
std::string two_gyros(int samples) {
  Writer w;
  w.flag_bits().format(testing_ulog::kSensorGyroFormat).add(0, 1, "sensor_gyro").add(1, 2, "sensor_gyro");
  for (int i = 0; i < samples; ++i) {
    const auto t = static_cast<std::uint64_t>(1000000 + 10000 * i);
    const float s = 0.01f * static_cast<float>(i % 7);
    w.data(1, testing_ulog::sensor_gyro(t, 11, s, -s, 0.5f * s, 30.f + 0.01f * static_cast<float>(i)));
    w.data(2, testing_ulog::sensor_gyro(t + 3000, 22, -s, s, s, 31.f + 0.01f * static_cast<float>(i)));
  }
  return w.bytes();
}

class LogCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = scratch_dir(::testing::UnitTest::GetInstance()->current_test_info()->name());
    write(dir_ / "gyros.ulg", two_gyros(400));
  }
  std::string p(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

TEST_F(LogCli, InfoListsTopicsInstancesTemperaturesAndDeviceIds) {
  const auto r = run_driftlab("log info " + p("gyros.ulg"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, AllOf(HasSubstr("PX4 ULog version 1"), HasSubstr("sensor_gyro"), HasSubstr("instance 1:"),
                           HasSubstr("device_id 22 (0x16), 400 messages at 100.0 Hz, 31.00 to 34.99 degC")));
}

TEST_F(LogCli, ExportWritesTheImuRecordTheCsvReaderReadsBack) {
  const auto r = run_driftlab("log export " + p("gyros.ulg") + " --out " + p("imu.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.err, HasSubstr("time base: sensor_gyro multi_id 0"));
  CsvReadOptions options;
  options.required_roles = {"gyro_z", "gyro1_z", "temperature", "temperature1"};
  const auto record = read_csv(p("imu.csv"), options);
  EXPECT_EQ(record.size(), 400 - 1);  // the first base sample (1.000 s) lies before instance 1's first (1.003 s)
  EXPECT_EQ(record.time()[0], 1.01);
  EXPECT_EQ(record.device_id(0), "11");
  EXPECT_EQ(record.device_id(1), "22");
  EXPECT_EQ(record.channel("gyro_z").unit, "rad/s");
  // Temperatures are logged as float32 (spacing 1.9e-6 degC near 30 degC) and written with 6
  // decimals; instance 1's is interpolated onto the base time stamps.
  constexpr double kFloatTemperatureTolerance = 1e-6;         // degC: a stored float32 value
  constexpr double kInterpolatedTemperatureTolerance = 1e-5;  // degC: between two such values
  EXPECT_NEAR(record.channel("temperature").values[0], 30.01, kFloatTemperatureTolerance);
  EXPECT_NEAR(record.channel("temperature1").values[0], 31.007,
              kInterpolatedTemperatureTolerance);  // 31.00 at 1.003 s, 31.01 at 1.013 s

  const auto one = run_driftlab("log export " + p("gyros.ulg") + " --instance 1 --out " + p("one.csv"));
  ASSERT_EQ(one.exit_code, 0) << one.err;
  EXPECT_THAT(read_text(p("one.csv")).substr(0, 60),
              HasSubstr("t_s,gyro1_x_rad_s,gyro1_y_rad_s,gyro1_z_rad_s,temp1_c"));
}

TEST_F(LogCli, RecordCommandsReadALogWithAColumnMapping) {
  const auto r = run_driftlab("allan --data " + p("gyros.ulg") + " --column rate=gyro1_z --out " + p("a.csv"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const auto no_rate = run_driftlab("allan --data " + p("gyros.ulg") + " --out " + p("b.csv"));
  EXPECT_EQ(no_rate.exit_code, 3);
  EXPECT_THAT(no_rate.err, HasSubstr("--column rate=gyro_z"));
  EXPECT_FALSE(fs::exists(p("b.csv")));
}

// calibrate reads a ULog directly: the two gyros of a simulated imu3 oven run (16 200 samples at
// 1 Hz, temperatures and device ids) written as sensor_gyro multi_id 0 and 1 fit the models that
// calibrate fits on the log's CSV export (the same float32 values), with the device ids.
TEST(LogCliUlog, CalibrateOnAUlogFitsWhatItFitsOnTheLogsExport) {
  const auto dir = scratch_dir("log_cli_ulog_calibrate");
  const auto sim = dir / "imu3.csv";
  const auto s = run_driftlab("simulate --device " + std::string(DRIFTLAB_SOURCE_DIR) +
                              "/devices/imu3.yaml --fs 1 --seed 1 --out " + sim.string());
  ASSERT_EQ(s.exit_code, 0) << s.err;
  CsvReadOptions options;
  options.required_roles = {"gyro_x", "gyro1_x", "temperature", "temperature1"};
  const TimeSeries record = read_csv(sim, options);
  Writer w;
  w.flag_bits().format(testing_ulog::kSensorGyroFormat).add(0, 1, "sensor_gyro").add(1, 2, "sensor_gyro");
  for (Eigen::Index i = 0; i < record.size(); ++i) {
    const auto t = static_cast<std::uint64_t>(std::llround(1e6 + record.time()[i] * 1e6));
    for (int instance = 0; instance < 2; ++instance) {
      const std::string n = instance == 0 ? "" : "1";
      auto v = [&](const std::string& role) { return static_cast<float>(record.channel(role).values[i]); };
      w.data(static_cast<std::uint16_t>(instance + 1),
             testing_ulog::sensor_gyro(t + 3000 * static_cast<std::uint64_t>(instance),
                                       instance == 0 ? 2424842u : 2490378u, v("gyro" + n + "_x"), v("gyro" + n + "_y"),
                                       v("gyro" + n + "_z"), v("temperature" + n)));
    }
  }
  const auto ulg = (dir / "oven.ulg").string();
  write(ulg, w.bytes());

  const auto from_ulg = run_driftlab("-q calibrate --data " + ulg + " --out " + (dir / "ulg.json").string());
  ASSERT_EQ(from_ulg.exit_code, 0) << from_ulg.err;
  EXPECT_THAT(from_ulg.out, HasSubstr("6 channels"));
  const auto exported = run_driftlab("log export " + ulg + " --out " + (dir / "export.csv").string());
  ASSERT_EQ(exported.exit_code, 0) << exported.err;
  const auto from_csv =
      run_driftlab("-q calibrate --data " + (dir / "export.csv").string() + " --out " + (dir / "csv.json").string());
  ASSERT_EQ(from_csv.exit_code, 0) << from_csv.err;
  auto a = nlohmann::json::parse(read_text(dir / "ulg.json")), b = nlohmann::json::parse(read_text(dir / "csv.json"));
  ASSERT_EQ(a["channels"].size(), 6u);
  ASSERT_EQ(b["channels"].size(), 6u);
  for (std::size_t i = 0; i < 6; ++i) {
    SCOPED_TRACE(a["channels"][i]["role"].get<std::string>());
    EXPECT_EQ(a["channels"][i]["role"], b["channels"][i]["role"]);
    EXPECT_EQ(a["channels"][i]["device_id"], a["channels"][i]["instance"] == 0 ? "2424842" : "2490378");
    auto& ma = a["channels"][i]["model"];
    auto& mb = b["channels"][i]["model"];
    ma["fit"].erase("records");  // the file each was fitted on
    mb["fit"].erase("records");
    EXPECT_EQ(ma, mb);
  }
  fs::remove_all(dir);
}

TEST_F(LogCli, BadLogsExitWithThreeNamingFileAndOffset) {
  const std::string good = two_gyros(50);
  write(dir_ / "cut.ulg", good.substr(0, good.size() - 5));
  write(dir_ / "unknown.ulg", Writer().flag_bits().message('Z', "??").bytes());
  for (const auto& args :
       {"log info " + p("cut.ulg"), "log export " + p("cut.ulg") + " --out " + p("x.csv"),
        "allan --data " + p("cut.ulg") + " --column rate=gyro_z --out " + p("x.csv"), "log info " + p("unknown.ulg")}) {
    SCOPED_TRACE(args);
    const auto r = run_driftlab(args);
    EXPECT_EQ(r.exit_code, 3);
    EXPECT_THAT(r.err, AllOf(HasSubstr(".ulg: byte "), Not(HasSubstr("failed"))));
    EXPECT_FALSE(fs::exists(p("x.csv")));
  }
  const auto missing_topic = run_driftlab("log export " + p("gyros.ulg") + " --topic sensor_accel --out " + p("x.csv"));
  EXPECT_EQ(missing_topic.exit_code, 3);
  EXPECT_THAT(missing_topic.err, HasSubstr("'sensor_accel' is not in the log"));
  write(dir_ / "record.csv", "t_s,rate_dps\n0,1\n0.1,1\n");
  const auto csv = run_driftlab("log info " + p("record.csv"));
  EXPECT_EQ(csv.exit_code, 3);
  EXPECT_THAT(csv.err, HasSubstr("not a log driftlab reads"));
}

// sensor_gyro_fifo multi_id 0 and 1 (devices 11 and 22): 50 messages of 8 samples 125 us apart,
// one message per ms from 1 s (instance 1 300 us later); x counts (j % 11) - 5 of sample j, y and z
// 0 and 100. sensor_gyro of the same devices every 10 ms carries 30 (31) degC + 0.5 degC/s.
constexpr float kFifoScale = 1.0f / 1024.0f;  // rad/s per count, exact in float and in decimal CSV
std::string gyro_fifos() {
  Writer w;
  w.flag_bits().format(testing_ulog::kSensorGyroFifoFormat).format(testing_ulog::kSensorGyroFormat);
  w.add(0, 1, "sensor_gyro_fifo").add(1, 2, "sensor_gyro_fifo").add(0, 3, "sensor_gyro").add(1, 4, "sensor_gyro");
  for (int m = 0; m < 50; ++m)
    for (int k = 0; k < 2; ++k) {
      testing_ulog::FifoMessage msg;
      msg.timestamp_sample = static_cast<std::uint64_t>(1000000 + 1000 * m + 300 * k);
      msg.device_id = k == 0 ? 11 : 22;
      msg.dt_us = 125.f;
      msg.scale = kFifoScale;
      for (int i = 0; i < 8; ++i) msg.counts.push_back({static_cast<std::int16_t>((8 * m + i) % 11 - 5), 0, 100});
      w.data(static_cast<std::uint16_t>(1 + k), testing_ulog::sensor_fifo(msg));
    }
  for (int j = 0; j <= 6; ++j)
    for (int k = 0; k < 2; ++k) {
      const auto t = static_cast<std::uint64_t>(990000 + 10000 * j);
      w.data(static_cast<std::uint16_t>(3 + k),
             testing_ulog::sensor_gyro(t, k == 0 ? 11 : 22, 0, 0, 0, 30.f + k + 0.005f * static_cast<float>(j)));
    }
  return w.bytes();
}

TEST_F(LogCli, InfoAndExportOfTheFifoTopics) {
  write(dir_ / "fifo.ulg", gyro_fifos());
  const auto info = run_driftlab("log info " + p("fifo.ulg"));
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_THAT(info.out, AllOf(HasSubstr("sensor_gyro_fifo"), HasSubstr("instance 1:"),
                              HasSubstr("gyro FIFO:  device_id 22 (0x16), 50 messages at 1000.0 Hz, 400 samples"),
                              HasSubstr("gyro:  device_id 22 (0x16), 7 messages at 100.0 Hz, 31.00 to 31.03 degC")));

  const auto r = run_driftlab("log export " + p("fifo.ulg") + " --topic sensor_gyro_fifo --out " + p("fifo.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.err, HasSubstr("time base: sensor_gyro_fifo multi_id 0"));
  CsvReadOptions options;
  options.required_roles = {"gyro_x", "gyro1_x", "temperature", "temperature1"};
  const auto record = read_csv(p("fifo.csv"), options);
  // Instance 0's 400 samples from 0.999125 s; the 3 before instance 1's first (0.999425 s) dropped.
  ASSERT_EQ(record.size(), 400 - 3);
  for (Eigen::Index i = 0; i < record.size(); ++i) {
    const int j = static_cast<int>(i) + 3;  // sample j of instance 0: message j / 8, at its stamp - (7 - j % 8) dt
    EXPECT_EQ(record.time()[i], (1000000.0 + 1000.0 * (j / 8) - 125.0 * (7 - j % 8)) / 1e6) << i;
    EXPECT_EQ(record.channel("gyro_x").values[i], (j % 11 - 5) * static_cast<double>(kFifoScale)) << i;
    EXPECT_EQ(record.channel("gyro_z").values[i], 100.0 * static_cast<double>(kFifoScale)) << i;
  }
  EXPECT_EQ(record.device_id(0), "11");
  EXPECT_EQ(record.device_id(1), "22");
  // 30 degC + 0.5 degC/s, stored as float32 (spacing 1.9e-6 degC near 30: each stored value within
  // 9.6e-7 of the line, and so their linear interpolation); the CSV's numbers round-trip exactly.
  constexpr double kFloatTemperatureTolerance = 1e-6;  // degC: the float32 spacing and half of it, bounded
  EXPECT_NEAR(record.channel("temperature").values[0], 30.0 + 0.5 * (record.time()[0] - 0.99),
              kFloatTemperatureTolerance);
}

TEST(LogCliPyulog, InfoOnEachFixture) {
  if (!fs::exists(pyulog_dir() / "sample.ulg")) GTEST_SKIP() << "no shared data: " << pyulog_dir();
  for (const char* name : {"sample.ulg", "sample_log_small.ulg", "sample_appended_multiple.ulg"}) {
    SCOPED_TRACE(name);
    const auto r = run_driftlab("log info " + (pyulog_dir() / name).string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_THAT(r.out, AllOf(HasSubstr("sys_name: PX4"), HasSubstr("sensor_combined")));
  }
  const auto small = run_driftlab("log info " + (pyulog_dir() / "sample_log_small.ulg").string());
  EXPECT_THAT(small.out, AllOf(HasSubstr("ver_hw: CUBEPILOT_CUBEORANGE"), HasSubstr("instance 2:"), HasSubstr("degC")));
}

// --- ArduPilot DataFlash ------------------------------------------------------------------------

fs::path dataflash_logs() { return fs::path(DRIFTLAB_TEST_DATA) / "logs"; }
const fs::path kSpark404 =
    dataflash_logs() / "spark404-dataflashlog" / "log.bin";  // 1 258 IMU + IMU2, pymavlink's counts

TEST(LogCliDataflash, InfoOnEachFixture) {
  for (const char* file :
       {"pymavlink/test.BIN", "spark404-dataflashlog/log.bin", "methodic-configurator/backend_log_80k.bin"}) {
    SCOPED_TRACE(file);
    const auto r = run_driftlab("log info " + (dataflash_logs() / file).string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_THAT(r.out, AllOf(HasSubstr("ArduPilot DataFlash log"), HasSubstr("IMU instances"), HasSubstr("instance 1:"),
                             HasSubstr("PARM"), HasSubstr("TCLR (temperature-calibration learning): none")));
  }
  const auto spark = run_driftlab("log info " + kSpark404.string());
  EXPECT_THAT(spark.out, AllOf(HasSubstr("instance 0: 1258 messages at 24.7 Hz, 27.18 to 27.68 degC"),
                               HasSubstr("gyro  device id 2163722 (0x21040a) (INS_GYR_ID)"),
                               HasSubstr("temperature calibration: no INS_TCAL* parameters")));
  const auto newer =
      run_driftlab("log info " + (dataflash_logs() / "methodic-configurator" / "backend_log_80k.bin").string());
  EXPECT_THAT(newer.out, AllOf(HasSubstr("IMU messages by I"), HasSubstr("INS_TCAL1_ENABLE 0 (off"),
                               HasSubstr("INS_GYR1_CALTEMP = 30.7045"), HasSubstr("its last 2 bytes left out")));
}

// AHRS_ORIENTATION: ArduPilot logs IMU values in the body frame; the record is in the sensor frame.
TEST(LogCliDataflash, ABoardRotationIsReportedAndUndoneAndACustomOneIsRefused) {
  const auto dir = scratch_dir("log_cli_dataflash_orientation");
  const auto test_bin = (dataflash_logs() / "pymavlink" / "test.BIN").string();  // AHRS_ORIENTATION 8 (ROLL_180)
  const auto info = run_driftlab("log info " + test_bin);
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_THAT(info.out, HasSubstr("AHRS_ORIENTATION 8 (ROTATION_ROLL_180): IMU values are logged in the body frame"));
  const auto exported = run_driftlab("log export " + test_bin + " --out " + (dir / "imu.csv").string());
  ASSERT_EQ(exported.exit_code, 0) << exported.err;
  EXPECT_THAT(exported.err, HasSubstr("rotated back into the sensor frame"));
  CsvReadOptions options;
  options.required_roles = {"gyro_y", "accel_z"};
  options.max_gap_factor = 0.0;
  const auto record = read_csv(dir / "imu.csv", options);
  // pymavlink DFReader's first IMU message (test.BIN.reference.txt) has AccZ -9.780994415283203 in
  // the body frame: the sensor's z axis points the other way on a board mounted upside down.
  EXPECT_EQ(record.channel("accel_z").values[0], 9.780994415283203);

  testing_dataflash::Writer w;
  testing_dataflash::define_imu_log(w);
  testing_dataflash::parm(w, 0, "AHRS_ORIENTATION", 100);  // ROTATION_CUSTOM
  for (int i = 0; i < 5; ++i) testing_dataflash::imu(w, 1e6 + 1e4 * i, 0, 0.01, 0.02, 0.03, 0.1, 0.2, -9.8, 30);
  write(dir / "custom.bin", w.bytes());
  const auto custom =
      run_driftlab("log export " + (dir / "custom.bin").string() + " --out " + (dir / "c.csv").string());
  EXPECT_EQ(custom.exit_code, 3);
  EXPECT_THAT(custom.err,
              AllOf(HasSubstr("custom.bin"), HasSubstr("AHRS_ORIENTATION is 100"), HasSubstr("body frame")));
  const auto custom_info = run_driftlab("log info " + (dir / "custom.bin").string());
  EXPECT_EQ(custom_info.exit_code, 0) << custom_info.err;
  EXPECT_THAT(custom_info.out, HasSubstr("AHRS_ORIENTATION 100: not one of ArduPilot's fixed rotations 0..43"));
}

TEST(LogCliDataflash, ExportWritesEveryInstanceTheCsvReaderReadsBack) {
  const auto dir = scratch_dir("log_cli_dataflash_export");
  const auto out = (dir / "imu.csv").string();
  const auto r = run_driftlab("log export " + kSpark404.string() + " --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  CsvReadOptions options;
  options.required_roles = {"gyro_z", "gyro1_z", "accel1_z", "temperature", "temperature1"};
  const auto record = read_csv(out, options);
  EXPECT_EQ(record.size(), 1258);
  EXPECT_EQ(record.time()[0], 402.644506);  // TimeUS 402644506 of the first IMU message (DFReader)
  EXPECT_EQ(record.channel("temperature").values[0], 27.466842651367188);
  EXPECT_EQ(record.device_id(0), "2163722");
  EXPECT_EQ(record.device_id(1), "2228490");
  const auto gyros =
      run_driftlab("log export " + kSpark404.string() + " --sensor gyro1 --out " + (dir / "g1.csv").string());
  ASSERT_EQ(gyros.exit_code, 0) << gyros.err;
  EXPECT_THAT(read_text(dir / "g1.csv").substr(0, 60),
              HasSubstr("t_s,gyro1_x_rad_s,gyro1_y_rad_s,gyro1_z_rad_s,temp1_c"));
}

TEST(LogCliDataflash, CalibrateCompensateAndAllanReadTheBinDirectly) {
  const auto dir = scratch_dir("log_cli_dataflash_commands");
  const std::string bin = kSpark404.string(), model = (dir / "cal.json").string();
  // A flight log, not an oven run: instance 0 warms by 0.5 K, its model does not beat no model
  // (--force writes it anyway; what is checked here is that calibrate reads the .bin); IMU2 of this
  // log reports 0 degC throughout, which the calibration's quality gate refuses.
  const auto cal = run_driftlab("-q calibrate --data " + bin + " --instance 0 --bin 2 --force --out " + model);
  ASSERT_EQ(cal.exit_code, 0) << cal.err;
  EXPECT_THAT(read_text(model), AllOf(HasSubstr("\"device_id\": \"2163722\""), HasSubstr("\"samples\": 1258")));
  EXPECT_THAT(cal.out, HasSubstr("6 channels"));
  const auto gyros = run_driftlab("-q calibrate --data " + bin + " --instance 0 --sensor gyro --bin 2 --force --out " +
                                  (dir / "g.json").string());
  ASSERT_EQ(gyros.exit_code, 0) << gyros.err;
  EXPECT_THAT(gyros.out, HasSubstr("3 channels"));
  const auto flat =
      run_driftlab("-q calibrate --data " + bin + " --instance 1 --bin 2 --force --out " + (dir / "g1.json").string());
  EXPECT_EQ(flat.exit_code, 3);
  EXPECT_THAT(flat.err, AllOf(HasSubstr("log.bin"), HasSubstr("IMU2")));

  // compensate on the .bin writes what it writes on the log's export
  const auto exported = run_driftlab("log export " + bin + " --out " + (dir / "imu.csv").string());
  ASSERT_EQ(exported.exit_code, 0) << exported.err;
  const auto from_csv = run_driftlab("-q compensate --model " + model + " --data " + (dir / "imu.csv").string() +
                                     " --out " + (dir / "c1.csv").string());
  const auto from_bin =
      run_driftlab("-q compensate --model " + model + " --data " + bin + " --out " + (dir / "c2.csv").string());
  ASSERT_EQ(from_csv.exit_code, 0) << from_csv.err;
  ASSERT_EQ(from_bin.exit_code, 0) << from_bin.err;
  EXPECT_EQ(read_text(dir / "c1.csv"), read_text(dir / "c2.csv"));

  const auto allan = run_driftlab("allan --data " + bin + " --column rate=gyro1_z --out " + (dir / "a.csv").string());
  EXPECT_EQ(allan.exit_code, 0) << allan.err;
  EXPECT_THAT(allan.out, HasSubstr("1258 samples"));
}

TEST(LogCliDataflash, BadLogsExitWithThreeNamingFileAndOffset) {
  const auto dir = scratch_dir("log_cli_dataflash_bad");
  namespace df = testing_dataflash;
  df::Writer corrupt;
  corrupt.fmt(70, "BAD", "Qz", "TimeUS,Z", 20);
  df::Writer no_imu;
  df::define_imu_log(no_imu);
  df::parm(no_imu, 0, "INS_GYR_ID", 1);
  write(dir / "corrupt.bin", corrupt.bytes());
  write(dir / "noimu.bin", no_imu.bytes());
  write(dir / "cut.bin", read_text(kSpark404).substr(0, 60));
  const std::string x = (dir / "x.csv").string();
  for (const auto& [args, expected] : std::vector<std::pair<std::string, std::string>>{
           {"log info " + (dir / "corrupt.bin").string(), "corrupt.bin: byte 89: FMT of type 70"},
           {"log export " + (dir / "cut.bin").string() + " --out " + x, "cut.bin: byte 0: truncated"},
           {"log export " + (dir / "noimu.bin").string() + " --out " + x, "no IMU messages"},
           {"-q calibrate --data " + (dir / "noimu.bin").string() + " --out " + x, "no IMU messages"},
           {"log export " + kSpark404.string() + " --instance 5 --out " + x, "matches no stream of the log"}}) {
    SCOPED_TRACE(args);
    const auto r = run_driftlab(args);
    EXPECT_EQ(r.exit_code, 3);
    EXPECT_THAT(r.err, HasSubstr(expected));
    EXPECT_FALSE(fs::exists(x));
  }
  const auto topic = run_driftlab("log export " + kSpark404.string() + " --topic sensor_gyro --out " + x);
  EXPECT_EQ(topic.exit_code, 2);
  EXPECT_THAT(topic.err, HasSubstr("--topic IMU"));
}

}  // namespace
}  // namespace driftlab
