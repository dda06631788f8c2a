// MRPT rawlogs through the reader registry (framework/rawlog.hpp): chosen by content, gzip'ed or
// plain, and read by every record-reading command -- log info, log export, calibrate, compensate,
// allan, run, discrepancy -- exactly as the same record read from CSV. The rawlog is written by
// MRPT's own serializer (`driftlab mrpt export`) from a simulated whole-IMU oven run; its truth is
// the CSV it was written from. Without MRPT every test is skipped.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "framework/csv.hpp"
#include "framework/record_reader.hpp"
#include "tests/tools/cli_harness.hpp"

#if DRIFTLAB_HAVE_MRPT
#include <zlib.h>
#endif

#define SKIP_WITHOUT_MRPT() \
  if (!DRIFTLAB_HAVE_MRPT) GTEST_SKIP() << "built without MRPT (libmrpt-obs-dev): rawlogs are not read"

namespace driftlab {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using namespace testing_cli;

// The bridge's CSV names (tools/mrpt/rawlog_io.hpp) of the fields a 3-axis IMU carries, and the
// record role each becomes.
const std::pair<const char*, const char*> kBridgeColumns[] = {
    {"rate_rps", "gyro_z"},    {"wx_rps", "gyro_x"},      {"wy_rps", "gyro_y"},     {"acc_x_mps2", "accel_x"},
    {"acc_y_mps2", "accel_y"}, {"acc_z_mps2", "accel_z"}, {"temp_c", "temperature"}};

struct Fixture {
  fs::path dir, rawlog, truth;  // the rawlog and the record it holds (instance 0 of a simulated imu3 run)
};

fs::path& fixture_dir() {  // set once the fixture is made
  static fs::path dir;
  return dir;
}

// Simulates the imu3 oven run (1 Hz, 16 200 samples), takes instance 0 and writes it as a rawlog
// through `driftlab mrpt export` (whole seconds: MRPT's 100-ns ticks hold them exactly).
const Fixture& fixture() {
  static const Fixture f = [] {
    Fixture out;
    out.dir = fixture_dir() = scratch_dir("rawlog_record");
    const auto sim = out.dir / "imu3.csv";
    const auto s = run_driftlab("simulate --device " + std::string(DRIFTLAB_SOURCE_DIR) +
                                "/devices/imu3.yaml --fs 1 --seed 1 --out " + sim.string());
    EXPECT_EQ(s.exit_code, 0) << s.err;
    CsvReadOptions options;
    options.required_roles = {"gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z", "temperature"};
    const TimeSeries record = read_csv(sim, options);
    out.truth = out.dir / "bridge.csv";
    {
      std::ofstream csv(out.truth);
      csv << "t_s";
      for (const auto& [column, role] : kBridgeColumns) csv << "," << column;
      csv << "\n";
      char cell[64];
      for (Eigen::Index i = 0; i < record.size(); ++i) {
        std::snprintf(cell, sizeof cell, "%.17g", record.time()[i]);
        csv << cell;
        for (const auto& [column, role] : kBridgeColumns) {
          std::snprintf(cell, sizeof cell, ",%.17g", record.channel(role).values[i]);
          csv << cell;
        }
        csv << "\n";
      }
    }
    out.rawlog = out.dir / "imu.rawlog";
    const auto e = run_driftlab("mrpt export " + out.truth.string() + " --label IMU0 --out " + out.rawlog.string());
    EXPECT_EQ(e.exit_code, 0) << e.err;
    return out;
  }();
  return f;
}

std::string path_of(const fs::path& p) { return p.string(); }

// The shared fixture's directory goes when the tests are done.
struct RemoveFixture : ::testing::Environment {
  void TearDown() override {
    std::error_code ec;
    if (!fixture_dir().empty()) fs::remove_all(fixture_dir(), ec);
  }
};
[[maybe_unused]] ::testing::Environment* const kRemoveFixture = ::testing::AddGlobalTestEnvironment(new RemoveFixture);

TEST(RawlogRecord, TheRegistryChoosesTheRawlogReaderByContentGzippedOrPlain) {
  SKIP_WITHOUT_MRPT();
#if DRIFTLAB_HAVE_MRPT
  const auto& f = fixture();
  EXPECT_EQ(sniff_record_format(f.rawlog), RecordFormat::Rawlog);
  // The same objects without gzip, under a name that says nothing.
  const auto plain = f.dir / "imu.dat";
  {
    gzFile in = gzopen(f.rawlog.c_str(), "rb");
    ASSERT_NE(in, nullptr);
    std::ofstream out(plain, std::ios::binary);
    char buffer[65536];
    for (int n; (n = gzread(in, buffer, sizeof buffer)) > 0;) out.write(buffer, n);
    gzclose(in);
  }
  EXPECT_EQ(sniff_record_format(plain), RecordFormat::Rawlog);
  // Neither the bridge's CSV nor a gzip'ed CSV is a rawlog.
  EXPECT_EQ(sniff_record_format(f.truth), RecordFormat::Csv);
  const auto gz_csv = f.dir / "bridge.csv.gz";
  {
    gzFile out = gzopen(gz_csv.c_str(), "wb");
    const std::string text = read_text(f.truth);
    gzwrite(out, text.data(), static_cast<unsigned>(text.size()));
    gzclose(out);
  }
  EXPECT_EQ(sniff_record_format(gz_csv), RecordFormat::Csv);
  // The header of older archives (the name's length as a uint32) is recognised too; a byte 0x80 | n
  // followed by anything but a rawlog object's class name is not.
  const auto header = [&](const std::string& name, const std::string& bytes) {
    std::ofstream(f.dir / name, std::ios::binary) << bytes << std::string(64, '\0');
    return sniff_record_format(f.dir / name);
  };
  EXPECT_EQ(header("old.rawlog", std::string("\x0f\0\0\0CObservationIMU", 19)), RecordFormat::Rawlog);
  EXPECT_EQ(header("frame.rawlog",
                   "\x8d"
                   "CSensoryFrame"),
            RecordFormat::Rawlog);
  EXPECT_EQ(header("other.rawlog",
                   "\x8e"
                   "mrpt::poses::X"),
            RecordFormat::Csv);
  EXPECT_EQ(header("text.rawlog", "\x8ds_t,rate_dps\n"), RecordFormat::Csv);

  CsvReadOptions options;
  options.required_roles = {};
  const TimeSeries from_gz = read_record(f.rawlog, options);
  const TimeSeries from_plain = read_record(plain, options);
  ASSERT_EQ(from_gz.size(), from_plain.size());
  EXPECT_EQ(from_gz.time(), from_plain.time());
  EXPECT_EQ(from_gz.channel("gyro_z").values, from_plain.channel("gyro_z").values);
#endif
}

TEST(RawlogRecord, LogInfoAndLogExportGiveTheRecordTheRawlogWasWrittenFrom) {
  SKIP_WITHOUT_MRPT();
  const auto& f = fixture();
  const auto info = run_driftlab("log info " + path_of(f.rawlog));
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_THAT(info.out, AllOf(HasSubstr("MRPT rawlog (observations-only)"), HasSubstr("16200 IMU observations"),
                              HasSubstr("'IMU0': 16200 observations at 1.0 Hz over 16199.000 s"),
                              HasSubstr("IMU_WZ IMU_TEMPERATURE IMU_WX IMU_WY IMU_X_ACC IMU_Y_ACC IMU_Z_ACC")));

  const auto exported = f.dir / "export.csv";
  const auto r = run_driftlab("log export " + path_of(f.rawlog) + " --out " + path_of(exported));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("16200 samples, 7 channels"));
  CsvReadOptions roles;
  roles.required_roles = {"gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z", "temperature"};
  const TimeSeries got = read_csv(exported, roles);
  CsvReadOptions bridge;
  bridge.required_roles = {};
  for (const auto& [column, role] : kBridgeColumns)
    bridge.columns.push_back({role, column,
                              std::string(role) == "temperature" ? "degC"
                              : role[0] == 'g'                   ? "rad/s"
                                                                 : "m/s^2"});
  const TimeSeries truth = read_csv(f.truth, bridge);
  ASSERT_EQ(got.size(), truth.size());
  EXPECT_EQ(got.time(), truth.time());
  for (const auto& [column, role] : kBridgeColumns)
    EXPECT_EQ(got.channel(role).values, truth.channel(role).values) << role;

  const auto gyros = run_driftlab("log export " + path_of(f.rawlog) + " --sensor gyro --topic IMU0 --out " +
                                  path_of(f.dir / "gyros.csv"));
  ASSERT_EQ(gyros.exit_code, 0) << gyros.err;
  EXPECT_THAT(read_text(f.dir / "gyros.csv").substr(0, 60),
              HasSubstr("t_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,temp_c"));
}

// Each command on the rawlog writes what it writes on the rawlog's CSV export.
TEST(RawlogRecord, EveryRecordCommandReadsTheRawlogAsItReadsItsCsv) {
  SKIP_WITHOUT_MRPT();
  const auto& f = fixture();
  const std::string raw = path_of(f.rawlog), csv = path_of(f.dir / "same.csv");
  ASSERT_EQ(run_driftlab("log export " + raw + " --out " + csv).exit_code, 0);
  const std::string d = path_of(f.dir);

  // calibrate: the same models
  const auto cal_raw = run_driftlab("-q calibrate --data " + raw + " --channels gyro --out " + d + "/raw.json");
  ASSERT_EQ(cal_raw.exit_code, 0) << cal_raw.err;
  const auto cal_csv = run_driftlab("-q calibrate --data " + csv + " --channels gyro --out " + d + "/csv.json");
  ASSERT_EQ(cal_csv.exit_code, 0) << cal_csv.err;
  auto a = nlohmann::json::parse(read_text(f.dir / "raw.json")),
       b = nlohmann::json::parse(read_text(f.dir / "csv.json"));
  ASSERT_EQ(a["channels"].size(), 3u);
  ASSERT_EQ(b["channels"].size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(a["channels"][i]["role"], b["channels"][i]["role"]);
    auto& ma = a["channels"][i]["model"];
    auto& mb = b["channels"][i]["model"];
    EXPECT_EQ(ma["fit"]["records"], nlohmann::json::array({raw}));
    ma["fit"].erase("records");  // the file each was fitted on: everything else is equal
    mb["fit"].erase("records");
    EXPECT_EQ(ma, mb) << i;
  }

  // compensate: the same output, byte for byte
  const auto c_raw =
      run_driftlab("-q compensate --model " + d + "/csv.json --data " + raw + " --out " + d + "/c_raw.csv");
  ASSERT_EQ(c_raw.exit_code, 0) << c_raw.err;
  const auto c_csv =
      run_driftlab("-q compensate --model " + d + "/csv.json --data " + csv + " --out " + d + "/c_csv.csv");
  ASSERT_EQ(c_csv.exit_code, 0) << c_csv.err;
  EXPECT_EQ(read_text(f.dir / "c_raw.csv"), read_text(f.dir / "c_csv.csv"));

  // allan: the same deviations
  const auto al_raw = run_driftlab("-q allan --data " + raw + " --column rate=gyro_z --out " + d + "/al_raw.csv");
  ASSERT_EQ(al_raw.exit_code, 0) << al_raw.err;
  const auto al_csv =
      run_driftlab("-q allan --data " + csv + " --column rate=gyro_z_rad_s:rad/s --out " + d + "/al_csv.csv");
  ASSERT_EQ(al_csv.exit_code, 0) << al_csv.err;
  EXPECT_EQ(read_text(f.dir / "al_raw.csv"), read_text(f.dir / "al_csv.csv"));

  // run: the same pipeline outputs
  const std::string pipeline = std::string(DRIFTLAB_SOURCE_DIR) + "/models/pipelines/polynomial_baseline.yaml";
  const auto run_raw = run_driftlab("-q run --pipeline " + pipeline + " --data " + raw +
                                    " --column rate=gyro_z --column temperature=temperature --out " + d + "/run_raw");
  ASSERT_EQ(run_raw.exit_code, 0) << run_raw.err;
  const auto run_csv =
      run_driftlab("-q run --pipeline " + pipeline + " --data " + csv +
                   " --column rate=gyro_z_rad_s:rad/s --column temperature=temp_c:degC --out " + d + "/run_csv");
  ASSERT_EQ(run_csv.exit_code, 0) << run_csv.err;
  EXPECT_EQ(read_text(f.dir / "run_raw" / "outputs.csv"), read_text(f.dir / "run_csv" / "outputs.csv"));

  // discrepancy: the same report numbers
  const auto dis_raw =
      run_driftlab("-q discrepancy --data " + raw + " --column rate=gyro_z --column temperature=temperature --report " +
                   d + "/dis_raw.json");
  ASSERT_EQ(dis_raw.exit_code, 0) << dis_raw.err;
  const auto dis_csv = run_driftlab("-q discrepancy --data " + csv +
                                    " --column rate=gyro_z_rad_s:rad/s --column temperature=temp_c:degC --report " + d +
                                    "/dis_csv.json");
  ASSERT_EQ(dis_csv.exit_code, 0) << dis_csv.err;
  const auto r1 = nlohmann::json::parse(read_text(f.dir / "dis_raw.json")),
             r2 = nlohmann::json::parse(read_text(f.dir / "dis_csv.json"));
  EXPECT_EQ(r1["gap_initial"], r2["gap_initial"]);
  EXPECT_EQ(r1["named_effects"], r2["named_effects"]);
}

TEST(RawlogRecord, BadRawlogsAndSelectionsAreNamedWithTheirExitCodes) {
  SKIP_WITHOUT_MRPT();
  const auto& f = fixture();
  const auto dir = scratch_dir("rawlog_record_bad");
  // A gzip'ed rawlog cut in the middle: the reader names the file and the object.
  {
    gzFile in = gzopen(f.rawlog.c_str(), "rb");
    ASSERT_NE(in, nullptr);
    std::string bytes(200000, '\0');
    const int n = gzread(in, bytes.data(), static_cast<unsigned>(bytes.size()));
    gzclose(in);
    ASSERT_GT(n, 100000);
    std::ofstream(dir / "cut.rawlog", std::ios::binary).write(bytes.data(), 100000 + 7);
  }
  const auto cut = run_driftlab("log export " + path_of(dir / "cut.rawlog") + " --out " + path_of(dir / "x.csv"));
  EXPECT_EQ(cut.exit_code, 3);
  EXPECT_THAT(cut.err, AllOf(HasSubstr("cut.rawlog"), HasSubstr("object"), HasSubstr("truncated")));
  const auto cal =
      run_driftlab("-q calibrate --data " + path_of(dir / "cut.rawlog") + " --out " + path_of(dir / "m.json"));
  EXPECT_EQ(cal.exit_code, 3);

  // A label that is not there, an instance other than 0, a sensor the rawlog lacks.
  const auto label = run_driftlab("log export " + path_of(f.rawlog) + " --topic GYRO --out " + path_of(dir / "y.csv"));
  EXPECT_EQ(label.exit_code, 2);
  EXPECT_THAT(label.err, AllOf(HasSubstr("'GYRO'"), HasSubstr("'IMU0'")));
  const auto instance =
      run_driftlab("log export " + path_of(f.rawlog) + " --instance 1 --out " + path_of(dir / "z.csv"));
  EXPECT_EQ(instance.exit_code, 2);
  EXPECT_THAT(instance.err, HasSubstr("instance 0"));
  const auto sensor =
      run_driftlab("allan --data " + path_of(f.rawlog) + " --column rate=gyro1_z --out " + path_of(dir / "a.csv"));
  EXPECT_EQ(sensor.exit_code, 3);
  EXPECT_THAT(sensor.err, AllOf(HasSubstr("gyro1_z"), HasSubstr("gyro_z")));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace driftlab
