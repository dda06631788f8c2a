#include "tools/driftlab/calibration_report.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "framework/sampling.hpp"
#include "framework/units.hpp"
#include "framework/error.hpp"
#include "models/calibration/evidence.hpp"
#include "models/evaluation/evaluation.hpp"
#include "tools/driftlab/html_report.hpp"

namespace driftlab::cli {
namespace {


struct Scored {
  std::string name, description, bandwidth;
  double drift_dph = 0, b_dph = NAN, n_dph_rthz = NAN, extrapolated = 0;
  bool b_resolved = false;  // b_dph is B; otherwise only the bound B < b_dph (models/allan/analysis.hpp)
  double b_within_tau_s = 0;
  std::vector<double> block_t, block_mean_dph;
};

Scored score(const std::string& name, const std::string& description, const calibration::Record& r,
             const Eigen::VectorXd& out, const std::vector<char>* extrapolated) {
  Scored s{name, description, ""};
  const Eigen::VectorXd truth = r.true_rate_rad_s.size() ? r.true_rate_rad_s : Eigen::VectorXd::Zero(r.time_s.size());
  const Eigen::VectorXd error = out - truth;
  s.drift_dph = evaluation::block_mean_rms(r.time_s, error) * kDphPerRadPerSec;
  const auto facts = sampling::facts_of(r.time_s);
  const double fs = facts.mean_rate_hz;
  // Allan figures need an evenly sampled record: none for records with gaps (bursts).
  const bool even = facts.evenly_sampled();
  if (const auto a = even ? calibration::allan_figures(error, fs) : std::nullopt) {
    const auto& b = a->bias_instability;
    s.b_resolved = b.resolved;
    s.b_dph = (b.resolved ? b.value : b.high) * kDphPerRadPerSec;
    s.b_within_tau_s = b.longest_tau_s;
    s.n_dph_rthz = a->arw_rad_sqrt_s * kDphPerRadPerSec;
  }
  if (extrapolated) {
    double n = 0;
    for (char c : *extrapolated) n += c;
    s.extrapolated = n / static_cast<double>(extrapolated->size());
  }
  const auto blocks = evaluation::block_means(r.time_s, error);
  for (Eigen::Index b = 0; b < blocks.means.size(); ++b) {
    const auto k = static_cast<std::size_t>(b);
    s.block_t.push_back(r.time_s.segment(blocks.first[k], blocks.samples[k]).mean());
    s.block_mean_dph.push_back(blocks.means[b] * kDphPerRadPerSec);
  }
  return s;
}

std::string terms_text(const calibration::CalibrationModel& m) {
  char buf[64];
  std::string t = "polynomial";
  if (m.lag_tau_s > 0) {
    std::snprintf(buf, sizeof buf, ", lag %g s", m.lag_tau_s);
    t += buf;
  }
  if (m.temperature_rate_rad_s_per_k_s != 0.0) t += ", dT/dt";
  if (m.hysteresis_width_k > 0) {
    std::snprintf(buf, sizeof buf, ", hysteresis (width %g K)", m.hysteresis_width_k);
    t += buf;
  }
  if (m.rbf && m.rbf->centres.rows() > 0) t += ", RBF " + std::to_string(m.rbf->centres.rows()) + " centres";
  if (!m.scale_factor_per_k.empty()) t += ", scale factor";
  return t;
}

nlohmann::json model_json(const CompetingModel& m) {
  nlohmann::json j{{"name", m.name}, {"description", m.description}};
  if (m.model) {
    j["kind"] = calibration::to_string(m.model->kind);
    j["order"] = m.model->order();
    j["valid_range_c"] = {m.model->valid_min_c, m.model->valid_max_c};
    j["extrapolation"] = calibration::to_string(m.model->extrapolation);
    j["heating_only"] = m.model->fit.heating_only;
    j["lag_tau_s"] = m.model->lag_tau_s;
    j["temperature_rate_rad_s_per_k_s"] = m.model->temperature_rate_rad_s_per_k_s;
    j["hysteresis_rad_s"] = m.model->hysteresis_rad_s;
    j["hysteresis_width_k"] = m.model->hysteresis_width_k;
    j["rbf_centres"] = m.model->rbf ? m.model->rbf->centres.rows() : 0;
    j["calibration_holdout_rms_dph"] = m.model->fit.holdout_rms_rad_s * kDphPerRadPerSec;
    j["selection"] = m.model->fit.selection;
  }
  return j;
}

}  // namespace

nlohmann::json write_calibration_report(const ReportInput& in, const ReportFiles& files, OutputSet& outputs) {
  nlohmann::json j;
  j["format"] = "driftlab-calibrate-report/1";
  j["command"] = in.command;
  j["calibration_records"] = in.calibration_records;
  j["truth"] = in.truth_note;
  j["metrics"] = {
      {"residual_drift_dph", "rms of 60-s block means of (output - true rate), deg/h, on records not fitted to"},
      {"B_dph", "bias instability: min overlapping Allan deviation of (output - true rate) / 0.664, deg/h"},
      {"N_dph_rthz", "Allan deviation at tau = 1 s, deg/h/sqrt(Hz); every causal model keeps the full bandwidth fs/2"},
      {"extrapolated_fraction", "share of samples whose model temperature was outside the calibrated range"}};
  j["notes"] = in.notes;
  j["models"] = nlohmann::json::array();
  for (const auto& m : in.models) j["models"].push_back(model_json(m));

  HtmlReport html("driftlab calibrate: held-out evidence");
  html.paragraph("Command: " + in.command);
  html.paragraph("Calibration records: " + [&] {
    std::string s;
    for (const auto& r : in.calibration_records) s += (s.empty() ? "" : ", ") + r;
    return s;
  }());
  html.paragraph("Truth: " + in.truth_note);
  for (const auto& n : in.notes) html.paragraph("Note: " + n);
  {
    HtmlTable t{"Competing models, all fitted on the calibration records", {"name", "kind", "order", "terms", "valid range (degC)", "extrapolation", "fitted on", "held-out CV residual (deg/h)"}};
    for (const auto& m : in.models) {
      if (!m.model) {
        t.rows.push_back({m.name, std::string("none"), std::string("-"), std::string("-"), std::string("-"),
                          std::string("-"), std::string("-"), std::string("-")});
        continue;
      }
      char range[64];
      std::snprintf(range, sizeof range, "%.2f .. %.2f", m.model->valid_min_c, m.model->valid_max_c);
      t.rows.push_back({m.name, calibration::to_string(m.model->kind), static_cast<double>(m.model->order()),
                        terms_text(*m.model), std::string(range), calibration::to_string(m.model->extrapolation),
                        std::string(m.model->fit.heating_only ? "heating only" : "heating and cooling"),
                        m.model->fit.holdout_rms_rad_s * kDphPerRadPerSec});
    }
    t.note = "Held-out CV residual: pooled RMS of fitting-bin residuals on contiguous time blocks left out in turn.";
    html.table(t);
  }

  j["evaluations"] = nlohmann::json::array();
  for (std::size_t e = 0; e < in.evaluations.size(); ++e) {
    const auto& r = in.evaluations[e];
    std::vector<Scored> scores;
    for (const auto& m : in.models) {
      if (!m.model) {
        scores.push_back(score(m.name, m.description, r, r.rate_rad_s, nullptr));
      } else {
        const auto c = calibration::compensate(*m.model, r.time_s, r.rate_rad_s, r.temp_c);
        scores.push_back(score(m.name, m.description, r, c.rate_rad_s, &c.extrapolated));
      }
      scores.back().bandwidth = "fs/2 (unchanged: the correction is a slow bias)";
    }
    for (const auto& x : in.external) {
      if (x.record == e) {
        scores.push_back(score(x.name, x.description, r, x.rate_rad_s, nullptr));
        scores.back().bandwidth = x.bandwidth;
      }
    }
    nlohmann::json ej{{"record", r.name},
                      {"samples", r.time_s.size()},
                      {"duration_s", r.time_s[r.time_s.size() - 1] - r.time_s[0]},
                      {"temperature_range_c", {r.temp_c.minCoeff(), r.temp_c.maxCoeff()}}};
    if (r.systematic_rad_s.size()) {
      const Eigen::VectorXd floor_err = r.rate_rad_s - r.systematic_rad_s;
      ej["intrinsic_floor_drift_dph"] =
          evaluation::block_mean_rms(r.time_s, floor_err) * kDphPerRadPerSec;
    }
    ej["methods"] = nlohmann::json::array();
    HtmlTable t{"Held-out record " + r.name, {"method", "residual drift (deg/h)", "B (deg/h)", "N (deg/h/sqrt(Hz))", "output bandwidth", "extrapolated (%)"}};
    for (const auto& s : scores) {
      ej["methods"].push_back({{"name", s.name},
                               {"description", s.description},
                               {"residual_drift_dph", s.drift_dph},
                               {"B_dph", std::isfinite(s.b_dph) && s.b_resolved ? nlohmann::json(s.b_dph) : nlohmann::json()},
                               {"B_resolved", s.b_resolved},
                               {"B_upper_dph", std::isfinite(s.b_dph) && !s.b_resolved ? nlohmann::json(s.b_dph) : nlohmann::json()},
                               {"N_dph_rthz", std::isfinite(s.n_dph_rthz) ? nlohmann::json(s.n_dph_rthz) : nlohmann::json()},
                               {"output_bandwidth", s.bandwidth},
                               {"extrapolated_fraction", s.extrapolated}});
      const HtmlCell b = !std::isfinite(s.b_dph) ? HtmlCell(std::string("–"))
                         : s.b_resolved            ? HtmlCell(s.b_dph)
                                                   : HtmlCell("< " + format_number(s.b_dph) + " (not resolved within tau ≤ " +
                                                              format_number(s.b_within_tau_s) + " s)");
      t.rows.push_back({s.name, s.drift_dph, b, s.n_dph_rthz, s.bandwidth, 100.0 * s.extrapolated});
    }
    t.note = "Residual drift: rms of 60-s block means of (output - true rate). B and N need an evenly sampled "
             "record (none for burst records); B is a value only where the Allan deviation has a floor, otherwise "
             "the bound '< x'. " +
             (r.systematic_rad_s.size()
                  ? "Intrinsic floor (measured - true systematic rate): " +
                        std::to_string(ej["intrinsic_floor_drift_dph"].get<double>()) + " deg/h."
                  : std::string("No systematic-rate column: no intrinsic floor."));
    html.section("Held-out record " + r.name + " (" + std::to_string(r.time_s.size()) + " samples)");
    html.table(t);
    Figure fig;
    PlotPanel p{"60-s block means of output - true rate", "time (s)", "deg/h"};
    for (const auto& s : scores) {
      PlotSeries ps;
      ps.label = s.name;
      ps.x = s.block_t;
      ps.y = s.block_mean_dph;
      ps.style = s.block_t.size() < 60 ? PlotSeries::Style::Markers : PlotSeries::Style::Line;
      p.series.push_back(ps);
    }
    fig.panels.push_back(p);
    try {
      html.figure(fig, "Residual drift of every method on " + r.name);
    } catch (const PlotError& err) {
      html.paragraph(std::string("(figure not drawn: ") + err.what() + ")");
    }
    j["evaluations"].push_back(ej);
  }
  outputs.write(files.json, j.dump(2) + "\n");
  outputs.write(files.html, html.html());
  return j;
}

}  // namespace driftlab::cli
