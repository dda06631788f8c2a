#include "framework/pipeline.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/registry.hpp"
#include "tests/framework/test_plugins.hpp"

namespace driftlab {
namespace {

using ::testing::HasSubstr;

const std::filesystem::path kPipelines = std::filesystem::path(DRIFTLAB_TEST_DATA) / "pipelines";

class PipelineTest : public ::testing::Test {
 protected:
  PipelineTest() { testing_plugins::register_test_plugins(registry_); }

  std::vector<Diagnostic> problems_of(const std::string& file) {
    try {
      load_pipeline(kPipelines / file, registry_);
    } catch (const ConfigError& e) {
      return e.problems();
    }
    ADD_FAILURE() << file << " was accepted";
    return {};
  }

  static bool reported(const std::vector<Diagnostic>& problems, int line, const std::string& key,
                       const std::string& text) {
    for (const auto& p : problems)
      if (p.where.line == line && p.where.field == key && p.message.find(text) != std::string::npos) return true;
    return false;
  }

  static std::string all(const std::vector<Diagnostic>& problems) {
    std::string s;
    for (const auto& p : problems) s += p.to_string() + "\n";
    return s;
  }

  static TimeSeries record() {
    TimeSeries r(Eigen::VectorXd::LinSpaced(200, 0.0, 19.9));
    const Eigen::VectorXd temp = 20.0 + 0.5 * r.time().array();
    r.set_channel(
        {role::kRate, "rad/s", "test", (0.01 * temp.array() + (r.time().array() * 3.0).sin() * 1e-3).matrix()});
    r.set_channel({role::kTemperature, "degC", "test", temp});
    return r;
  }

  Registry registry_;
};

// RunContext's sample rate (framework/plugin.hpp): run_pipeline gives it; a context built by hand
// (python, tests) may leave it at 0 and rate_hz() derives it from the time stamps.
TEST(RunContextSampleRate, IsGivenOrDerivedFromTheTimeStamps) {
  RunContext ctx;
  EXPECT_EQ(ctx.rate_hz(), 0.0) << "no time stamps: no rate";
  ctx.time_s = Eigen::VectorXd::LinSpaced(11, 0.0, 1.0);
  EXPECT_EQ(ctx.rate_hz(), 10.0);
  ctx.sample_rate_hz = 4.0;
  EXPECT_EQ(ctx.rate_hz(), 4.0);
}

TEST_F(PipelineTest, ReportsThreeDifferentMistakesTogetherWithTheirLines) {
  const auto problems = problems_of("three_mistakes.yaml");
  const auto file = (kPipelines / "three_mistakes.yaml").string();
  EXPECT_EQ(problems.size(), 3u) << all(problems);
  EXPECT_TRUE(reported(problems, 7, "smooth.params.gain", "out of range")) << all(problems);
  EXPECT_TRUE(reported(problems, 11, "fit.params.solver_tolerance", "unknown parameter")) << all(problems);
  EXPECT_TRUE(reported(problems, 11, "fit.params.solver_tolerance", "valid: optimizer, min_terms, max_terms, method"))
      << "an unknown key lists the valid keys";
  EXPECT_TRUE(reported(problems, 13, "trend.plugin", "unknown plugin")) << all(problems);
  for (const auto& p : problems) EXPECT_EQ(p.where.file, file);
}

TEST_F(PipelineTest, ReportsDuplicateStepNames) {
  const auto problems = problems_of("duplicate_names.yaml");
  EXPECT_TRUE(reported(problems, 10, "steps[2].name", "duplicate step name 'first' (first used on line 4)"))
      << all(problems);
}

TEST_F(PipelineTest, ReportsCyclicReferences) {
  const auto problems = problems_of("cycle.yaml");
  EXPECT_TRUE(reported(problems, 4, "first", "cyclic reference: steps first, second depend on each other"))
      << all(problems);
}

TEST_F(PipelineTest, ReportsStructuralMistakesWithoutTouchingData) {
  const auto problems = problems_of("structural_mistakes.yaml");
  EXPECT_TRUE(reported(problems, 1, "format", "unsupported format 'driftlab-pipeline/2'")) << all(problems);
  EXPECT_TRUE(reported(problems, 3, "colour", "unknown key")) << all(problems);
  EXPECT_TRUE(reported(problems, 7, "a.inputs.extra", "unknown input port")) << all(problems);
  EXPECT_TRUE(reported(problems, 7, "a.inputs", "dangling reference 'rat'")) << all(problems);
  EXPECT_TRUE(reported(problems, 9, "b.plugin", "cannot run as pipeline steps")) << all(problems);
  EXPECT_TRUE(reported(problems, 12, "c.inputs", "step 'a' has outputs signal")) << all(problems);
  EXPECT_TRUE(reported(problems, 12, "c.inputs.features", "required input port is not connected")) << all(problems);
  EXPECT_TRUE(reported(problems, 13, "c.params.method", "'svd' is not one of: qr normal")) << all(problems);
  EXPECT_TRUE(reported(problems, 13, "c.params.optimizer.params.evaluations", "out of range")) << all(problems);
  EXPECT_TRUE(reported(problems, 14, "outputs", "no step named 'missing'")) << all(problems);
}

TEST_F(PipelineTest, RejectsCrossParameterRuleViolations) {
  try {
    parse_pipeline(R"(format: driftlab-pipeline/1
steps:
  - name: fit
    plugin: regressor/test_linear
    inputs: {target: rate, features: time}
    params: {min_terms: 5, max_terms: 2}
outputs: {out: fit.fitted}
)",
                   "inline.yaml", registry_);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(),
                HasSubstr("fit.params.min_terms,fit.params.max_terms: violates rule: min_terms <= max_terms"));
  }
}

TEST_F(PipelineTest, DeclaredStagesKeepTheirOrderAndLabelsAndMustBeOutputs) {
  const std::string head = R"(format: driftlab-pipeline/1
steps:
  - {name: s, plugin: filter/test_gain, inputs: {signal: rate}}
outputs: {a: s.signal, b: s.signal}
)";
  const auto p = parse_pipeline(head + "stages: {b: second stage, a: first stage}\n", "stages.yaml", registry_);
  ASSERT_EQ(p.stages.size(), 2u);
  EXPECT_EQ(p.stages[0].output, "b");
  EXPECT_EQ(p.stages[0].label, "second stage");
  EXPECT_EQ(p.stages[1].output, "a");
  const auto again = parse_pipeline(effective_pipeline_yaml(p, registry_), "effective.yaml", registry_);
  ASSERT_EQ(again.stages.size(), 2u);
  EXPECT_EQ(again.stages[1].label, "first stage");
  try {
    parse_pipeline(head + "stages: {c: not an output, a: [1]}\n", "bad_stages.yaml", registry_);
    FAIL() << "a stage that is not an output was accepted";
  } catch (const ConfigError& e) {
    EXPECT_TRUE(reported(e.problems(), 5, "stages", "stage 'c' is not one of the pipeline's outputs"))
        << all(e.problems());
    EXPECT_TRUE(reported(e.problems(), 5, "stages.a", "expected a label")) << all(e.problems());
  }
}

TEST_F(PipelineTest, AReferenceIsReadWithItsRowsWrittenBackAndCheckedAsData) {
  const std::string head = R"(format: driftlab-pipeline/1
steps:
  - {name: s, plugin: filter/test_gain, inputs: {signal: rate}}
outputs: {a: s.signal}
)";
  const auto p = parse_pipeline(head + R"(reference:
  source: A paper, Table 2
  rows: {original: {B_deg_h: 34.66, N_deg_h_rtHz: 99.608}, a: {B_deg_h: 3.589, N_deg_h_rtHz: 0.967814}}
  figures: {record: Fig. 10, allan: Fig. 15}
  record: {sample_rate_hz: 10, duration_s: 16200, temperature_range_c: [-30, 60]}
)",
                                "reference.yaml", registry_);
  ASSERT_TRUE(p.reference.has_value());
  EXPECT_EQ(p.reference->source, "A paper, Table 2");
  ASSERT_EQ(p.reference->rows.size(), 2u);
  EXPECT_EQ(p.reference->rows.at("original").b_deg_h, 34.66);
  EXPECT_EQ(p.reference->rows.at("a").n_deg_h_rthz, 0.967814);
  const std::string effective = effective_pipeline_yaml(p, registry_);
  const auto again = parse_pipeline(effective, "effective.yaml", registry_);
  ASSERT_TRUE(again.reference.has_value());
  EXPECT_EQ(again.reference->rows.at("a").b_deg_h, 3.589);
  EXPECT_EQ(again.reference->figures,
            (std::map<std::string, std::string>{{"allan", "Fig. 15"}, {"record", "Fig. 10"}}));
  ASSERT_TRUE(again.reference->record.has_value());
  EXPECT_EQ(again.reference->record->duration_s, 16200.0);
  EXPECT_EQ(again.reference->record->temperature_min_c, -30.0);
  EXPECT_EQ(effective_pipeline_yaml(again, registry_), effective);
  EXPECT_FALSE(parse_pipeline(head, "none.yaml", registry_).reference.has_value());
  try {
    parse_pipeline(head + R"(reference:
  rows: {z: {B_deg_h: 1, N_deg_h_rtHz: 1}, a: {B_deg_h: -1, N_deg_h_rtHz: 1}, original: {B_deg_h: 1}}
  figures: {raw: Fig. 10, allan: ""}
  record: {sample_rate_hz: 10, duration_s: 16200, temperature_range_c: [60]}
)",
                   "bad_reference.yaml", registry_);
    FAIL() << "a bad reference was accepted";
  } catch (const ConfigError& e) {
    // The reference map starts on line 6 (its first key): the missing source is reported there.
    EXPECT_TRUE(reported(e.problems(), 6, "reference.source", "expected the publication")) << all(e.problems());
    EXPECT_TRUE(reported(e.problems(), 6, "reference.rows", "row 'z' is neither original nor an output"))
        << all(e.problems());
    EXPECT_TRUE(reported(e.problems(), 6, "reference.rows.a.B_deg_h", "expected a finite number > 0"))
        << all(e.problems());
    EXPECT_TRUE(reported(e.problems(), 6, "reference.rows.original.N_deg_h_rtHz", "missing")) << all(e.problems());
    EXPECT_TRUE(reported(e.problems(), 7, "reference.figures.raw", "unknown figure (expected one of record, "))
        << all(e.problems());
    EXPECT_TRUE(reported(e.problems(), 7, "reference.figures.allan", "expected the publication's figure"))
        << all(e.problems());
    EXPECT_TRUE(reported(e.problems(), 8, "reference.record.temperature_range_c", "expected [min, max] in degC"))
        << all(e.problems());
  }
}

TEST_F(PipelineTest, RunsStepsInDependencyOrderAndFillsTheReport) {
  const auto pipeline = load_pipeline(kPipelines / "compensate.yaml", registry_);
  std::vector<std::string> order;
  for (const auto& s : pipeline.steps) order.push_back(s.name);
  EXPECT_THAT(order, ::testing::ElementsAre("decompose", "classify", "fit", "scale", "reconstruct"));

  nlohmann::json report;
  const auto outputs = run_pipeline(pipeline, registry_, record(), {}, report);
  ASSERT_EQ(report["steps"].size(), 5u);
  for (const auto& step : report["steps"]) EXPECT_EQ(step["status"], "ok");
  EXPECT_EQ(report["steps"][3]["diagnostics"]["gain"], 2.0);

  // compensated = imfs + 2 * (drift - fit(temperature, time)) + jitter; check it independently.
  const auto r = record();
  const Eigen::VectorXd x = r.channel("rate").values;
  const Eigen::VectorXd trend = Eigen::VectorXd::LinSpaced(x.size(), x[0], x[x.size() - 1]);
  Eigen::MatrixXd A(x.size(), 3);
  A << r.channel("temperature").values, r.time(), Eigen::VectorXd::Ones(x.size());
  const Eigen::VectorXd residual = x - A * A.colPivHouseholderQr().solve(x);
  const double jitter = 1e-3 * static_cast<double>(pipeline.steps[3].params.integer("seed") % 1000);
  const Eigen::VectorXd expected = (x - trend) + (2.0 * residual.array() + jitter).matrix();
  constexpr double kLeastSquaresTolerance = 1e-10;  // QR solve of a well-conditioned 200x3 system
  EXPECT_LT((outputs.at("compensated").sum() - expected).cwiseAbs().maxCoeff(), kLeastSquaresTolerance);
}

TEST_F(PipelineTest, FillsEverySeedFromThePipelineSeedAndNamesThemInTheEffectivePipeline) {
  const auto pipeline = load_pipeline(kPipelines / "compensate.yaml", registry_);
  const auto yaml = effective_pipeline_yaml(pipeline, registry_);
  EXPECT_THAT(yaml, HasSubstr("seed: 11"));
  EXPECT_THAT(yaml, HasSubstr("seed: " + std::to_string(pipeline.steps[3].params.integer("seed"))));
  EXPECT_THAT(yaml, HasSubstr("offset: 0"));
  EXPECT_THAT(yaml, HasSubstr("plugin: optimizer/test_midpoint"));
}

TEST_F(PipelineTest, RerunningTheEffectivePipelineReproducesTheOutputs) {
  const auto original = load_pipeline(kPipelines / "compensate.yaml", registry_);
  const auto effective = parse_pipeline(effective_pipeline_yaml(original, registry_), "effective.yaml", registry_);
  EXPECT_EQ(effective_pipeline_yaml(effective, registry_), effective_pipeline_yaml(original, registry_));
  nlohmann::json r1, r2;
  const auto a = run_pipeline(original, registry_, record(), {}, r1);
  const auto b = run_pipeline(effective, registry_, record(), {}, r2);
  EXPECT_EQ(a.at("compensated").columns, b.at("compensated").columns);
  EXPECT_EQ(a.at("fitted").columns, b.at("fitted").columns);
}

TEST_F(PipelineTest, ADifferentPipelineSeedChangesSeededSteps) {
  const auto a = parse_pipeline(std::string(R"(format: driftlab-pipeline/1
seed: 1
steps:
  - {name: s, plugin: filter/test_gain, inputs: {signal: rate}}
outputs: {o: s.signal})"),
                                "a.yaml", registry_);
  const auto b = parse_pipeline(std::string(R"(format: driftlab-pipeline/1
seed: 2
steps:
  - {name: s, plugin: filter/test_gain, inputs: {signal: rate}}
outputs: {o: s.signal})"),
                                "b.yaml", registry_);
  EXPECT_NE(a.steps[0].params.integer("seed"), b.steps[0].params.integer("seed"));
}

TEST_F(PipelineTest, AMissingChannelIsADataErrorNamingTheRole) {
  const auto pipeline = load_pipeline(kPipelines / "compensate.yaml", registry_);
  TimeSeries no_temperature(Eigen::VectorXd::LinSpaced(10, 0.0, 0.9));
  no_temperature.set_channel({role::kRate, "rad/s", "test", Eigen::VectorXd::Zero(10)});
  nlohmann::json report;
  EXPECT_THROW(run_pipeline(pipeline, registry_, no_temperature, {}, report), DataError);
}

TEST_F(PipelineTest, StepsThatRunAtOnceGiveTheSameOutputsAndReportAsASerialRun) {
  const auto pipeline = load_pipeline(kPipelines / "compensate.yaml", registry_);
  nlohmann::json serial_report, graph_report;
  const auto serial = run_pipeline(pipeline, registry_, record(), {.threads = 1}, serial_report);
  const auto graph = run_pipeline(pipeline, registry_, record(), {.threads = 3}, graph_report);
  EXPECT_EQ(graph.at("compensated").columns, serial.at("compensated").columns);
  EXPECT_EQ(graph.at("fitted").columns, serial.at("fitted").columns);
  for (auto* report : {&serial_report, &graph_report})
    for (auto& step : (*report)["steps"]) step.erase("seconds");
  EXPECT_EQ(graph_report, serial_report);
}

TEST_F(PipelineTest, AFailedStepEndsTheReportAsInASerialRunOnAnyThreadCount) {
  // `broken` fails; `after` does not read it, so a graph run may have run it too, but the report
  // lists the steps a serial run reaches, and the error is the failed step's.
  registry_.add({.name = "filter/test_broken",
                 .summary = "always fails",
                 .reference = "",
                 .params = {},
                 .make = [](const ParamValues&, const Registry&) -> std::unique_ptr<Plugin> {
                   struct Broken final : Filter {
                     Eigen::VectorXd filter(const Eigen::VectorXd&, RunContext&) override {
                       throw DataError({"", 0, "signal"}, "test_broken: no data for you");
                     }
                   };
                   return std::make_unique<Broken>();
                 }});
  const auto pipeline = parse_pipeline(std::string(R"(format: driftlab-pipeline/1
steps:
  - {name: before, plugin: filter/test_gain, inputs: {signal: rate}}
  - {name: broken, plugin: filter/test_broken, inputs: {signal: rate}}
  - {name: after, plugin: filter/test_gain, inputs: {signal: time}}
outputs: {a: before.signal, b: broken.signal, c: after.signal})"),
                                       "broken.yaml", registry_);
  for (unsigned threads : {1u, 2u, 3u}) {
    nlohmann::json report;
    try {
      run_pipeline(pipeline, registry_, record(), {.threads = threads}, report);
      ADD_FAILURE() << "no error with " << threads << " threads";
    } catch (const DataError& e) {
      EXPECT_THAT(e.what(), HasSubstr("no data for you")) << threads << " threads";
    }
    ASSERT_EQ(report["steps"].size(), 2u) << report.dump(1);
    EXPECT_EQ(report["steps"][0]["status"], "ok");
    EXPECT_EQ(report["steps"][1]["name"], "broken");
    EXPECT_EQ(report["steps"][1]["status"], "failed");
    EXPECT_THAT(report["steps"][1]["error"].get<std::string>(), HasSubstr("no data for you"));
  }
}

}  // namespace
}  // namespace driftlab
