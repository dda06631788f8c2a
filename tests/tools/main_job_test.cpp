// The main job end to end (issue 12): the paper's FMVMG oven run simulated, compensated by
// models/pipelines/li2023.yaml and scored against the truth, for two seeds and two oven profiles.
// Claims checked on each record, from report.json:
//   - every Table 2 row is there;
//   - B is not resolved on the compensated stages nor on the intrinsic floor: the gyro's white noise
//     (N = 99.6 deg/h/sqrt(Hz)) meets its flicker floor (0.664 x 1 deg/h) only near tau = 22 000 s,
//     beyond the record's longest tau (3 277 s), so the Allan deviation cannot have a floor there and
//     B is only a bound (B_deg_h null, B_upper_deg_h given);
//   - the bound on B does not rise from one stage to the next, and the final stage's bound is below
//     the paper's 3.589 deg/h (whatever its B, it is below the paper's);
//   - the residual drift (rms of 60-s block means of output - true rate) falls at least 10x;
//   - the Allan deviation of (output - true rate) stays within 1.5x of the intrinsic noise's at every
//     tau (allowing for both intervals);
//   - the pipeline beats the PX4-style polynomial baseline on residual drift;
//   - report.html holds the figures, each a real plot.
// Plus: swapping one block by configuration still runs, and the same seeds give identical outputs.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

using namespace testing_cli;

const std::string kSource = DRIFTLAB_SOURCE_DIR;
const std::string kPipeline = kSource + "/models/pipelines/li2023.yaml";
constexpr double kPaperFinalB = 3.589;       // deg/h, Li et al. 2023 Table 2
constexpr double kMinDriftReduction = 10.0;  // issue 12
// The bound on B of a stage may equal the previous one within the reading's rounding (the Kalman
// filter leaves the long-tau deviation where B is read unchanged); it must never rise by more than this.
constexpr double kMonotoneSlack = 1.005;

struct MainJob {
  nlohmann::json report;
  std::string html;
  std::map<std::string, nlohmann::json> rows;
};

MainJob run_main_job(const std::string& name, const std::string& profile, int seed) {
  const auto dir = scratch_dir("main_job_" + name);
  const auto record = (dir / "oven.csv").string();
  const auto sim = run_driftlab("simulate --device " + kSource + "/devices/fmvmg.yaml --profile " + profile +
                                " --fs 10 --seed " + std::to_string(seed) + " --out " + record);
  EXPECT_EQ(sim.exit_code, 0) << sim.err;
  const auto run = run_driftlab("--threads 2 run --pipeline " + kPipeline + " --data " + record + " --out " +
                                (dir / "run").string());
  EXPECT_EQ(run.exit_code, 0) << run.err;
  MainJob job;
  job.report = nlohmann::json::parse(read_text(dir / "run" / "report.json"));
  job.html = read_text(dir / "run" / "report.html");
  for (const auto& row : job.report["table2"]) job.rows[row["stage"].get<std::string>()] = row;
  std::filesystem::remove_all(dir);
  return job;
}

void expect_the_papers_claims_hold(const MainJob& job, const std::string& label) {
  SCOPED_TRACE(label);
  const std::vector<std::string> stages{"original", "rbf", "rbf_ga", "rbf_ga_kf"};
  for (const auto& s : stages) ASSERT_TRUE(job.rows.count(s)) << "missing Table 2 row " << s;
  ASSERT_TRUE(job.rows.count("px4_polynomial"));
  ASSERT_TRUE(job.rows.count("cubic_whole_record"));
  for (const auto& [stage, row] : job.rows)
    EXPECT_TRUE(row.contains("systematic_error_deg_h")) << stage << ": the record carries its systematic rate";
  ASSERT_TRUE(job.report.contains("intrinsic_floor"));

  for (std::size_t k = 1; k < stages.size(); ++k) {
    const auto& row = job.rows.at(stages[k]);
    EXPECT_FALSE(row["B_resolved"].get<bool>()) << stages[k] << " at tau " << row["B_tau_s"];
    EXPECT_TRUE(row["B_deg_h"].is_null()) << stages[k];
    EXPECT_LE(row["B_upper_deg_h"].get<double>(),
              job.rows.at(stages[k - 1])["B_upper_deg_h"].get<double>() * kMonotoneSlack)
        << stages[k] << " after " << stages[k - 1];
  }
  EXPECT_FALSE(job.report["intrinsic_floor"]["B_resolved"].get<bool>());
  // The paper's figures come from the pipeline's `reference` block, beside its rows, on a record like
  // the paper's (its oven cycle at 10 Hz) only; beside another, the table says why they are not shown.
  if (job.report.contains("reference")) {
    EXPECT_EQ(job.report["reference"]["source"], "Li et al., Micromachines 2023, 14, 971, Table 2");
    EXPECT_EQ(job.rows.at("original")["reference"]["B_deg_h"], 34.66);
    EXPECT_EQ(job.rows.at("rbf_ga_kf")["reference"]["B_deg_h"], kPaperFinalB);
    EXPECT_FALSE(job.rows.at("px4_polynomial").contains("reference"));
    EXPECT_NE(job.html.find("paper B (°/h)"), std::string::npos);
  } else {
    EXPECT_THAT(job.report["reference_not_shown"].get<std::string>(), ::testing::HasSubstr("is not the one"));
    EXPECT_EQ(job.html.find("paper B (°/h)"), std::string::npos);
    for (const auto& [stage, row] : job.rows) EXPECT_FALSE(row.contains("reference")) << stage;
  }
  const auto& final_row = job.rows.at("rbf_ga_kf");
  EXPECT_LE(final_row["B_upper_deg_h"].get<double>(), kPaperFinalB);

  const double raw_drift = job.rows.at("original")["residual_drift_deg_h"];
  const double final_drift = final_row["residual_drift_deg_h"];
  EXPECT_GE(raw_drift / final_drift, kMinDriftReduction);
  EXPECT_LT(final_drift, job.rows.at("px4_polynomial")["residual_drift_deg_h"].get<double>());
  EXPECT_TRUE(final_row["error_vs_floor"]["within_1_5x"].get<bool>())
      << "max ratio " << final_row["error_vs_floor"]["max_ratio"] << " at tau "
      << final_row["error_vs_floor"]["tau_of_max_s"];

  // The figures: Table 2's Allan plot, the record, two decompositions, two entropy plots, the
  // temperature trend, the reconstruction and the residual against temperature; each a real plot.
  std::size_t figures = 0;
  for (auto start = job.html.find("<svg"); start != std::string::npos; start = job.html.find("<svg", start + 1)) {
    const auto end = job.html.find("</svg>", start);
    ASSERT_NE(end, std::string::npos);
    ++figures;
    EXPECT_GT(end - start, 5000u) << "figure " << figures << " is nearly empty";
  }
  EXPECT_GE(figures, 9u);
  EXPECT_EQ(job.html.find("http://"), std::string::npos);
  EXPECT_EQ(job.html.find("https://"), std::string::npos);
}

TEST(MainJob, ReproducesTheShapeOfTable2OnThePapersOvenRun) {
  const auto job = run_main_job("seed1", "oven", 1);
  ASSERT_TRUE(job.report.contains("reference")) << "the paper's oven run shows the paper's columns";
  expect_the_papers_claims_hold(job, "oven, seed 1");
}

TEST(MainJob, HoldsForASecondSeed) { expect_the_papers_claims_hold(run_main_job("seed2", "oven", 2), "oven, seed 2"); }

TEST(MainJob, HoldsForAnOvenProfileWithOtherRampRates) {
  const auto job = run_main_job("ramps", std::string(DRIFTLAB_TEST_DATA) + "/profiles/oven_other_ramps.yaml", 3);
  EXPECT_FALSE(job.report.contains("reference")) << "another oven cycle is not the paper's record";
  expect_the_papers_claims_hold(job, "2 degC/min heating, 0.5 degC/min cooling, seed 3");
}

TEST(MainJob, ABlockSwappedByConfigurationStillRunsAndSameSeedsGiveIdenticalOutputs) {
  const auto dir = scratch_dir("main_job_swap");
  const auto record = (dir / "short.csv").string();
  ASSERT_EQ(run_driftlab("simulate --device " + kSource + "/devices/fmvmg.yaml --fs 5 --duration 2400 --seed 4 --out " +
                         record)
                .exit_code,
            0);
  // One line: the rate's decomposition becomes CEEMDAN (a small ensemble keeps the test short).
  std::string text = read_text(kPipeline);
  const std::string line = "    plugin: decomposition/emd\n    inputs: {signal: rate}\n";
  ASSERT_NE(text.find(line), std::string::npos);
  text.replace(text.find(line), line.size(),
               "    plugin: decomposition/ceemdan\n    inputs: {signal: rate}\n    params: {ensemble_size: 8}\n");
  const auto swapped = dir / "swapped.yaml";
  std::ofstream(swapped) << text;
  for (const std::string out : {"a", "b"}) {
    const auto r =
        run_driftlab("run --pipeline " + swapped.string() + " --data " + record + " --out " + (dir / out).string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  EXPECT_EQ(read_text(dir / "a" / "outputs.csv"), read_text(dir / "b" / "outputs.csv"));
  const auto threads = run_driftlab("--threads 2 run --pipeline " + swapped.string() + " --data " + record + " --out " +
                                    (dir / "c").string());
  ASSERT_EQ(threads.exit_code, 0) << threads.err;
  EXPECT_EQ(read_text(dir / "a" / "outputs.csv"), read_text(dir / "c" / "outputs.csv"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace driftlab
