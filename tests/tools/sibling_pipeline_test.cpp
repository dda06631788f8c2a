// The sibling paper's method (Micromachines 2024, 15(5), 609) rebuilt from registered plugins:
// models/pipelines/iceemdan_tfpf_elm.yaml runs end to end, and swapping one block for another
// registered plugin is a one-line change that still runs (the VMD paper's pipeline has its own
// test, tests/models/vmd_wavelet_svr_pipeline_test.cpp). On a short simulated FMVMG oven record
// (15 min at 1 Hz) so the test stays fast; the full record's numbers are in docs/evidence.md.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

using ::testing::HasSubstr;
using testing_cli::read_text;
using testing_cli::run_driftlab;
using testing_cli::scratch_dir;

const std::string kSource = DRIFTLAB_SOURCE_DIR;
const std::string kPipeline = kSource + "/models/pipelines/iceemdan_tfpf_elm.yaml";

std::filesystem::path short_record(const std::filesystem::path& dir) {
  const auto csv = dir / "sim.csv";
  const auto r =
      run_driftlab("simulate --device " + kSource +
                   "/devices/fmvmg.yaml --profile oven --fs 1 --duration 900 --seed 1 --out " + csv.string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return csv;
}

// Replaces exactly one line of the pipeline (the first matching `from`) and writes the copy.
std::filesystem::path one_line_swap(const std::filesystem::path& dir, const std::string& from, const std::string& to) {
  std::ifstream in(kPipeline);
  std::ofstream out(dir / "swapped.yaml");
  int changed = 0;
  for (std::string line; std::getline(in, line);) {
    if (changed == 0 && line.find(from) != std::string::npos) {
      line.replace(line.find(from), from.size(), to);
      ++changed;
    }
    out << line << "\n";
  }
  EXPECT_EQ(changed, 1) << from;
  return dir / "swapped.yaml";
}

TEST(SiblingPipeline, RunsEndToEndFromItsYaml) {
  const auto dir = scratch_dir("sibling_runs");
  const auto csv = short_record(dir);
  const auto r = run_driftlab("--quiet run --pipeline " + kPipeline + " --data " + csv.string() + " --out " +
                              (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string report = read_text(dir / "out" / "report.json");
  for (const char* step : {"decomposition/ceemdan", "filter/tfpf", "regressor/elm"}) {
    EXPECT_THAT(report, HasSubstr(step));
  }
  EXPECT_THAT(report, HasSubstr("output_weight_norm"));  // tuned on the paper's two objectives
  EXPECT_THAT(report, HasSubstr("pareto_front"));
  EXPECT_THAT(read_text(dir / "out" / "outputs.csv"), HasSubstr("tfpf_elm_dps"));
  // Not the paper's pipeline: no figure is captioned as one of the paper's.
  EXPECT_THAT(read_text(dir / "out" / "report.html"), ::testing::Not(HasSubstr("paper Fig.")));
}

TEST(SiblingPipeline, SwappingOneBlockIsAOneLineChangeThatStillRuns) {
  const auto dir = scratch_dir("sibling_swaps");
  const auto csv = short_record(dir);
  const std::vector<std::pair<std::string, std::string>> swaps{
      {"plugin: regressor/elm", "plugin: regressor/svr"},
      {"plugin: filter/tfpf", "plugin: filter/kalman"},
      {"plugin: optimizer/pagmo, params: {algorithm: nsga2, population: 16, generations: 10}",
       "plugin: optimizer/ga, params: {population: 8, generations: 3}"},
      {"algorithm: nsga2, population: 16", "algorithm: de, population: 16"}};
  for (const auto& [from, to] : swaps) {
    const auto yaml = one_line_swap(dir, from, to);
    const auto r = run_driftlab("--quiet run --pipeline " + yaml.string() + " --data " + csv.string() + " --out " +
                                (dir / "out").string());
    EXPECT_EQ(r.exit_code, 0) << to << "\n" << r.err;
  }
}

}  // namespace
}  // namespace driftlab
