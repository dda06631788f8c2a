#include "tools/driftlab/discrepancy_report.hpp"

#include <cmath>
#include <cstdio>

#include "framework/params_io.hpp"
#include "framework/units.hpp"
#include "tools/driftlab/html_report.hpp"

namespace driftlab::cli {
namespace {

double dph(double rad_s) { return rad_s * kDphPerRadPerSec; }

nlohmann::json number_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json score_json(const discrepancy::Score& s) {
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

nlohmann::json scores_json(const std::vector<discrepancy::Score>& scores) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& s : scores) a.push_back(score_json(s));
  return a;
}

nlohmann::json bins_json(const std::vector<discrepancy::Bin>& bins, const char* center_key, double center_scale) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& b : bins)
    a.push_back({{center_key, b.center * center_scale},
                 {"mean_dph", dph(b.mean_rad_s)},
                 {"standard_error_dph", dph(b.standard_error_rad_s)},
                 {"blocks", b.count}});
  return a;
}

nlohmann::json regime_json(const discrepancy::Bin& b) {
  return {{"mean_dph", dph(b.mean_rad_s)}, {"standard_error_dph", dph(b.standard_error_rad_s)}, {"blocks", b.count}};
}

nlohmann::json views_json(const discrepancy::Views& v) {
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

// ΔBIC and Δχ² as the report prints them: one decimal.
std::string one_decimal(double v) {
  char text[64];
  std::snprintf(text, sizeof text, "%.1f", v);
  return text;
}

std::vector<double> to_vector(const Eigen::VectorXd& v, double scale) {
  std::vector<double> out(static_cast<std::size_t>(v.size()));
  for (Eigen::Index i = 0; i < v.size(); ++i) out[static_cast<std::size_t>(i)] = v[i] * scale;
  return out;
}

PlotSeries bin_series(const std::string& label, const std::vector<discrepancy::Bin>& bins, double center_scale,
                      PlotSeries::Style style) {
  PlotSeries s{label, {}, {}, {}, {}, style};
  for (const auto& b : bins) {
    s.x.push_back(b.center * center_scale);
    s.y.push_back(dph(b.mean_rad_s));
    s.y_low.push_back(dph(b.mean_rad_s - b.standard_error_rad_s));
    s.y_high.push_back(dph(b.mean_rad_s + b.standard_error_rad_s));
  }
  return s;
}

PlotSeries spectrum_series(const std::string& label, const discrepancy::Views& v, PlotSeries::Style style) {
  PlotSeries s{label, {}, {}, {}, {}, style};
  for (const auto& line : v.spectrum) {
    s.x.push_back(line.period_s);
    s.y.push_back(dph(line.amplitude_rad_s));
  }
  return s;
}

Figure residual_figure(const discrepancy::Result& r) {
  const auto& a = r.initial_views;
  const auto& b = r.final_views;
  Figure f;
  f.panels.push_back(
      {"residual over time (block means): measured - model",
       "time (h)",
       "residual (deg/h)",
       false,
       false,
       {{"initial model", to_vector(a.time_s, 1.0 / kSecondsPerHour), to_vector(a.residual_rad_s, kDphPerRadPerSec)},
        {"final model", to_vector(b.time_s, 1.0 / kSecondsPerHour), to_vector(b.residual_rad_s, kDphPerRadPerSec)}}});
  f.panels.push_back({"residual by temperature, heating and cooling (mean +- s/sqrt(n) per bin)",
                      "temperature (degC)",
                      "residual (deg/h)",
                      false,
                      false,
                      {bin_series("initial, heating", a.heating_by_temperature, 1.0, PlotSeries::Style::Markers),
                       bin_series("initial, cooling", a.cooling_by_temperature, 1.0, PlotSeries::Style::Markers),
                       bin_series("final, heating", b.heating_by_temperature, 1.0, PlotSeries::Style::Line),
                       bin_series("final, cooling", b.cooling_by_temperature, 1.0, PlotSeries::Style::Line)}});
  f.panels.push_back({"residual by temperature rate",
                      "dT/dt (degC/min)",
                      "residual (deg/h)",
                      false,
                      false,
                      {bin_series("initial model", a.by_temperature_rate, 60.0, PlotSeries::Style::Markers),
                       bin_series("final model", b.by_temperature_rate, 60.0, PlotSeries::Style::Line)}});
  if (!a.spectrum.empty())
    f.panels.push_back({"residual spectrum (least-squares sinusoid amplitude)",
                        "period (s)",
                        "amplitude (deg/h)",
                        true,
                        false,
                        {spectrum_series("initial model", a, PlotSeries::Style::Line),
                         spectrum_series("final model", b, PlotSeries::Style::Line)}});
  if (!a.allan.empty()) {
    PlotSeries before{"initial model residual", {}, {}, {}, {}, PlotSeries::Style::Markers};
    PlotSeries after{"final model residual", {}, {}, {}, {}, PlotSeries::Style::Markers};
    PlotSeries model{"noise terms (device)", {}, {}, {}, {}, PlotSeries::Style::Dashed};
    for (const auto& p : a.allan) {
      before.x.push_back(p.tau_s);
      before.y.push_back(dph(p.residual_rad_s));
      model.x.push_back(p.tau_s);
      model.y.push_back(dph(p.model_rad_s));
    }
    for (const auto& p : b.allan) {
      after.x.push_back(p.tau_s);
      after.y.push_back(dph(p.residual_rad_s));
    }
    f.panels.push_back({"Allan deviation of the residual against the model's noise terms",
                        "tau (s)",
                        "Allan deviation (deg/h)",
                        true,
                        true,
                        {before, after, model}});
  }
  return f;
}

std::string parameter_text(const discrepancy::ReportedValue& v) {
  std::string text = v.key + " = ";
  for (std::size_t i = 0; i < v.values.size(); ++i) {
    text += (i ? ", " : "") + format_number(v.values[i]);
    if (std::isfinite(v.sigmas[i])) text += " ± " + format_number(v.sigmas[i], 2);
  }
  return text + " " + v.unit;
}

nlohmann::json unexplained_json(const discrepancy::Unexplained& u) {
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

nlohmann::json discrepancy_json(const discrepancy::Result& r, const DiscrepancyReportInfo& info) {
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
              {"rate_random_walk_dph_rth", dph(r.noise.rate_random_walk_rad_s_sqrt_s) * 60.0}}},
            {"noise_estimated", r.noise_estimated}}},
          {"views", {{"initial", views_json(r.initial_views)}, {"final", views_json(r.final_views)}}}};
}

std::string discrepancy_html(const discrepancy::Result& r, const DiscrepancyReportInfo& info) {
  HtmlReport html("driftlab discrepancy: " + info.data);
  const std::string initial_model = info.device.empty() ? "the bias polynomial" : "the device's model";
  html.paragraph("Data: " + info.data + "; device: " + (info.device.empty() ? "none (bias polynomial only)" : info.device) +
                 ".");
  html.paragraph("Gap (rms of the block-mean residual, " + std::to_string(r.blocks) + " blocks of " +
                 format_number(r.block_s) + " s): " + format_number(dph(r.gap_initial_rad_s)) +
                 " deg/h with " + initial_model + ", " + format_number(dph(r.gap_final_rad_s)) +
                 " deg/h after the named effects. Noise alone would leave about " +
                 format_number(dph(r.noise_floor_rad_s)) + " deg/h.");
  html.section("Named effects");
  if (r.unexplained.found) {
    const auto& v = r.unexplained.views.front();
    html.paragraph("Unexplained: structure remains that no candidate explains, in the " + v.view + " view (ΔBIC = " +
                   one_decimal(v.delta_bic) + ", " + format_number(dph(v.size_rad_s)) + " deg/h rms): " + v.where +
                   ". See the residual plots below.");
  }
  if (r.steps.empty() && !r.unexplained.found) {
    std::string text = "Nothing significant is missing";
    if (!r.final_scores.empty() && r.final_scores.front().applicable)
      text += " (best candidate " + r.final_scores.front().effect + ", ΔBIC = " +
              one_decimal(r.final_scores.front().delta_bic) + ", needs > " +
              format_number(info.options->significance) + ")";
    html.paragraph(text + ".");
  } else if (!r.steps.empty()) {
    HtmlTable named{"", {"step", "effect", "parameters (final model)", "ΔBIC", "gap before → after (deg/h)"}};
    for (std::size_t i = 0; i < r.steps.size(); ++i) {
      const auto& s = r.steps[i];
      std::string parameters;
      for (const auto& p : s.parameters) parameters += (parameters.empty() ? "" : "; ") + parameter_text(p);
      named.rows.push_back({static_cast<double>(i + 1), s.effect, parameters, one_decimal(s.delta_bic),
                            format_number(dph(s.gap_before_rad_s)) + " → " + format_number(dph(s.gap_after_rad_s))});
    }
    html.table(named);
  }
  html.section("Where the model misses: before and after");
  html.figure(residual_figure(r), "The residual (measured - modelled systematic rate) of " + initial_model +
                                      " and of the final model with the named effects, in the views the candidates are "
                                      "scored on");
  html.section("Last round of scores");
  HtmlTable scores{"", {"effect", "Δχ²", "ΔBIC", "parameters added"}};
  for (const auto& s : r.final_scores) {
    if (s.applicable)
      scores.rows.push_back({s.effect, one_decimal(s.delta_chi2), one_decimal(s.delta_bic),
                             static_cast<double>(s.added_parameters)});
    else
      scores.rows.push_back({s.effect, "not applicable: " + s.note, std::string(), std::string()});
  }
  html.table(scores);
  html.paragraph("An effect is named when ΔBIC = Δχ²/s² - q ln(blocks) > " + format_number(info.options->significance) +
                 ", with χ² from the generalized least-squares fit under the covariance the noise terms predict "
                 "(see models/discrepancy/discrepancy.hpp).");
  return html.html();
}

std::vector<discrepancy::Candidate> discrepancy_candidates(
    const Registry& registry, const std::vector<std::string>& names,
    const std::map<std::string, std::vector<std::string>>& assignments, std::vector<std::unique_ptr<Effect>>& owned) {
  std::vector<discrepancy::Candidate> candidates;
  for (const auto& name : names) {
    ParamValues params;
    try {
      const auto a = assignments.find(name);
      params = params_from_assignments(registry, name, a == assignments.end() ? std::vector<std::string>{} : a->second);
    } catch (const ConfigError& e) {
      auto problems = e.problems();
      for (auto& p : problems) p.where = {"", 0, "--set " + name + "." + p.where.field};
      throw ConfigError(std::move(problems));
    }
    owned.push_back(registry.create_as<Effect>({name, std::move(params)}));
    candidates.push_back({name.substr(7), owned.back().get()});
  }
  return candidates;
}

}  // namespace driftlab::cli
