// report.html of `driftlab run` (Li et al. 2023, Table 2 and Figs. 10-15), around the
// scores of models/evaluation/run_scores.hpp.
#pragma once

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "framework/pipeline.hpp"
#include "framework/time_series.hpp"
#include "models/evaluation/run_scores.hpp"
#include "tools/driftlab/html_report.hpp"

namespace driftlab::cli {

using evaluation::b_deg_h;
using evaluation::b_text;
using evaluation::BStyle;
using evaluation::intrinsic_floor_json;
using evaluation::is_pipeline_stage;
using evaluation::rate_stages;
using evaluation::RunScores;
using evaluation::score_run;
using evaluation::scores_json;
using evaluation::stage_json;
using evaluation::StageScore;
using evaluation::table2_text;

// A stage as figures and tables name it: the pipeline's label ("RBF NN + GA + KF"), "original
// record", "PX4-style polynomial", "cubic on the whole record", else its name in words (readable_name).
std::string stage_label(const StageScore& stage);

// An IMF group as figures and tables name it, with its IMFs: "mixed group (IMFs 3–4)".
std::string group_label(ImfGroup group, const std::vector<ImfDecision>& decisions);

// One row of a Table 2 HTML table: a scored stage (or the intrinsic floor) and what the report
// adds beside it.
struct Table2Row {
  std::string pipeline;                       // compare: the pipeline's label, "(record)"
  std::string stage;                          // the stage column's text
  const allan::Analysis* analysis = nullptr;  // B, N and the minimum's tau
  double bandwidth_hz = 0.0;
  std::optional<double> residual_drift_rad_s;         // none: "–"
  std::optional<double> systematic_error_rad_s;       // none: "–"
  const PipelineReference::Row* reference = nullptr;  // the published figures, if any
  const evaluation::FloorComparison* against_floor = nullptr;
  std::optional<double> seconds;  // compare: until the stage's step finished
};
// A stage's row: its analysis, bandwidth, residual drift, reference row and comparison with the floor.
Table2Row table2_row(const RunScores& scores, const StageScore& stage);
// The intrinsic floor's row (scores.intrinsic must be set): the Allan figures of measured - systematic
// at the record's full bandwidth (half its sample rate, Hz).
Table2Row intrinsic_floor_row(const RunScores& scores, double sample_rate_hz);

// The two Table 2 tables: `driftlab run`'s (stage, the reference's B and N when the pipeline has
// one, B, its interval, the minimum's tau, N, noise bandwidth, residual drift, systematic error when a
// row has one, max error / floor) and `driftlab compare`'s (pipeline, stage, B, interval, N, bandwidth,
// residual drift, systematic error when a row has one, run time).
enum class Table2Layout { Run, Compare };
HtmlTable table2_html(Table2Layout layout, const std::vector<Table2Row>& rows,
                      const std::optional<PipelineReference>& reference);

// What the steps' hyperparameter tunings (plugins/tuning: diagnostics["tuning"]["notes"]) did not
// settle, one line each: "step rbf_ga (regressor/rbf): sigma ended at its upper search bound ...".
std::vector<std::string> tuning_notes(const std::vector<StepRecord>& steps);

// report.html: Table 2 with the honest columns, the IMF groups and their reasons, and the paper's
// figures (Figs. 10-15, captioned with the publication's figure where the pipeline's reference names
// it: PipelineReference::figures) plus the residual against temperature, heating and cooling apart, and the
// tuned steps (best hyperparameters, held-out error, evaluations, tuning_notes). The
// figures come from what the run produced: every decomposition step (its IMFs), every classifier
// step (sample entropy per IMF and the groups, from its step record), temperature-unit step outputs
// (the trend), the stages and, with a truth column, the residual. `data`: the record's path as the
// report names it. Returns the document. Throws PlotError when gnuplot fails.
std::string run_html(const std::string& title, const std::string& data, const TimeSeries& record,
                     const Pipeline& pipeline, const std::map<std::string, Signal>& outputs,
                     const std::map<std::string, Signal>& step_signals, const std::vector<StepRecord>& steps,
                     const RunScores& scores);

}  // namespace driftlab::cli
