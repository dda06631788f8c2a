// The Table 2 report of `driftlab run` (issue 12; Li et al. 2023, Table 2 and Figs. 10-15): every
// pipeline output in a rate unit is a stage, scored by models/evaluation beside the original record,
// the intrinsic floor (when the record has a systematic_dps column) and the PX4-style polynomial
// baseline (when it has a temperature): calibration::fit_px4_style fitted on the scored record itself
// (rate and temperature, never the truth; in-sample like the pipeline's stages) and applied by the
// model's causal compensator. Units in the JSON: deg/h for B and the residual drift,
// deg/h/sqrt(Hz) for N, Hz for bandwidths, s for taus.
#pragma once

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "framework/pipeline.hpp"
#include "framework/time_series.hpp"
#include "models/calibration/calibration_model.hpp"
#include "models/evaluation/evaluation.hpp"

namespace driftlab::cli {

// The pipeline's compensated-rate stages, in the pipeline file's output order: every output that
// is one rad/s column, except `drift_model` (li2023.yaml's model of the drift, not a compensated
// rate). The last is the pipeline's final stage.
std::vector<std::string> rate_stages(const Pipeline& pipeline, const std::map<std::string, Signal>& outputs);

struct Px4Baseline {
  calibration::CalibrationModel model;
  Eigen::VectorXd compensated_rad_s;
};

struct RunScores {
  std::vector<evaluation::StageScore> stages;  // "original", the pipeline's rate outputs, "px4_polynomial"
  std::optional<allan::Analysis> intrinsic;    // measured - systematic
  std::optional<Px4Baseline> baseline;
  std::map<std::string, evaluation::FloorComparison> against_floor;  // per stage, factor 1.5
};

inline constexpr double kFloorFactor = 1.5;  // "nothing left, nothing added": error curve within 1.5x

// Scores the record's rate and every rate output (in output_order). Throws DataError when the record
// is too short for the analysis.
RunScores score_run(const TimeSeries& record, const Pipeline& pipeline, const std::map<std::string, Signal>& outputs);

// B as every report gives it (models/allan/analysis.hpp), deg/h: a value with its 68.3 % interval only
// where the OADEV has a floor, otherwise the bound. JSON: B_resolved, B_deg_h (null when not resolved),
// B_ci (resolved only), B_upper_deg_h (the interval's upper end: the bound when not resolved),
// B_tau_s (the minimum's tau) and B_within_tau_s (the longest tau). Text: "1.75 [1.6,1.9]" or
// "< 1.89 (tau<=3277s)".
nlohmann::json b_json(const allan::FloorReading& b);
std::string b_text(const allan::FloorReading& b);

// report.json's "table2", "intrinsic_floor", "baseline" and "allan" entries.
nlohmann::json scores_json(const RunScores& scores);

// Table 2 as text for the terminal, with the paper's rows beside ours.
std::string table2_text(const RunScores& scores);

}  // namespace driftlab::cli

namespace driftlab::cli {

// report.html: Table 2 with the honest columns, the IMF groups and their reasons, and the paper's
// figures (Figs. 10-15) plus the residual against temperature, heating and cooling apart. The
// figures come from what the run produced: every decomposition step (its IMFs), every classifier
// step (sample entropy per IMF and the groups), temperature-unit step outputs (the trend), the
// stages and, with a truth column, the residual. Throws PlotError when gnuplot fails.
void write_run_html(const std::filesystem::path& path, const std::string& title, const TimeSeries& record,
                    const Pipeline& pipeline, const std::map<std::string, Signal>& outputs,
                    const std::map<std::string, Signal>& step_signals, const nlohmann::json& report,
                    const RunScores& scores);

}  // namespace driftlab::cli
