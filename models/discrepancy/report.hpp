// The discrepancy workflow (discrepancy.hpp) as `driftlab discrepancy` and the Python module's
// discrepancy() run it: the candidate effects from the registry, and report.json's data. Rates in
// the report are in deg/h (the unit of the device file's bias and effect keys).
//
// report.json:
//   named_effects[]  {effect, parameters {key: value | [values]}, uncertainty {key: sigma | null},
//                     units {key: unit}, gap_before, gap_after, evidence {delta_chi2, delta_bic,
//                     chi2_scale, runner_up {effect, delta_bic}, scores[]}}; empty when nothing
//                     significant is missing. Parameters are those of the final model, in the keys
//                     and units of a device file's `effects:` section.
//   gap_initial, gap_final, gap_metric, gap_unit, noise_floor
//   criterion {name, significance, blocks, block_s}, final_scores[] (the round that stopped)
//   unexplained {found, views[]}: structure no candidate explains
//   model {data, device, bias_degree, bias_coefficients_initial/final (deg/h per K^i), noise {N, B, K},
//   noise_estimated} views {initial, final}: bins by temperature (heating, cooling), by dT/dt, regime means, spectrum
//                     peaks, Allan deviation of the residual against the noise terms
#pragma once

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "models/discrepancy/discrepancy.hpp"

namespace driftlab {
class Registry;
}

namespace driftlab::discrepancy {

struct CandidateSet {
  std::vector<std::unique_ptr<Effect>> owned;
  std::vector<Candidate> candidates;  // pointing into `owned`
};

// The candidates: the effect/* plugins `names` ("effect/" may be left out; empty: every effect/*
// plugin of the registry, only those a device file can hold when device_file_effects_only), with
// `sets` ("effect/NAME.key=value": search bounds and options, validated by the plugin's table).
// Throws ConfigError (field "--set ...") for a malformed or unknown assignment, UnknownPluginError
// for an unknown effect.
CandidateSet make_candidates(const Registry& registry, std::vector<std::string> names,
                             const std::vector<std::string>& sets, bool device_file_effects_only);

struct ReportInfo {
  std::string data;    // input file
  std::string device;  // device file, or empty
  const Options* options = nullptr;
};

nlohmann::json report_json(const Result& result, const ReportInfo& info);

}  // namespace driftlab::discrepancy
