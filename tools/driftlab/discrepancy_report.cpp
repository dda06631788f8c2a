#include "tools/driftlab/discrepancy_report.hpp"

#include <cmath>
#include <cstdio>

#include "framework/units.hpp"
#include "tools/driftlab/html_report.hpp"

namespace driftlab::cli {
namespace {

double dph(double rad_s) { return rad_s * kDphPerRadPerSec; }

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

// One colour per model in every panel: the initial model blue, the final model red.
const std::string kInitialColor = palette_color(0), kFinalColor = palette_color(1);

PlotSeries bin_series(const std::string& label, const std::vector<discrepancy::Bin>& bins, double center_scale,
                      PlotSeries::Style style, const std::string& color) {
  PlotSeries s{label, {}, {}, {}, {}, style};
  s.color = color;
  for (const auto& b : bins) {
    s.x.push_back(b.center * center_scale);
    s.y.push_back(dph(b.mean_rad_s));
    s.y_low.push_back(dph(b.mean_rad_s - b.standard_error_rad_s));
    s.y_high.push_back(dph(b.mean_rad_s + b.standard_error_rad_s));
  }
  return s;
}

PlotSeries spectrum_series(const std::string& label, const discrepancy::Views& v, const std::string& color) {
  PlotSeries s{label, {}, {}, {}, {}, PlotSeries::Style::Line};
  s.color = color;
  for (const auto& line : v.spectrum) {
    s.x.push_back(line.period_s);
    s.y.push_back(dph(line.amplitude_rad_s));
  }
  return s;
}

Figure residual_figure(const discrepancy::Result& r) {
  const auto& a = r.initial_views;
  const auto& b = r.final_views;
  const auto over_time = [](const std::string& label, const discrepancy::Views& v, const std::string& color) {
    PlotSeries s{label, to_vector(v.time_s, 1.0 / kSecondsPerHour), to_vector(v.residual_rad_s, kDphPerRadPerSec)};
    s.color = color;
    s.break_at_gaps = true;  // a burst record's gaps stay gaps
    return s;
  };
  Figure f;
  f.panels.push_back({"residual over time (block means): measured - model",
                      "time (h)",
                      "residual (°/h)",
                      false,
                      false,
                      {over_time("initial model", a, kInitialColor), over_time("final model", b, kFinalColor)}});
  f.panels.push_back(
      {"residual by temperature, heating solid, cooling dashed (mean ± s/√n per bin)",
       "temperature (°C)",
       "residual (°/h)",
       false,
       false,
       {bin_series("initial model, heating", a.heating_by_temperature, 1.0, PlotSeries::Style::Line, kInitialColor),
        bin_series("initial model, cooling", a.cooling_by_temperature, 1.0, PlotSeries::Style::Dashed, kInitialColor),
        bin_series("final model, heating", b.heating_by_temperature, 1.0, PlotSeries::Style::Line, kFinalColor),
        bin_series("final model, cooling", b.cooling_by_temperature, 1.0, PlotSeries::Style::Dashed, kFinalColor)}});
  f.panels.push_back(
      {"residual by temperature rate (mean ± s/√n per bin)",
       "dT/dt (°C/min)",
       "residual (°/h)",
       false,
       false,
       {bin_series("initial model", a.by_temperature_rate, 60.0, PlotSeries::Style::Markers, kInitialColor),
        bin_series("final model", b.by_temperature_rate, 60.0, PlotSeries::Style::Markers, kFinalColor)}});
  if (!a.spectrum.empty())
    f.panels.push_back(
        {"residual spectrum (least-squares sinusoid amplitude)",
         "period (s)",
         "amplitude (°/h)",
         true,
         false,
         {spectrum_series("initial model", a, kInitialColor), spectrum_series("final model", b, kFinalColor)}});
  if (!a.allan.empty()) {
    PlotSeries before{"initial model residual", {}, {}, {}, {}, PlotSeries::Style::Markers};
    PlotSeries after{"final model residual", {}, {}, {}, {}, PlotSeries::Style::Markers};
    PlotSeries model{"noise terms (device)", {}, {}, {}, {}, PlotSeries::Style::Dashed};
    before.color = kInitialColor, after.color = kFinalColor, model.color = "#555555";
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
                        "Allan deviation (°/h)",
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

}  // namespace

std::string discrepancy_html(const discrepancy::Result& r, const discrepancy::ReportInfo& info) {
  HtmlReport html("driftlab discrepancy: " + info.data);
  const std::string initial_model = info.device.empty() ? "the bias polynomial" : "the device's model";
  html.paragraph("Data: " + info.data +
                 "; device: " + (info.device.empty() ? "none (bias polynomial only)" : info.device) + ".");
  html.paragraph("Gap (rms of the block-mean residual, " + std::to_string(r.blocks) + " blocks of " +
                 format_number(r.block_s) + " s): " + format_number(dph(r.gap_initial_rad_s)) + " deg/h with " +
                 initial_model + ", " + format_number(dph(r.gap_final_rad_s)) +
                 " deg/h after the named effects. Noise alone would leave about " +
                 format_number(dph(r.noise_floor_rad_s)) + " deg/h.");
  html.section("Named effects");
  if (r.unexplained.found) {
    const auto& v = r.unexplained.views.front();
    html.paragraph("Unexplained: structure remains that no candidate explains, in the " + v.view +
                   " view (ΔBIC = " + one_decimal(v.delta_bic) + ", " + format_number(dph(v.size_rad_s)) +
                   " deg/h rms): " + v.where + ". See the residual plots below.");
  }
  if (r.steps.empty() && !r.unexplained.found) {
    std::string text = "Nothing significant is missing";
    if (!r.final_scores.empty() && r.final_scores.front().applicable)
      text += " (best candidate " + r.final_scores.front().effect +
              ", ΔBIC = " + one_decimal(r.final_scores.front().delta_bic) + ", needs > " +
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
                                      " (blue) and of the final model with the named effects (red), in the views the "
                                      "candidates are scored on: over time, by temperature (heating solid, cooling "
                                      "dashed: apart where a lag or hysteresis is missing), by temperature rate, as a "
                                      "spectrum and as an Allan deviation against the model's noise terms (grey). "
                                      "Red flat on zero: nothing left to explain.");
  html.section("Last round of scores");
  HtmlTable scores{"", {"effect", "Δχ²", "ΔBIC", "parameters added"}};
  for (const auto& s : r.final_scores) {
    if (s.applicable)
      scores.rows.push_back(
          {s.effect, one_decimal(s.delta_chi2), one_decimal(s.delta_bic), static_cast<double>(s.added_parameters)});
    else
      scores.rows.push_back({s.effect, "not applicable: " + s.note, std::string(), std::string()});
  }
  html.table(scores);
  html.paragraph("An effect is named when ΔBIC = Δχ²/s² - q ln(blocks) > " + format_number(info.options->significance) +
                 ", with χ² from the generalized least-squares fit under the covariance the noise terms predict "
                 "(see models/discrepancy/discrepancy.hpp).");
  return html.html();
}

}  // namespace driftlab::cli
