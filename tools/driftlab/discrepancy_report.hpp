// Outputs of `driftlab discrepancy`: report.json and a self-contained report.html (html_report.hpp) with plots of
// the residual views (models/discrepancy/views.hpp) before the first and after the last named
// effect. Rates are shown in deg/h (the unit of the device file's bias and effect keys).
//
// report.json:
//   named_effects[]  {effect, parameters {key: value | [values]}, uncertainty {key: sigma | null},
//                     units {key: unit}, gap_before, gap_after, evidence {delta_chi2, delta_bic,
//                     chi2_scale, runner_up {effect, delta_bic}, scores[]}}; empty when nothing
//                     significant is missing. Parameters are those of the final model, in the keys
//                     and units of a device file's `effects:` section.
//   gap_initial, gap_final, gap_metric, gap_unit, noise_floor
//   criterion {name, significance, blocks, block_s}, final_scores[] (the round that stopped)
//   model {device, bias_degree, bias_coefficients_initial/final (deg/h per K^i), noise {N, B, K}, noise_estimated}
//   views {initial, final}: bins by temperature (heating, cooling), by dT/dt, regime means, spectrum
//                     peaks, Allan deviation of the residual against the noise terms
#pragma once

#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <vector>
#include <string>

#include "framework/registry.hpp"
#include "models/discrepancy/discrepancy.hpp"

namespace driftlab::cli {

struct DiscrepancyReportInfo {
  std::string data;    // input file
  std::string device;  // device file, or empty
  const discrepancy::Options* options = nullptr;
};

nlohmann::json discrepancy_json(const discrepancy::Result& result, const DiscrepancyReportInfo& info);
std::string discrepancy_html(const discrepancy::Result& result, const DiscrepancyReportInfo& info);

// The candidate effects of a discrepancy run: the registry's plugins `names` ("effect/NAME"), each
// with its assignments (effect/NAME -> "key=value", as --set gives them) validated by its table;
// the plugins are kept in `owned`. ConfigError naming --set NAME.key on a bad assignment.
std::vector<discrepancy::Candidate> discrepancy_candidates(
    const Registry& registry, const std::vector<std::string>& names,
    const std::map<std::string, std::vector<std::string>>& assignments, std::vector<std::unique_ptr<Effect>>& owned);

}  // namespace driftlab::cli
