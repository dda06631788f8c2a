// End-to-end tests of `driftlab allan`: the published ADIS16405 OADEV through the CSV/JSON/SVG
// outputs, a simulated white-noise record whose angle random walk is known, and bad input.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "models/allan/gmwm.hpp"
#include "framework/units.hpp"
#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

using ::testing::HasSubstr;
using namespace testing_cli;

std::vector<std::vector<double>> read_csv_rows(const std::filesystem::path& path, std::string& header) {
  std::ifstream in(path);
  std::getline(in, header);
  std::vector<std::vector<double>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream s(line);
    std::string cell;
    while (std::getline(s, cell, ',')) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return rows;
}

// 2^16 samples at 100 Hz of white rate noise with N = 0.5 deg/sqrt(h) (std N sqrt(fs) in deg/s)
// on a 0.3 deg/s bias; no time column (--fs).
std::filesystem::path white_noise_csv(const std::filesystem::path& dir) {
  constexpr double kFs = 100.0;
  const double n_deg_per_sqrt_s = 0.5 / 60.0;
  std::mt19937_64 engine(42);
  std::normal_distribution<double> normal;
  const auto path = dir / "white.csv";
  std::ofstream out(path);
  out << "rate_dps\n";
  char line[64];
  for (int i = 0; i < (1 << 16); ++i) {
    std::snprintf(line, sizeof line, "%.17g\n", 0.3 + n_deg_per_sqrt_s * std::sqrt(kFs) * normal(engine));
    out << line;
  }
  return path;
}

TEST(AllanCommand, WritesIntervalsTermsAndAPlotForAWhiteNoiseRecord) {
  const auto dir = scratch_dir("allan_white");
  const auto csv = white_noise_csv(dir);
  const auto out = dir / "allan.csv", json = dir / "summary.json", svg = dir / "allan.svg";
  const auto r = run_driftlab("allan --data " + csv.string() + " --fs 100 --out " + out.string() + " --json " +
                              json.string() + " --plot " + svg.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::string header;
  const auto rows = read_csv_rows(out, header);
  EXPECT_EQ(header, "tau_s,dev,dev_lo,dev_hi,n");
  ASSERT_EQ(rows.size(), 15u);  // octave grid up to (N-1)/4 = 16384 samples
  EXPECT_DOUBLE_EQ(rows.front()[0], 0.01);
  EXPECT_EQ(rows.front()[4], 65535.0);  // N - 2m terms at m = 1 (N = 65537 angle samples)
  for (const auto& row : rows) {
    EXPECT_LT(row[2], row[1]);
    EXPECT_GT(row[3], row[1]);
  }
  const auto summary = nlohmann::json::parse(read_text(json));
  for (const auto& [key, unit] : std::vector<std::pair<std::string, std::string>>{
           {"Q", "deg"}, {"N", "deg/sqrt(h)"}, {"B", "deg/h"}, {"K", "deg/h/sqrt(h)"}, {"R", "deg/h/h"}}) {
    ASSERT_TRUE(summary.contains(key)) << key;
    EXPECT_EQ(summary[key]["unit"], unit);
    // A resolved term has a value, sigma and interval; an unresolved one only its bound.
    const bool resolved = summary[key]["resolved"].get<bool>();
    EXPECT_EQ(summary[key]["value"].is_null(), !resolved) << key;
    EXPECT_EQ(summary[key].contains("sigma"), resolved) << key;
    EXPECT_EQ(summary[key].contains("upper"), !resolved) << key;
  }
  EXPECT_TRUE(summary["N"]["resolved"].get<bool>());
  // White noise alone has no floor: B is only a bound, not a value, and the summary says so.
  EXPECT_FALSE(summary["readings"]["B_flat_floor"]["resolved"].get<bool>());
  EXPECT_TRUE(summary["readings"]["B_flat_floor"]["value"].is_null());
  EXPECT_THAT(r.out, HasSubstr("B < "));
  EXPECT_THAT(r.out, HasSubstr("chi2/dof = "));
  EXPECT_EQ(summary["sampling"]["layout"], "even");
  constexpr double kRecoveryTolerance = 0.05;  // relative; 2^16 samples of white noise
  EXPECT_NEAR(summary["N"]["value"].get<double>() / 0.5, 1.0, kRecoveryTolerance);
  EXPECT_NEAR(summary["N_density"]["value"].get<double>() / 30.0, 1.0, kRecoveryTolerance);
  EXPECT_NEAR(summary["kalibr"]["gyroscope_noise_density"]["value"].get<double>() /
                  (0.5 / 60.0 * 3.14159265358979323846 / 180.0),
              1.0, kRecoveryTolerance);
  EXPECT_DOUBLE_EQ(summary["record_length_s"].get<double>(), 655.36);
  const std::string plot = read_text(svg);
  EXPECT_THAT(plot, HasSubstr("<svg"));
  EXPECT_THAT(plot, HasSubstr("tau (s)"));
  EXPECT_THAT(plot, HasSubstr("slope -1/2: N"));  // the reading guides
  EXPECT_THAT(plot, HasSubstr("oadev (°/h)"));    // the text's unit
}

TEST(AllanCommand, SaysWhichGnuplotItCouldNotRunWhenAPlotIsAsked) {
  const auto dir = scratch_dir("allan_no_gnuplot");
  const auto csv = white_noise_csv(dir);
  const auto r = run_driftlab("allan --data " + csv.string() + " --fs 100 --out " + (dir / "allan.csv").string() +
                                  " --plot " + (dir / "allan.svg").string(),
                              "DRIFTLAB_GNUPLOT=/nonexistent/gnuplot");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("/nonexistent/gnuplot"));
  EXPECT_THAT(r.err, HasSubstr("gnuplot-nox"));
  EXPECT_FALSE(std::filesystem::exists(dir / "allan.svg"));
}

TEST(AllanCommand, ReproducesThePublishedAdis16405AllanVariance) {
  const auto data =
      std::filesystem::path(DRIFTLAB_SHARED_DATA) / "real" / "smac-imudata-static" / "adis16405_imu1_gyro_dps.csv";
  if (!std::filesystem::exists(data)) GTEST_SKIP() << "shared reference data not found: " << data;
  const auto dir = scratch_dir("allan_adis");
  const auto out = dir / "allan.csv";
  const auto r =
      run_driftlab("allan --data " + data.string() +
                   " --column rate=gyro_x_dps:deg/s --fs 100 --taus 0.02,1.28,2621.44 --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::string header;
  const auto rows = read_csv_rows(out, header);
  ASSERT_EQ(rows.size(), 3u);
  constexpr double kPublishedTolerance = 1e-4;
  const double published[] = {6.6290651997e-02, 1.3045389364e-03, 3.2755302229e-05};  // (deg/s)^2
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_NEAR(rows[i][1] * rows[i][1] / published[i], 1.0, kPublishedTolerance) << rows[i][0];
  }
}

TEST(AllanCommand, RejectsBadOptionsAndData) {
  const auto dir = scratch_dir("allan_bad");
  const auto csv = white_noise_csv(dir);
  const auto out = (dir / "allan.csv").string();
  EXPECT_EQ(run_driftlab("allan --data " + csv.string() + " --fs 100 --kind bogus --out " + out).exit_code, 2);
  EXPECT_EQ(run_driftlab("allan --data " + csv.string() + " --fs 100 --taus 1e6 --out " + out).exit_code, 2);
  EXPECT_EQ(run_driftlab("allan --data " + csv.string() + " --fs 100 --out " + csv.string()).exit_code, 2);
  EXPECT_EQ(run_driftlab("allan --data " + (dir / "missing.csv").string() + " --fs 100 --out " + out).exit_code, 3);
}

const std::filesystem::path kReal = std::filesystem::path(DRIFTLAB_SHARED_DATA) / "real";
const std::filesystem::path kLsm6dsm = kReal / "pan-lsm6dsm-tvac" / "tvac_lsm6dsm_derived.csv";
const std::filesystem::path kMpu6050 = kReal / "sunsided-mpu6050-static" / "mpu6050_unmoved_x_forward_10min.csv";

// --gmwm: a seeded 6-h record of white noise, rate random walk and a Gauss-Markov bias (10 Hz, deg/s
// in the CSV) read back by `driftlab allan --gmwm wn+rw+gm`: every parameter resolved and within
// three sigma of the truth, in the IEEE 952 units; the same seed gives the same numbers on any thread
// count; a bad model is a usage error naming the option; a burst record refuses the bootstrap.
TEST(AllanCommand, FitsAGmwmModelBesideTheSlopeFit) {
  namespace gmwm = allan::gmwm;
  const double fs = 10.0, n = 2e-4, k = 2e-6, sigma = 3e-5, t = 100.0;  // SI
  const auto term = [](gmwm::Process p, std::vector<double> v) {
    gmwm::Component c{p, {}};
    for (const double x : v) c.parameters.push_back({"", "", x, x, x, true});
    return c;
  };
  const Eigen::VectorXd x = gmwm::simulate({term(gmwm::Process::WhiteNoise, {n}), term(gmwm::Process::RandomWalk, {k}),
                                            term(gmwm::Process::GaussMarkov, {sigma, t})},
                                           fs, 216000, 9);
  const auto dir = scratch_dir("allan_gmwm");
  const auto csv = dir / "noise.csv", json = dir / "summary.json";
  {
    std::ofstream out(csv);
    out << "t_s,rate_dps\n";
    char line[80];
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      std::snprintf(line, sizeof line, "%.17g,%.17g\n", static_cast<double>(i) / fs, x[i] * kDegPerRad);
      out << line;
    }
  }
  const auto r = run_driftlab("--threads 2 allan --data " + csv.string() + " --out " + (dir / "a.csv").string() +
                              " --json " + json.string() + " --gmwm wn+rw+gm --gmwm-bootstrap 20 --seed 4");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("GMWM wn+rw+gm"));
  EXPECT_THAT(r.out, HasSubstr("bootstrap, 20 of 20 replicates"));
  const auto g = nlohmann::json::parse(read_text(json))["gmwm"];
  EXPECT_EQ(g["model"], "wn+rw+gm");

  // In the IEEE 952 units: N deg/sqrt(h), K deg/h/sqrt(h), the Gauss-Markov sigma deg/h and T s.
  const double deg_sqrt_h = kDegPerRad * kSqrtSecondsPerHour, deg_h = kDphPerRadPerSec;
  const double truth[] = {n * deg_sqrt_h, k * deg_h * kSqrtSecondsPerHour, sigma * deg_h, t};
  for (int i = 0; i < 4; ++i) {
    const auto& file = g["components"][std::min(i, 2)]["parameters"][i == 3 ? 1 : 0];
    ASSERT_TRUE(file["resolved"].get<bool>()) << file.dump();
    const double value = file["value"], high = file["interval"][1];
    EXPECT_LT(std::abs(std::log(value / truth[i])) / std::log(high / value), 3.0) << file.dump();
  }
  // Same seed, same file on one thread; another seed moves only the intervals.
  const auto one = run_driftlab("allan --data " + csv.string() + " --out " + (dir / "a1.csv").string() + " --json " +
                                (dir / "one.json").string() + " --gmwm wn+rw+gm --gmwm-bootstrap 20 --seed 4");
  ASSERT_EQ(one.exit_code, 0) << one.err;
  EXPECT_EQ(nlohmann::json::parse(read_text(dir / "one.json"))["gmwm"], g);
  const auto other = run_driftlab("allan --data " + csv.string() + " --out " + (dir / "a2.csv").string() + " --json " +
                                  (dir / "other.json").string() + " --gmwm wn+rw+gm --gmwm-bootstrap 20 --seed 5");
  ASSERT_EQ(other.exit_code, 0) << other.err;
  const auto o = nlohmann::json::parse(read_text(dir / "other.json"))["gmwm"];
  EXPECT_EQ(o["components"][0]["parameters"][0]["value"], g["components"][0]["parameters"][0]["value"]);
  EXPECT_NE(o["components"][0]["parameters"][0]["interval"], g["components"][0]["parameters"][0]["interval"]);
  const auto bad =
      run_driftlab("allan --data " + csv.string() + " --out " + (dir / "b.csv").string() + " --gmwm wn+flicker");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_THAT(bad.err, HasSubstr("--gmwm"));
  EXPECT_THAT(bad.err, HasSubstr("flicker"));
  const auto one_replicate = run_driftlab("allan --data " + csv.string() + " --out " + (dir / "b.csv").string() +
                                          " --gmwm wn --gmwm-bootstrap 1");
  EXPECT_EQ(one_replicate.exit_code, 2);
  EXPECT_THAT(one_replicate.err, HasSubstr("--gmwm-bootstrap"));
  EXPECT_THAT(one_replicate.err, HasSubstr("one replicate gives no interval"));
  if (std::filesystem::exists(kLsm6dsm)) {
    const auto bursts = run_driftlab("allan --data " + kLsm6dsm.string() +
                                     " --column time=time_s:s --column rate=gyro_x_rad_s:rad/s --out " +
                                     (dir / "c.csv").string() + " --gmwm wn");
    EXPECT_EQ(bursts.exit_code, 2);
    EXPECT_THAT(bursts.err, HasSubstr("--gmwm-bootstrap 0"));
  }
}

// The LSM6DSM thermal-vacuum record: 25 bursts of 5 s at 50 Hz, one every ~5 min. With or without
// --max-gap 0 (which the README used to pass to read it as one record), never a contiguous reading
// at the mean rate of 0.85 Hz: the Allan deviation of every burst pooled, tau within a burst.
TEST(AllanCommand, AnalysesTheLsm6dsmBurstRecordPerBurst) {
  if (!std::filesystem::exists(kLsm6dsm)) GTEST_SKIP() << "shared data not found: " << kLsm6dsm;
  const auto dir = scratch_dir("allan_bursts");
  for (const std::string gap : {"", " --max-gap 0"}) {
    SCOPED_TRACE("options:" + gap);
    const auto out = dir / "allan.csv", json = dir / "summary.json";
    std::filesystem::remove(json);
    const auto r =
        run_driftlab("allan --data " + kLsm6dsm.string() + " --column time=time_s:s --column rate=gyro_x_rad_s:rad/s" +
                     gap + " --out " + out.string() + " --json " + json.string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_THAT(r.out, HasSubstr("25 regular bursts"));
    EXPECT_THAT(r.out, HasSubstr("per burst"));
    const auto summary = nlohmann::json::parse(read_text(json));
    EXPECT_EQ(summary["sampling"]["layout"], "regular_bursts");
    EXPECT_EQ(summary["sampling"]["bursts"], 25);
    constexpr double kBurstRateHz = 50.0, kRateTolerance = 0.01;  // relative: time stamps in ms
    EXPECT_NEAR(summary["sample_rate_hz"].get<double>() / kBurstRateHz, 1.0, kRateTolerance);
    std::string header;
    const auto rows = read_csv_rows(out, header);
    ASSERT_FALSE(rows.empty());
    constexpr double kBurstS = 5.0;
    EXPECT_LE(rows.back()[0], kBurstS);  // no tau across a gap
    // Every burst contributes: at tau0 there are more terms than one burst has samples.
    EXPECT_GT(rows.front()[4], 24.0 * kBurstS * kBurstRateHz);
    // A few seconds of data per burst: B is not resolved there.
    EXPECT_FALSE(summary["readings"]["B_flat_floor"]["resolved"].get<bool>());
  }
}

// The MPU6050 record has irregular host time stamps (median step 2 ms, steps up to 0.5 s): not an
// Allan record as it stands. Exit 3 naming the first gap and the ways out, with --max-gap 0 too.
TEST(AllanCommand, RefusesTheIrregularMpu6050RecordNamingTheFirstGap) {
  if (!std::filesystem::exists(kMpu6050)) GTEST_SKIP() << "shared data not found: " << kMpu6050;
  const auto dir = scratch_dir("allan_irregular");
  for (const std::string gap : {"", " --max-gap 0"}) {
    SCOPED_TRACE("options:" + gap);
    const auto r =
        run_driftlab("allan --data " + kMpu6050.string() + " --column time=time_s:s --column rate=gyro_z_dps:deg/s" +
                     gap + " --out " + (dir / "allan.csv").string());
    EXPECT_EQ(r.exit_code, 3);
    EXPECT_THAT(r.err, HasSubstr("assumes even sampling"));
    EXPECT_THAT(r.err, HasSubstr("the first of"));
    EXPECT_THAT(r.err, HasSubstr("after t = "));
    EXPECT_THAT(r.err, HasSubstr("Resample"));
    EXPECT_THAT(r.err, HasSubstr("split"));
    EXPECT_FALSE(std::filesystem::exists(dir / "allan.csv"));
  }
}

// `driftlab run` decomposes and filters the record as one evenly sampled series: a burst record and
// an irregular one are refused (exit 3) before any step runs, naming the first gap; for bursts it
// points to `driftlab allan`.
TEST(RunCommand, RefusesBurstAndIrregularRecordsNamingTheFirstGap) {
  if (!std::filesystem::exists(kLsm6dsm) || !std::filesystem::exists(kMpu6050)) GTEST_SKIP() << "shared data not found";
  const auto dir = scratch_dir("run_gaps");
  const std::string pipeline = std::string(DRIFTLAB_SOURCE_DIR) + "/models/pipelines/polynomial_baseline.yaml";
  const auto bursts = run_driftlab("--quiet run --pipeline " + pipeline + " --data " + kLsm6dsm.string() +
                                   " --column time=time_s:s --column rate=gyro_x_rad_s:rad/s"
                                   " --column temperature=temp_C_est:degC --max-gap 0 --out " +
                                   (dir / "b").string());
  EXPECT_EQ(bursts.exit_code, 3);
  EXPECT_THAT(bursts.err, HasSubstr("25 regular bursts"));
  EXPECT_THAT(bursts.err, HasSubstr("driftlab allan"));
  EXPECT_FALSE(std::filesystem::exists(dir / "b" / "outputs.csv"));
  const auto irregular = run_driftlab("--quiet run --pipeline " + pipeline + " --data " + kMpu6050.string() +
                                      " --column time=time_s:s --column rate=gyro_z_dps:deg/s"
                                      " --column temperature=temp_C:degC --out " +
                                      (dir / "i").string());
  EXPECT_EQ(irregular.exit_code, 3);
  EXPECT_THAT(irregular.err, HasSubstr("irregular"));
  EXPECT_THAT(irregular.err, HasSubstr("Resample"));
}

}  // namespace
}  // namespace driftlab
