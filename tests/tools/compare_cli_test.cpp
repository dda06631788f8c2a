// driftlab compare: several pipelines on one record, one report (report.json, report.html).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

using testing_cli::read_text;
using testing_cli::run_driftlab;
using testing_cli::scratch_dir;
using ::testing::HasSubstr;

const std::string kSource = DRIFTLAB_SOURCE_DIR;

TEST(CompareCli, RunsEveryPipelineOnTheSameRecordAndWritesOneReport) {
  const auto dir = scratch_dir("compare_runs");
  const auto csv = (dir / "sim.csv").string();
  ASSERT_EQ(run_driftlab("simulate --device " + kSource + "/devices/fmvmg.yaml --profile oven --fs 1 --duration 1800 "
                         "--seed 1 --out " + csv).exit_code, 0);
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
    for (const auto& r : report["pipelines"][pipeline]["table2"])
      if (r["stage"] == "polynomial") return r;
    return nlohmann::json();
  };
  const auto row = stage_row(0);
  ASSERT_FALSE(row.is_null());
  for (const char* key : {"B_deg_h", "B_ci", "N_deg_h_rtHz", "bandwidth_hz", "residual_drift_deg_h", "seconds"}) {
    EXPECT_TRUE(row.contains(key)) << key;
  }
  // Same pipeline, same seed, same record: the same scores.
  EXPECT_EQ(row["B_deg_h"], stage_row(1)["B_deg_h"]);
  // The polynomial removes the temperature-driven bias: its residual drift is below the record's.
  EXPECT_LT(row["residual_drift_deg_h"].get<double>(), report["original"]["residual_drift_deg_h"].get<double>());
  const std::string html = read_text(dir / "out" / "report.html");
  EXPECT_THAT(html, HasSubstr("<svg"));
  EXPECT_THAT(html, HasSubstr("polynomial_baseline_2: polynomial"));
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

}  // namespace
}  // namespace driftlab
