// Fleet calibration end to end (issue 24): a simulated fleet of imu3 units with planted faults
// (`driftlab simulate --fleet`), calibrated by `driftlab fleet` with one and with two workers, scored
// against the answer key; a rerun resumes; a truncated log is a recorded failure; `calibrate`
// refuses two units given as one device.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/types.h>
#include <unistd.h>

#include <cstdlib>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "tests/tools/cli_harness.hpp"
#include "framework/units.hpp"

namespace driftlab {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using testing_cli::read_text;
using testing_cli::run_driftlab;

// 20 units at 1 Hz over the default oven profile (4.5 h, 16 200 samples per unit), gyro channels
// only: small enough for a test, long enough for the quality gate and the hysteresis term.
constexpr int kUnits = 20;
// Issue 24 allows 2 false flags among 192 normal units; the robust z cut of 3.5 over about 30
// figures per unit makes a false flag among 16 normal units possible, 2 unlikely.
constexpr std::size_t kMaxFalselyFlagged = 2;

const fs::path kDir = testing_cli::scratch_dir("fleet_cli");
const fs::path kSim = kDir / "sim";

nlohmann::json read_json(const fs::path& p) { return nlohmann::json::parse(read_text(p)); }

testing_cli::CliResult run_fleet(const fs::path& out, int workers, const fs::path& manifest = kSim / "manifest.csv") {
  return run_driftlab("fleet --manifest " + manifest.string() + " --out " + out.string() + " --workers " +
                      std::to_string(workers) + " --channels gyro");
}

class FleetCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const auto s = run_driftlab("simulate --fleet " + std::to_string(kUnits) + " --device imu3 --fs 1 --seed 7 --out " +
                                kSim.string());
    ASSERT_EQ(s.exit_code, 0) << s.err;
    one_ = new testing_cli::CliResult(run_fleet(kDir / "w1", 1));
    two_ = new testing_cli::CliResult(run_fleet(kDir / "w2", 2));
  }
  static void TearDownTestSuite() {
    delete one_;
    delete two_;
  }
  static testing_cli::CliResult* one_;
  static testing_cli::CliResult* two_;
};
testing_cli::CliResult* FleetCli::one_ = nullptr;
testing_cli::CliResult* FleetCli::two_ = nullptr;

std::string planted(const nlohmann::json& key, const std::string& kind) {
  for (const auto& u : key["units"])
    if (!u["fault"].is_null() && u["fault"]["kind"] == kind) return u["unit"];
  return "";
}

TEST_F(FleetCli, EveryPlantedFaultIsFlaggedWithItsReasonAndFewNormalUnitsAre) {
  const auto key = read_json(kSim / "key.json");
  const auto report = read_json(kDir / "w1" / "report.json");
  std::set<std::string> faulty, flagged;
  for (const auto& u : key["units"]) {
    if (u["fault"].is_null()) continue;
    faulty.insert(u["unit"]);
    const auto& expected = u["fault"]["expected"];
    if (expected["figure"] == "failed") continue;
    bool found = false;
    for (const auto& o : report["outliers"])
      found = found || (o["unit"] == u["unit"] && o["channel"] == expected["channel"] &&
                        o["figure"].get<std::string>().rfind(expected["figure"].get<std::string>() + "_", 0) == 0);
    EXPECT_TRUE(found) << u["unit"] << " (" << u["fault"]["description"] << ") is not flagged on " << expected;
  }
  for (const auto& o : report["outliers"])
    if (!faulty.count(o["unit"])) flagged.insert(o["unit"]);
  EXPECT_LE(flagged.size(), kMaxFalselyFlagged) << report["outliers"].dump(1);
}

TEST_F(FleetCli, TheTruncatedLogIsARecordedFailureAndTheBatchCompletes) {
  EXPECT_EQ(one_->exit_code, 1) << one_->err;
  const auto key = read_json(kSim / "key.json");
  const std::string truncated = planted(key, "truncated");
  const auto report = read_json(kDir / "w1" / "report.json");
  EXPECT_EQ(report["units"], kUnits);
  EXPECT_EQ(report["passed"], kUnits - 1);
  ASSERT_EQ(report["failures"].size(), 1u);
  EXPECT_EQ(report["failures"][0]["unit"], truncated);
  EXPECT_EQ(report["failures"][0]["exit_class"], 3);
  EXPECT_THAT(report["failures"][0]["reason"].get<std::string>(), HasSubstr(truncated + ".csv"));
  const auto status = read_json(kDir / "w1" / "units" / truncated / "status.json");
  EXPECT_EQ(status["status"], "failed");
  EXPECT_FALSE(fs::exists(kDir / "w1" / "units" / truncated / "model.json"));
  for (const auto& u : key["units"]) {
    if (u["unit"] == truncated) continue;
    for (const char* f : {"model.json", "px4.params", "ardupilot.params", "status.json"})
      EXPECT_TRUE(fs::exists(kDir / "w1" / "units" / u["unit"].get<std::string>() / f)) << u["unit"] << " " << f;
  }
  EXPECT_TRUE(fs::exists(kDir / "w1" / "units.csv"));
  EXPECT_TRUE(fs::exists(kDir / "w1" / "report.html"));
}

TEST_F(FleetCli, AUnitThatPassedAndThenFailsKeepsNoModelAndNoStaleTemporary) {
  const fs::path work = kDir / "refail", out = work / "out";
  fs::create_directories(work);
  std::string normal;
  const auto key = read_json(kSim / "key.json");
  for (const auto& u : key["units"])
    if (normal.empty() && u["fault"].is_null()) normal = u["data"];
  fs::copy_file(kSim / normal, work / "unit.csv", fs::copy_options::overwrite_existing);
  std::ofstream(work / "manifest.csv") << "unit,data\nu1,unit.csv\n";
  ASSERT_EQ(run_fleet(out, 1, work / "manifest.csv").exit_code, 0);
  const fs::path unit = out / "units" / "u1";
  ASSERT_TRUE(fs::exists(unit / "model.json"));
  // A killed run's hidden temporary, and a log that no longer reads (other inputs: the unit reruns).
  std::ofstream(unit / ".model.json.tmp-Ab12Cd") << "half a model";
  const std::string text = read_text(work / "unit.csv");
  std::ofstream(work / "unit.csv", std::ios::trunc) << text.substr(0, text.find('\n') + 1) << "1,2\n";
  const auto r = run_fleet(out, 1, work / "manifest.csv");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(read_json(unit / "status.json")["status"], "failed");
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(unit)) left.push_back(e.path().filename().string());
  EXPECT_EQ(left, std::vector<std::string>{"status.json"});
}

TEST_F(FleetCli, OneAndTwoWorkersWriteIdenticalUnitFoldersAndReports) {
  EXPECT_EQ(two_->exit_code, one_->exit_code) << two_->err;
  std::size_t files = 0;
  for (const auto& e : fs::recursive_directory_iterator(kDir / "w1" / "units")) {
    if (!e.is_regular_file()) continue;
    const auto other = kDir / "w2" / fs::relative(e.path(), kDir / "w1");
    EXPECT_EQ(read_text(e.path()), read_text(other)) << e.path();
    ++files;
  }
  EXPECT_EQ(files, 4u * (kUnits - 1) + 1u);
  for (const char* f : {"report.json", "units.csv"})
    EXPECT_EQ(read_text(kDir / "w1" / f), read_text(kDir / "w2" / f)) << f;
}

TEST_F(FleetCli, TwoShardsAndAMergeGiveTheSingleRunsFoldersAndReport) {
  const fs::path out = kDir / "shards";
  for (const char* shard : {"1/2", "2/2"}) {
    const auto r = run_driftlab("fleet --manifest " + (kSim / "manifest.csv").string() + " --out " + out.string() +
                                " --channels gyro --shard " + shard);
    EXPECT_NE(r.exit_code, 2) << r.err;
    EXPECT_THAT(r.out, HasSubstr("shard " + std::string(shard) + ": 10 units"));
    EXPECT_FALSE(fs::exists(out / "report.json"));
  }
  const auto m = run_driftlab("fleet merge --manifest " + (kSim / "manifest.csv").string() + " --out " + out.string());
  EXPECT_EQ(m.exit_code, one_->exit_code) << m.err;
  for (const auto& e : fs::recursive_directory_iterator(kDir / "w1" / "units")) {
    if (e.is_regular_file()) {
      EXPECT_EQ(read_text(e.path()), read_text(out / fs::relative(e.path(), kDir / "w1"))) << e.path();
    }
  }
  for (const char* f : {"report.json", "units.csv"}) EXPECT_EQ(read_text(kDir / "w1" / f), read_text(out / f)) << f;
}

TEST_F(FleetCli, ThreeMpiRanksGiveTheSingleRunsFoldersAndReport) {
  if (!DRIFTLAB_HAVE_MPI) GTEST_SKIP() << "built without MPI (DRIFTLAB_WITH_MPI)";
  const fs::path out = kDir / "mpi";
  // Open MPI refuses to run as root unless told; the tests run as root in the project's container.
  // DRIFTLAB_PROGRESS_INTERVAL_S=0: a progress line (stderr is a file) for every finished unit.
  const auto r = testing_cli::run_driftlab(
      "fleet --manifest " + (kSim / "manifest.csv").string() + " --out " + out.string() + " --channels gyro",
      "DRIFTLAB_PROGRESS_INTERVAL_S=0 OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun "
      "--oversubscribe -np 3");
  EXPECT_NE(r.exit_code, 0) << "a unit failed: rank 0 exits 1";
  EXPECT_THAT(r.out,
              HasSubstr(std::to_string(kUnits) + " units: " + std::to_string(kUnits - 1) + " calibrated, 1 failed"))
      << r.err;
  // Rank 0 reports the units as their results arrive; the worker ranks report nothing.
  const std::string task = "driftlab: fleet: " + std::to_string(kUnits) + " units: ";
  const auto started = r.err.find(task + "started\n");
  ASSERT_NE(started, std::string::npos) << r.err;
  EXPECT_EQ(r.err.find(task + "started\n", started + 1), std::string::npos) << r.err;
  for (int done = 1; done < kUnits; ++done)
    EXPECT_THAT(r.err, HasSubstr(task + std::to_string(100 * done / kUnits) + "%, ")) << r.err;
  EXPECT_THAT(r.err, HasSubstr(task + "done in ")) << r.err;
  for (const auto& e : fs::recursive_directory_iterator(kDir / "w1" / "units")) {
    if (e.is_regular_file()) {
      EXPECT_EQ(read_text(e.path()), read_text(out / fs::relative(e.path(), kDir / "w1"))) << e.path();
    }
  }
  for (const char* f : {"report.json", "units.csv"}) EXPECT_EQ(read_text(kDir / "w1" / f), read_text(out / f)) << f;
}

TEST_F(FleetCli, ARerunSkipsFinishedUnitsAndRedoesOnlyADeletedOne) {
  const fs::path out = kDir / "rerun";
  fs::copy(kDir / "w2", out, fs::copy_options::recursive);
  std::string normal;
  const auto key = read_json(kSim / "key.json");
  for (const auto& u : key["units"])
    if (normal.empty() && u["fault"].is_null()) normal = u["unit"];
  fs::remove_all(out / "units" / normal);
  const auto r = run_fleet(out, 2);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  std::size_t skipped = 0;
  for (std::size_t p = r.out.find("skipped"); p != std::string::npos; p = r.out.find("skipped", p + 1)) ++skipped;
  EXPECT_EQ(skipped, kUnits - 1u) << r.out;
  EXPECT_THAT(r.out, HasSubstr(normal + ": passed"));
  for (const char* f : {"model.json", "status.json"})
    EXPECT_EQ(read_text(out / "units" / normal / f), read_text(kDir / "w1" / "units" / normal / f));
  EXPECT_EQ(read_text(out / "report.json"), read_text(kDir / "w1" / "report.json"));
}

std::size_t finished_units(const fs::path& out) {
  std::size_t n = 0;
  if (!fs::exists(out / "units")) return 0;
  for (const auto& e : fs::directory_iterator(out / "units")) n += fs::exists(e.path() / "status.json");
  return n;
}

TEST_F(FleetCli, ARunKilledMidwayIsCompletedByARerunThatKeepsItsFinishedUnits) {
  const fs::path out = kDir / "killed", pid_file = kDir / "killed.pid";
  std::system((std::string(DRIFTLAB_EXE) + " fleet --manifest " + (kSim / "manifest.csv").string() + " --out " +
               out.string() + " --workers 1 --channels gyro >/dev/null 2>&1 & echo $! > " + pid_file.string())
                  .c_str());
  const pid_t pid = std::stoi(read_text(pid_file));
  // Wait (polling) until a few units have finished, then SIGKILL the whole run.
  while (finished_units(out) < 3 && ::kill(pid, 0) == 0) ::usleep(20000);
  ASSERT_EQ(::kill(pid, SIGKILL), 0) << "the run ended before it could be killed";
  while (::kill(pid, 0) == 0) ::usleep(20000);
  const std::size_t finished = finished_units(out);
  ASSERT_LT(finished, static_cast<std::size_t>(kUnits));
  const auto r = run_fleet(out, 2);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  std::size_t skipped = 0;
  for (std::size_t p = r.out.find("skipped"); p != std::string::npos; p = r.out.find("skipped", p + 1)) ++skipped;
  EXPECT_EQ(skipped, finished) << r.out;
  for (const auto& e : fs::recursive_directory_iterator(kDir / "w1" / "units")) {
    if (e.is_regular_file()) {
      EXPECT_EQ(read_text(e.path()), read_text(out / fs::relative(e.path(), kDir / "w1"))) << e.path();
    }
  }
  std::size_t files = 0;
  for (const auto& e : fs::recursive_directory_iterator(out / "units")) files += e.is_regular_file();
  EXPECT_EQ(files, 4u * (kUnits - 1) + 1u) << "a staged file of the killed unit was left behind";
}

TEST_F(FleetCli, SpecLimitsFromTheManifestGiveTheYieldWithoutRedoingUnits) {
  // The same units with a held-out limit that only the worst gyro channels exceed: limits are
  // scored in the report, not in the units, so every unit is skipped.
  const auto report = read_json(kDir / "w1" / "report.json");
  std::string manifest = "unit,data,gyro.holdout_dph_max\n";
  const auto key = read_json(kSim / "key.json");
  for (const auto& u : key["units"])
    manifest += u["unit"].get<std::string>() + "," + (kSim / u["data"].get<std::string>()).string() + "," +
                (u["unit"] == "unit001" ? "0.001" : "") + "\n";
  const fs::path m = kDir / "spec_manifest.csv";
  std::ofstream(m) << manifest;
  const fs::path out = kDir / "spec";
  fs::copy(kDir / "w1", out, fs::copy_options::recursive);
  const auto r = run_fleet(out, 1, m);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  const auto spec = read_json(out / "report.json");
  const int expected_within =
      report["passed"].get<int>() - (read_json(out / "units" / "unit001" / "status.json")["status"] == "passed");
  EXPECT_EQ(spec["within_spec"], expected_within);
  EXPECT_DOUBLE_EQ(spec["yield"].get<double>(), expected_within / static_cast<double>(kUnits));
  for (const auto& u : spec["unit_results"]) {
    if (u["unit"] == "unit001" && u["status"] == "passed") {
      EXPECT_THAT(u["spec_violations"].dump(), HasSubstr("gyro.holdout_dph_max"));
    }
  }
}

// Without the fleet above (ctest runs each test in its own process, and these need none of it).

TEST(FleetManifest, ABadManifestIsRefusedNamingLineAndColumn) {
  const fs::path m = kDir / "bad_manifest.csv";
  std::ofstream(m) << "unit,data,gyro.bogus_max\nu1,x.csv,1\n";
  const auto r = run_fleet(kDir / "bad", 1, m);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, ::testing::AllOf(HasSubstr("bad_manifest.csv:1"), HasSubstr("gyro.bogus_max")));
}

TEST(FleetManifest, MergeRefusesAUnitWhoseShardHasNotRun) {
  const fs::path m = kDir / "unrun_manifest.csv";
  std::ofstream(m) << "unit,data\nlate,late.csv\n";
  fs::create_directories(kDir / "unrun" / "units");  // the shards' output directory, without this unit
  const auto r = run_driftlab("fleet merge --manifest " + m.string() + " --out " + (kDir / "unrun").string());
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_THAT(r.err, HasSubstr("unit late has not run"));
}

TEST(FleetManifest, AMissingLogIsThatUnitsFailure) {
  const fs::path m = kDir / "missing_manifest.csv";
  std::ofstream(m) << "unit,data\nghost,does_not_exist.csv\n";
  const auto r = run_fleet(kDir / "missing", 1, m);
  EXPECT_EQ(r.exit_code, 1);
  const auto status = read_json(kDir / "missing" / "units" / "ghost" / "status.json");
  EXPECT_EQ(status["status"], "failed");
  EXPECT_THAT(status["reason"].get<std::string>(), HasSubstr("does_not_exist.csv"));
}

// One column of a simulated unit's CSV (the simulator writes no quoting).
std::vector<double> csv_column(const fs::path& csv, const std::string& name) {
  std::istringstream in(read_text(csv));
  std::string line, cell;
  std::getline(in, line);
  int index = -1, c = 0;
  for (std::istringstream h(line); std::getline(h, cell, ','); ++c)
    if (cell == name) index = c;
  EXPECT_GE(index, 0) << name << " is no column of " << csv;
  std::vector<double> values;
  while (std::getline(in, line)) {
    std::istringstream row(line);
    for (int k = 0; std::getline(row, cell, ','); ++k)
      if (k == index) values.push_back(std::stod(cell));
  }
  return values;
}

std::string unit_with(const nlohmann::json& key, const std::string& kind, const fs::path& dir) {
  const std::string id = planted(key, kind);
  return id.empty() ? "" : (dir / (id + ".csv")).string();
}

TEST(FleetSimulate, TheOptionsPlantTheFaultsTheyNameAndSetTheSpread) {
  // In LSBs: a multiple of 0.05 deg/s read back from its shortest decimal text divides to a whole
  // number to rounding (measured 2e-15).
  constexpr double kOnTheLsb = 1e-6;
  const fs::path sim = kDir / "options";
  const auto s = run_driftlab(
      "simulate --fleet 8 --device imu3 --fs 0.2 --duration 3000 --seed 11 --spread 0 "
      "--outliers lag:1,dead_axis:2,lsb:1,hysteresis:0 --out " +
      sim.string());
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const auto key = read_json(sim / "key.json");
  std::map<std::string, int> kinds;
  std::vector<std::string> normal;
  for (const auto& u : key["units"]) {
    if (u["fault"].is_null()) {
      normal.push_back((sim / u["data"].get<std::string>()).string());
      continue;
    }
    ++kinds[u["fault"]["kind"]];
    EXPECT_FALSE(u["fault"]["expected"]["channel"].get<std::string>().empty()) << u;
  }
  EXPECT_EQ(kinds, (std::map<std::string, int>{{"lag", 1}, {"dead_axis", 2}, {"lsb", 1}}));
  EXPECT_EQ(key["spread"]["bias_polynomial_sigma"], 0.0);
  // A dead axis is constant; the LSB unit's axis sits on multiples of the LSB (0.05 deg/s) and moves.
  const auto dead = csv_column(unit_with(key, "dead_axis", sim), "gyro1_z_dps");
  EXPECT_EQ(std::set<double>(dead.begin(), dead.end()).size(), 1u);
  const auto lsb = csv_column(unit_with(key, "lsb", sim), "gyro1_x_dps");
  EXPECT_GT(std::set<double>(lsb.begin(), lsb.end()).size(), 3u);
  for (double v : lsb) EXPECT_NEAR(v / 0.05, std::round(v / 0.05), kOnTheLsb) << v;
  // Without spread two normal units share every systematic column.
  ASSERT_GE(normal.size(), 2u);
  for (const char* column : {"systematic_gyro_x_dps", "systematic_gyro1_z_dps", "systematic_accel_y_mps2"})
    EXPECT_EQ(csv_column(normal[0], column), csv_column(normal[1], column)) << column;
}

TEST(FleetSimulate, TheDefaultOptionsAreTheFourFaultsWithATenPercentSpread) {
  const std::string common = "simulate --fleet 6 --device imu3 --fs 0.2 --duration 1200 --seed 3 --out ";
  const auto a = run_driftlab(common + (kDir / "default_a").string());
  const auto b = run_driftlab(common + (kDir / "default_b").string() +
                              " --spread bias=0.1,scale_factor=0.1,noise=0.1,time_constant=0.1"
                              " --outliers hysteresis:1,bias_step:1,noisy:1,truncated:1");
  ASSERT_EQ(a.exit_code, 0) << a.err;
  ASSERT_EQ(b.exit_code, 0) << b.err;
  for (const auto& e : fs::directory_iterator(kDir / "default_a"))
    EXPECT_EQ(read_text(e.path()), read_text(kDir / "default_b" / e.path().filename())) << e.path();
  const auto spread = read_json(kDir / "default_a" / "key.json");
  std::vector<double> x;
  for (const auto& u : spread["units"])
    if (u["fault"].is_null())
      x.push_back(csv_column(kDir / "default_a" / u["data"].get<std::string>(), "systematic_gyro_x_dps")[0]);
  ASSERT_GE(x.size(), 2u);
  EXPECT_NE(x[0], x[1]) << "a spread fleet's units differ";
}

TEST(FleetSimulate, BadSpreadOrOutliersAreRefusedNamingTheOption) {
  const std::string common =
      "simulate --fleet 6 --device imu3 --fs 0.2 --duration 600 --out " + (kDir / "bad_sim").string();
  const auto a = run_driftlab(common + " --outliers lag:1,wobble:2");
  EXPECT_EQ(a.exit_code, 2);
  EXPECT_THAT(a.err, ::testing::AllOf(HasSubstr("--outliers"), HasSubstr("wobble:2"), HasSubstr("dead_axis")));
  const auto b = run_driftlab(common + " --spread bias=-1");
  EXPECT_EQ(b.exit_code, 2);
  EXPECT_THAT(b.err, ::testing::AllOf(HasSubstr("--spread"), HasSubstr("bias=-1")));
  const auto c = run_driftlab(common + " --outliers lsb:6");
  EXPECT_EQ(c.exit_code, 2);
  EXPECT_THAT(c.err, ::testing::AllOf(HasSubstr("--fleet"), HasSubstr("at least 7")));
}

// Issue 24's checked fleet: 200 units, 8 planted faults (every kind), a spec limit on the gyro
// noise density, scored against the key. One test: ctest gives each test its own process, and the
// fleet is its cost (0.2 Hz over the whole oven profile, 3 241 samples per unit, gyro channels,
// 2 workers: about 50 s CPU; see docs/evidence.md for the measured wall time).
constexpr int kFleetUnits = 200;
constexpr double kNoiseLimitDph = 100.0;  // gyro.N_dph_rthz_max: normal units 14-50, the noisy one x5

TEST(FleetOf200, EveryPlantedFaultIsFoundForItsReasonAndTheYieldIsTheKeys) {
  constexpr double kLsbDph = 1e-6;  // the LSB found in the rad/s data, shown in deg/h: rounding (measured 1e-13)
  const fs::path sim = kDir / "f200", out = kDir / "f200_out";
  const auto s = run_driftlab("simulate --fleet " + std::to_string(kFleetUnits) +
                              " --device imu3 --fs 0.2 --seed 7 --outliers "
                              "hysteresis:2,lag:1,bias_step:1,noisy:1,dead_axis:1,truncated:1,lsb:1 --out " +
                              sim.string());
  ASSERT_EQ(s.exit_code, 0) << s.err;
  std::istringstream rows(read_text(sim / "manifest.csv"));
  std::string manifest, line;
  std::getline(rows, line);
  manifest = line + ",gyro.N_dph_rthz_max\n";
  while (std::getline(rows, line)) manifest += line + "," + std::to_string(kNoiseLimitDph) + "\n";
  std::ofstream(sim / "spec_manifest.csv") << manifest;
  const auto r = run_fleet(out, 2, sim / "spec_manifest.csv");
  EXPECT_EQ(r.exit_code, 1) << r.err;

  const auto key = read_json(sim / "key.json");
  const auto report = read_json(out / "report.json");
  ASSERT_EQ(report["units"], kFleetUnits);
  std::map<std::string, nlohmann::json> findings;  // unit -> its findings
  for (const auto& o : report["outliers"]) findings[o["unit"]].push_back(o);

  // Every fault unit flagged with its reason; at most 2 of the 192 others flagged at all.
  std::set<std::string> faulty, falsely;
  std::size_t expected_within = 0;
  for (const auto& u : key["units"]) {
    const std::string id = u["unit"];
    bool noise_ok = true;
    for (const auto& [channel, truth] : u["truth"].items())
      if (channel.rfind("gyro", 0) == 0) noise_ok = noise_ok && truth["N_dph_rthz"].get<double>() <= kNoiseLimitDph;
    const bool truncated = !u["fault"].is_null() && u["fault"]["kind"] == "truncated";
    expected_within += noise_ok && !truncated;
    if (u["fault"].is_null()) {
      if (findings.count(id)) falsely.insert(id);
      continue;
    }
    faulty.insert(id);
    const auto& expected = u["fault"]["expected"];
    if (expected["figure"] == "failed") {
      const auto status = read_json(out / "units" / id / "status.json");
      EXPECT_EQ(status["status"], "failed") << id;
      EXPECT_EQ(status["exit_class"], 3) << id;
      continue;
    }
    bool found = false, distance = false;
    for (const auto& o : findings[id]) {
      found = found || (o["channel"] == expected["channel"] &&
                        o["figure"].get<std::string>().rfind(expected["figure"].get<std::string>() + "_", 0) == 0);
      // The whole-model distance flags every passed fault unit, naming the fault's channel among
      // its drivers (the noisy unit's three channels are all expected).
      distance = distance ||
                 (o["rule"] == "distance" &&
                  (o["text"].get<std::string>().find(expected["channel"].get<std::string>()) != std::string::npos ||
                   u["fault"]["kind"] == "noisy"));
    }
    EXPECT_TRUE(found) << id << " (" << u["fault"]["description"] << ") is not flagged on " << expected << ": "
                       << nlohmann::json(findings[id]).dump(1);
    EXPECT_TRUE(distance) << id << " has no whole-model distance flag naming " << expected["channel"];
  }
  EXPECT_EQ(faulty.size(), 8u);
  EXPECT_LE(falsely.size(), kMaxFalselyFlagged) << nlohmann::json(falsely).dump();

  // Quantisation: exactly the LSB unit, on its channel.
  const std::string lsb = planted(key, "lsb");
  for (const auto& o : report["outliers"])
    if (o["rule"] == "quantisation") {
      EXPECT_EQ(o["unit"], lsb);
      EXPECT_EQ(o["channel"], "gyro1_x");
      EXPECT_NEAR(o["value"].get<double>(), 0.05 * kSecondsPerHour, kLsbDph);  // the LSB, deg/h
    }
  EXPECT_TRUE(read_json(out / "units" / lsb / "status.json")["quantisation"]["gyro1_x"]["quantised"].get<bool>());

  // Spec-limit yield: the key's truth (every gyro channel's drawn N under the limit, the log whole).
  EXPECT_EQ(report["within_spec"], expected_within);
  EXPECT_DOUBLE_EQ(report["yield"].get<double>(), expected_within / static_cast<double>(kFleetUnits));
  EXPECT_LT(expected_within, static_cast<std::size_t>(kFleetUnits - 1)) << "the noisy unit is outside the limit";

  // One lot: one family.
  EXPECT_EQ(report["families"]["k"], 1) << report["families"].dump();

  // report.html links every flagged unit to its status and draws the two figures.
  const std::string html = read_text(out / "report.html");
  for (const auto& [unit, list] : findings)
    EXPECT_THAT(html, HasSubstr("href=\"units/" + unit + "/status.json\"")) << unit;
  std::size_t svgs = 0;
  for (auto p = html.find("<svg"); p != std::string::npos; p = html.find("<svg", p + 1)) ++svgs;
  EXPECT_EQ(svgs, 2u);
}

// Two part lots whose gyro_x bias slopes differ in sign: two families, each exactly one lot.
TEST(FleetFamilies, TwoLotsOfDifferentThermalBehaviourAreTwoFamilies) {
  std::string device = read_text(fs::path(DRIFTLAB_SOURCE_DIR) / "devices" / "imu3.yaml");
  const std::string slope = "bias_polynomial_dps: [0.35, 0.021, 1.2e-4]";
  ASSERT_NE(device.find(slope), std::string::npos);
  device.replace(device.find(slope), slope.size(), "bias_polynomial_dps: [0.35, -0.021, 1.2e-4]");
  std::ofstream(kDir / "lot_b.yaml") << device;
  std::string manifest = "unit,data\n";
  for (const auto& [lot, file] :
       {std::pair<std::string, std::string>{"a", "imu3"}, {"b", (kDir / "lot_b.yaml").string()}}) {
    const fs::path dir = kDir / ("lot_" + lot);
    const auto s = run_driftlab("simulate --fleet 8 --device " + file + " --fs 0.2 --seed " + (lot == "a" ? "1" : "2") +
                                " --outliers none --out " + dir.string());
    ASSERT_EQ(s.exit_code, 0) << s.err;
    for (int u = 1; u <= 8; ++u)
      manifest += lot + std::to_string(u) + "," + (dir / ("unit00" + std::to_string(u) + ".csv")).string() + "\n";
  }
  std::ofstream(kDir / "lots.csv") << manifest;
  const auto r = run_fleet(kDir / "lots_out", 2, kDir / "lots.csv");
  EXPECT_NE(r.exit_code, 2) << r.err;
  const auto families = read_json(kDir / "lots_out" / "report.json")["families"];
  ASSERT_EQ(families["k"], 2) << families.dump();
  const auto report = read_json(kDir / "lots_out" / "report.json");
  std::map<char, std::set<int>> lot_families;
  for (const auto& u : report["unit_results"])
    lot_families[u["unit"].get<std::string>()[0]].insert(u["family"].get<int>());
  EXPECT_EQ(lot_families['a'].size(), 1u);
  EXPECT_EQ(lot_families['b'].size(), 1u);
  EXPECT_NE(*lot_families['a'].begin(), *lot_families['b'].begin());
}

// --discrepancy: the discrepancy workflow on every gyro channel names the planted hysteresis on
// the hysteresis unit's gyro_x and no hysteresis on a normal unit's; without the option nothing is
// checked.
TEST(FleetDiscrepancy, TheCheckNamesThePlantedHysteresisOnItsChannelOnly) {
  const fs::path sim = kDir / "disc";
  const auto s =
      run_driftlab("simulate --fleet 5 --device imu3 --fs 0.2 --seed 5 --outliers hysteresis:1 --out " + sim.string());
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const auto r = run_driftlab("fleet --manifest " + (sim / "manifest.csv").string() + " --out " +
                              (kDir / "disc_out").string() + " --workers 2 --channels gyro_x --discrepancy");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const auto key = read_json(sim / "key.json");
  const auto report = read_json(kDir / "disc_out" / "report.json");
  for (const auto& u : key["units"]) {
    const auto status = read_json(kDir / "disc_out" / "units" / u["unit"].get<std::string>() / "status.json");
    std::set<std::string> named;
    for (const auto& n : status["discrepancy"]["gyro_x"]["named"]) named.insert(n["effect"]);
    EXPECT_EQ(named.count("hysteresis"), u["fault"].is_null() ? 0u : 1u) << u["unit"] << " " << status["discrepancy"];
  }
  const std::string hysteresis = planted(key, "hysteresis");
  for (const auto& u : report["unit_results"])
    if (u["unit"] == hysteresis) {
      ASSERT_EQ(u["discrepancy"].size(), 1u);
      EXPECT_THAT(u["discrepancy"][0].get<std::string>(), HasSubstr("gyro_x: hysteresis named, delta BIC"));
    }
  const auto plain = run_driftlab("fleet --manifest " + (sim / "manifest.csv").string() + " --out " +
                                  (kDir / "plain_out").string() + " --channels gyro_x");
  EXPECT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_TRUE(read_json(kDir / "plain_out" / "units" / hysteresis / "status.json")["discrepancy"].empty());
}

// A unit whose log names its columns its own way is read through its manifest row's mappings (as
// --column: what is mapped is what is read, here instance 0's gyros and temperature): the same
// models as from the unit's original log (CSV and YAML manifests alike); a malformed mapping is a
// manifest error naming line and unit.
TEST(FleetManifest, AUnitsOwnColumnMappingsReadItsLog) {
  const fs::path sim = kDir / "columns";
  const auto s =
      run_driftlab("simulate --fleet 2 --device imu3 --fs 0.2 --seed 5 --outliers none --out " + sim.string());
  ASSERT_EQ(s.exit_code, 0) << s.err;
  {  // unit002's log with the gyro columns of instance 0 renamed gx, gy, gz (in deg/s)
    std::string text = read_text(sim / "unit002.csv");
    const auto header_end = text.find('\n');
    std::string header = text.substr(0, header_end);
    for (const char axis : {'x', 'y', 'z'}) {
      const std::string from = std::string("gyro_") + axis + "_dps,", to = std::string("g") + axis + ",";
      header.replace(header.find(from), from.size(), to);
    }
    std::ofstream(sim / "renamed.csv") << header << text.substr(header_end);
  }
  std::ofstream(sim / "m.csv")
      << "unit,data,columns\nunit001,unit001.csv,\n"
         "unit002,renamed.csv,gyro_x=gx:deg/s;gyro_y=gy:deg/s;gyro_z=gz:deg/s;temperature=temp_c:degC\n";
  std::ofstream(sim / "m.yaml") << "units:\n  - {unit: unit001, data: unit001.csv}\n"
                                   "  - {unit: unit002, data: renamed.csv, columns: [gyro_x=gx:deg/s, gyro_y=gy:deg/s, "
                                   "gyro_z=gz:deg/s, temperature=temp_c:degC]}\n";
  std::ofstream(sim / "original.csv") << "unit,data\nunit001,unit001.csv\nunit002,unit002.csv\n";
  const auto original = run_fleet(kDir / "columns_original", 1, sim / "original.csv");
  const auto mapped = run_fleet(kDir / "columns_csv", 1, sim / "m.csv");
  const auto yaml = run_fleet(kDir / "columns_yaml", 1, sim / "m.yaml");
  ASSERT_EQ(mapped.exit_code, original.exit_code) << mapped.err;
  ASSERT_EQ(yaml.exit_code, original.exit_code) << yaml.err;
  const auto coefficients = [](const fs::path& model) {  // instance 0's gyro channels
    std::vector<double> out;
    const auto j = read_json(model);
    for (const auto& c : j["channels"])
      if (c["role"].get<std::string>().rfind("gyro_", 0) == 0)
        for (const double a : c["model"]["bias"]["polynomial_rad_s_per_k_i"]) out.push_back(a);
    return out;
  };
  const auto expected = coefficients(kDir / "columns_original" / "units" / "unit002" / "model.json");
  ASSERT_FALSE(expected.empty());
  EXPECT_EQ(coefficients(kDir / "columns_csv" / "units" / "unit002" / "model.json"), expected);
  EXPECT_EQ(coefficients(kDir / "columns_yaml" / "units" / "unit002" / "model.json"), expected);
  EXPECT_EQ(read_json(kDir / "columns_csv" / "units" / "unit002" / "model.json")["channels"][0]["column"], "gx");

  std::ofstream(sim / "bad.csv") << "unit,data,columns\nunit001,unit001.csv,gyro_x=gx:furlongs\n";
  const auto bad = run_fleet(kDir / "columns_bad", 1, sim / "bad.csv");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_THAT(bad.err, ::testing::AllOf(HasSubstr("bad.csv:2"), HasSubstr("unit001"), HasSubstr("furlongs")));
}

// A YAML manifest with the CSV manifest's content gives the same unit folders and report.
TEST(FleetManifest, AYamlManifestIsTheCsvOne) {
  const fs::path sim = kDir / "yaml";
  const auto s =
      run_driftlab("simulate --fleet 4 --device imu3 --fs 0.2 --seed 9 --outliers none --out " + sim.string());
  ASSERT_EQ(s.exit_code, 0) << s.err;
  std::ofstream(sim / "m.csv")
      << "unit,data,gyro.holdout_dph_max\nunit001,unit001.csv,0.001\nunit002,unit002.csv;unit002.csv,\n"
         "unit003,unit003.csv,\nunit004,unit004.csv,\n";
  std::ofstream(sim / "m.yaml") << "units:\n"
                                   "  - {unit: unit001, data: unit001.csv, limits: {gyro.holdout_dph_max: 0.001}}\n"
                                   "  - unit: unit002\n    data: [unit002.csv, unit002.csv]\n"
                                   "  - {unit: unit003, data: unit003.csv}\n  - {unit: unit004, data: [unit004.csv]}\n";
  const auto c = run_fleet(kDir / "yaml_csv", 2, sim / "m.csv");
  const auto y = run_fleet(kDir / "yaml_yaml", 2, sim / "m.yaml");
  EXPECT_EQ(c.exit_code, 1) << c.err;  // unit001 is outside its limit
  EXPECT_EQ(y.exit_code, c.exit_code) << y.err;
  std::size_t files = 0;
  for (const auto& e : fs::recursive_directory_iterator(kDir / "yaml_csv" / "units"))
    if (e.is_regular_file()) {
      EXPECT_EQ(read_text(e.path()), read_text(kDir / "yaml_yaml" / fs::relative(e.path(), kDir / "yaml_csv")))
          << e.path();
      ++files;
    }
  EXPECT_EQ(files, 16u);
  auto a = read_json(kDir / "yaml_csv" / "report.json"), b = read_json(kDir / "yaml_yaml" / "report.json");
  a.erase("command");
  b.erase("command");
  EXPECT_EQ(a, b);
  EXPECT_EQ(a["within_spec"], 3);
}

TEST(FleetManifest, ABadYamlManifestIsRefusedNamingFileLineAndKey) {
  const fs::path m = kDir / "bad_manifest.yaml";
  std::ofstream(m) << "units:\n  - unit: a\n    data: a.csv\n  - unit: b\n    limits: {gyro.bogus_max: 1}\n"
                      "  - {unit: a, data: a2.csv, colour: red}\n";
  const auto r = run_fleet(kDir / "bad_yaml", 1, m);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err,
              ::testing::AllOf(HasSubstr("bad_manifest.yaml:4"), HasSubstr("data"), HasSubstr("bad_manifest.yaml:5"),
                               HasSubstr("units[1].limits.gyro.bogus_max"), HasSubstr("bad_manifest.yaml:6"),
                               HasSubstr("appears twice"), HasSubstr("colour")));
}

TEST(FleetCalibrate, CalibrateRefusesTwoUnitsGivenAsOneDevice) {
  const fs::path sim = kDir / "small";
  const auto s = run_driftlab("simulate --fleet 6 --device imu3 --fs 1 --duration 1200 --seed 3 --out " + sim.string());
  ASSERT_EQ(s.exit_code, 0) << s.err;
  std::vector<std::string> normal;
  const auto key = read_json(sim / "key.json");
  for (const auto& u : key["units"])
    if (u["fault"].is_null()) normal.push_back((sim / u["data"].get<std::string>()).string());
  ASSERT_GE(normal.size(), 2u);
  const auto r = run_driftlab("calibrate --data " + normal[0] + " --data " + normal[1] + " --channels gyro --out " +
                              (kDir / "two.json").string());
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_THAT(r.err, HasSubstr("two devices"));
}

}  // namespace
}  // namespace driftlab
