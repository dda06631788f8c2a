// driftlab compare: several pipelines on one record, one report (report.json, report.html).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
using testing_cli::read_text;
using testing_cli::run_driftlab;
using testing_cli::scratch_dir;

namespace fs = std::filesystem;

const std::string kSource = DRIFTLAB_SOURCE_DIR;
const std::string kPolynomial = kSource + "/models/pipelines/polynomial_baseline.yaml";

// Files in `dir` (at any depth), temporaries of a failed run included.
std::vector<std::string> files_in(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) names.push_back(fs::relative(e.path(), dir).string());
  return names;
}

TEST(CompareCli, RunsEveryPipelineOnTheSameRecordAndWritesOneReport) {
  const auto dir = scratch_dir("compare_runs");
  const auto csv = (dir / "sim.csv").string();
  ASSERT_EQ(run_driftlab("simulate --device " + kSource +
                         "/devices/fmvmg.yaml --profile oven --fs 1 --duration 1800 "
                         "--seed 1 --out " +
                         csv)
                .exit_code,
            0);
  const std::string poly = kSource + "/models/pipelines/polynomial_baseline.yaml";
  const auto r = run_driftlab("--quiet compare --data " + csv + " --pipeline " + poly + " --pipeline " + poly +
                              " --out " + (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto report = nlohmann::json::parse(read_text(dir / "out" / "report.json"));
  EXPECT_EQ(report["format"], "driftlab-compare-report/1");
  ASSERT_EQ(report["pipelines"].size(), 2u);
  EXPECT_EQ(report["pipelines"][0]["label"], "polynomial_baseline");
  EXPECT_EQ(report["pipelines"][1]["label"], "polynomial_baseline_2");  // labels stay unique
  const auto stage_row = [&](int pipeline) {
    for (const auto& entry : report["pipelines"][pipeline]["table2"])
      if (entry["stage"] == "polynomial") return entry;
    return nlohmann::json();
  };
  const auto row = stage_row(0);
  ASSERT_FALSE(row.is_null());
  for (const char* key : {"B_resolved", "B_deg_h", "B_upper_deg_h", "B_within_tau_s", "N_deg_h_rtHz", "bandwidth_hz",
                          "residual_drift_deg_h", "seconds"}) {
    EXPECT_TRUE(row.contains(key)) << key;
  }
  // B is a value with its interval only where it is resolved; otherwise null beside its bound.
  EXPECT_EQ(row["B_deg_h"].is_null(), !row["B_resolved"].get<bool>());
  EXPECT_EQ(row.contains("B_ci"), row["B_resolved"].get<bool>());
  // Same pipeline, same seed, same record: the same scores.
  EXPECT_EQ(row["B_upper_deg_h"], stage_row(1)["B_upper_deg_h"]);
  // The polynomial removes the temperature-driven bias: its residual drift is below the record's.
  EXPECT_LT(row["residual_drift_deg_h"].get<double>(), report["original"]["residual_drift_deg_h"].get<double>());
  const std::string html = read_text(dir / "out" / "report.html");
  EXPECT_THAT(html, HasSubstr("<svg"));
  EXPECT_THAT(html, HasSubstr("polynomial_baseline_2: polynomial"));
  // The terminal table has its header, and the record's rows include the intrinsic floor (the
  // simulated record has its systematic column), as in the HTML table.
  EXPECT_EQ(r.out.substr(0, r.out.find('\n')).rfind("pipeline  stage  B", 0), 0u) << r.out;
  EXPECT_THAT(r.out, HasSubstr("\n(record)  intrinsic floor  "));
  EXPECT_THAT(html, HasSubstr("<td>intrinsic floor</td>"));
  EXPECT_THAT(r.out, HasSubstr("polynomial_baseline"));
}

TEST(CompareCli, ChecksEveryPipelineBeforeReadingData) {
  const auto dir = scratch_dir("compare_bad");
  const auto r = run_driftlab("--quiet compare --data " + (dir / "missing.csv").string() + " --pipeline " + kSource +
                              "/models/pipelines/polynomial_baseline.yaml --pipeline " + (dir / "nope.yaml").string() +
                              " --out " + (dir / "out").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("nope.yaml"));
}

// Outputs (report.json, report.html) follow the OutputSet rules: planned before the record is read,
// written together at the end or not at all.
class CompareOutputs : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    record_dir_ = new fs::path(scratch_dir("compare_outputs_record"));
    ASSERT_EQ(run_driftlab("simulate --device " + kSource +
                           "/devices/fmvmg.yaml --profile oven --fs 1 --duration 1800 "
                           "--seed 1 --out " +
                           (*record_dir_ / "sim.csv").string())
                  .exit_code,
              0);
  }
  static void TearDownTestSuite() {
    fs::remove_all(*record_dir_);
    delete record_dir_;
  }
  void SetUp() override { dir_ = scratch_dir(::testing::UnitTest::GetInstance()->current_test_info()->name()); }
  static fs::path record() { return *record_dir_ / "sim.csv"; }

  static fs::path* record_dir_;
  fs::path dir_;
};
fs::path* CompareOutputs::record_dir_ = nullptr;

TEST_F(CompareOutputs, AnOutputDirectoryThatCannotBeMadeIsAUsageErrorBeforeTheDataIsRead) {
  std::ofstream(dir_ / "file.txt") << "a file, not a directory\n";
  // The data file does not exist: had the record been read (or a pipeline run) first, the error
  // would name it, with exit code 3.
  const auto missing = (dir_ / "missing.csv").string();
  for (const auto& out : {dir_ / "file.txt" / "out", dir_ / "file.txt"}) {
    const auto r =
        run_driftlab("--quiet compare --data " + missing + " --pipeline " + kPolynomial + " --out " + out.string());
    EXPECT_EQ(r.exit_code, 2) << out << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr("--out: cannot create the directory")) << out;
    EXPECT_THAT(r.err, Not(HasSubstr("missing.csv"))) << out;
  }
  if (::geteuid() != 0) {  // root writes anywhere
    fs::create_directories(dir_ / "ro");
    fs::permissions(dir_ / "ro", fs::perms::owner_read | fs::perms::owner_exec);
    const auto r = run_driftlab("--quiet compare --data " + missing + " --pipeline " + kPolynomial + " --out " +
                                (dir_ / "ro").string());
    fs::permissions(dir_ / "ro", fs::perms::owner_all);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_THAT(r.err, HasSubstr("cannot write to the output directory"));
  }
  EXPECT_EQ(files_in(dir_), std::vector<std::string>{"file.txt"});
}

TEST_F(CompareOutputs, AnOutputThatIsAnInputIsRefusedAndTheInputIsUnchanged) {
  fs::create_directories(dir_ / "data_as_json");
  fs::copy_file(record(), dir_ / "data_as_json" / "report.json");
  fs::create_directories(dir_ / "pipeline_as_html");
  fs::copy_file(kPolynomial, dir_ / "pipeline_as_html" / "report.html");
  const std::vector<std::pair<std::string, fs::path>> cases{
      {"--data " + (dir_ / "data_as_json" / "report.json").string() + " --pipeline " + kPolynomial + " --out " +
           (dir_ / "data_as_json").string(),
       dir_ / "data_as_json" / "report.json"},
      {"--data " + record().string() + " --pipeline " + (dir_ / "pipeline_as_html" / "report.html").string() +
           " --out " + (dir_ / "pipeline_as_html").string(),
       dir_ / "pipeline_as_html" / "report.html"}};
  for (const auto& [args, input] : cases) {
    const std::string before = read_text(input);
    const auto r = run_driftlab("--quiet compare " + args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr("inputs are never overwritten")) << args;
    EXPECT_EQ(read_text(input), before) << args;
  }
  EXPECT_EQ(files_in(dir_ / "data_as_json"), std::vector<std::string>{"report.json"});
  EXPECT_EQ(files_in(dir_ / "pipeline_as_html"), std::vector<std::string>{"report.html"});
}

TEST_F(CompareOutputs, AFailureLeavesNoPartialReportAndKeepsTheEarlierOne) {
  // The figure fails after every pipeline has run and report.json is ready: nothing of this run may
  // appear, and the report.json of an earlier run stays as it was.
  fs::create_directories(dir_ / "out");
  std::ofstream(dir_ / "out" / "report.json") << "earlier report\n";
  const auto r = run_driftlab("--quiet compare --data " + record().string() + " --pipeline " + kPolynomial + " --out " +
                                  (dir_ / "out").string(),
                              "DRIFTLAB_GNUPLOT=/bin/false");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr("gnuplot"));
  EXPECT_EQ(read_text(dir_ / "out" / "report.json"), "earlier report\n");
  EXPECT_EQ(files_in(dir_ / "out"), std::vector<std::string>{"report.json"});  // no report.html, no temporaries
}

}  // namespace
}  // namespace driftlab
