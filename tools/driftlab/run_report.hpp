// report.html of `driftlab run` (issue 12; Li et al. 2023, Table 2 and Figs. 10-15), around the
// scores of models/evaluation/run_scores.hpp.
#pragma once

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "framework/pipeline.hpp"
#include "framework/time_series.hpp"
#include "models/evaluation/run_scores.hpp"

namespace driftlab::cli {

using evaluation::intrinsic_floor_json;
using evaluation::is_pipeline_stage;
using evaluation::rate_stages;
using evaluation::RunScores;
using evaluation::score_run;
using evaluation::scores_json;
using evaluation::stage_json;
using evaluation::StageScore;
using evaluation::table2_text;

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
