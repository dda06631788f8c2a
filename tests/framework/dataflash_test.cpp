// The ArduPilot DataFlash reader (framework/dataflash.hpp), its IMU adapter
// (framework/dataflash_imu.hpp) and its place in the reader registry.
// Truth: pymavlink's DFReader on three real logs nobody here wrote (tests/data/logs/*: message
// counts and first/last time stamps per type, IMU counts and first/last values per instance, device
// id and temperature-calibration parameters; produced by tests/data/logs/dataflash_reference.py,
// see tests/data/logs/README.md). Structure and bad input: small logs from
// tests/framework/dataflash_writer.hpp.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <numbers>
#include <sstream>

#include "framework/csv.hpp"
#include "framework/dataflash.hpp"
#include "framework/dataflash_imu.hpp"
#include "framework/error.hpp"
#include "framework/record_reader.hpp"
#include "tests/framework/dataflash_writer.hpp"

namespace driftlab {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using testing_dataflash::Writer;
namespace df = testing_dataflash;

constexpr double kSecondsPerMicrosecond = 1e-6;
constexpr double kTimeTolerance = 1e-9;  // s: a us count divided by 1e6, compared as double
// A rotation matrix entry computed two ways (the firmware's sequence of rotations, a closed form):
// a few ulps of 1.
constexpr double kRotationTolerance = 1e-15;

fs::path logs_dir() { return fs::path(DRIFTLAB_TEST_DATA) / "logs"; }

struct Fixture {
  const char* dir;
  const char* file;
};
const Fixture kFixtures[] = {
    {"pymavlink", "test.BIN"}, {"spark404-dataflashlog", "log.bin"}, {"methodic-configurator", "backend_log_80k.bin"}};

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

fs::path write_temp(const std::string& name, const std::string& bytes) {
  const auto dir = fs::temp_directory_path() / ("driftlab_dataflash_test_" + std::to_string(::getpid()));
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

// What tests/data/logs/dataflash_reference.py printed for a log.
struct Reference {
  struct Type {
    std::uint64_t count = 0;
    std::string first, last;  // TimeUS, or "None"
  };
  std::map<std::string, Type> types;
  std::map<int, std::uint64_t> imu_count;
  std::map<int, std::map<std::string, double>> imu_first, imu_last;
  std::map<std::string, double> params;
};

Reference reference_of(const fs::path& file) {
  Reference r;
  std::ifstream in(file.string() + ".reference.txt");
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string kind;
    s >> kind;
    if (kind == "type") {
      std::string name;
      Reference::Type t;
      s >> name >> t.count >> t.first >> t.last;
      r.types[name] = t;
    } else if (kind == "imu") {
      int instance = 0;
      s >> instance >> r.imu_count[instance];
    } else if (kind == "imu_first" || kind == "imu_last") {
      int instance = 0;
      std::string column, value;
      s >> instance >> column >> value;
      (kind == "imu_first" ? r.imu_first : r.imu_last)[instance][column] = std::stod(value);
    } else if (kind == "param") {
      std::string name, value;
      s >> name >> value;
      r.params[name] = std::stod(value);
    }
  }
  return r;
}

// --- the real logs, against pymavlink's DFReader -----------------------------------------------

class DataflashFixture : public ::testing::TestWithParam<Fixture> {
 protected:
  fs::path path() const { return logs_dir() / GetParam().dir / GetParam().file; }
};

TEST_P(DataflashFixture, EveryMessageTypeCountAndTimeSpanIsDfReaders) {
  const Reference ref = reference_of(path());
  ASSERT_FALSE(ref.types.empty()) << "no reference for " << path();
  const auto log = dataflash::read(path());
  std::size_t with_messages = 0;
  for (const auto& t : log.types) with_messages += t.count > 0;
  EXPECT_EQ(with_messages, ref.types.size()) << "types with messages";
  for (const auto& [name, expected] : ref.types) {
    SCOPED_TRACE(name);
    const auto* t = log.find(name);
    ASSERT_NE(t, nullptr);
    EXPECT_EQ(t->count, expected.count);
    if (expected.first == "None") {
      EXPECT_FALSE(t->timed);
    } else {
      ASSERT_TRUE(t->timed);
      EXPECT_EQ(t->first_time_us, std::stoull(expected.first));
      EXPECT_EQ(t->last_time_us, std::stoull(expected.last));
    }
  }
}

// DFReader's logged (body-frame) value of an axis in the sensor frame the record holds, for the
// fixtures' board rotations: AHRS_ORIENTATION 0 (none) and 8 (ROTATION_ROLL_180: ArduPilot's
// Vector3::rotate makes y and z -y and -z, its own inverse).
double sensor_frame(double ahrs_orientation, char axis, double logged) {
  if (ahrs_orientation == 0.0 || axis == 'X') return logged;
  if (ahrs_orientation == 8.0) return -logged;
  ADD_FAILURE() << "no hand-written inverse for AHRS_ORIENTATION " << ahrs_orientation;
  return logged;
}

TEST_P(DataflashFixture, EachImuInstanceHasDfReadersCountFirstAndLastValuesAndDeviceIds) {
  const Reference ref = reference_of(path());
  ASSERT_FALSE(ref.imu_count.empty());
  const double orientation = ref.params.at("AHRS_ORIENTATION");
  for (const auto& [instance, count] : ref.imu_count) {
    SCOPED_TRACE("instance " + std::to_string(instance));
    LogSelection one;
    one.instance = instance;
    std::vector<std::string> notes;
    const TimeSeries record = dataflash::read_imu(path(), one, &notes);
    const std::string suffix = instance == 0 ? "" : std::to_string(instance);
    ASSERT_EQ(static_cast<std::uint64_t>(record.size()), count) << ::testing::PrintToString(notes);
    for (const auto& [which, values] :
         {std::pair{0, ref.imu_first.at(instance)}, std::pair{-1, ref.imu_last.at(instance)}}) {
      const Eigen::Index i = which == 0 ? 0 : record.size() - 1;
      EXPECT_NEAR(record.time()[i], values.at("TimeUS") * kSecondsPerMicrosecond, kTimeTolerance);
      const char* axes = "XYZ";
      for (int a = 0; a < 3; ++a) {
        const std::string axis(1, static_cast<char>(std::tolower(axes[a])));
        EXPECT_EQ(record.channel("gyro" + suffix + "_" + axis).values[i],
                  sensor_frame(orientation, axes[a], values.at(std::string("Gyr") + axes[a])));
        EXPECT_EQ(record.channel("accel" + suffix + "_" + axis).values[i],
                  sensor_frame(orientation, axes[a], values.at(std::string("Acc") + axes[a])));
      }
      EXPECT_EQ(record.channel("temperature" + suffix).values[i], values.at("T"));
    }
    EXPECT_EQ(record.channel("gyro" + suffix + "_z").unit, "rad/s");
    EXPECT_EQ(record.channel("accel" + suffix + "_z").unit, "m/s^2");
    const std::string id_name = "INS_GYR" + (instance == 0 ? std::string() : std::to_string(instance + 1)) + "_ID";
    EXPECT_EQ(record.device_id(instance), std::to_string(static_cast<std::uint64_t>(ref.params.at(id_name))));
  }
}

TEST_P(DataflashFixture, TheFirstLoggedParametersAreDfReaders) {
  const Reference ref = reference_of(path());
  const auto log = dataflash::read(path());
  for (const auto& [name, value] : ref.params) EXPECT_EQ(log.parameter(name), value) << name;
}

TEST_P(DataflashFixture, TheWholeImuRecordHasEveryInstanceAndReadsThroughTheRegistry) {
  const Reference ref = reference_of(path());
  ASSERT_EQ(sniff_record_format(path()), RecordFormat::DataFlash);
  CsvReadOptions options;
  options.required_roles = {};
  options.max_gap_factor = 0.0;
  std::vector<std::string> notes;
  const TimeSeries record = read_record(path(), options, {}, &notes);
  for (const auto& [instance, count] : ref.imu_count) {
    const std::string suffix = instance == 0 ? "" : std::to_string(instance);
    for (const char* role : {"gyro", "accel"})
      for (const char* axis : {"_x", "_y", "_z"})
        EXPECT_TRUE(record.has(role + suffix + axis)) << role << suffix << axis;
    EXPECT_TRUE(record.has("temperature" + suffix));
  }
  EXPECT_EQ(static_cast<std::uint64_t>(record.size()), ref.imu_count.begin()->second);  // instances share time stamps
}

INSTANTIATE_TEST_SUITE_P(RealLogs, DataflashFixture, ::testing::ValuesIn(kFixtures), [](const auto& test) {
  std::string name = test.param.dir;
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
});

TEST(DataflashRealLogs, TheNewFormatLogHasUnitsMultipliersAndAnInstanceColumn) {
  const auto log = dataflash::read(logs_dir() / "methodic-configurator" / "backend_log_80k.bin");
  const auto* imu = log.find("IMU");
  ASSERT_NE(imu, nullptr);
  const auto& c = imu->columns;
  EXPECT_EQ(c[*imu->column_index("I")].unit_id, '#');
  EXPECT_EQ(c[*imu->column_index("GyrX")].unit, "rad/s");
  EXPECT_EQ(c[*imu->column_index("AccZ")].unit, "m/s/s");
  EXPECT_EQ(c[*imu->column_index("T")].unit, "degC");
  EXPECT_EQ(c[*imu->column_index("TimeUS")].unit, "s");
  EXPECT_EQ(c[*imu->column_index("TimeUS")].multiplier, 1e-6);
  // The file is the first 80 KiB of a longer log: it ends within a message, which is left out.
  EXPECT_EQ(log.truncated_bytes, 2u);
  EXPECT_EQ(log.skipped_bytes, 0u);
}

TEST(DataflashRealLogs, CutAtManyOffsetsEachReadIsAPrefixOrADataErrorNamingTheOffset) {
  const std::string bytes = read_file(logs_dir() / "methodic-configurator" / "backend_log_80k.bin");
  const auto full = dataflash::parse(bytes, "full.bin");
  // Offsets through the FMT block, the parameters and the data, 331 bytes apart (prime: every phase).
  for (std::size_t cut = 0; cut < bytes.size(); cut += 331) {
    SCOPED_TRACE(cut);
    try {
      const auto log =
          dataflash::parse(std::string_view(bytes).substr(0, cut), "cut.bin", {false, dataflash::imu_types()});
      EXPECT_LE(log.messages, full.messages);
      EXPECT_LT(log.truncated_bytes, 256u);
      for (const auto& t : log.types)
        if (const auto* f = full.find(t.name)) {
          EXPECT_LE(t.count, f->count);
        }
      const auto reason = error_of([&] { dataflash::imu_record(log, {}); });
      EXPECT_THAT(reason, ::testing::AnyOf(HasSubstr("no error"), HasSubstr("DataError: cut.bin")));
    } catch (const DataError& e) {
      EXPECT_THAT(e.what(), AllOf(HasSubstr("cut.bin"), HasSubstr("byte 0")));
      EXPECT_LT(cut, 89u) << "only a file without one complete message is refused";
    }
  }
}

// --- structure ---------------------------------------------------------------------------------

std::string small_log(int samples) {
  Writer w;
  df::define_imu_log(w);
  w.message(df::kUnit, {0.0, double('E'), std::string("rad/s")})
      .message(df::kUnit, {0.0, double('O'), std::string("degC")});
  w.message(df::kMult, {0.0, double('F'), 1e-6});
  w.message(df::kFmtu, {0.0, double(df::kImu), std::string("s#EEEnnn--O----"), std::string("F-000000-0-----")});
  df::parm(w, 1000, "INS_GYR_ID", 2621706).message(df::kParm, {1000.0, std::string("INS_ACC2_ID"), 2688010.0, 0.0});
  for (int i = 0; i < samples; ++i) {
    const double t = 2000000 + 2500.0 * i;
    df::imu(w, t, 0, 0.01 * i, -0.01, 0.5, 0.1, 0.2, -9.8, 40.0 + 0.01 * i);
    df::imu(w, t, 1, -0.01 * i, 0.02, 0.25, 0.3, 0.4, -9.7, 30.0 + 0.01 * i);
  }
  return w.bytes();
}

TEST(DataflashStructure, FormatCharactersDecodeAsTheTableSays) {
  Writer w;
  // A format holds at most 16 characters: two types.
  w.fmt(90, "NUM", "QbBhHiIqfdcCeELM", "TimeUS,b,B,h,H,i,I,q,f,d,c,C,e,E,L,M");
  w.fmt(91, "TXT", "QgnNZa", "TimeUS,g,n,N,Z,a");
  w.message(90, {7.0, -5.0, 250.0, -30000.0, 60000.0, -2e9, 4e9, -5e12, 0.25, 1e300, -1234.0, 6553.0, -2e8, 4e9,
                 -35.1332423, 3.0});
  w.message(91, {8.0, -1.5, std::string("abcd"), std::string("sixteen-chars-ok"), std::string("zed"), std::string()});
  dataflash::ReadOptions keep;
  keep.keep_all = true;
  const auto log = dataflash::parse(w.bytes(), "all.bin", keep);
  const auto* num = log.find("NUM");
  const auto* txt = log.find("TXT");
  ASSERT_TRUE(num && txt);
  EXPECT_EQ(num->length, 3u + 8 + 1 + 1 + 2 + 2 + 4 + 4 + 8 + 4 + 8 + 2 + 2 + 4 + 4 + 4 + 1);
  EXPECT_EQ(txt->length, 3u + 8 + 2 + 4 + 16 + 64 + 64);
  const std::map<std::string, double> expected{{"b", -5},    {"B", 250},         {"h", -30000}, {"H", 60000},
                                               {"i", -2e9},  {"I", 4e9},         {"q", -5e12},  {"f", 0.25},
                                               {"d", 1e300}, {"c", -12.34},      {"C", 65.53},  {"e", -2e6},
                                               {"E", 4e7},   {"L", -35.1332423}, {"M", 3}};
  for (const auto& [column, value] : expected) EXPECT_DOUBLE_EQ(num->column(column).front(), value) << column;
  EXPECT_EQ(txt->column("g").front(), -1.5);
  EXPECT_EQ(num->time_us, std::vector<std::uint64_t>{7});
  EXPECT_FALSE(txt->columns[*txt->column_index("Z")].numeric());
  EXPECT_THAT(error_of([&] { txt->column("N"); }), HasSubstr("holds text"));
}

TEST(DataflashStructure, FmtuUnitMultAndParametersAreRead) {
  const auto log = dataflash::parse(small_log(3), "small.bin");
  const auto* imu = log.find("IMU");
  ASSERT_NE(imu, nullptr);
  EXPECT_EQ(imu->count, 6u);
  EXPECT_EQ(imu->columns[0].multiplier, 1e-6);
  EXPECT_EQ(imu->columns[1].unit_id, '#');
  EXPECT_EQ(imu->columns[2].unit, "rad/s");
  EXPECT_EQ(imu->columns[10].unit, "degC");
  EXPECT_FALSE(imu->columns[3].multiplier.has_value());  // '0' has no MULT in this log
  EXPECT_EQ(log.parameter("INS_GYR_ID"), 2621706.0);
  EXPECT_EQ(log.parameter("INS_NOT_THERE"), std::nullopt);
  ASSERT_EQ(log.parameters.size(), 2u);
  EXPECT_EQ(log.parameters[1].time_us, 1000u);
}

TEST(DataflashStructure, OldLogsTimedInMillisecondsWithImu2AreInstances) {
  Writer w;
  w.fmt(70, "IMU", "Iffffff", "TimeMS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ")
      .fmt(71, "IMU2", "Iffffff", "TimeMS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ");
  for (int i = 0; i < 5; ++i) {
    w.message(70, {1000.0 + 20 * i, 0.1, 0.2, 0.3, 1.0, 2.0, -9.0});
    w.message(71, {1000.0 + 20 * i, -0.1, -0.2, -0.3, -1.0, -2.0, -9.5});
  }
  std::vector<std::string> notes;
  const auto record =
      dataflash::imu_record(dataflash::parse(w.bytes(), "old.bin", {false, dataflash::imu_types()}), {}, &notes);
  EXPECT_EQ(record.size(), 5);
  EXPECT_NEAR(record.time()[1], 1.02, kTimeTolerance);
  EXPECT_FLOAT_EQ(static_cast<float>(record.channel("gyro1_z").values[0]), -0.3f);
  EXPECT_FALSE(record.has("temperature"));
  EXPECT_THAT(::testing::PrintToString(notes), HasSubstr("IMU: no temperature column T"));
}

TEST(DataflashStructure, GarbageBetweenMessagesIsSkippedAndCountedLikeArduPilotsReaders) {
  const std::string clean = small_log(4);
  // Garbage after the definitions: zeros, a stray header of a type no FMT defines, text.
  const std::size_t cut = clean.find(std::string("\xA3\x95") + static_cast<char>(df::kParm));
  const std::string junk = std::string(7, '\0') + "\xA3\x95\x07" + "junk";
  std::string dirty = clean.substr(0, cut) + junk + clean.substr(cut);
  dirty += "\xA3\x95";  // and a header cut off by the end of the file
  const auto log = dataflash::parse(dirty, "dirty.bin", {false, dataflash::imu_types()});
  EXPECT_EQ(log.skipped_bytes, junk.size());
  EXPECT_EQ(log.skipped_runs, 1u);
  EXPECT_EQ(log.first_skip_offset, cut);
  ASSERT_EQ(log.unknown_types.count(7), 1u);
  EXPECT_EQ(log.unknown_types.at(7).first_offset, cut + 7);
  EXPECT_EQ(log.truncated_bytes, 2u);
  const auto clean_log = dataflash::parse(clean, "clean.bin", {false, dataflash::imu_types()});
  EXPECT_EQ(log.find("IMU")->count, clean_log.find("IMU")->count);
  EXPECT_EQ(log.find("IMU")->column("GyrX"), clean_log.find("IMU")->column("GyrX"));
}

TEST(DataflashStructure, OutOfOrderAndRepeatedTimeStampsAreSortedAndDroppedWithNotes) {
  Writer w;
  df::define_imu_log(w);
  for (const double t : {1000.0, 3000.0, 2000.0, 3000.0, 4000.0}) df::imu(w, t, 0, t * 1e-6, 0, 0, 0, 0, -9.8, 25);
  std::vector<std::string> notes;
  const auto record =
      dataflash::imu_record(dataflash::parse(w.bytes(), "order.bin", {false, dataflash::imu_types()}), {}, &notes);
  ASSERT_EQ(record.size(), 4);
  EXPECT_FLOAT_EQ(static_cast<float>(record.channel("gyro_x").values[1]), 2000.0f * 1e-6f);
  EXPECT_THAT(::testing::PrintToString(notes),
              AllOf(HasSubstr("IMU I=0: 1 samples earlier than the one before; sorted"),
                    HasSubstr("IMU I=0: 1 repeated time stamps")));
}

// --- the firmware's temperature correction (INS_TCALn) ----------------------------------------

// A log recorded with INS_TCAL1_ENABLE = 1: the IMU values are what the firmware wrote, i.e. the
// raw values (known here) minus its correction, computed independently below from the equation of
// AP_InertialSensor_tempcal.cpp.
struct TcalLog {
  std::string bytes;
  std::vector<double> temperature, raw_gyro_x, raw_accel_z;
};

// body = R sensor for the board rotation the log is written with.
using BodyFromSensor = std::function<std::array<double, 3>(std::array<double, 3>)>;
std::array<double, 3> unrotated(std::array<double, 3> v) { return v; }

TcalLog tcal_log(double enable, double orientation, const BodyFromSensor& to_body = unrotated) {
  const double tmin = 20, tmax = 60, gyro_cal = 30, accel_cal = -300;  // accel offsets never calibrated
  const double g1 = 1000, g2 = -20, g3 = 0.5;                          // INS_TCAL1_GYRk_X (x 1e6)
  const double a1 = 40000, a2 = 300, a3 = -2;                          // INS_TCAL1_ACCk_Z (x 1e6)
  auto p = [](double c1, double c2, double c3, double t) {
    const double d = t - 35.0;
    return (c1 * d + c2 * d * d + c3 * d * d * d) * 1e-6;
  };
  auto clamp = [&](double t) { return std::min(std::max(t, tmin), tmax); };
  Writer w;
  df::define_imu_log(w);
  df::parm(w, 0, "INS_TCAL1_ENABLE", enable);
  df::parm(w, 0, "INS_TCAL1_TMIN", tmin);
  df::parm(w, 0, "INS_TCAL1_TMAX", tmax);
  df::parm(w, 0, "INS_GYR1_CALTEMP", gyro_cal);
  df::parm(w, 0, "INS_ACC1_CALTEMP", accel_cal);
  df::parm(w, 0, "AHRS_ORIENTATION", orientation);
  for (const char* sensor : {"GYR", "ACC"})
    for (int k = 1; k <= 3; ++k)
      for (const char* axis : {"X", "Y", "Z"}) {
        const std::string name = std::string("INS_TCAL1_") + sensor + std::to_string(k) + "_" + axis;
        double v = 0;
        if (std::string(sensor) == "GYR" && std::string(axis) == "X") v = k == 1 ? g1 : k == 2 ? g2 : g3;
        if (std::string(sensor) == "ACC" && std::string(axis) == "Z") v = k == 1 ? a1 : k == 2 ? a2 : a3;
        df::parm(w, 0, name, v);
      }
  TcalLog out;
  for (int i = 0; i < 50; ++i) {
    const double t = 10.0 + 1.2 * i;  // 10 to 68.8 degC: below TMIN and above TMAX too
    const double raw_g = 0.002 + 1e-5 * i, raw_a = -9.81 + 1e-3 * i;
    const float logged_g = static_cast<float>(raw_g - p(g1, g2, g3, clamp(t)) + p(g1, g2, g3, clamp(gyro_cal)));
    const float logged_a = static_cast<float>(raw_a - p(a1, a2, a3, clamp(t)) + p(a1, a2, a3, clamp(accel_cal)));
    // The firmware corrects in the sensor frame, then rotates into the body frame, then logs.
    const auto g = to_body({enable == 1 ? logged_g : raw_g, 0.001, 0.002});
    const auto a = to_body({0.1, 0.2, enable == 1 ? logged_a : raw_a});
    df::imu(w, 1e6 + 1e4 * i, 0, g[0], g[1], g[2], a[0], a[1], a[2], t);
    out.temperature.push_back(static_cast<float>(t));
    out.raw_gyro_x.push_back(raw_g);
    out.raw_accel_z.push_back(raw_a);
  }
  out.bytes = w.bytes();
  return out;
}

constexpr double kFloatLogged = 1e-6;  // the firmware logs float: ~1e-7 relative of |9.81|

TEST(DataflashTemperatureCalibration, ALogRecordedWithTcalOnGivesTheRawValuesBack) {
  const TcalLog log = tcal_log(1, 0);
  std::vector<std::string> notes;
  const auto record =
      dataflash::imu_record(dataflash::parse(log.bytes, "tcal.bin", {false, dataflash::imu_types()}), {}, &notes);
  ASSERT_EQ(record.size(), 50);
  for (Eigen::Index i = 0; i < record.size(); ++i) {
    EXPECT_NEAR(record.channel("gyro_x").values[i], log.raw_gyro_x[static_cast<std::size_t>(i)], kFloatLogged) << i;
    EXPECT_NEAR(record.channel("accel_z").values[i], log.raw_accel_z[static_cast<std::size_t>(i)], kFloatLogged) << i;
  }
  EXPECT_THAT(::testing::PrintToString(notes),
              AllOf(HasSubstr("INS_TCAL1_ENABLE=1"), HasSubstr("removed"), HasSubstr("tempcal_IMU.py")));
}

TEST(DataflashTemperatureCalibration, TheCorrectionIsThePolynomialOfTheFirmware) {
  dataflash::TemperatureCalibration t;
  t.enable = 1;
  t.tmin = 20;
  t.tmax = 60;
  t.gyro[0][1] = 1e6;  // 1 (rad/s)/degC on y
  t.gyro_cal_temp = 35;
  EXPECT_DOUBLE_EQ(dataflash::firmware_correction(t, imu::Sensor::Gyro, 1, 45), 10.0);  // (45-35) - 0
  EXPECT_DOUBLE_EQ(dataflash::firmware_correction(t, imu::Sensor::Gyro, 1, 80), 25.0);  // clamped to 60
  EXPECT_DOUBLE_EQ(dataflash::firmware_correction(t, imu::Sensor::Gyro, 0, 80), 0.0);   // no x coefficient
  t.gyro_cal_temp = -300;                                                               // clamped to TMIN
  EXPECT_DOUBLE_EQ(dataflash::firmware_correction(t, imu::Sensor::Gyro, 1, 35), 15.0);
}

TEST(DataflashTemperatureCalibration, NotRemovedWhenDisabled) {
  const TcalLog off = tcal_log(0, 0);
  std::vector<std::string> notes;
  const auto raw =
      dataflash::imu_record(dataflash::parse(off.bytes, "off.bin", {false, dataflash::imu_types()}), {}, &notes);
  EXPECT_EQ(raw.channel("gyro_x").values[3], static_cast<float>(off.raw_gyro_x[3]));
  EXPECT_THAT(::testing::PrintToString(notes), ::testing::Not(HasSubstr("TCAL")));
}

// --- board orientation (AHRS_ORIENTATION) -------------------------------------------------------

// A rotated board: the log holds body-frame values; the record gives the sensor frame back and
// removes the firmware's correction there. The rotations below are ArduPilot's Vector3::rotate
// cases written out (AP_Math/vector3.cpp), not the reader's matrices.
TEST(DataflashBoardOrientation, ARotatedBoardsBodyFrameValuesComeBackInTheSensorFrameWithTcalRemoved) {
  constexpr double kHalfSqrt2 = 0.70710678118654757;
  const std::pair<double, BodyFromSensor> boards[] = {
      {8,
       [](std::array<double, 3> v) {
         return std::array<double, 3>{v[0], -v[1], -v[2]};
       }},  // ROLL_180
      {1,
       [&](std::array<double, 3> v) {  // YAW_45
         return std::array<double, 3>{kHalfSqrt2 * (v[0] - v[1]), kHalfSqrt2 * (v[0] + v[1]), v[2]};
       }},
      {42,
       [&](std::array<double, 3> v) {  // ROLL_45
         return std::array<double, 3>{v[0], kHalfSqrt2 * (v[1] - v[2]), kHalfSqrt2 * (v[1] + v[2])};
       }},
  };
  for (const auto& [orientation, to_body] : boards) {
    SCOPED_TRACE(orientation);
    const TcalLog log = tcal_log(1, orientation, to_body);
    std::vector<std::string> notes;
    const auto record =
        dataflash::imu_record(dataflash::parse(log.bytes, "rot.bin", {false, dataflash::imu_types()}), {}, &notes);
    ASSERT_EQ(record.size(), 50);
    for (Eigen::Index i = 0; i < record.size(); ++i) {
      const auto k = static_cast<std::size_t>(i);
      EXPECT_NEAR(record.channel("gyro_x").values[i], log.raw_gyro_x[k], kFloatLogged) << i;
      EXPECT_NEAR(record.channel("gyro_y").values[i], 0.001, kFloatLogged) << i;
      EXPECT_NEAR(record.channel("gyro_z").values[i], 0.002, kFloatLogged) << i;
      EXPECT_NEAR(record.channel("accel_x").values[i], 0.1, kFloatLogged) << i;
      EXPECT_NEAR(record.channel("accel_y").values[i], 0.2, kFloatLogged) << i;
      EXPECT_NEAR(record.channel("accel_z").values[i], log.raw_accel_z[k], kFloatLogged) << i;
    }
    EXPECT_THAT(::testing::PrintToString(notes),
                AllOf(HasSubstr("body frame"), HasSubstr("sensor frame"), HasSubstr("removed (TMIN")));
  }
}

// pymavlink's rotmat (Vector3.rotate_by_id / rotate_by_inverse_id, the table tempcal_IMU.py uses)
// applied to (1, 2, 3): tests/data/logs/pymavlink-rotations/rotations_reference.txt.
TEST(DataflashBoardOrientation, EveryFixedRotationIsPymavlinksExceptWherePymavlinkDiffersFromTheFirmware) {
  std::ifstream in(logs_dir() / "pymavlink-rotations" / "rotations_reference.txt");
  ASSERT_TRUE(in) << "no rotations_reference.txt";
  constexpr double kRounding = 1e-12;  // pymavlink rounds through float64 trigonometry of 90-deg multiples
  std::string line;
  int rows = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream row(line);
    int id = 0;
    std::string name;
    double body[3], sensor[3];
    row >> id >> name >> body[0] >> body[1] >> body[2] >> sensor[0] >> sensor[1] >> sensor[2];
    ASSERT_FALSE(row.fail()) << line;
    ++rows;
    const auto r = dataflash::board_rotation(id);
    ASSERT_TRUE(r) << id;
    EXPECT_EQ(r->name, name);
    if (id == 38) continue;  // pymavlink has (90, 68, 270) deg; the firmware (90, 68.8, 293.3): checked below
    const double v[3] = {1, 2, 3};
    for (int a = 0; a < 3; ++a) {
      const auto& m = r->body_from_sensor;
      EXPECT_NEAR(m[a][0] * v[0] + m[a][1] * v[1] + m[a][2] * v[2], body[a], kRounding) << name << " axis " << a;
      EXPECT_NEAR(m[0][a] * v[0] + m[1][a] * v[1] + m[2][a] * v[2], sensor[a], kRounding) << name << " axis " << a;
    }
  }
  EXPECT_EQ(rows, 42);  // pymavlink's table ends at 41 (ROTATION_PITCH_7)
}

TEST(DataflashBoardOrientation, TheFirmwaresOwnRotationsBeyondPymavlinksTableAndExactQuarterTurns) {
  // ROTATION_ROLL_90_PITCH_68_YAW_293: the firmware's test (AP_Math/tests/test_rotations.cpp)
  // checks it against from_euler(90, 68.8, 293.3); rows of that matrix, computed here directly.
  const double d = std::numbers::pi / 180, sp = std::sin(68.8 * d), cp = std::cos(68.8 * d), sy = std::sin(293.3 * d),
               cy = std::cos(293.3 * d);
  const std::array<std::array<double, 3>, 3> m38 = {{{cp * cy, sp * cy, sy}, {cp * sy, sp * sy, -cy}, {-sp, cp, 0}}};
  const auto r38 = dataflash::board_rotation(38);
  ASSERT_TRUE(r38);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(r38->body_from_sensor[i][j], m38[i][j], kRotationTolerance) << i << j;
  // ROTATION_ROLL_315 (43): Vector3::rotate gives y' = s (y + z), z' = s (z - y), s = sqrt(2)/2.
  const auto r43 = dataflash::board_rotation(43);
  ASSERT_TRUE(r43);
  EXPECT_EQ(r43->name, "ROTATION_ROLL_315");
  EXPECT_NEAR(r43->body_from_sensor[1][1], std::sqrt(0.5), kRotationTolerance);
  EXPECT_NEAR(r43->body_from_sensor[1][2], std::sqrt(0.5), kRotationTolerance);
  EXPECT_NEAR(r43->body_from_sensor[2][1], -std::sqrt(0.5), kRotationTolerance);
  // Quarter turns are exact: the record of a ROLL_180 board is the logged value with its sign flipped.
  const auto r8 = dataflash::board_rotation(8);
  ASSERT_TRUE(r8);
  const std::array<std::array<double, 3>, 3> roll_180 = {{{1, 0, 0}, {0, -1, 0}, {0, 0, -1}}};
  EXPECT_EQ(r8->body_from_sensor, roll_180);
  for (const double not_fixed : {44.0, 100.0, 101.0, 2.5, -1.0, 1e300})
    EXPECT_FALSE(dataflash::board_rotation(not_fixed)) << not_fixed;
}

TEST(DataflashBoardOrientation, ACustomOrUnknownRotationIsADataErrorNamingTheParameter) {
  for (const double orientation : {100.0, 101.0, 57.0}) {
    SCOPED_TRACE(orientation);
    const TcalLog log = tcal_log(0, orientation);
    try {
      dataflash::imu_record(dataflash::parse(log.bytes, "custom.bin", {false, dataflash::imu_types()}), {});
      ADD_FAILURE() << "no error";
    } catch (const DataError& e) {
      EXPECT_THAT(e.what(), AllOf(HasSubstr("custom.bin"), HasSubstr("AHRS_ORIENTATION"), HasSubstr("body frame"),
                                  HasSubstr("0..43")));
    }
  }
}

// --- bad input ---------------------------------------------------------------------------------

TEST(DataflashBadInput, ASmallLogCutAtEveryOffsetIsAPrefixOrADataError) {
  const std::string bytes = small_log(20);
  for (std::size_t cut = 0; cut <= bytes.size(); ++cut) {
    SCOPED_TRACE(cut);
    const auto reason = error_of([&] {
      const auto log =
          dataflash::parse(std::string_view(bytes).substr(0, cut), "cut.bin", {false, dataflash::imu_types()});
      dataflash::imu_record(log, {});
    });
    if (reason != "no error") {
      EXPECT_THAT(reason, HasSubstr("DataError: cut.bin"));
    }
  }
}

TEST(DataflashBadInput, CorruptFmtMessagesAreDataErrorsNamingTheOffset) {
  const std::size_t fmt_size = Writer().bytes().size();  // the FMT of FMT: the next FMT starts here
  const std::string at = "byte " + std::to_string(fmt_size);
  const std::map<std::string, std::function<void(Writer&)>> cases{
      {"unknown format character 'z'", [](Writer& w) { w.fmt(70, "BAD", "Qz", "TimeUS,Z", 20); }},
      {"Length 20 differs from the 15 bytes", [](Writer& w) { w.fmt(70, "BAD", "Qf", "TimeUS,F", 20); }},
      {"1 column names for the 2 format characters", [](Writer& w) { w.fmt(70, "BAD", "Qf", "TimeUS"); }},
      {"the name is empty or not printable", [](Writer& w) { w.fmt(70, "", "Qf", "TimeUS,F"); }},
      {"FMT redefines itself", [](Writer& w) { w.fmt(Writer::kFmt, "FMT", "BBnN", "Type,Length,Name,Format"); }},
  };
  for (const auto& [expected, write] : cases) {
    Writer w;
    write(w);
    EXPECT_THAT(error_of([&] { dataflash::parse(w.bytes(), "bad.bin"); }),
                AllOf(HasSubstr("bad.bin"), HasSubstr(at), HasSubstr(expected)));
  }
  Writer redefined;
  redefined.fmt(70, "AAA", "Qf", "TimeUS,F").message(70, {1.0, 2.0}).fmt(70, "BBB", "Qff", "TimeUS,F,G");
  EXPECT_THAT(error_of([&] { dataflash::parse(redefined.bytes(), "bad.bin"); }),
              AllOf(HasSubstr("redefines type 70 ('AAA'"), HasSubstr("after 1 messages")));
  Writer before_messages;  // a redefinition before any message of the type is accepted
  before_messages.fmt(70, "AAA", "Qf", "TimeUS,F").fmt(70, "BBB", "Qff", "TimeUS,F,G").message(70, {1.0, 2.0, 3.0});
  EXPECT_EQ(dataflash::parse(before_messages.bytes(), "ok.bin").find("BBB")->count, 1u);
}

TEST(DataflashBadInput, NotADataflashFileOrNoCompleteMessageIsADataError) {
  EXPECT_THAT(error_of([] { dataflash::parse("t_s,rate\n0,1\n", "x.csv"); }),
              AllOf(HasSubstr("x.csv"), HasSubstr("byte 0"), HasSubstr("not an ArduPilot DataFlash log")));
  EXPECT_THAT(error_of([] { dataflash::parse(Writer().bytes().substr(0, 50), "cut.bin"); }),
              AllOf(HasSubstr("byte 0"), HasSubstr("ends before its first message is complete")));
  EXPECT_THAT(error_of([] { dataflash::read("/no/such/log.bin"); }), HasSubstr("does not exist"));
}

TEST(DataflashBadInput, MissingImuUnknownTypesAndBadSelectionsAreNamed) {
  Writer w;
  df::define_imu_log(w);
  df::parm(w, 0, "INS_GYR_ID", 1);
  w.raw(std::string("\xA3\x95\x09", 3) + std::string(60, 'x'));  // IMU data whose FMT was lost
  const auto log = dataflash::parse(w.bytes(), "noimu.bin", {false, dataflash::imu_types()});
  EXPECT_THAT(
      error_of([&] { dataflash::imu_record(log, {}); }),
      AllOf(HasSubstr("noimu.bin"), HasSubstr("no IMU messages"), HasSubstr("without an FMT, the first (9) at byte")));

  const auto small = dataflash::parse(small_log(5), "small.bin", {false, dataflash::imu_types()});
  LogSelection topic;
  topic.topic = "sensor_gyro";
  EXPECT_THAT(error_of([&] { dataflash::imu_record(small, topic); }),
              AllOf(HasSubstr("ConfigError"), HasSubstr("--topic")));
  LogSelection instance;
  instance.instance = 4;
  EXPECT_THAT(error_of([&] { dataflash::imu_record(small, instance); }),
              AllOf(HasSubstr("DataError: small.bin"),
                    HasSubstr("it has: IMU I=0 gyro, IMU I=0 accel, IMU I=1 gyro, IMU I=1 accel")));

  Writer nan;
  df::define_imu_log(nan);
  for (int i = 0; i < 3; ++i) df::imu(nan, 1000.0 * (i + 1), 0, i == 1 ? NAN : 0.1, 0, 0, 0, 0, -9.8, 25);
  EXPECT_THAT(error_of([&] {
                dataflash::imu_record(dataflash::parse(nan.bytes(), "nan.bin", {false, dataflash::imu_types()}), {});
              }),
              AllOf(HasSubstr("nan.bin"), HasSubstr("non-finite value at time stamp 2000 us")));
}

TEST(DataflashRecordReader, ChoosesByContentAndAppliesColumnMappings) {
  const auto path = write_temp("imu.csv", small_log(40));  // a DataFlash log, whatever its name
  EXPECT_EQ(sniff_record_format(path), RecordFormat::DataFlash);
  CsvReadOptions options;
  options.columns = {parse_column_mapping("rate=gyro1_z"), parse_column_mapping("temperature=temperature1")};
  options.required_roles = {"rate"};
  const auto record = read_record(path, options);
  EXPECT_EQ(record.channels().size(), 2u);
  EXPECT_FLOAT_EQ(static_cast<float>(record.channel("rate").values[0]), 0.25f);
  EXPECT_EQ(record.device_id(0), "2621706");
  EXPECT_EQ(record.device_id(1), "2688010");  // no INS_GYR2_ID in the log: the accelerometer's INS_ACC2_ID
}

}  // namespace
}  // namespace driftlab
