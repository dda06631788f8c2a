// `driftlab run/compare --set STEP.KEY=VALUE` (framework/pipeline.hpp PipelineOverride): a step's
// parameter, a nested plugin's parameter or the step's plugin changed without editing the YAML,
// checked by the parameter tables; the report records what was applied and the stage labels say it.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

using ::testing::HasSubstr;
using testing_cli::read_text;
using testing_cli::run_driftlab;
using testing_cli::scratch_dir;

namespace fs = std::filesystem;

const std::string kSource = DRIFTLAB_SOURCE_DIR;
const std::string kPolynomial = kSource + "/models/pipelines/polynomial_baseline.yaml";
const std::string kLi2023 = kSource + "/models/pipelines/li2023.yaml";

// A simulated oven record (30 min at 1 Hz) in `dir`.
std::string simulated_record(const fs::path& dir) {
  const auto csv = (dir / "sim.csv").string();
  const auto r = run_driftlab("--quiet simulate --device " + kSource +
                              "/devices/fmvmg.yaml --profile oven --fs 1 --duration 1800 --seed 3 --out " + csv);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return csv;
}

// The polynomial baseline with a declared, labelled stage.
std::string staged_polynomial(const fs::path& dir) {
  const auto path = (dir / "staged.yaml").string();
  std::ofstream(path) << "format: driftlab-pipeline/1\n"
                         "inputs: {rate: rate, temperature: temperature}\n"
                         "steps:\n"
                         "  - name: compensate\n"
                         "    plugin: regressor/polynomial\n"
                         "    inputs: {target: rate, features: temperature}\n"
                         "outputs: {polynomial: compensate.residual}\n"
                         "stages: {polynomial: Polynomial fit}\n";
  return path;
}

TEST(PipelineOverrides, RunSetsAParameterRecordsItAndLabelsTheStageThatDependsOnIt) {
  const auto dir = scratch_dir("overrides_run");
  const auto csv = simulated_record(dir);
  const auto pipeline = staged_polynomial(dir);
  for (const std::string order : {"1", "3"}) {
    const auto r = run_driftlab("--quiet run --pipeline " + pipeline + " --data " + csv +
                                " --set compensate.order=" + order + " --out " + (dir / ("order" + order)).string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  const auto report = nlohmann::json::parse(read_text(dir / "order1" / "report.json"));
  EXPECT_EQ(report["overrides"], nlohmann::json::array({"compensate.order=1"}));
  bool labelled = false;
  for (const auto& row : report["table2"])
    if (row["stage"] == "polynomial") labelled = row["label"] == "Polynomial fit [compensate.order=1]";
  EXPECT_TRUE(labelled) << report["table2"].dump();
  EXPECT_THAT(read_text(dir / "order1" / "pipeline.effective.yaml"), HasSubstr("order: 1"));
  EXPECT_NE(read_text(dir / "order1" / "outputs.csv"), read_text(dir / "order3" / "outputs.csv"));
}

TEST(PipelineOverrides, ValidatesAPluginSwapAndNestedParametersAgainstTheTables) {
  const auto r = run_driftlab("run --validate-only --pipeline " + kLi2023 +
                              " --set decompose.plugin=decomposition/ceemdan --set decompose.ensemble_size=20"
                              " --set mixed_rbf_ga.optimizer.population=30");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("valid (14 steps, 3 overrides)"));
}

TEST(PipelineOverrides, EachBadOverrideExitsTwoNamingTheOptionTheStepTheParameterAndWhatWasExpected) {
  const struct {
    std::string pipeline, set;
    std::vector<std::string> expected;
  } cases[] = {
      {kPolynomial, "nosuch.order=1", {"--set nosuch.order=1: nosuch: no step 'nosuch'", "its steps: compensate"}},
      {kPolynomial,
       "compensate.degree=2",
       {"--set compensate.degree=2: compensate.params.degree: unknown parameter of regressor/polynomial", "max_order"}},
      {kPolynomial, "compensate.order=13", {"--set compensate.order=13: compensate.params.order", "12"}},
      {kPolynomial, "compensate.order=abc", {"--set compensate.order=abc: compensate.params.order", "integer"}},
      {kPolynomial, "compensate", {"--set", "no '='", "expected STEP.PARAM=VALUE"}},
      {kPolynomial,
       "compensate.plugin=filter/kalman",
       {"--set compensate.plugin=filter/kalman: compensate.plugin: expected a regressor plugin", "regressor/rbf"}},
      {kPolynomial, "compensate.plugin=regressor/nope", {"compensate.plugin: expected a regressor plugin name"}},
      {kLi2023, "stage_rbf.order=1", {"step 'stage_rbf' is a sum step"}},
      {kLi2023,
       "mixed_rbf_ga.optimizer.population=1",
       {"--set mixed_rbf_ga.optimizer.population=1: mixed_rbf_ga.params.optimizer.params.population"}},
      {kLi2023, "mixed_rbf_ga.optimizer.nope=1", {"unknown parameter of optimizer/ga"}},
      {kLi2023,
       "classify.m.x=1",
       {"classify.params.m: parameter 'm' of classifier/sample_entropy is not a nested plugin"}},
  };
  for (const auto& c : cases) {
    const auto r = run_driftlab("run --validate-only --pipeline " + c.pipeline + " --set " + c.set);
    EXPECT_EQ(r.exit_code, 2) << c.set << "\n" << r.err;
    for (const auto& text : c.expected) EXPECT_THAT(r.err, HasSubstr(text)) << c.set;
  }
}

TEST(PipelineOverrides, CompareAppliesAnOverrideToThePipelinesWithThatStepAndNamesItInTheLabel) {
  const auto dir = scratch_dir("overrides_compare");
  const auto csv = simulated_record(dir);
  const auto r = run_driftlab("--quiet compare --data " + csv + " --pipeline " + kPolynomial +
                              " --set compensate.order=2 --out " + (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto report = nlohmann::json::parse(read_text(dir / "out" / "report.json"));
  EXPECT_EQ(report["pipelines"][0]["overrides"], nlohmann::json::array({"compensate.order=2"}));
  EXPECT_EQ(report["pipelines"][0]["label"], "polynomial_baseline [compensate.order=2]");

  const auto bad = run_driftlab("compare --data " + csv + " --pipeline " + kPolynomial +
                                " --set nosuch.order=1 --out " + (dir / "bad").string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_THAT(bad.err, HasSubstr("--set nosuch.order=1: nosuch: no pipeline has a step 'nosuch'"));
}

}  // namespace
}  // namespace driftlab
