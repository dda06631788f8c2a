// End-to-end tests of the `driftlab` command: exit codes, messages, outputs on disk.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
using namespace testing_cli;

const std::string kData = DRIFTLAB_TEST_DATA;
const std::string kPlugins = std::string("--plugin-path ") + DRIFTLAB_TEST_PLUGIN_DIR;

TEST(Cli, PrintsHelpForEveryCommandAndItsVersion) {
  for (const std::string cmd : {"", "plugins", "plugins list", "plugins describe", "run"}) {
    const auto r = run_driftlab(cmd + " --help");
    EXPECT_EQ(r.exit_code, 0) << cmd;
    EXPECT_THAT(r.out, HasSubstr("Usage:")) << cmd;
  }
  EXPECT_THAT(run_driftlab("--version").out, HasSubstr("driftlab 0."));
}

TEST(Cli, BadUsageExitsWithTwo) {
  EXPECT_EQ(run_driftlab("").exit_code, 2);
  EXPECT_EQ(run_driftlab("frobnicate").exit_code, 2);
  EXPECT_EQ(run_driftlab("run --pipeline").exit_code, 2);
}

TEST(Cli, ListsPluginsByKindIncludingExternalOnes) {
  const auto r = run_driftlab(kPlugins + " plugins list");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("decomposition:\n"));
  EXPECT_THAT(r.out, HasSubstr("filter:\n"));
  EXPECT_THAT(r.out, HasSubstr("filter/moving_average"));
}

TEST(Cli, DescribesEachParameterWithTypeDefaultUnitRangeAndDoc) {
  const auto r = run_driftlab(kPlugins + " plugins describe filter/moving_average");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("window  integer  default 5  [samples]  >= 1; odd"));
  EXPECT_THAT(r.out, HasSubstr("odd window length"));
  EXPECT_EQ(run_driftlab("plugins describe filter/nope").exit_code, 2);
}

TEST(Cli, APipelineWithThreeMistakesExitsTwoAndNamesAllThreeWithTheirLines) {
  const auto dir = scratch_dir("three_mistakes");
  const auto pipeline = kData + "/pipelines/cli_three_mistakes.yaml";
  const auto r = run_driftlab(kPlugins + " run --pipeline " + pipeline + " --data " + kData + "/csv/good.csv --out " +
                              dir.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr(pipeline + ":7: smooth.params.window: window must be odd"));
  EXPECT_THAT(r.err, HasSubstr(pipeline + ":11: again.params.width: unknown parameter"));
  EXPECT_THAT(r.err, HasSubstr(pipeline + ":13: detrend.plugin: unknown plugin"));
  EXPECT_FALSE(std::filesystem::exists(dir / "outputs.csv"));
}

TEST(Cli, ACsvWithANanOnLine1234ExitsThreeNamingFileLineAndColumn) {
  const auto dir = scratch_dir("nan");
  const auto data = kData + "/csv/nan_line_1234.csv";
  const auto r = run_driftlab(kPlugins + " run --pipeline " + kData + "/pipelines/external.yaml --data " + data +
                              " --out " + dir.string());
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_THAT(r.err, HasSubstr(data + ":1234: rate_dps: value is 'nan' (NaN/Inf not allowed)"));
}

// Progress on stderr when it is a file (the harness redirects it): a plain line when each step
// starts and ends, no carriage returns; --quiet silences it, and the outputs do not depend on it.
TEST(Cli, WritesProgressLinesWhenStderrIsAFileAndNoneWithQuiet) {
  const auto dir = scratch_dir("progress_lines"), quiet_dir = scratch_dir("progress_quiet");
  const std::string args = " run --pipeline " + kData + "/pipelines/external.yaml --data " + kData + "/csv/good.csv";
  const auto r = run_driftlab(kPlugins + args + " --out " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.err, HasSubstr("driftlab: [1/1] smooth: started\n"));
  EXPECT_THAT(r.err, ::testing::ContainsRegex("driftlab: \\[1/1\\] smooth: done in [0-9.]+ s\n"));
  EXPECT_THAT(r.err, Not(HasSubstr("\r")));

  const auto q = run_driftlab(kPlugins + " --quiet" + args + " --out " + quiet_dir.string());
  ASSERT_EQ(q.exit_code, 0) << q.err;
  EXPECT_THAT(q.err, Not(HasSubstr("smooth")));
  EXPECT_EQ(read_text(quiet_dir / "outputs.csv"), read_text(dir / "outputs.csv"));
}

TEST(Cli, RunsAPipelineWithAnExternalPluginAndTheEffectivePipelineReproducesIt) {
  const auto dir = scratch_dir("external");
  const auto r = run_driftlab(kPlugins + " run --pipeline " + kData + "/pipelines/external.yaml --data " + kData +
                              "/csv/good.csv --out " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto outputs = read_text(dir / "outputs.csv");
  EXPECT_THAT(outputs, ::testing::StartsWith("t_s,smoothed_dps\n"));
  EXPECT_THAT(read_text(dir / "pipeline.effective.yaml"), HasSubstr("window: 7"));
  EXPECT_THAT(read_text(dir / "report.json"), HasSubstr("\"status\": \"ok\""));

  const auto again = scratch_dir("external_again");
  const auto r2 = run_driftlab(kPlugins + " run --pipeline " + (dir / "pipeline.effective.yaml").string() + " --data " +
                               kData + "/csv/good.csv --out " + again.string());
  ASSERT_EQ(r2.exit_code, 0) << r2.err;
  EXPECT_EQ(read_text(again / "outputs.csv"), outputs);
}

TEST(Cli, FindsExternalPluginsThroughTheEnvironment) {
  const auto r = run_driftlab("plugins list", std::string("DRIFTLAB_PLUGIN_PATH=") + DRIFTLAB_TEST_PLUGIN_DIR);
  EXPECT_THAT(r.out, HasSubstr("filter/moving_average"));
}

TEST(Cli, NeverOverwritesAnInput) {
  const auto dir = scratch_dir("overwrite");
  std::filesystem::copy_file(kData + "/csv/good.csv", dir / "outputs.csv");
  const auto before = read_text(dir / "outputs.csv");
  const auto r = run_driftlab(kPlugins + " run --pipeline " + kData + "/pipelines/external.yaml --data " +
                              (dir / "outputs.csv").string() + " --out " + dir.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("inputs are never overwritten"));
  EXPECT_EQ(read_text(dir / "outputs.csv"), before);
}

TEST(Cli, ValidatesAPipelineWithoutData) {
  const auto r = run_driftlab(kPlugins + " run --validate-only --pipeline " + kData + "/pipelines/external.yaml");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("valid (1 steps)"));
}

// --pipeline takes a file or the name of a bundled pipeline (models/pipelines/, or an installed
// driftlab's share/driftlab/pipelines); a name that is neither is an error listing the bundled ones.
TEST(Cli, APipelineIsAFileOrTheNameOfABundledOne) {
  for (const std::string name : {"li2023", "li2023.yaml"}) {
    const auto r = run_driftlab("run --validate-only --pipeline " + name);
    EXPECT_EQ(r.exit_code, 0) << name << ": " << r.err;
    EXPECT_THAT(r.out, HasSubstr("valid (14 steps)")) << name;
  }
  for (const std::string command :
       {"run --validate-only --pipeline no_such_pipeline", "compare --pipeline no_such_pipeline --data x.csv --out cmp",
        "calibrate --data x.csv --paper-pipeline no_such_pipeline --out m.json"}) {
    const auto r = run_driftlab(command);
    EXPECT_EQ(r.exit_code, 2) << command;
    EXPECT_THAT(r.err, HasSubstr("no_such_pipeline")) << command;
    EXPECT_THAT(r.err, HasSubstr("no bundled pipeline of that name")) << command << ": " << r.err;
    EXPECT_THAT(r.err, HasSubstr("li2023")) << command;
  }
}

}  // namespace
}  // namespace driftlab
