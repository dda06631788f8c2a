// The 60-s block means of models/evaluation, the one home of the residual-drift metric: time blocks
// that agree with the sample-count blocking on evenly sampled records (a partial last block left
// out), skip gaps, and keep every block of a record with gaps, a burst record's last burst too.
// Table 2's scores: the reference columns, the systematic error (what a stage left of the drift once
// the intrinsic noise is taken out) and the two baselines fitted on the record.
#include "models/evaluation/evaluation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "framework/error.hpp"
#include "framework/units.hpp"
#include "models/evaluation/run_scores.hpp"

namespace driftlab::evaluation {
namespace {

constexpr double kSum = 1e-12;  // the same sums in another order

Eigen::VectorXd values(Eigen::Index n) {
  Eigen::VectorXd x(n);
  for (Eigen::Index i = 0; i < n; ++i) x[i] = std::sin(0.37 * static_cast<double>(i)) + 1e-3 * static_cast<double>(i);
  return x;
}

Eigen::VectorXd times(Eigen::Index n, double rate_hz, double start_s = 0.0) {
  Eigen::VectorXd t(n);
  for (Eigen::Index i = 0; i < n; ++i) t[i] = start_s + static_cast<double>(i) / rate_hz;
  return t;
}

TEST(BlockMeans, OnAnEvenlySampledRecordEqualTheWholeBlocksOfSamples) {
  // 10 Hz: 600 samples a block; 10 345 samples = 17 whole blocks and 145 samples left over. Time
  // stamps k / 10 do not add up to whole minutes exactly, and the record does not start at 0.
  const Eigen::Index n = 10345, per_block = 600;
  const Eigen::VectorXd x = values(n);
  const auto b = block_means(times(n, 10.0, 1234.567), x);
  ASSERT_EQ(b.means.size(), n / per_block);
  for (Eigen::Index k = 0; k < n / per_block; ++k) {
    EXPECT_NEAR(b.means[k], x.segment(k * per_block, per_block).mean(), kSum) << "block " << k;
    EXPECT_EQ(b.blocks[static_cast<std::size_t>(k)].first, k * per_block);
    EXPECT_EQ(b.blocks[static_cast<std::size_t>(k)].samples, per_block);
  }
}

TEST(BlockMeans, KeepTheLastBlockWhenTheRecordFillsIt) {
  const Eigen::Index n = 18000;  // 30 min at 10 Hz
  EXPECT_EQ(block_means(times(n, 10.0), values(n)).means.size(), 30);
  EXPECT_EQ(block_means(times(n - 1, 10.0), values(n - 1)).means.size(), 29);
}

TEST(BlockMeans, SkipBlocksWithoutSamplesAndAverageWhatAGapLeavesThePartialLastBlockIncluded) {
  // 1 Hz, 0..619 s with 130..249 s missing: block 2 (120..179 s) holds 120..129 s, block 3
  // (180..239 s) is empty, block 4 (240..299 s) holds 250..299 s, block 10 (600..659 s) 600..619 s.
  std::vector<double> t;
  for (int s = 0; s < 620; ++s)
    if (s < 130 || s >= 250) t.push_back(s);
  const Eigen::VectorXd time = Eigen::Map<const Eigen::VectorXd>(t.data(), static_cast<Eigen::Index>(t.size()));
  const auto b = block_means(time, time);
  ASSERT_EQ(b.means.size(), 10);
  EXPECT_DOUBLE_EQ(b.means[2], (120.0 + 129.0) / 2.0);
  EXPECT_DOUBLE_EQ(b.means[3], (250.0 + 299.0) / 2.0);
  EXPECT_DOUBLE_EQ(b.means[8], (540.0 + 599.0) / 2.0);
  EXPECT_DOUBLE_EQ(b.means[9], (600.0 + 619.0) / 2.0);
}

TEST(BlockMeans, GiveOneMeanPerBurstOfABurstRecordTheLastBurstIncluded) {
  // Bursts of 5 s at 10 Hz every 300 s (the LSM6DSM cooling run's pattern): every burst is its own
  // block, none fills it, the last one counts like the others.
  std::vector<double> t;
  for (int burst = 0; burst < 6; ++burst)
    for (int i = 0; i < 50; ++i) t.push_back(300.0 * burst + 0.1 * i);
  const Eigen::VectorXd time = Eigen::Map<const Eigen::VectorXd>(t.data(), static_cast<Eigen::Index>(t.size()));
  const auto b = block_means(time, time);
  ASSERT_EQ(b.means.size(), 6);
  for (Eigen::Index k = 0; k < 6; ++k) EXPECT_NEAR(b.means[k], 300.0 * static_cast<double>(k) + 2.45, kSum);
}

TEST(BlockMeanRms, IsTheRmsOfTheBlockMeansAndRefusesARecordShorterThanOneBlock) {
  const Eigen::VectorXd t = times(1800, 10.0);
  Eigen::VectorXd x(1800);
  x << Eigen::VectorXd::Constant(600, 3.0), Eigen::VectorXd::Constant(600, -4.0), Eigen::VectorXd::Constant(600, 0.0);
  EXPECT_NEAR(block_mean_rms(t, x), std::sqrt(25.0 / 3.0), kSum);
  EXPECT_THROW(block_mean_rms(t.head(599), x.head(599)), DataError);
  EXPECT_THROW(block_means(t, x.head(10)), DataError);
}

TEST(RateStages, AreTheDeclaredStagesOrElseEveryOutputOfOneRateColumn) {
  const auto rate = Signal::single(Eigen::VectorXd::Zero(4), "rate", "rad/s");
  const auto temperature = Signal::single(Eigen::VectorXd::Zero(4), "temperature", "degC");
  const std::map<std::string, Signal> outputs{{"b", rate}, {"a", rate}, {"model", rate}, {"trend", temperature}};
  Pipeline p;
  p.file = "p.yaml";
  p.output_order = {"b", "a", "model", "trend"};
  const auto undeclared = rate_stages(p, outputs);
  ASSERT_EQ(undeclared.size(), 3u) << "every rad/s output, in output order";
  EXPECT_EQ(undeclared[0].output, "b");
  EXPECT_EQ(undeclared[2].label, "model");
  p.stages = {{"a", "first"}, {"b", "second"}};
  const auto declared = rate_stages(p, outputs);
  ASSERT_EQ(declared.size(), 2u) << "the model output is not a stage once stages are declared";
  EXPECT_EQ(declared[0].output, "a");
  EXPECT_EQ(declared[1].label, "second");
  p.stages = {{"trend", "a temperature"}};
  EXPECT_THROW(rate_stages(p, outputs), DataError);
}

// Table 2 shows published figures only beside a pipeline that names them (its `reference`): the
// text's two columns and source line, each row's "reference" and the report's "reference" entry.
TEST(RunScores, ShowTheReferenceColumnsOnlyForAPipelineWithAReference) {
  const Eigen::Index n = 4000;  // 400 s at 10 Hz
  TimeSeries record(times(n, 10.0));
  Eigen::VectorXd rate(n);
  for (Eigen::Index i = 0; i < n; ++i) rate[i] = 1e-3 * std::sin(1.7 * static_cast<double>(i * i % 97));
  record.set_channel({role::kRate, "rad/s", "test", rate});
  const std::map<std::string, Signal> outputs{{"out", Signal::single(0.5 * rate, "signal", "rad/s")}};
  Pipeline p;
  p.file = "p.yaml";
  p.outputs = {{"out", "s.signal"}};
  p.output_order = {"out"};
  const RunScores plain = score_run(record, p, outputs);
  EXPECT_EQ(table2_text(plain).find("paper"), std::string::npos) << table2_text(plain);
  const auto plain_json = scores_json(plain);
  EXPECT_FALSE(plain_json.contains("reference"));
  for (const auto& row : plain_json["table2"]) EXPECT_FALSE(row.contains("reference")) << row["stage"];

  p.reference = PipelineReference{"A paper, Table 2", {{"original", {34.66, 99.608}}, {"out", {3.589, 0.967814}}}};
  const RunScores referenced = score_run(record, p, outputs);
  const std::string text = table2_text(referenced);
  EXPECT_NE(text.find("paper B    paper N"), std::string::npos) << text;
  EXPECT_NE(text.find("3.589"), std::string::npos) << text;
  EXPECT_NE(text.find("paper: A paper, Table 2\n"), std::string::npos) << text;
  const auto json = scores_json(referenced);
  EXPECT_EQ(json["reference"]["source"], "A paper, Table 2");
  EXPECT_FALSE(json.contains("reference_not_shown"));

  // A reference that names its record is shown beside a record like it only: this one is 400 s at
  // 10 Hz without a temperature.
  p.reference->record = PipelineReference::Record{10.0, 16200.0, -30.0, 60.0};
  const RunScores other = score_run(record, p, outputs);
  EXPECT_FALSE(other.reference.has_value());
  EXPECT_EQ(table2_text(other).find("paper B"), std::string::npos) << table2_text(other);
  EXPECT_NE(table2_text(other).find("paper columns not shown: this record is not the one A paper, Table 2 reports "
                                    "on (399.9 s, not 16200, no temperature)"),
            std::string::npos)
      << table2_text(other);
  EXPECT_TRUE(scores_json(other).contains("reference_not_shown"));
  p.reference->record = PipelineReference::Record{10.0, 400.0, -30.0, 60.0};
  TimeSeries warm = record;
  warm.set_channel({role::kTemperature, "degC", "test", Eigen::VectorXd::LinSpaced(n, -29.0, 61.0)});
  EXPECT_TRUE(score_run(warm, p, outputs).reference.has_value()) << "within the tolerances";
  warm.set_channel({role::kTemperature, "degC", "test", Eigen::VectorXd::LinSpaced(n, -20.0, 61.0)});
  EXPECT_FALSE(score_run(warm, p, outputs).reference.has_value()) << "the cold end 10 degC off";
  EXPECT_EQ(json["table2"][1]["stage"], "out");
  EXPECT_EQ(json["table2"][1]["reference"]["N_deg_h_rtHz"], 0.967814);
}

// A simulated oven record: true rate 0, a systematic bias that is an exact quadratic in temperature
// (two cycles, heating and cooling), white noise on top. Outputs of known residual: the noise alone
// (the drift removed exactly) and the noise plus a constant. The systematic error reads 0 and the
// constant where the residual drift reads the noise's block means as well; the whole-record cubic
// recovers the quadratic (its systematic error a small fraction of the record's).
TEST(RunScores, SystematicErrorIsTheDriftLeftOnceTheIntrinsicNoiseIsTakenOut) {
  const Eigen::Index n = 72000;  // 2 h at 10 Hz
  const double kOffset = 2e-5;   // rad/s
  TimeSeries record(times(n, 10.0));
  Eigen::VectorXd temp(n), systematic(n), noise(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / 10.0;
    temp[i] = 20.0 - 30.0 * std::cos(2.0 * M_PI * t / 3600.0);
    const double d = temp[i] - 25.0;
    systematic[i] = 1e-3 + 2e-5 * d + 3e-7 * d * d;
    noise[i] = 1e-4 * std::sin(1.7 * static_cast<double>(i * i % 997));
  }
  record.set_channel({role::kRate, "rad/s", "test", systematic + noise});
  record.set_channel({role::kTemperature, "degC", "test", temp});
  record.set_channel({role::kTrueRate, "rad/s", "test", Eigen::VectorXd::Zero(n)});
  record.set_channel({role::kSystematic, "rad/s", "test", systematic});
  const std::map<std::string, Signal> outputs{{"exact", Signal::single(noise, "signal", "rad/s")},
                                              {"offset", Signal::single(noise.array() + kOffset, "signal", "rad/s")}};
  Pipeline p;
  p.file = "p.yaml";
  p.outputs = {{"exact", "s.a"}, {"offset", "s.b"}};
  p.output_order = {"exact", "offset"};
  const RunScores scores = score_run(record, p, outputs);
  std::map<std::string, const StageScore*> by_stage;
  for (const auto& st : scores.stages) by_stage[st.stage] = &st;
  ASSERT_EQ(by_stage.size(), 5u) << table2_text(scores);
  ASSERT_TRUE(by_stage.count(kPx4BaselineStage) && by_stage.count(kCubicBaselineStage)) << table2_text(scores);
  for (const auto& [stage, st] : by_stage) ASSERT_TRUE(st->systematic_error_rad_s.has_value()) << stage;

  const double original = *by_stage.at(kOriginalStage)->systematic_error_rad_s;
  EXPECT_NEAR(*by_stage.at("exact")->systematic_error_rad_s, 0.0, 1e-15);
  EXPECT_GT(*by_stage.at("exact")->residual_drift_rad_s, 1e-7) << "the noise's block means are in the residual drift";
  EXPECT_NEAR(*by_stage.at("offset")->systematic_error_rad_s, kOffset, 1e-15);
  EXPECT_LT(*by_stage.at(kCubicBaselineStage)->systematic_error_rad_s, 0.02 * original);
  EXPECT_NE(table2_text(scores).find("syst. error"), std::string::npos);
  const auto json = scores_json(scores);
  EXPECT_TRUE(json["baselines"].contains(kCubicBaselineStage));
  EXPECT_FALSE(json["baselines"][kCubicBaselineStage]["heating_only"].get<bool>());
  EXPECT_NEAR(json["table2"][2]["systematic_error_deg_h"].get<double>(), kOffset * kDphPerRadPerSec, 1e-9);

  // Without the systematic column, no such column.
  TimeSeries bare(record.time());
  for (const auto* r : {role::kRate, role::kTemperature, role::kTrueRate}) bare.set_channel(record.channel(r));
  const RunScores without = score_run(bare, p, outputs);
  EXPECT_EQ(table2_text(without).find("syst. error"), std::string::npos);
  for (const auto& st : without.stages) EXPECT_FALSE(st.systematic_error_rad_s.has_value()) << st.stage;
}

}  // namespace
}  // namespace driftlab::evaluation
