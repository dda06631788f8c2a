// End-to-end tests of `driftlab decompose` on a synthetic record: two tones on a ramp.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

using ::testing::HasSubstr;
using namespace testing_cli;

constexpr double kPi = 3.14159265358979323846;
constexpr double kSampleRateHz = 100.0;
constexpr int kSamples = 4000;
constexpr double kFastHz = 5.0, kSlowHz = 0.25;

double fast(double t) { return 0.4 * std::sin(2.0 * kPi * kFastHz * t + 0.3); }
double slow(double t) { return 0.8 * std::sin(2.0 * kPi * kSlowHz * t + 1.1); }
double ramp(double t) { return 0.05 + 0.002 * t; }

// t_s, rate_dps: 5 Hz + 0.25 Hz tones on a ramp, deg/s.
std::filesystem::path tones_csv(const std::filesystem::path& dir) {
  const auto path = dir / "tones.csv";
  std::ofstream out(path);
  out << "t_s,rate_dps\n";
  char line[80];
  for (int i = 0; i < kSamples; ++i) {
    const double t = i / kSampleRateHz;
    std::snprintf(line, sizeof line, "%.2f,%.17g\n", t, fast(t) + slow(t) + ramp(t));
    out << line;
  }
  return path;
}

// Columns of a CSV written by the command, by header name.
struct Table {
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;
};

Table read_table(const std::filesystem::path& path) {
  std::ifstream in(path);
  Table table;
  std::string line, cell;
  std::getline(in, line);
  std::stringstream header(line);
  while (std::getline(header, cell, ',')) table.names.push_back(cell);
  table.columns.resize(table.names.size());
  while (std::getline(in, line)) {
    std::stringstream row(line);
    for (std::size_t k = 0; std::getline(row, cell, ','); ++k) table.columns[k].push_back(std::stod(cell));
  }
  return table;
}

TEST(DecomposeCommand, WritesImfsThatSumBackToTheInputInItsUnitWithASummaryAndAPlot) {
  // deg/s -> rad/s -> deg/s and the shortest round-trip CSV text keep the sum within a few ulps.
  constexpr double kReconstructionTolerance = 1e-12;
  // The zero-crossing rate of an IMF that is a clean tone is its frequency, up to one crossing.
  constexpr double kFrequencyTolerance = 0.02;
  // The 0.25-Hz tone crosses zero only 20 times in the 40 s, so one crossing is 5 %: 4 x 2 %.
  constexpr double kFewCrossings = 4.0;
  constexpr double kShareSum = 1e-12;  // the energy shares are fractions of one total: they sum to 1 to rounding
  const auto dir = scratch_dir("decompose_tones");
  const auto csv = tones_csv(dir);
  const auto out = dir / "imfs.csv", json = dir / "summary.json", plot = dir / "imfs.svg";
  const auto r = run_driftlab("--threads 2 decompose --data " + csv.string() + " --set end_policy=linear --out " +
                              out.string() + " --json " + json.string() + " --plot " + plot.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("imf1"));
  EXPECT_THAT(r.out, HasSubstr("residue"));

  const Table table = read_table(out);
  ASSERT_GE(table.names.size(), 4u);
  EXPECT_EQ(table.names.front(), "t_s");
  EXPECT_EQ(table.names[1], "imf1");
  EXPECT_EQ(table.names.back(), "residue");
  ASSERT_EQ(table.columns[0].size(), static_cast<std::size_t>(kSamples));
  for (int i = 0; i < kSamples; i += 7) {
    const double t = table.columns[0][static_cast<std::size_t>(i)];
    double sum = 0.0;
    for (std::size_t k = 1; k < table.names.size(); ++k) sum += table.columns[k][static_cast<std::size_t>(i)];
    ASSERT_NEAR(sum, fast(t) + slow(t) + ramp(t), kReconstructionTolerance) << "row " << i;
  }

  const auto summary = nlohmann::json::parse(read_text(json));
  EXPECT_EQ(summary["plugin"], "decomposition/emd");
  EXPECT_EQ(summary["unit"], "deg/s");
  const auto& imfs = summary["imfs"];
  ASSERT_EQ(imfs.size() + 2, table.names.size());
  double shares = summary["residue"]["energy_share"].get<double>();
  for (const auto& imf : imfs) {
    shares += imf["energy_share"].get<double>();
    EXPECT_TRUE(imf["group"] == "noise" || imf["group"] == "mixed" || imf["group"] == "drift") << imf;
    EXPECT_TRUE(imf["sample_entropy"].is_number() || imf["sample_entropy"] == "Inf") << imf;
  }
  EXPECT_NEAR(shares, 1.0, kShareSum);
  EXPECT_NEAR(imfs[0]["mean_frequency_hz"].get<double>(), kFastHz, kFastHz * kFrequencyTolerance);
  EXPECT_NEAR(imfs[1]["mean_frequency_hz"].get<double>(), kSlowHz, kSlowHz * kFrequencyTolerance * kFewCrossings);
  EXPECT_GT(imfs[0]["sample_entropy"].get<double>(), 0.0);
  EXPECT_TRUE(summary["decomposition"].contains("orthogonality_index"));
  EXPECT_EQ(summary["decomposition"]["sifts_per_imf"].size(), imfs.size());

  const std::string svg = read_text(plot);
  EXPECT_THAT(svg, HasSubstr("<svg"));
  EXPECT_THAT(svg, HasSubstr("imf1"));
  EXPECT_THAT(svg, HasSubstr("residue"));
}

TEST(DecomposeCommand, RunsTheEnsemblePluginsWithTheSameOutputForAnyThreadCount) {
  const auto dir = scratch_dir("decompose_ceemdan");
  const auto csv = tones_csv(dir);
  std::string outputs[2];
  for (int threads : {1, 2}) {
    const auto out = dir / ("imfs" + std::to_string(threads) + ".csv");
    const auto r =
        run_driftlab("--threads " + std::to_string(threads) + " decompose --data " + csv.string() +
                     " --plugin decomposition/ceemdan --set ensemble_size=8 --set seed=5 --out " + out.string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    outputs[threads - 1] = read_text(out);
  }
  EXPECT_EQ(outputs[0], outputs[1]);
}

// CEEMDAN reports per ensemble member: with plain lines allowed at any interval
// ($DRIFTLAB_PROGRESS_INTERVAL_S=0), stderr (a file here) holds percentages between the start and
// the end line, each with its elapsed time; a bad interval is a usage error naming the variable.
TEST(DecomposeCommand, ReportsEnsembleProgressAsPlainLinesBetweenStartAndEnd) {
  const auto dir = scratch_dir("decompose_progress");
  const auto csv = tones_csv(dir);
  const std::string args = "decompose --data " + csv.string() +
                           " --plugin decomposition/ceemdan --set ensemble_size=8 --out " + (dir / "imfs.csv").string();
  const auto r = run_driftlab(args, "DRIFTLAB_PROGRESS_INTERVAL_S=0");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto started = r.err.find("driftlab: decompose: started\n");
  const auto done = r.err.find("driftlab: decompose: done in ");
  ASSERT_NE(started, std::string::npos) << r.err;
  ASSERT_NE(done, std::string::npos) << r.err;
  std::size_t percentages = 0;  // lines "driftlab: decompose: NN%, ..." between the two
  for (auto at = r.err.find("%, ", started); at < done; at = r.err.find("%, ", at + 1)) ++percentages;
  EXPECT_GE(percentages, 8u) << r.err;  // at least one line per member of the first stage
  EXPECT_THAT(r.err, ::testing::ContainsRegex("driftlab: decompose: [0-9]+%, [0-9.]+ s elapsed"));

  const auto bad = run_driftlab(args, "DRIFTLAB_PROGRESS_INTERVAL_S=soon");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_THAT(bad.err, HasSubstr("DRIFTLAB_PROGRESS_INTERVAL_S: expected a finite number of seconds >= 0"));
}

TEST(DecomposeCommand, RejectsBadParametersAndPluginsOfAnotherKind) {
  const auto dir = scratch_dir("decompose_errors");
  const auto csv = tones_csv(dir);
  const auto out = (dir / "imfs.csv").string();
  const auto bad_value = run_driftlab("decompose --data " + csv.string() + " --set s_number=0 --out " + out);
  EXPECT_EQ(bad_value.exit_code, 2);
  EXPECT_THAT(bad_value.err, HasSubstr("s_number"));
  const auto wrong_kind = run_driftlab("decompose --data " + csv.string() + " --plugin filter/kalman --out " + out);
  EXPECT_EQ(wrong_kind.exit_code, 2);
  EXPECT_THAT(wrong_kind.err, HasSubstr("not a decomposition plugin"));
  EXPECT_EQ(run_driftlab("decompose --data " + csv.string() + " --out " + csv.string()).exit_code, 2)
      << "the input must not be overwritten";
  EXPECT_EQ(run_driftlab("decompose --data " + csv.string() + "_missing --out " + out).exit_code, 3);
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace driftlab
