#include "models/discrepancy/report.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "framework/effect_catalogue.hpp"
#include "framework/error.hpp"
#include "framework/number_text.hpp"
#include "framework/params_io.hpp"
#include "framework/registry.hpp"
#include "framework/units.hpp"

namespace driftlab::discrepancy {
namespace {

double dph(double rad_s) { return rad_s * kDphPerRadPerSec; }

nlohmann::json gauss_markov_json(const std::vector<error_model::GaussMarkovComponent>& terms) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& g : terms) out.push_back({{"tau_s", g.tau_s}, {"sigma_dph", dph(g.sigma_rad_s)}});
  return out;
}

nlohmann::json number_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json score_json(const Score& s) {
  nlohmann::json j{{"effect", s.effect}, {"applicable", s.applicable}};
  if (!s.applicable) {
    j["note"] = s.note;
    return j;
  }
  j["delta_chi2"] = s.delta_chi2;
  j["delta_bic"] = s.delta_bic;
  j["added_parameters"] = s.added_parameters;
  return j;
}

nlohmann::json scores_json(const std::vector<Score>& scores) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& s : scores) a.push_back(score_json(s));
  return a;
}

nlohmann::json bins_json(const std::vector<Bin>& bins, const char* center_key, double center_scale) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& b : bins)
    a.push_back({{center_key, b.center * center_scale},
                 {"mean_dph", dph(b.mean_rad_s)},
                 {"standard_error_dph", dph(b.standard_error_rad_s)},
                 {"blocks", b.count}});
  return a;
}

nlohmann::json regime_json(const Bin& b) {
  return {{"mean_dph", dph(b.mean_rad_s)}, {"standard_error_dph", dph(b.standard_error_rad_s)}, {"blocks", b.count}};
}

nlohmann::json views_json(const Views& v) {
  nlohmann::json peaks = nlohmann::json::array(), allan = nlohmann::json::array();
  for (const auto& p : v.peaks) peaks.push_back({{"period_s", p.period_s}, {"amplitude_dph", dph(p.amplitude_rad_s)}});
  for (const auto& a : v.allan)
    allan.push_back(
        {{"tau_s", a.tau_s}, {"residual_dph", dph(a.residual_rad_s)}, {"noise_model_dph", dph(a.model_rad_s)}});
  return {{"by_temperature_heating", bins_json(v.heating_by_temperature, "temp_c", 1.0)},
          {"by_temperature_cooling", bins_json(v.cooling_by_temperature, "temp_c", 1.0)},
          {"by_temperature_rate", bins_json(v.by_temperature_rate, "rate_c_per_min", 60.0)},
          {"heating", regime_json(v.heating)},
          {"cooling", regime_json(v.cooling)},
          {"soak", regime_json(v.soak)},
          {"spectrum_peaks", peaks},
          {"allan_deviation", allan}};
}

nlohmann::json unexplained_json(const Unexplained& u) {
  nlohmann::json views = nlohmann::json::array();
  for (const auto& v : u.views) {
    nlohmann::json view{{"view", v.view},
                        {"delta_bic", number_or_null(v.delta_bic)},
                        {"delta_chi2", v.delta_chi2},
                        {"parameters", v.parameters},
                        {"size_dph", dph(v.size_rad_s)},
                        {"where", v.where}};
    if (v.step) view["step"] = {{"level_c", v.step->level_c}, {"size_dph", dph(v.step->size_rad_s)}};
    views.push_back(std::move(view));
  }
  return {{"found", u.found}, {"views", views}};
}

}  // namespace

CandidateSet make_candidates(const Registry& registry, std::vector<std::string> names,
                             const std::vector<std::string>& sets, bool device_file_effects_only) {
  if (names.empty())
    for (const auto* info : registry.list("effect"))
      if (!device_file_effects_only || find_effect_info(info->name.substr(7))) names.push_back(info->name);
  for (auto& name : names) {
    if (name.rfind("effect/", 0) != 0) name = "effect/" + name;
    registry.info(name);  // an unknown name: UnknownPluginError listing the known effects
  }
  std::map<std::string, std::vector<std::string>> assignments;
  for (const auto& set : sets) {
    const auto dot = set.find('.');
    const auto eq = set.find('=');
    if (dot == std::string::npos || eq == std::string::npos || dot > eq)
      throw ConfigError({"", 0, "--set " + set},
                        "expected effect/NAME.key=value, e.g. effect/thermal_lag.tau_max_s=8000");
    std::string name = set.substr(0, dot);
    if (name.rfind("effect/", 0) != 0) name = "effect/" + name;
    if (std::find(names.begin(), names.end(), name) == names.end())
      throw ConfigError({"", 0, "--set " + set},
                        name + " is not a candidate (see --effects and `driftlab plugins list`)");
    assignments[name].push_back(set.substr(dot + 1));
  }
  CandidateSet c;
  for (const auto& name : names) {
    ParamValues params;
    try {
      params = params_from_assignments(registry, name, assignments[name]);
    } catch (const ConfigError& e) {
      auto problems = e.problems();
      for (auto& p : problems) p.where = {"", 0, "--set " + name + "." + p.where.field};
      throw ConfigError(std::move(problems));
    }
    c.owned.push_back(registry.create_as<Effect>({name, std::move(params)}));
    c.candidates.push_back({name.substr(7), c.owned.back().get()});
  }
  return c;
}

nlohmann::json report_json(const Result& r, const ReportInfo& info) {
  nlohmann::json named = nlohmann::json::array();
  for (const auto& step : r.steps) {
    nlohmann::json parameters = nlohmann::json::object(), sigmas = nlohmann::json::object(),
                   units = nlohmann::json::object();
    for (const auto& p : step.parameters) {
      const bool single = p.values.size() == 1;
      parameters[p.key] = single ? nlohmann::json(p.values[0]) : nlohmann::json(p.values);
      nlohmann::json s = nlohmann::json::array();
      for (double sigma : p.sigmas) s.push_back(number_or_null(sigma));
      sigmas[p.key] = single ? s[0] : s;
      units[p.key] = p.unit;
    }
    nlohmann::json evidence{{"delta_chi2", step.delta_chi2},
                            {"delta_bic", step.delta_bic},
                            {"chi2_scale", step.chi2_scale},
                            {"scores", scores_json(step.scores)}};
    if (step.scores.size() > 1 && step.scores[1].applicable)
      evidence["runner_up"] = {{"effect", step.scores[1].effect}, {"delta_bic", step.scores[1].delta_bic}};
    named.push_back({{"effect", step.effect},
                     {"parameters", parameters},
                     {"uncertainty", sigmas},
                     {"units", units},
                     {"gap_before", dph(step.gap_before_rad_s)},
                     {"gap_after", dph(step.gap_after_rad_s)},
                     {"evidence", evidence}});
  }
  const auto& o = *info.options;
  std::vector<double> initial, final;
  for (double b : r.bias_coefficients_initial) initial.push_back(dph(b));
  for (double b : r.bias_coefficients_final) final.push_back(dph(b));
  return {{"named_effects", named},
          {"gap_initial", dph(r.gap_initial_rad_s)},
          {"gap_final", dph(r.gap_final_rad_s)},
          {"gap_metric", "rms of the block-mean residual (measured - modelled systematic rate) over " +
                             std::to_string(r.blocks) + " blocks of " + format_number(r.block_s) + " s, deg/h"},
          {"gap_unit", "deg/h"},
          {"noise_floor", dph(r.noise_floor_rad_s)},
          {"criterion",
           {{"name", "BIC of the generalized least-squares fit under the model's noise covariance"},
            {"significance", o.significance},
            {"blocks", r.blocks},
            {"block_s", r.block_s},
            {"chi2_initial", r.chi2_initial},
            {"chi2_final", r.chi2_final}}},
          {"final_scores", scores_json(r.final_scores)},
          {"unexplained", unexplained_json(r.unexplained)},
          {"model",
           {{"data", info.data},
            {"device", info.device},
            {"reference_temp_c", o.reference_temp_c},
            {"bias_degree", o.bias_degree},
            {"bias_coefficients_initial_dph", initial},
            {"bias_coefficients_final_dph", final},
            {"noise",
             {{"arw_dph_rthz", dph(r.noise.arw_rad_sqrt_s)},
              {"bias_instability_dph", dph(r.noise.bias_instability_rad_s)},
              {"rate_random_walk_dph_rth", dph(r.noise.rate_random_walk_rad_s_sqrt_s) * 60.0},
              {"gauss_markov", gauss_markov_json(r.noise.gauss_markov)}}},
            {"noise_estimated", r.noise_estimated},
            {"noise_estimator", !r.noise_estimated     ? "given (device file)"
                                : o.noise_gmwm.empty() ? "IEEE 952 slope fit of the residual's OADEV (N, B, K)"
                                                       : "GMWM " + o.noise_gmwm + " of the residual's OADEV"}}},
          {"views", {{"initial", views_json(r.initial_views)}, {"final", views_json(r.final_views)}}}};
}

}  // namespace driftlab::discrepancy
