// Pipeline descriptions (`format: driftlab-pipeline/1`, DESIGN.md §4):
//
//   format: driftlab-pipeline/1
//   seed: 7                                  # optional (default 1); fills every step's `seed`
//   inputs: {rate: rate, temperature: temperature}   # name -> channel role of the record
//   steps:                                   # `time` is always available as an input name
//     - name: decompose
//       plugin: decomposition/emd
//       inputs: {signal: rate}               # port -> reference (input name or step.output)
//       params: {max_imfs: 8}
//     - name: reconstruct
//       sum: [denoise.signal, compensate.residual]   # built-in: adds signals; output `signal`
//   outputs: {compensated: reconstruct.signal}
//   stages: {compensated: "EMD + Kalman"}   # optional: outputs scored as stages, with their labels
//   reference:                               # optional: published figures shown beside Table 2
//     source: "Li et al., Micromachines 2023, 14, 971, Table 2"
//     rows: {original: {B_deg_h: 34.66, N_deg_h_rtHz: 99.608}, compensated: {...}}
//
// Ports per plugin kind are listed by ports_of_kind() (plugin.hpp); a port marked `many` takes a
// list of references whose columns are put side by side. load_pipeline() validates everything
// before any data is touched and reports every problem at once (file, line, key): unknown keys,
// wrong format version, unknown plugin, unknown or invalid parameter, unknown port, missing
// required port, dangling reference, cycle, duplicate step name, steps of a kind that cannot run
// as a step, a stage that is not an output. Steps run in dependency order (file order among
// independent steps). Reports (`driftlab run`, Pipeline.run) score the declared stages in file
// order; without `stages`, every output of one rad/s column is a stage labelled by its name. A
// `reference` names the publication whose figures the pipeline reproduces and its B and N per row
// ("original": the record; otherwise an output); reports show them only for such a pipeline.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "framework/params.hpp"
#include "framework/plugin.hpp"
#include "framework/time_series.hpp"

namespace driftlab {

class Registry;

inline constexpr const char* kPipelineFormat = "driftlab-pipeline/1";

struct PipelineStep {
  std::string name;
  std::string plugin;                                      // "kind/name"; empty for the built-in sum
  std::map<std::string, std::vector<std::string>> inputs;  // port -> references
  ParamValues params;                                      // resolved, defaults and seed filled in
  int line = 0;
};

// An output that reports score as a compensated rate (a row of Table 2), and its label.
struct PipelineStage {
  std::string output;
  std::string label;
};

// Published Allan figures a pipeline reproduces, per Table 2 row, and the publication's figures that
// the run report's figures correspond to.
struct PipelineReference {
  struct Row {
    double b_deg_h = 0.0;       // bias instability B, deg/h
    double n_deg_h_rthz = 0.0;  // angle random walk N, deg/h/sqrt(Hz)
  };
  std::string source;               // the publication and its table
  std::map<std::string, Row> rows;  // "original" (the record) or an output name
  // report figure (one of kReferenceFigures) -> the publication's figure, e.g. "Fig. 10"; the report
  // captions "(paper Fig. 10)" only where a pipeline names one.
  std::map<std::string, std::string> figures;
  // The record the published figures come from, when the pipeline names it: the rows are shown
  // beside a record like it only (models/evaluation/run_scores.hpp, reference_mismatch).
  struct Record {
    double sample_rate_hz = 0.0;                              // Hz
    double duration_s = 0.0;                                  // s
    double temperature_min_c = 0.0, temperature_max_c = 0.0;  // degC
  };
  std::optional<Record> record;
};
// The run report's figures a reference may name: the record, the rate's IMFs, the rate's grouping
// by sample entropy, the temperature trend, the stages over time, the stages' Allan deviation.
inline const std::vector<std::string> kReferenceFigures{"record", "rate_imfs", "rate_grouping", "temperature_trend",
                                                        "stages", "allan"};

struct Pipeline {
  std::string file;
  std::int64_t seed = 1;
  std::map<std::string, std::string> inputs;   // input name -> channel role
  std::vector<PipelineStep> steps;             // in execution order
  std::map<std::string, std::string> outputs;  // output name -> reference
  std::vector<std::string> output_order;       // output names in file order
  std::vector<PipelineStage> stages;           // declared stages in file order; empty: not declared
  std::optional<PipelineReference> reference;  // published figures, when the pipeline reproduces some
  std::vector<std::string> overrides;          // the overrides applied (PipelineOverride::text), in order
};

// One change to a step made outside the file (`driftlab run/compare --set STEP.KEY=VALUE`):
//   STEP.plugin=KIND/NAME     swaps the step's plugin for another of the same kind; the step's
//                             parameters that the new plugin does not declare are dropped;
//   STEP.PARAM=VALUE          sets a parameter of the step's plugin;
//   STEP.PARAM.SUB...=VALUE   sets a parameter of a nested plugin (`mixed_rbf_ga.optimizer.population=40`);
//                             `STEP.PARAM=KIND/NAME` or `STEP.PARAM={plugin: ..., params: {...}}`
//                             replaces the nested plugin (its old parameters go with it).
// VALUE is read as YAML (a number, text, a list [a, b] or a map). Swaps are applied before the
// parameter settings, each in the order given; the result is validated by the parameter tables
// exactly as the file is.
struct PipelineOverride {
  std::string step;
  std::vector<std::string> key;  // "plugin", or a parameter name followed by nested parameter names
  std::string value;             // YAML text
  std::string text;              // as given ("decompose.plugin=decomposition/ceemdan"), for messages
};
// Parses "STEP.KEY=VALUE". Throws ConfigError at field `option` saying what was expected.
PipelineOverride parse_pipeline_override(const std::string& text, const std::string& option = "--set");

// Parses and validates, after applying `overrides`. Throws ConfigError with every problem found;
// a problem caused by an override is reported at that override ("--set STEP.KEY=VALUE" as the
// file, the step's key path as the field), an unknown step with the steps the pipeline has, and
// a plugin swap across kinds with the kind expected. With overrides, every declared stage whose
// output depends on an overridden step has the overrides of those steps appended to its label
// ("RBF NN + GA [mixed_rbf_ga.optimizer.population=40]"), so reports name what ran.
Pipeline load_pipeline(const std::filesystem::path& path, const Registry& registry,
                       const std::vector<PipelineOverride>& overrides = {});
Pipeline parse_pipeline(const std::string& yaml_text, const std::string& file_label, const Registry& registry,
                        const std::vector<PipelineOverride>& overrides = {});

// The effective pipeline: every parameter and seed written out. Loading it gives the same run.
std::string effective_pipeline_yaml(const Pipeline& pipeline, const Registry& registry);

struct PipelineRunOptions {
  unsigned threads = 1;
  // Called with (step index, step count, step name, fraction of that step done); one call at a
  // time, but steps that run at once interleave their calls.
  std::function<void(std::size_t, std::size_t, const std::string&, double)> progress;
  // When set, receives every step's output signals as "step.port" (for reports and figures).
  std::map<std::string, Signal>* step_signals = nullptr;
};

// One step of a run as reports list it.
struct StepRecord {
  std::string name;
  std::string plugin;                                     // "kind/name", or "sum" for the built-in sum
  bool ok = false;                                        // false: the step threw
  double seconds = 0.0;                                   // wall-clock time of an ok step
  std::string error;                                      // what a failed step threw
  nlohmann::json diagnostics = nlohmann::json::object();  // the plugin's RunContext::diagnostics

  // report.json's entry: name, plugin, status ("ok" or "failed"), seconds (ok) or error (failed),
  // diagnostics.
  nlohmann::json to_json() const;
};

// report.json's "steps": the records in order.
nlohmann::json steps_json(const std::vector<StepRecord>& steps);

// Runs the steps on a record as a graph: a step starts once the steps it reads have finished, and
// up to `threads` steps run at once (each also gets `threads` for its own kernels). Outputs and
// steps do not depend on the thread count. `steps` receives status, seconds and diagnostics per
// step, in file order; when a step throws, it holds the steps before it and the failed one (as a
// serial run would), and the error of the first failed step in file order propagates. Throws
// DataError when a pipeline input's role is missing from the record; other errors propagate from
// plugins.
std::map<std::string, Signal> run_pipeline(const Pipeline& pipeline, const Registry& registry, const TimeSeries& record,
                                           const PipelineRunOptions& options, std::vector<StepRecord>& steps);
// The same, with the steps as `report["steps"]` (steps_json), also when a step throws.
std::map<std::string, Signal> run_pipeline(const Pipeline& pipeline, const Registry& registry, const TimeSeries& record,
                                           const PipelineRunOptions& options, nlohmann::json& report);

}  // namespace driftlab
