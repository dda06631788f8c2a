// The Table 2 scores (issue 12; Li et al. 2023, Table 2) of `driftlab run`, `driftlab compare` and
// the Python module's Pipeline.run: every pipeline output in a rate unit is a stage, scored by
// evaluation.hpp beside the original record, the intrinsic floor (when the record has a systematic
// rate) and two simple baselines (when it has a temperature): the PX4-style polynomial
// (calibration::fit_px4_style) and a cubic on every bin of the record (calibration::fit_cubic_all_bins,
// the strongest simple in-sample peer), each fitted on the scored record itself (rate and temperature,
// never the truth; in-sample like the pipeline's stages) and applied by the model's causal
// compensator. Units in the JSON: deg/h for B, the residual drift and the systematic error,
// deg/h/sqrt(Hz) for N, Hz for bandwidths, s for taus.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "framework/pipeline.hpp"
#include "framework/time_series.hpp"
#include "models/calibration/calibration_model.hpp"
#include "models/evaluation/evaluation.hpp"

namespace driftlab::evaluation {

// The pipeline's compensated-rate stages with their labels: its declared `stages` (each must be one
// rad/s column, else DataError), or, when none are declared, every output of one rad/s column in
// output order, labelled by its name. The last is the pipeline's final stage.
std::vector<PipelineStage> rate_stages(const Pipeline& pipeline, const std::map<std::string, Signal>& outputs);

struct Baseline {
  std::string stage;  // kPx4BaselineStage or kCubicBaselineStage
  calibration::CalibrationModel model;
  Eigen::VectorXd compensated_rad_s;
};

// The stage names of the record itself and of the baselines in RunScores::stages.
inline constexpr const char* kOriginalStage = "original";
inline constexpr const char* kPx4BaselineStage = "px4_polynomial";
inline constexpr const char* kCubicBaselineStage = "cubic_whole_record";

inline bool is_pipeline_stage(const StageScore& stage) { return stage.source == StageScore::Source::Pipeline; }

struct RunScores {
  std::vector<StageScore> stages;              // kOriginalStage, the pipeline's stages, the baselines
  std::optional<PipelineReference> reference;  // the pipeline's published figures, when shown beside this record
  std::string reference_not_shown;             // why the pipeline's figures are not shown (reference_mismatch)
  std::optional<allan::Analysis> intrinsic;    // measured - systematic
  std::vector<Baseline> baselines;             // in the order of their stages
  std::map<std::string, FloorComparison> against_floor;  // per stage, factor 1.5
};

inline constexpr double kFloorFactor = 1.5;  // "nothing left, nothing added": error curve within 1.5x

// Why a reference's figures do not belong beside `record` (empty when they do): the reference names
// its record (PipelineReference::record) and this one differs from it in sample rate by more than
// 1 %, in duration by more than 5 %, or in either end of its temperature range by more than 2 degC.
// A reference that names no record is shown beside any record.
inline constexpr double kReferenceRateTolerance = 0.01, kReferenceDurationTolerance = 0.05;
inline constexpr double kReferenceTemperatureToleranceC = 2.0;
std::string reference_mismatch(const TimeSeries& record, const PipelineReference& reference);

// Scores the record's rate and every rate output (in output_order); the pipeline's reference is kept
// only where reference_mismatch finds none. Throws DataError when the record is too short for the
// analysis.
RunScores score_run(const TimeSeries& record, const Pipeline& pipeline, const std::map<std::string, Signal>& outputs);

// B as every report gives it (models/allan/analysis.hpp), deg/h: a value with its 68.3 % interval only
// where the OADEV has a floor, otherwise the bound. JSON: B_resolved, B_deg_h (null when not resolved),
// B_ci (resolved only), B_upper_deg_h (the interval's upper end: the bound when not resolved),
// B_tau_s (the minimum's tau) and B_within_tau_s (the longest tau). Text: "1.75 [1.6,1.9]" or
// "< 1.89 (tau<=3277s)".
nlohmann::json b_json(const allan::FloorReading& b);
std::string b_text(const allan::FloorReading& b);

// B in deg/h, as every report words it (the one home of that wording): a FloorReading converted,
// or the figures a report kept (value or bound, and the longest tau read).
struct BDegH {
  bool resolved = false;
  double value = 0.0;            // B (resolved)
  double low = 0.0, high = 0.0;  // its 68.3 % interval; high: the bound when not resolved
  double tau_s = 0.0;            // the minimum's tau
  double longest_tau_s = 0.0;    // the longest tau read
};
BDegH b_deg_h(const allan::FloorReading& b);

enum class BStyle {
  Table2Text,         // table2_text: "1.75 [1.6,1.9]" or "< 1.89 (tau<=3277s)"
  AllanLine,          // driftlab allan's line: "B = 1.754 deg/h (...) at tau = ..., 68.3 % interval [...]" or "B < ..."
  Bound,              // a table's value cell when not resolved: "< 1.89"
  BoundFourDigits,    // the same with four significant digits: "< 1.891"
  BoundWithin,        // one cell, bound and range: "< 1.891 (not resolved within tau ≤ 3277 s)"
  Interval,           // a table's interval cell: "1.6 – 1.9" or "not resolved within tau ≤ 3277 s"
  IntervalBracketed,  // the same as "[1.601, 1.9]" or "not resolved within tau ≤ 3277 s" (four digits)
};
// The text of B in a style; for the value-cell styles (Bound, BoundFourDigits, BoundWithin) of a
// resolved B, the value with four significant digits (tables write the number itself).
std::string b_text(const BDegH& b, BStyle style);

// report.json's "table2", "intrinsic_floor", "baselines" (by stage) and "allan" entries.
nlohmann::json scores_json(const RunScores& scores);
// One "table2" row of scores_json, and its "intrinsic_floor" entry.
nlohmann::json stage_json(const RunScores& scores, const StageScore& stage);
nlohmann::json intrinsic_floor_json(const allan::Analysis& intrinsic);

// Table 2 as text for the terminal; with the pipeline's reference, its rows beside ours and its
// source below.
std::string table2_text(const RunScores& scores);

// The reference's row for a stage, or null (no reference, or none for that stage).
const PipelineReference::Row* reference_row(const RunScores& scores, const std::string& stage);

}  // namespace driftlab::evaluation
