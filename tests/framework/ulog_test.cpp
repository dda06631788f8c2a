// The PX4 ULog reader (framework/ulog.hpp), its IMU adapter (framework/ulog_imu.hpp) and the reader
// registry (framework/record_reader.hpp).
// Truth: pyulog's own outputs for its sample logs (../shared/data/logs/px4-pyulog: ulog_info's
// message counts and byte totals per topic and multi_id, dropouts, info values, logged messages).
// Structure and bad input: small files from tests/framework/ulog_writer.hpp.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <sstream>

#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/record_reader.hpp"
#include "framework/ulog.hpp"
#include "framework/ulog_imu.hpp"
#include "tests/framework/ulog_writer.hpp"

namespace driftlab {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using testing_ulog::Writer;

constexpr double kFloatTolerance = 1e-6;  // values logged as float, compared as double

fs::path pyulog_dir() { return fs::path(DRIFTLAB_SHARED_DATA) / "logs" / "px4-pyulog"; }

#define SKIP_WITHOUT_PYULOG_LOGS() \
  if (!fs::exists(pyulog_dir() / "sample.ulg")) GTEST_SKIP() << "no shared data: " << pyulog_dir()

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

fs::path write_temp(const std::string& name, const std::string& bytes) {
  const auto dir = fs::temp_directory_path() / ("driftlab_ulog_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const auto path = dir / name;
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const DataError& e) {
    return std::string("DataError: ") + e.what();
  } catch (const ConfigError& e) {
    return std::string("ConfigError: ") + e.what();
  }
  return "no error";
}

// pyulog's ulog_info table: "(name, multi_id)" -> (messages, total bytes).
std::map<std::pair<std::string, int>, std::pair<std::uint64_t, std::uint64_t>> pyulog_counts(const fs::path& info) {
  std::map<std::pair<std::string, int>, std::pair<std::uint64_t, std::uint64_t>> out;
  std::ifstream in(info);
  static const std::regex row(R"(^ (\S+) \((\d+), (\d+)\)\s+(\d+)\s+(\d+)\s*$)");
  std::string line;
  std::smatch m;
  while (std::getline(in, line))
    if (std::regex_match(line, m, row))
      out[{m[1].str(), std::stoi(m[2].str())}] = {std::stoull(m[4].str()), std::stoull(m[5].str())};
  return out;
}

void expect_counts_as_pyulog(const ulog::Log& log, const fs::path& info) {
  const auto expected = pyulog_counts(info);
  ASSERT_FALSE(expected.empty()) << info;
  for (const auto& [key, counts] : expected) {
    const auto* t = log.find(key.first, key.second);
    ASSERT_NE(t, nullptr) << key.first << " " << key.second;
    EXPECT_EQ(t->count, counts.first) << key.first << " " << key.second;
    EXPECT_EQ(t->data_bytes, counts.second) << key.first << " " << key.second;
  }
  for (const auto& t : log.topics)  // pyulog lists every topic with data
    if (t.count > 0) {
      EXPECT_TRUE(expected.count({t.name, t.multi_id})) << t.name << " " << t.multi_id;
    }
}

// "0:02:38" as pyulog prints a time stamp in us.
std::string hms(std::uint64_t us) {
  const auto s = us / 1000000;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%d:%02d:%02d", static_cast<int>(s / 3600), static_cast<int>(s / 60 % 60),
                static_cast<int>(s % 60));
  return buf;
}

std::string level_name(std::uint8_t level) {
  static const char* names[] = {"EMERGENCY", "ALERT", "CRITICAL", "ERROR", "WARNING", "NOTICE", "INFO", "DEBUG"};
  return level >= '0' && level <= '7' ? names[level - '0'] : "?";
}

// pyulog's messages file: "0:02:38 ERROR: [sensors] no barometer found ..." per logged string.
void expect_logged_as_pyulog(const ulog::Log& log, const fs::path& messages) {
  std::ifstream in(messages);
  std::vector<std::string> expected;
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) expected.push_back(line);
  std::vector<std::string> got;
  for (const auto& l : log.logged) got.push_back(hms(l.timestamp_us) + " " + level_name(l.level) + ": " + l.text);
  EXPECT_EQ(got, expected);
}

std::uint64_t last_timestamp(const ulog::Log& log) {
  std::uint64_t last = 0;
  for (const auto& t : log.topics)
    if (t.count) last = std::max(last, t.last_timestamp_us);
  return last;
}

// --- pyulog's sample logs -------------------------------------------------------------------

TEST(UlogPyulogSamples, SampleUlgCountsInfoDropoutsAndMessagesAreThoseOfPyulog) {
  SKIP_WITHOUT_PYULOG_LOGS();
  const auto log = ulog::read(pyulog_dir() / "sample.ulg");
  expect_counts_as_pyulog(log, pyulog_dir() / "sample_info.txt");
  EXPECT_EQ(log.find("sensor_combined", 0)->count, 17070u);
  EXPECT_EQ(log.info.at("sys_name"), "PX4");
  EXPECT_EQ(log.info.at("ver_hw"), "AUAV_X21");
  EXPECT_EQ(log.info.at("ver_sw"), "fd483321a5cf50ead91164356d15aa474643aa73");
  EXPECT_EQ(log.info.at("time_ref_utc"), "0");
  // "Logging start time: 0:01:52, duration: 0:01:08"
  EXPECT_EQ(hms(log.start_timestamp_us), "0:01:52");
  EXPECT_EQ(hms(last_timestamp(log) - log.start_timestamp_us), "0:01:08");
  // "Dropouts: count: 4, total duration: 0.1 s, max: 62 ms, mean: 29 ms"
  ASSERT_EQ(log.dropouts.size(), 4u);
  int total = 0, longest = 0;
  for (const auto& d : log.dropouts) {
    total += d.duration_ms;
    longest = std::max<int>(longest, d.duration_ms);
  }
  EXPECT_EQ(longest, 62);
  EXPECT_EQ(total / 4, 29);
  // A coarse check of the total beside the exact longest and mean above: about 0.1 s lost in all.
  constexpr double kDropoutTotalTolerance = 0.05;  // s
  EXPECT_NEAR(total / 1000.0, 0.1, kDropoutTotalTolerance);
  expect_logged_as_pyulog(log, pyulog_dir() / "sample_messages.txt");
}

TEST(UlogPyulogSamples, AppendedDataLogCountsAreThoseOfPyulog) {
  SKIP_WITHOUT_PYULOG_LOGS();
  ulog::ReadOptions keep;
  keep.keep_topics = {"sensor_combined"};
  const auto log = ulog::read(pyulog_dir() / "sample_appended_multiple.ulg", keep);
  EXPECT_EQ(log.incompat_flags[0] & 1, 1);
  EXPECT_GT(log.appended_offsets[0], 0u);
  expect_counts_as_pyulog(log, pyulog_dir() / "sample_appended_multiple_info.txt");
  EXPECT_EQ(log.find("sensor_combined", 0)->count, 2373u);
  EXPECT_EQ(log.find("sensor_combined", 0)->timestamp_us.size(), 2373u);
  EXPECT_TRUE(log.dropouts.empty());  // "No Dropouts"
  EXPECT_EQ(log.info.at("ver_hw"), "PX4FMU_V4PRO");
  EXPECT_EQ(log.info.at("perf_top_preflight-24"), "Processes: 22 total, 8 running, 14 sleeping");
  EXPECT_EQ(hms(log.start_timestamp_us), "0:00:12");
  EXPECT_EQ(hms(last_timestamp(log) - log.start_timestamp_us), "0:00:09");
  EXPECT_EQ(log.info_multiple.at("hardfault_plain").size(), 3u);  // the appended crash dumps
  expect_logged_as_pyulog(log, pyulog_dir() / "sample_appended_multiple_messages.txt");
}

TEST(UlogPyulogSamples, SampleLogSmallLoggedMessagesAreThoseOfPyulog) {
  SKIP_WITHOUT_PYULOG_LOGS();
  const auto log = ulog::read(pyulog_dir() / "sample_log_small.ulg");
  expect_logged_as_pyulog(log, pyulog_dir() / "sample_log_small_messages.txt");
  EXPECT_EQ(log.info.at("ver_hw"), "CUBEPILOT_CUBEORANGE");
  EXPECT_EQ(log.instances("sensor_gyro").size(), 3u);
  EXPECT_EQ(log.instances("sensor_accel").size(), 3u);
}

TEST(UlogPyulogSamples, OnlyTheKeptTopicsHoldValues) {
  SKIP_WITHOUT_PYULOG_LOGS();
  ulog::ReadOptions keep;
  keep.keep_topics = {"sensor_combined"};
  const auto log = ulog::read(pyulog_dir() / "sample.ulg", keep);
  for (const auto& t : log.topics) {
    EXPECT_EQ(t.kept, t.name == "sensor_combined") << t.name;
    if (!t.kept) {
      EXPECT_TRUE(t.timestamp_us.empty() && t.values.empty()) << t.name;
    }
  }
  const auto& combined = *log.find("sensor_combined", 0);
  EXPECT_EQ(combined.column("gyro_rad[2]").size(), 17070u);
  EXPECT_THAT(error_of([&] { log.find("cpuload", 0)->column("load"); }), HasSubstr("not kept"));
}

TEST(UlogPyulogSamples, MultiInstanceSensorGyroIsReadPerInstanceWithTemperature) {
  SKIP_WITHOUT_PYULOG_LOGS();
  const auto path = pyulog_dir() / "sample_log_small.ulg";
  ulog::ReadOptions keep;
  keep.keep_topics = {"sensor_gyro"};
  const auto log = ulog::read(path, keep);
  for (int instance = 0; instance < 3; ++instance) {
    SCOPED_TRACE(instance);
    const auto& topic = *log.find("sensor_gyro", instance);
    LogSelection selection;
    selection.instance = instance;
    selection.sensor = "gyro";
    std::vector<std::string> notes;
    const auto record = ulog::read_imu(path, selection, &notes);
    const std::string suffix = instance ? std::to_string(instance) : "";
    ASSERT_EQ(record.channels().size(), 4u);
    // One stream: its samples as logged, at timestamp_sample.
    ASSERT_EQ(record.size(), static_cast<Eigen::Index>(topic.count));
    const auto& temp = record.channel("temperature" + suffix);
    EXPECT_EQ(temp.unit, "degC");
    for (Eigen::Index i = 0; i < record.size(); ++i) {
      const auto k = static_cast<std::size_t>(i);
      EXPECT_EQ(record.time()[i], topic.column("timestamp_sample")[k] / 1e6);
      EXPECT_DOUBLE_EQ(record.channel("gyro" + suffix + "_x").values[i], topic.column("x")[k]);
      EXPECT_DOUBLE_EQ(temp.values[i], topic.column("temperature")[k]);
      EXPECT_GT(temp.values[i], 0.0);  // a board on a bench: plausible die temperatures
      EXPECT_LT(temp.values[i], 70.0);
    }
    EXPECT_EQ(record.device_id(instance), std::to_string(static_cast<std::uint64_t>(topic.column("device_id")[0])));
    EXPECT_TRUE(notes.empty());
  }
}

TEST(UlogPyulogSamples, WholeImuRecordInterpolatesOntoTheFirstGyro) {
  SKIP_WITHOUT_PYULOG_LOGS();
  std::vector<std::string> notes;
  const auto record = ulog::read_imu(pyulog_dir() / "sample_log_small.ulg", {}, &notes);
  // 3 gyros, 3 accelerometers, 3 temperatures.
  EXPECT_EQ(record.channels().size(), 21u);
  for (const char* role : {"gyro_z", "gyro2_x", "accel1_y", "temperature", "temperature1", "temperature2"})
    EXPECT_TRUE(record.has(role)) << role;
  EXPECT_THAT(notes, ::testing::Contains(HasSubstr("time base: sensor_gyro multi_id 0")));
  EXPECT_FALSE(record.device_id(2).empty());
}

TEST(UlogPyulogSamples, SensorCombinedIsTheFallbackAndSaysItHasNoTemperature) {
  SKIP_WITHOUT_PYULOG_LOGS();
  std::vector<std::string> notes;
  const auto record = ulog::read_imu(pyulog_dir() / "sample.ulg", {}, &notes);
  EXPECT_EQ(record.size(), 17070);
  EXPECT_TRUE(record.has("gyro_z") && record.has("accel_z"));
  EXPECT_FALSE(record.has("temperature"));
  EXPECT_THAT(notes, ::testing::Contains(HasSubstr("no IMU temperature")));
  // Level on the ground before take-off: gravity on -z, within the accelerometer's bias and the
  // vehicle's small tilt on the ground.
  constexpr double kOnGroundTolerance = 0.5;  // m/s^2
  EXPECT_NEAR(record.channel("accel_z").values[0], -9.8, kOnGroundTolerance);
}

// vehicle_imu (PX4's integrated IMU) of sample_log_small.ulg against pyulog's reading of the same
// messages (tests/data/logs/pyulog-vehicle-imu: mean rate delta / dt, written by make_reference.py
// with pyulog): per instance and sensor, every sample at timestamp_sample - dt / 2 with pyulog's
// value, and the device ids.
TEST(UlogPyulogSamples, VehicleImuIsTheMeanRateOfEachIntegrationPeriodAsPyulogReadsIt) {
  SKIP_WITHOUT_PYULOG_LOGS();
  std::ifstream in(fs::path(DRIFTLAB_TEST_DATA) / "logs" / "pyulog-vehicle-imu" / "vehicle_imu_reference.csv");
  std::string line;
  std::getline(in, line);
  std::map<int, std::vector<std::vector<double>>> reference;  // multi_id -> rows
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream cells(line);
    std::string cell;
    while (std::getline(cells, cell, ',')) row.push_back(std::stod(cell));
    reference[static_cast<int>(row[0])].push_back(row);
  }
  ASSERT_EQ(reference.size(), 3u);
  for (const auto& [instance, rows] : reference) {
    for (const bool gyro : {true, false}) {
      SCOPED_TRACE(std::to_string(instance) + (gyro ? " gyro" : " accel"));
      LogSelection selection;
      selection.topic = "vehicle_imu";
      selection.instance = instance;
      selection.sensor = gyro ? "gyro" : "accel";
      std::vector<std::string> notes;
      const auto record = ulog::read_imu(pyulog_dir() / "sample_log_small.ulg", selection, &notes);
      ASSERT_EQ(record.size(), static_cast<Eigen::Index>(rows.size()));
      const std::string prefix = (gyro ? "gyro" : "accel") + (instance ? std::to_string(instance) : std::string());
      for (Eigen::Index i = 0; i < record.size(); ++i) {
        const auto& r = rows[static_cast<std::size_t>(i)];
        const double dt = gyro ? r[2] : r[3];
        EXPECT_EQ(record.time()[i], std::round(r[1] - dt / 2) / 1e6);
        for (int a = 0; a < 3; ++a)
          EXPECT_DOUBLE_EQ(record.channel(prefix + "_" + "xyz"[a]).values[i], r[(gyro ? 4 : 7) + a]) << i << " " << a;
      }
      EXPECT_EQ(record.device_id(instance), std::to_string(static_cast<std::uint64_t>(rows[0][gyro ? 10 : 11])));
      EXPECT_THAT(notes, ::testing::Contains(HasSubstr("vehicle_imu carries no IMU temperature")));
    }
  }
}

TEST(UlogPyulogSamples, TruncatedFixtureIsADataErrorNamingFileAndOffset) {
  SKIP_WITHOUT_PYULOG_LOGS();
  const std::string bytes = read_file(pyulog_dir() / "sample_log_small.ulg");
  for (const std::size_t cut : {std::size_t{3}, std::size_t{15}, std::size_t{17}, std::size_t{1000},
                                std::size_t{180800}, bytes.size() / 2, bytes.size() - 1}) {
    SCOPED_TRACE(cut);
    EXPECT_THAT(
        error_of([&] { ulog::parse(std::string_view(bytes).substr(0, cut), "cut.ulg"); }),
        AllOf(HasSubstr("DataError: cut.ulg: byte "), ::testing::AnyOf(HasSubstr("truncated"), HasSubstr("header"))));
  }
}

TEST(UlogPyulogSamples, AMissingTopicIsADataErrorNamingWhatTheLogHas) {
  SKIP_WITHOUT_PYULOG_LOGS();
  LogSelection selection;
  selection.topic = "sensor_gyro";
  EXPECT_THAT(error_of([&] { ulog::read_imu(pyulog_dir() / "sample.ulg", selection); }),
              AllOf(HasSubstr("DataError"), HasSubstr("sample.ulg"), HasSubstr("'sensor_gyro' is not in the log"),
                    HasSubstr("sensor_combined[0]")));
  selection.topic = "vehicle_imu";
  EXPECT_THAT(
      error_of([&] { ulog::read_imu(pyulog_dir() / "sample.ulg", selection); }),
      AllOf(HasSubstr("DataError"), HasSubstr("'vehicle_imu' is not in the log"), HasSubstr("sensor_combined[0]")));
  selection.topic = "vehicle_gps_position";
  EXPECT_THAT(error_of([&] { ulog::read_imu(pyulog_dir() / "sample.ulg", selection); }),
              AllOf(HasSubstr("ConfigError"), HasSubstr("--topic"), HasSubstr("vehicle_imu")));
  selection = {};
  selection.instance = 5;
  EXPECT_THAT(error_of([&] { ulog::read_imu(pyulog_dir() / "sample_log_small.ulg", selection); }),
              AllOf(HasSubstr("DataError"), HasSubstr("--instance"), HasSubstr("sensor_gyro multi_id 2")));
}

// --- structure, from small written files ----------------------------------------------------

std::string gyro_log(const std::vector<std::uint64_t>& times_us) {
  Writer w;
  w.flag_bits().format(testing_ulog::kSensorGyroFormat).info("char[3] sys_name", "PX4").add(0, 7, "sensor_gyro");
  for (std::size_t i = 0; i < times_us.size(); ++i)
    w.data(7, testing_ulog::sensor_gyro(times_us[i], 42, 0.001f * static_cast<float>(i), 0.f, 0.f, 30.f));
  return w.bytes();
}

TEST(UlogStructure, NestedFormatsArraysAndPaddingAreFlattened) {
  Writer w;
  w.flag_bits()
      .format("vec:float x;float y;")
      .format("thing:uint64_t timestamp;vec[2] v;int16_t[3] a;bool ok;uint8_t[3] _padding0;")
      .add(1, 3, "thing");
  const std::string payload = Writer::le(5000, 8) + Writer::f32(1.5f) + Writer::f32(-2.f) + Writer::f32(3.f) +
                              Writer::f32(4.f) + Writer::le(static_cast<std::uint16_t>(-7), 2) + Writer::le(8, 2) +
                              Writer::le(9, 2) + std::string(1, '\1');
  w.data(3, payload);                                               // trailing padding left out, as PX4 writes
  w.data(3, payload.substr(0, 8 + 16 + 6) + std::string(4, '\0'));  // and with it
  ulog::ReadOptions all;
  all.keep_all = true;
  const auto log = ulog::parse(w.bytes(), "nested.ulg", all);
  const auto& t = *log.find("thing", 1);
  EXPECT_EQ(t.message_size, 8u + 16u + 6u + 1u + 3u);
  std::vector<std::string> names;
  for (const auto& c : t.columns) names.push_back(c.name);
  EXPECT_EQ(names, (std::vector<std::string>{"timestamp", "v[0].x", "v[0].y", "v[1].x", "v[1].y", "a[0]", "a[1]",
                                             "a[2]", "ok"}));
  EXPECT_EQ(t.count, 2u);
  EXPECT_EQ(t.column("v[0].x")[0], 1.5);
  EXPECT_EQ(t.column("v[1].y")[0], 4.0);
  EXPECT_EQ(t.column("a[0]")[0], -7.0);
  EXPECT_EQ(t.column("ok")[0], 1.0);
  EXPECT_EQ(t.column("ok")[1], 0.0);
  EXPECT_EQ(t.timestamp_us, (std::vector<std::uint64_t>{5000, 5000}));
}

TEST(UlogStructure, InfoParametersDropoutsAndLoggedStrings) {
  Writer w;
  w.flag_bits()
      .info("char[3] sys_name", "PX4")
      .info("int32_t ver_sw_release", Writer::le(17498624, 4))
      .info("char[0] empty", "")
      .parameter_float("CAL_GYRO0_XOFF", 0.25f)
      .format(testing_ulog::kSensorGyroFormat)
      .add(0, 1, "sensor_gyro")
      .data(1, testing_ulog::sensor_gyro(2000, 1, 0, 0, 0, 25))
      .dropout(35)
      .parameter_float("CAL_GYRO0_XOFF", 0.5f)
      .logged('6', 2500, "[commander] hello");
  const auto log = ulog::parse(w.bytes(), "info.ulg");
  EXPECT_EQ(log.info.at("sys_name"), "PX4");
  EXPECT_EQ(log.info.at("ver_sw_release"), "17498624");
  EXPECT_EQ(log.info.at("empty"), "");
  ASSERT_EQ(log.parameters.size(), 1u);
  EXPECT_EQ(log.parameters[0].value, 0.25);
  ASSERT_EQ(log.parameter_changes.size(), 1u);
  EXPECT_EQ(log.parameter_changes[0].value, 0.5);
  EXPECT_EQ(log.parameter_changes[0].timestamp_us, 2000u);
  ASSERT_EQ(log.dropouts.size(), 1u);
  EXPECT_EQ(log.dropouts[0].duration_ms, 35);
  EXPECT_EQ(log.dropouts[0].timestamp_us, 2000u);
  ASSERT_EQ(log.logged.size(), 1u);
  EXPECT_EQ(log.logged[0].text, "[commander] hello");
}

TEST(UlogStructure, AMessageCutOffBeforeAppendedDataIsSkipped) {
  Writer w;
  w.flag_bits(1, {0}).format(testing_ulog::kSensorGyroFormat).add(0, 1, "sensor_gyro");
  w.data(1, testing_ulog::sensor_gyro(1000, 1, 0, 0, 0, 25));
  const std::string cut = Writer::le(46, 2) + "D" + Writer::le(1, 2) + "\x01\x02";  // a data message cut off
  const std::uint64_t appended_at = w.bytes().size() + cut.size();
  std::string bytes = w.bytes() + cut;
  bytes += Writer(0)
               .message('M', std::string("\0", 1) +
                                 "\x13"
                                 "char[5] hardfault_x"
                                 "crash")
               .bytes()
               .substr(16);
  // Point the flag bits' first appended offset at the appended part.
  bytes.replace(16 + 3 + 16, 8, Writer::le(appended_at, 8));
  ulog::ReadOptions all;
  all.keep_all = true;
  const auto log = ulog::parse(bytes, "appended.ulg", all);
  EXPECT_EQ(log.find("sensor_gyro", 0)->count, 1u);
  EXPECT_EQ(log.bytes_skipped_at_appended, cut.size());
  EXPECT_EQ(log.info_multiple.at("hardfault_x"), std::vector<std::string>{"crash"});
}

TEST(UlogStructure, OutOfOrderAndRepeatedTimeStampsAreSortedAndDroppedWithNotes) {
  const auto path = write_temp("unordered.ulg", gyro_log({1000, 3000, 2000, 4000, 4000, 5000}));
  std::vector<std::string> notes;
  const auto record = ulog::read_imu(path, {}, &notes);
  ASSERT_EQ(record.size(), 5);
  for (Eigen::Index i = 0; i < record.size(); ++i) EXPECT_EQ(record.time()[i], static_cast<double>(i + 1) / 1e3);
  EXPECT_NEAR(record.channel("gyro_x").values[1], 0.002, kFloatTolerance);  // the sample at 2000 us was logged third
  EXPECT_NEAR(record.channel("gyro_x").values[3], 0.003, kFloatTolerance);  // the first of the two at 4000 us
  EXPECT_THAT(notes, ::testing::Contains(HasSubstr("1 samples earlier than the one before; sorted")));
  EXPECT_THAT(notes, ::testing::Contains(HasSubstr("1 repeated time stamps")));
}

// --- sensor_gyro_fifo / sensor_accel_fifo: simulated, written, recovered ----------------------

constexpr float kGyroScale = static_cast<float>(2000.0 / 32768.0 * M_PI / 180.0);  // rad/s per count, +-2000 deg/s
// Recovered rate vs the simulated one: counts are rate / scale rounded to the nearest integer, so
// count * scale is within scale / 2; 1e-12 rad/s covers the double rounding of rate / scale and
// count * scale (rates below 2 rad/s: relative error 1e-16 each).
constexpr double kQuantization = kGyroScale / 2.0 + 1e-12;
// Temperatures (about 30 degC) stored as float32: spacing 2^-19 = 1.9e-6 degC there, so each
// stored value is within 9.6e-7 of the simulated line, and so is a linear interpolation of two.
constexpr double kFloatTemperature = 1e-6;

constexpr std::uint32_t kFifoDevice[2] = {2490378, 2424842};
constexpr float kFifoDt[2] = {312.5f, 125.f};  // us: 3.2 kHz (sample times on half microseconds), 8 kHz
constexpr int kFifoMessages = 60;

// The simulated rate of a FIFO instance's axis (rad/s) at t_us: a sinusoid plus a slope.
double fifo_rate(int instance, int axis, double t_us) {
  const double t = t_us * 1e-6;
  return (0.4 + 0.1 * axis) * std::sin(2.0 * M_PI * (3.0 + instance) * t + axis) + 0.05 * (axis - 1) * t +
         0.01 * instance;
}
// The simulated die temperature of a FIFO instance's device (degC): 0.5 degC/s from 30 (31).
double fifo_temperature(int instance, double t_us) { return 30.0 + instance + 0.5 * (t_us - 1e6) * 1e-6; }

struct FifoTruth {
  std::vector<std::int64_t> time_us;          // the sample times as the reader must round them
  std::vector<double> exact_us;               // unrounded: timestamp_sample - (N - 1 - i) dt
  std::vector<std::array<double, 3>> counts;  // the logged counts
};
struct FifoLog {
  std::string bytes;
  std::array<FifoTruth, 2> truth;
};

// sensor_gyro_fifo multi_id 0 and 1, 60 messages each of 1 to 32 samples (sampled without gaps:
// each message's timestamp_sample is the last sample's, rounded to 1 us as a driver stamps it);
// with `with_sensor_gyro`, sensor_gyro of the same devices under swapped multi_ids, every 8 ms from
// 10 ms before the first FIFO sample to after the last, carrying their temperatures.
FifoLog fifo_log(bool with_sensor_gyro) {
  Writer w;
  w.flag_bits().format(testing_ulog::kSensorGyroFifoFormat).format(testing_ulog::kSensorGyroFormat);
  w.add(0, 1, "sensor_gyro_fifo").add(1, 2, "sensor_gyro_fifo");
  if (with_sensor_gyro) w.add(0, 3, "sensor_gyro").add(1, 4, "sensor_gyro");
  FifoLog out;
  const int sizes[] = {1, 4, 7, 32, 13, 2, 9};
  std::uint64_t end_us = 0;
  for (int k = 0; k < 2; ++k) {
    double last = 1000000.0 + 37.0 * k;
    for (int m = 0; m < kFifoMessages; ++m) {
      const int n = sizes[(m + 3 * k) % 7];
      if (m > 0) last = std::round(last + n * static_cast<double>(kFifoDt[k]));
      testing_ulog::FifoMessage msg;
      msg.timestamp_sample = static_cast<std::uint64_t>(last);
      msg.device_id = kFifoDevice[k];
      msg.dt_us = kFifoDt[k];
      msg.scale = kGyroScale;
      for (int i = 0; i < n; ++i) {
        const double t = last - (n - 1 - i) * static_cast<double>(kFifoDt[k]);
        std::array<std::int16_t, 3> c{};
        std::array<double, 3> counts{};
        for (int a = 0; a < 3; ++a) {
          c[a] = static_cast<std::int16_t>(std::lround(fifo_rate(k, a, t) / static_cast<double>(kGyroScale)));
          counts[a] = c[a];
        }
        msg.counts.push_back(c);
        out.truth[k].exact_us.push_back(t);
        out.truth[k].time_us.push_back(std::llround(t));
        out.truth[k].counts.push_back(counts);
      }
      w.data(static_cast<std::uint16_t>(1 + k), testing_ulog::sensor_fifo(msg));
    }
    end_us = std::max(end_us, static_cast<std::uint64_t>(last));
  }
  if (with_sensor_gyro) {
    for (std::uint64_t t = 1000000 - 3875 - 10000; t < end_us + 8000; t += 8000)
      for (int k = 0; k < 2; ++k)  // multi_id 0 is FIFO instance 1's device, multi_id 1 instance 0's
        w.data(static_cast<std::uint16_t>(4 - k),
               testing_ulog::sensor_gyro(t, kFifoDevice[k], 0, 0, 0, static_cast<float>(fifo_temperature(k, t))));
  }
  out.bytes = w.bytes();
  return out;
}

TEST(UlogFifo, EverySampleIsRecoveredAtItsTimeWithItsValueAndItsDevicesTemperature) {
  const FifoLog log = fifo_log(true);
  const auto path = write_temp("fifo.ulg", log.bytes);
  for (int k = 0; k < 2; ++k) {
    SCOPED_TRACE(k);
    const auto& truth = log.truth[k];
    LogSelection selection;
    selection.topic = "sensor_gyro_fifo";
    selection.instance = k;
    std::vector<std::string> notes;
    const auto record = ulog::read_imu(path, selection, &notes);
    const std::string n = k ? "1" : "";
    ASSERT_EQ(record.size(), static_cast<Eigen::Index>(truth.time_us.size()));
    EXPECT_EQ(record.channel("gyro" + n + "_x").source, "sensor_gyro_fifo[" + std::to_string(k) + "]");
    EXPECT_EQ(record.channel("temperature" + n).source, "sensor_gyro[" + std::to_string(1 - k) + "]");
    EXPECT_EQ(record.device_id(k), std::to_string(kFifoDevice[k]));
    for (Eigen::Index i = 0; i < record.size(); ++i) {
      const auto j = static_cast<std::size_t>(i);
      ASSERT_EQ(record.time()[i], static_cast<double>(truth.time_us[j]) / 1e6) << i;
      for (int a = 0; a < 3; ++a) {
        const double value = record.channel("gyro" + n + "_" + "xyz"[a]).values[i];
        EXPECT_EQ(value, truth.counts[j][a] * static_cast<double>(kGyroScale)) << i << " " << a;
        EXPECT_NEAR(value, fifo_rate(k, a, truth.exact_us[j]), kQuantization) << i << " " << a;
      }
      EXPECT_NEAR(record.channel("temperature" + n).values[i],
                  fifo_temperature(k, static_cast<double>(truth.time_us[j])), kFloatTemperature)
          << i;
    }
    EXPECT_THAT(notes, ::testing::Not(::testing::Contains(HasSubstr("no temperature"))));
  }
}

TEST(UlogFifo, SensorGyroStaysTheDefaultAndTopicPicksTheFifo) {
  const auto path = write_temp("fifo_default.ulg", fifo_log(true).bytes);
  const auto plain = ulog::read_imu(path, {});
  EXPECT_EQ(plain.channel("gyro_x").source, "sensor_gyro[0]");
  EXPECT_EQ(plain.device_id(0), std::to_string(kFifoDevice[1]));  // sensor_gyro's own multi_id 0

  LogSelection fifo;
  fifo.topic = "sensor_gyro_fifo";
  std::vector<std::string> notes;
  const auto record = ulog::read_imu(path, fifo, &notes);
  EXPECT_EQ(record.channel("gyro_x").source, "sensor_gyro_fifo[0]");
  EXPECT_EQ(record.channel("gyro1_z").source, "sensor_gyro_fifo[1]");
  EXPECT_EQ(record.channel("temperature").source, "sensor_gyro[1]");
  EXPECT_EQ(record.channel("temperature1").source, "sensor_gyro[0]");
  EXPECT_EQ(record.device_id(1), std::to_string(kFifoDevice[1]));
  EXPECT_THAT(notes, ::testing::Contains(HasSubstr("time base: sensor_gyro_fifo multi_id 0; 3 other streams")));

  fifo.topic = "sensor_mag";
  EXPECT_THAT(error_of([&] { ulog::read_imu(path, fifo); }),
              AllOf(HasSubstr("ConfigError"), HasSubstr("--topic"), HasSubstr("sensor_gyro_fifo, sensor_accel_fifo")));
  fifo.topic = "sensor_accel_fifo";
  EXPECT_THAT(error_of([&] { ulog::read_imu(path, fifo); }),
              AllOf(HasSubstr("DataError"), HasSubstr("'sensor_accel_fifo' is not in the log"),
                    HasSubstr("sensor_gyro_fifo[1]")));
}

TEST(UlogFifo, WithoutSensorGyroTheFifoIsTheDefaultWithoutTemperatureAndANote) {
  const FifoLog log = fifo_log(false);
  std::vector<std::string> notes;
  const auto record = ulog::read_imu(write_temp("fifo_only.ulg", log.bytes), {}, &notes);
  EXPECT_EQ(record.channel("gyro_x").source, "sensor_gyro_fifo[0]");
  EXPECT_TRUE(record.has("gyro1_y"));
  EXPECT_FALSE(record.has("temperature") || record.has("temperature1"));
  for (int k = 0; k < 2; ++k)
    EXPECT_THAT(notes,
                ::testing::Contains(AllOf(HasSubstr("sensor_gyro_fifo multi_id " + std::to_string(k)),
                                          HasSubstr("device id (" + std::to_string(kFifoDevice[k]) + ")"),
                                          HasSubstr("no temperature channel for instance " + std::to_string(k)))));
  // Instance 0 is the time base: its samples as logged, from instance 1's first sample on.
  const auto& truth = log.truth[0];
  ASSERT_GT(record.size(), 2);
  const auto first = static_cast<std::size_t>(
      std::find(truth.time_us.begin(), truth.time_us.end(), std::llround(record.time()[0] * 1e6)) -
      truth.time_us.begin());
  ASSERT_LE(first + static_cast<std::size_t>(record.size()), truth.time_us.size());
  for (Eigen::Index i = 0; i < record.size(); ++i)
    EXPECT_EQ(record.time()[i], static_cast<double>(truth.time_us[first + static_cast<std::size_t>(i)]) / 1e6);
}

// sensor_accel_fifo as msg/SensorAccelFifo.msg defines it (no is_external): read by --topic, and by
// default from a log with no other IMU topic; count * scale in m/s^2.
TEST(UlogFifo, SensorAccelFifoWithoutIsExternalIsRead) {
  constexpr float kAccelScale = static_cast<float>(9.80665 / 2048.0);  // m/s^2 per count, +-16 g
  Writer w;
  w.flag_bits().format(testing_ulog::kSensorAccelFifoFormat).add(2, 1, "sensor_accel_fifo");
  for (int m = 0; m < 3; ++m) {
    testing_ulog::FifoMessage msg;
    msg.timestamp_sample = 2000000 + 1000 * static_cast<std::uint64_t>(m);
    msg.device_id = 7;
    msg.dt_us = 250.f;
    msg.scale = kAccelScale;
    msg.before_samples = "";
    for (int i = 0; i < 4; ++i)
      msg.counts.push_back({static_cast<std::int16_t>(m), static_cast<std::int16_t>(-i), 2048});
    w.data(1, testing_ulog::sensor_fifo(msg));
  }
  const auto path = write_temp("accel_fifo.ulg", w.bytes());
  for (const char* topic : {"", "sensor_accel_fifo"}) {
    SCOPED_TRACE(topic);
    LogSelection selection;
    selection.topic = topic;
    std::vector<std::string> notes;
    const auto record = ulog::read_imu(path, selection, &notes);
    ASSERT_EQ(record.size(), 12);
    EXPECT_EQ(record.time()[0], 1.99925);  // 2000000 - 3 * 250 us
    EXPECT_EQ(record.time()[11], 2.002);
    EXPECT_EQ(record.channel("accel2_x").values[4], 1.0 * static_cast<double>(kAccelScale));
    EXPECT_EQ(record.channel("accel2_y").values[7], -3.0 * static_cast<double>(kAccelScale));
    EXPECT_EQ(record.channel("accel2_z").values[0], 2048.0 * static_cast<double>(kAccelScale));
    EXPECT_EQ(record.device_id(2), "7");
    EXPECT_THAT(notes, ::testing::Contains(HasSubstr("no temperature channel for instance 2")));
  }
}

TEST(UlogFifo, OutOfOrderAndRepeatedMessagesAreSortedAndDroppedWithNotes) {
  Writer w;
  w.flag_bits().format(testing_ulog::kSensorGyroFifoFormat).add(0, 1, "sensor_gyro_fifo");
  for (const std::uint64_t last : {1000000, 1001000, 1000500, 1001000}) {
    testing_ulog::FifoMessage msg;
    msg.timestamp_sample = last;
    msg.device_id = 1;
    msg.dt_us = 125.f;
    msg.scale = kGyroScale;
    for (int i = 0; i < 4; ++i) msg.counts.push_back({static_cast<std::int16_t>(last / 100 + i), 0, 0});
    w.data(1, testing_ulog::sensor_fifo(msg));
  }
  std::vector<std::string> notes;
  const auto record = ulog::read_imu(write_temp("fifo_unordered.ulg", w.bytes()), {}, &notes);
  ASSERT_EQ(record.size(), 12);
  for (Eigen::Index i = 0; i < record.size(); ++i)
    EXPECT_EQ(record.time()[i], (999625.0 + 125.0 * static_cast<double>(i)) / 1e6) << i;
  EXPECT_EQ(record.channel("gyro_x").values[4], 10005 * static_cast<double>(kGyroScale));  // logged third
  EXPECT_THAT(notes,
              ::testing::Contains(HasSubstr("sensor_gyro_fifo multi_id 0: 1 samples earlier than the one before")));
  EXPECT_THAT(notes, ::testing::Contains(HasSubstr("sensor_gyro_fifo multi_id 0: 4 repeated time stamps")));
}

// Message 1 of sensor_gyro_fifo multi_id 1 spoiled one way at a time.
TEST(UlogFifo, BadMessagesAreDataErrorsNamingFileTopicInstanceAndMessage) {
  const std::string old_format_20 =  // early PX4: arrays of 20
      "sensor_gyro_fifo:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float dt;float scale;"
      "int16_t[20] x;int16_t[20] y;int16_t[20] z;uint8_t samples;";
  const std::string rotation_format =  // samples in the sensor's frame, and its rotation
      "sensor_gyro_fifo:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float dt;float scale;"
      "int16_t[32] x;int16_t[32] y;int16_t[32] z;uint8_t samples;uint8_t rotation;";
  const std::string signed_samples_format =  // a count that can be negative
      "sensor_gyro_fifo:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float dt;float scale;"
      "int16_t[32] x;int16_t[32] y;int16_t[32] z;int8_t samples;";
  struct Case {
    std::string name, format;
    std::function<void(testing_ulog::FifoMessage&)> spoil;
    std::string expected;
  };
  const Case cases[] = {
      {"dt 0", testing_ulog::kSensorGyroFifoFormat, [](auto& m) { m.dt_us = 0.f; },
       "sensor_gyro_fifo[1].dt: sensor_gyro_fifo multi_id 1 message 1: dt 0 us; expected a finite interval > 0"},
      {"dt negative", testing_ulog::kSensorGyroFifoFormat, [](auto& m) { m.dt_us = -125.f; }, "message 1: dt -125 us"},
      {"dt nan", testing_ulog::kSensorGyroFifoFormat, [](auto& m) { m.dt_us = std::nanf(""); }, "message 1: dt nan us"},
      {"scale 0", testing_ulog::kSensorGyroFifoFormat, [](auto& m) { m.scale = 0.f; },
       "sensor_gyro_fifo[1].scale: sensor_gyro_fifo multi_id 1 message 1: scale 0; expected a finite value > 0"},
      {"scale inf", testing_ulog::kSensorGyroFifoFormat, [](auto& m) { m.scale = INFINITY; }, "message 1: scale inf"},
      {"33 samples", testing_ulog::kSensorGyroFifoFormat, [](auto& m) { m.samples = 33; },
       "sensor_gyro_fifo[1].samples: sensor_gyro_fifo multi_id 1 message 1: samples 33; expected a whole number up "
       "to 32, the format's array length"},
      {"21 of 20", old_format_20, [](auto& m) { m.samples = 21; },
       "message 1: samples 21; expected a whole number up to 20"},
      {"samples -1", signed_samples_format, [](auto& m) { m.samples = 255; },
       "sensor_gyro_fifo[1].samples: sensor_gyro_fifo multi_id 1 message 1: samples -1; expected a whole number up "
       "to 32"},
      {"dt under 1 us", testing_ulog::kSensorGyroFifoFormat, [](auto& m) { m.dt_us = 0.4f; },
       "sensor_gyro_fifo[1].dt: sensor_gyro_fifo multi_id 1 message 1: sample 1 at 1000999 us is not after sample 0 "
       "(dt 0.4 us"},
      {"rotation", rotation_format, [](auto& m) { m.after_samples = "\x04"; },
       "sensor_gyro_fifo[1].rotation: sensor_gyro_fifo multi_id 1 message 1: rotation 4: the samples are in the "
       "sensor's own frame"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    Writer w;
    w.flag_bits().format(c.format).add(1, 1, "sensor_gyro_fifo");
    for (int m = 0; m < 3; ++m) {
      testing_ulog::FifoMessage msg;
      msg.timestamp_sample = 1000000 + 1000 * static_cast<std::uint64_t>(m);
      msg.device_id = 1;
      msg.dt_us = 125.f;
      msg.scale = kGyroScale;
      msg.counts.assign(4, {1, 2, 3});
      msg.capacity = c.format == old_format_20 ? 20 : 32;
      msg.before_samples = c.format == testing_ulog::kSensorGyroFifoFormat ? std::string(1, '\0') : "";
      msg.after_samples = c.format == rotation_format ? std::string(1, '\0') : "";
      if (m == 1) c.spoil(msg);
      w.data(1, testing_ulog::sensor_fifo(msg));
    }
    ulog::ReadOptions keep;
    keep.keep_topics = ulog::imu_topics();
    const auto log = ulog::parse(w.bytes(), "fifo_bad.ulg", keep);
    EXPECT_THAT(error_of([&] { ulog::imu_record(log, {}); }),
                AllOf(HasSubstr("DataError: fifo_bad.ulg: "), HasSubstr(c.expected)));
  }
}

// A revision of msg/SensorAccelFifo.msg has no scale: without it the counts cannot be read.
TEST(UlogFifo, AFormatWithoutScaleIsADataErrorNamingTheField) {
  Writer w;
  w.flag_bits()
      .format(
          "sensor_accel_fifo:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float dt;"
          "int16_t[32] x;int16_t[32] y;int16_t[32] z;uint8_t samples;")
      .add(0, 1, "sensor_accel_fifo");
  for (int m = 0; m < 2; ++m) {
    testing_ulog::FifoMessage msg;
    msg.timestamp_sample = 1000000 + 1000 * static_cast<std::uint64_t>(m);
    msg.dt_us = 250.f;
    msg.counts.assign(4, {1, 2, 3});
    msg.before_samples = "";
    w.data(1, testing_ulog::sensor_fifo(msg).erase(24, 4));  // the 4 bytes of scale, after dt
  }
  ulog::ReadOptions keep;
  keep.keep_topics = ulog::imu_topics();
  const auto log = ulog::parse(w.bytes(), "no_scale.ulg", keep);
  EXPECT_THAT(error_of([&] { ulog::imu_record(log, {}); }),
              HasSubstr("DataError: no_scale.ulg: sensor_accel_fifo.scale: topic 'sensor_accel_fifo' multi_id 0 has "
                        "no field 'scale'"));
}

// --- bad input ------------------------------------------------------------------------------

// Cut at a message boundary, a log is a shorter valid log; cut anywhere else, it is truncated.
TEST(UlogBadInput, TruncatedAtEveryOffsetIsADataErrorNamingFileAndOffset) {
  const std::string bytes = gyro_log({1000, 2000, 3000});
  std::vector<std::size_t> boundaries;
  for (std::size_t at = 16; at < bytes.size();) {
    boundaries.push_back(at);
    at += 3 + static_cast<unsigned char>(bytes[at]) + 256u * static_cast<unsigned char>(bytes[at + 1]);
  }
  for (std::size_t cut = 0; cut < bytes.size(); ++cut) {
    const std::string message = error_of([&] { ulog::parse(std::string_view(bytes).substr(0, cut), "t.ulg"); });
    if (std::find(boundaries.begin(), boundaries.end(), cut) != boundaries.end())
      EXPECT_EQ(message, "no error") << "cut at " << cut;
    else
      ASSERT_THAT(message, HasSubstr("DataError: t.ulg: byte ")) << "cut at " << cut;
  }
}

TEST(UlogBadInput, CorruptDefinitionsAreDataErrorsSayingWhatWasExpected) {
  struct Case {
    std::string format, expected;
  };
  const Case cases[] = {
      {"no_colon_here", "expected 'name:type field;...'"},
      {"t:uint64_t timestamp;float", "expected 'type name'"},
      {"t:uint64_t timestamp;float[0] x;", "bad array type"},
      {"t:uint64_t timestamp;float[99999] x;", "bad array type"},
      {"t:uint64_t timestamp;mystery x;", "no format 'F' defines 'mystery'"},
      {"t:uint64_t timestamp;t x;", "contains itself"},
      {"t:uint32_t time;float x;", "no 'uint64_t timestamp'"},
      {"t:uint64_t timestamp;uint8_t[65535] x;", "larger than 65535 bytes"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.format);
    Writer w;
    w.flag_bits().format(c.format).add(0, 1, "t");
    EXPECT_THAT(error_of([&] { ulog::parse(w.bytes(), "f.ulg"); }),
                AllOf(HasSubstr("DataError: f.ulg: byte "), HasSubstr(c.expected)));
  }
}

TEST(UlogBadInput, UnknownMessageTypeAndOtherCorruptionAreDataErrors) {
  const auto parse_error = [](const std::string& bytes) { return error_of([&] { ulog::parse(bytes, "c.ulg"); }); };
  const std::string head = Writer().flag_bits().bytes();
  EXPECT_THAT(parse_error(Writer().flag_bits().message('Z', "abc").bytes()),
              AllOf(HasSubstr("c.ulg: byte 59: unknown message type 'Z'")));
  EXPECT_THAT(parse_error(Writer().flag_bits().message(static_cast<char>(0xfe), "").bytes()), HasSubstr("0xfe"));
  EXPECT_THAT(parse_error("ULog\x01\x12\x36" + head.substr(7)), HasSubstr("byte 0: not a ULog file"));
  EXPECT_THAT(parse_error(Writer(1000, 2).bytes()), HasSubstr("byte 7: ULog version 2"));
  EXPECT_THAT(parse_error(Writer().flag_bits(2).bytes()), HasSubstr("unknown incompatible flag bits"));
  EXPECT_THAT(parse_error(Writer().flag_bits(1, {1u << 30}).bytes()), HasSubstr("appended-data offset"));
  EXPECT_THAT(parse_error(Writer().flag_bits().flag_bits().bytes()), HasSubstr("only as the first message"));
  EXPECT_THAT(parse_error(Writer().flag_bits().data(9, std::string(8, '\0')).bytes()),
              HasSubstr("msg_id 9, which no 'A' message added"));
  EXPECT_THAT(parse_error(Writer()
                              .flag_bits()
                              .format(testing_ulog::kSensorGyroFormat)
                              .add(0, 1, "sensor_gyro")
                              .data(1, std::string(10, '\0'))
                              .bytes()),
              HasSubstr("has 10 bytes; its format needs 40"));
  EXPECT_THAT(parse_error(Writer().flag_bits().info("char[9] sys_name", "PX4").bytes()),
              HasSubstr("the value has 3 bytes"));
  EXPECT_THAT(parse_error(Writer()
                              .flag_bits()
                              .message('I',
                                       "\x40"
                                       "abc")
                              .bytes()),
              HasSubstr("key of 64 bytes"));
}

TEST(UlogBadInput, MissingFileAndNonFiniteValuesAreDataErrors) {
  EXPECT_THAT(error_of([] { ulog::read("/nonexistent/x.ulg"); }), AllOf(HasSubstr("DataError"), HasSubstr("x.ulg")));
  Writer w;
  w.flag_bits().format(testing_ulog::kSensorGyroFormat).add(0, 1, "sensor_gyro");
  w.data(1, testing_ulog::sensor_gyro(1000, 1, 0, 0, 0, 25));
  w.data(1, testing_ulog::sensor_gyro(2000, 1, std::nanf(""), 0, 0, 25));
  const auto path = write_temp("nan.ulg", w.bytes());
  EXPECT_THAT(error_of([&] { ulog::read_imu(path, {}); }), AllOf(HasSubstr("nan.ulg"), HasSubstr("sensor_gyro[0].x"),
                                                                 HasSubstr("non-finite value at time stamp 2000 us")));
}

// --- the registry ----------------------------------------------------------------------------

TEST(RecordReader, ChoosesByContentNotByName) {
  const auto ulog_named_csv = write_temp("log.csv", gyro_log({1000, 2000, 3000}));
  const auto csv_named_ulg = write_temp("record.ulg", "t_s,rate_dps,temp_c\n0,1,20\n0.1,1,20\n0.2,1,20\n");
  EXPECT_EQ(sniff_record_format(ulog_named_csv), RecordFormat::Ulog);
  EXPECT_EQ(sniff_record_format(csv_named_ulg), RecordFormat::Csv);
  CsvReadOptions imu_options;
  imu_options.required_roles = {};
  EXPECT_TRUE(read_record(ulog_named_csv, imu_options).has("gyro_z"));
  // CSV reading is read_csv's, unchanged.
  const auto a = read_record(csv_named_ulg, {});
  const auto b = read_csv(csv_named_ulg, {});
  EXPECT_EQ(a.time(), b.time());
  EXPECT_EQ(a.channel("rate").values, b.channel("rate").values);
}

TEST(RecordReader, ColumnMappingsPickTheLogsChannels) {
  const auto path = write_temp("map.ulg", gyro_log({1000, 2000, 3000, 4000}));
  CsvReadOptions options;
  options.columns = {parse_column_mapping("rate=gyro_x"), parse_column_mapping("temp")};
  options.required_roles = {"rate", "temperature"};
  const auto record = read_record(path, options);
  ASSERT_EQ(record.channels().size(), 2u);
  EXPECT_NEAR(record.channel("rate").values[3], 0.003, kFloatTolerance);
  EXPECT_EQ(record.channel("temperature").values[0], 30.0);
  EXPECT_EQ(record.device_id(0), "42");

  CsvReadOptions unmapped;  // the default required role "rate" is not in a log's IMU record
  EXPECT_THAT(error_of([&] { read_record(path, unmapped); }),
              AllOf(HasSubstr("DataError"), HasSubstr("map.ulg"), HasSubstr("--column rate=gyro_z")));
  CsvReadOptions wrong_unit;
  wrong_unit.columns = {parse_column_mapping("rate=gyro_x:deg/s")};
  EXPECT_THAT(error_of([&] { read_record(path, wrong_unit); }), AllOf(HasSubstr("ConfigError"), HasSubstr("rad/s")));
  CsvReadOptions with_fs;
  with_fs.required_roles = {};
  with_fs.sample_rate_hz = 100;
  EXPECT_THAT(error_of([&] { read_record(path, with_fs); }), AllOf(HasSubstr("ConfigError"), HasSubstr("--fs")));
  CsvReadOptions absent;
  absent.columns = {parse_column_mapping("rate=gyro3_x")};
  EXPECT_THAT(error_of([&] { read_record(path, absent); }), HasSubstr("the log has no channel 'gyro3_x'"));
}

TEST(RecordReader, GapsInALogAreCheckedLikeCsvUnlessAllowed) {
  const auto path = write_temp("gap.ulg", gyro_log({1000, 2000, 3000, 4000, 50000, 51000}));
  CsvReadOptions options;
  options.required_roles = {};
  EXPECT_THAT(error_of([&] { read_record(path, options); }), AllOf(HasSubstr("gap of 0.046"), HasSubstr("--max-gap")));
  options.max_gap_factor = 0;
  EXPECT_EQ(read_record(path, options).size(), 6);
}

}  // namespace
}  // namespace driftlab
