#include "tools/driftlab/calibration_report.hpp"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>

#include "framework/sampling.hpp"
#include "framework/units.hpp"
#include "framework/error.hpp"
#include "models/allan/analysis.hpp"
#include "models/calibration/evidence.hpp"
#include "models/evaluation/evaluation.hpp"
#include "models/evaluation/run_scores.hpp"
#include "tools/driftlab/html_report.hpp"
#include "tools/driftlab/noise_report.hpp"

namespace driftlab::cli {
namespace {

// Leg directions in the figures: calibration records in saturated colours, held-out ones in light.
struct LegColours {
  const char *heating, *cooling, *level;
};
constexpr LegColours kCalibrationColours{"#d62728", "#1f77b4", "#7f7f7f"};
constexpr LegColours kHeldOutColours{"#ff9f4a", "#5fd3e0", "#c7c7c7"};

// The 60-s blocks of a record (evaluation::block_means, the residual-drift blocks): mean time,
// mean temperature and the direction of the leg the block lies in (+1 heating, -1 cooling, 0
// level or between legs), with the record's legs as the quality gate finds them.
struct RecordBlocks {
  std::vector<calibration::Leg> legs;
  std::vector<double> t_s, temp_c;
  std::vector<int> direction;
  std::vector<sampling::TimeBlock> blocks;
};

RecordBlocks blocks_of(const calibration::Record& r) {
  RecordBlocks b;
  b.legs = calibration::analyse_oven_run(r.name, r.time_s, r.temp_c, evaluation::kResidualBlockS).legs;
  const auto means = evaluation::block_means(r.time_s, r.temp_c);
  b.blocks = means.blocks;
  for (std::size_t k = 0; k < means.blocks.size(); ++k) {
    const double t = r.time_s.segment(means.blocks[k].first, means.blocks[k].samples).mean();
    b.t_s.push_back(t);
    b.temp_c.push_back(means.means[static_cast<Eigen::Index>(k)]);
    int direction = 0;
    for (const auto& leg : b.legs)
      if (t >= leg.start_s && t <= leg.end_s + evaluation::kResidualBlockS) direction = leg.direction;
    b.direction.push_back(direction);
  }
  return b;
}

// Mean of x over each block, deg/h.
std::vector<double> block_means_dph(const RecordBlocks& b, const Eigen::VectorXd& x_rad_s) {
  std::vector<double> out;
  for (const auto& block : b.blocks)
    out.push_back(x_rad_s.segment(block.first, block.samples).mean() * kDphPerRadPerSec);
  return out;
}

Eigen::VectorXd truth_of(const calibration::Record& r) {
  return r.true_rate_rad_s.size() ? r.true_rate_rad_s : Eigen::VectorXd::Zero(r.time_s.size());
}

MethodScore score(const std::string& name, const std::string& description, const calibration::Record& r,
                  const RecordBlocks& blocks, const Eigen::VectorXd& out, const calibration::Compensated* compensated,
                  const GmwmRequest& gmwm) {
  MethodScore s{name, description, ""};
  const Eigen::VectorXd error = out - truth_of(r);
  s.drift_dph = evaluation::block_mean_rms(r.time_s, error) * kDphPerRadPerSec;
  const auto facts = sampling::facts_of(r.time_s);
  // Allan figures need an evenly sampled record: none for records with gaps (bursts).
  if (const auto a = facts.evenly_sampled() ? calibration::allan_figures(error, facts.mean_rate_hz) : std::nullopt) {
    const auto& b = a->bias_instability;
    s.b_resolved = b.resolved;
    s.b_dph = (b.resolved ? b.value : b.high) * kDphPerRadPerSec;
    s.b_within_tau_s = b.longest_tau_s;
    s.n_dph_rthz = a->arw_rad_sqrt_s * kDphPerRadPerSec;
    s.allan = a;
  }
  if (!gmwm.model.empty()) {
    if (!s.allan) {
      s.gmwm_failure = facts.evenly_sampled() ? "no Allan curve: the record is too short"
                                              : "no Allan curve: the record is not evenly sampled";
    } else {
      try {
        s.gmwm = fit_gmwm(s.allan->curve, s.allan->sample_rate_hz, gmwm.model, s.allan->samples, gmwm.bootstrap,
                          gmwm.seed, gmwm.threads);
      } catch (const DataError& e) {
        s.gmwm_failure = e.what();
      }
    }
  }
  if (compensated) {
    const auto outside = std::count_if(compensated->outside.begin(), compensated->outside.end(),
                                       [](unsigned char flags) { return flags != 0; });
    s.extrapolated = static_cast<double>(outside) / static_cast<double>(compensated->outside.size());
    s.block_bias_dph = block_means_dph(blocks, compensated->bias_rad_s);
  }
  s.block_mean_dph = block_means_dph(blocks, error);
  for (const auto& leg : blocks.legs) {
    Eigen::Index from = 0, to = 0;
    while (from < r.time_s.size() && r.time_s[from] < leg.start_s) ++from;
    to = from;
    while (to < r.time_s.size() && r.time_s[to] < leg.end_s + evaluation::kResidualBlockS) ++to;
    try {
      s.leg_drift_dph.push_back(
          evaluation::block_mean_rms(r.time_s.segment(from, to - from), error.segment(from, to - from)) *
          kDphPerRadPerSec);
    } catch (const DataError&) {
      s.leg_drift_dph.push_back(NAN);
    }
  }
  return s;
}

std::string leg_text(const calibration::Leg& leg) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%s %.1f → %.1f °C, %.0f min", leg.name().c_str(), leg.from_c, leg.to_c,
                (leg.end_s - leg.start_s) / 60.0);
  return buf;
}

// Block means of measured - true rate against temperature, one marker series per leg direction.
void add_bias_points(PlotPanel& p, const std::string& what, const calibration::Record& r, const RecordBlocks& b,
                     const LegColours& colours) {
  const auto bias = block_means_dph(b, r.rate_rad_s - truth_of(r));
  for (const int direction : {+1, -1, 0}) {
    PlotSeries s;
    s.label = what + ", " + (direction > 0 ? "heating" : direction < 0 ? "cooling" : "soak / level");
    s.style = PlotSeries::Style::Markers;
    s.color = direction > 0 ? colours.heating : direction < 0 ? colours.cooling : colours.level;
    for (std::size_t k = 0; k < bias.size(); ++k)
      if (b.direction[k] == direction) {
        s.x.push_back(b.temp_c[k]);
        s.y.push_back(bias[k]);
      }
    if (!s.x.empty()) p.series.push_back(std::move(s));
  }
}

// The figures of one held-out record (see the header).
void add_figures(HtmlReport& html, const ReportInput& in, const std::vector<RecordBlocks>& calibration_blocks,
                 const calibration::Record& r, const RecordBlocks& blocks, const std::vector<MethodScore>& scores) {
  {
    PlotPanel p{"Bias against temperature (60-s block means) and each model's correction on " + r.name,
                "temperature (°C)", "bias (°/h)"};
    for (std::size_t c = 0; c < in.calibration.size(); ++c)
      add_bias_points(p, "calibration", in.calibration[c], calibration_blocks[c], kCalibrationColours);
    add_bias_points(p, "held out", r, blocks, kHeldOutColours);
    for (const auto& s : scores) {
      if (s.block_bias_dph.empty()) continue;
      PlotSeries line{s.name + " correction", blocks.temp_c, s.block_bias_dph};
      p.series.push_back(std::move(line));
    }
    html.figure_or_note({{p}, 900, 420, 1, ""},
                        "Bias (measured - true rate) of the calibration records and of " + r.name +
                            ", heating and cooling apart, with the correction each model applies to " + r.name);
  }
  PlotPanel by_temp{"|Residual| against temperature (60-s block means of output - true rate)", "temperature (°C)",
                    "|residual| (°/h)"};
  PlotPanel by_time{"|Residual| against time (60-s block means of output - true rate)", "time (s)", "|residual| (°/h)"};
  by_temp.log_y = by_time.log_y = true;
  PlotPanel allan{"Allan deviation of output - true rate, 68.3 % intervals", "tau (s)", "Allan deviation (°/h)"};
  allan.log_x = allan.log_y = true;
  for (const auto& s : scores) {
    PlotSeries t{s.name, blocks.temp_c, {}};
    PlotSeries h{s.name, blocks.t_s, {}};
    t.style = PlotSeries::Style::Markers;
    h.style = blocks.t_s.size() < 60 ? PlotSeries::Style::Markers : PlotSeries::Style::Line;
    h.break_at_gaps = true;  // a burst record's gaps stay gaps
    for (const double v : s.block_mean_dph) {
      t.y.push_back(std::abs(v));
      h.y.push_back(std::abs(v));
    }
    by_temp.series.push_back(std::move(t));
    by_time.series.push_back(std::move(h));
    if (!s.allan) continue;
    allan.series.push_back(allan_series(s.name, s.allan->curve, kDphPerRadPerSec));
  }
  // The reading guides of the model with the least residual drift (an external output may be
  // low-passed: its N is not the sensor's).
  const MethodScore* guided = nullptr;
  for (std::size_t k = 0; k < std::min(in.models.size(), scores.size()); ++k)
    if (scores[k].allan && (guided == nullptr || scores[k].drift_dph < guided->drift_dph)) guided = &scores[k];
  if (guided != nullptr)
    for (auto& g : allan_guides(*guided->allan, kDphPerRadPerSec, "°/h", guided->name))
      allan.series.push_back(std::move(g));
  html.figure_or_note({{by_temp}, 900, 360, 1, ""},
                      "Residual of every method against temperature on " + r.name +
                          " (log scale: 'none' is orders of magnitude above the models); a model whose points rise at "
                          "the ends of the range extrapolates badly there");
  html.figure_or_note({{by_time}, 900, 300, 1, ""}, "Residual of every method against time on " + r.name +
                                                        " (log scale); peaks at the turns of "
                                                        "the temperature are a lag the model "
                                                        "does not follow");
  if (!allan.series.empty())
    html.figure_or_note(
        {{allan}, 900, 420, 1, ""},
        "Allan deviation of every method's residual on " + r.name +
            ", 68.3 % intervals as bands: lower at long tau means less drift left" +
            (guided == nullptr ? std::string(".")
                               : ". Grey dashed guides, of " + guided->name +
                                     " (the model with the least residual drift): the -1/2 slope through N at "
                                     "tau = 1 s and the level of the floor where B is read (0.664 B), with the "
                                     "points they are read at (black dots, their values in the legend)."));
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
    std::snprintf(buf, sizeof buf, ", hysteresis %.3g °/h (width %g K)", m.hysteresis_height() * kDphPerRadPerSec,
                  m.hysteresis_width_k);
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
    j["hysteresis_height_dph"] = m.model->hysteresis_height() * kDphPerRadPerSec;
    j["hysteresis_height_sigma_dph"] = m.model->hysteresis_height_sigma() * kDphPerRadPerSec;
    j["hysteresis_width_k"] = m.model->hysteresis_width_k;
    j["rbf_centres"] = m.model->rbf ? m.model->rbf->centres.rows() : 0;
    j["calibration_holdout_rms_dph"] = m.model->fit.holdout_rms_rad_s * kDphPerRadPerSec;
    j["selection"] = m.model->fit.selection;
  }
  return j;
}

// report.json's head: the command, the records, what each metric means, the gate, the models.
nlohmann::json report_head_json(const ReportInput& in, const std::vector<std::string>& names) {
  nlohmann::json j;
  j["format"] = "driftlab-calibrate-report/1";
  j["command"] = in.command;
  j["calibration_records"] = names;
  j["truth"] = in.truth_note;
  j["metrics"] = {
      {"residual_drift_dph", "rms of 60-s block means of (output - true rate), deg/h, on records not fitted to"},
      {"residual_drift_by_leg_dph", "the same over each leg of the held-out record (legs: evaluations[].legs)"},
      {"B_dph", "bias instability: min overlapping Allan deviation of (output - true rate) / 0.664, deg/h"},
      {"N_dph_rthz", "Allan deviation at tau = 1 s, deg/h/sqrt(Hz); every causal model keeps the full bandwidth fs/2"},
      {"hysteresis_height_dph",
       "models[]: the full gap between the saturated heating and cooling branches, cooling minus heating (positive: "
       "the cooling branch above), deg/h, with its 1-sigma; the convention of driftlab discrepancy's hysteresis "
       "height_dph"},
      {"extrapolated_fraction",
       "share of samples with a model input (model temperature, dT/dt, branch state, RBF input) outside the range it "
       "was fitted on"}};
  if (!in.gmwm.model.empty())
    j["metrics"]["gmwm"] = "GMWM fit of " + allan::gmwm::to_string(in.gmwm.model) +
                           " to the same OADEV of (output - true rate) as B_dph and N_dph_rthz, as `driftlab allan "
                           "--gmwm` writes it (IEEE 952 gyro units, one-sigma intervals); null with gmwm_failure "
                           "when it could not be fitted";
  j["quality_gate"] = nlohmann::json::array();
  for (const auto& f : in.gate)
    j["quality_gate"].push_back(
        {{"severity", calibration::to_string(f.severity)}, {"code", f.code}, {"message", f.message}});
  j["chosen"] = in.chosen;
  j["notes"] = in.notes;
  j["models"] = nlohmann::json::array();
  for (const auto& m : in.models) j["models"].push_back(model_json(m));
  return j;
}

// report.html's head: the command, the records, the gate's findings and the competing models.
void add_overview(HtmlReport& html, const ReportInput& in, const std::vector<std::string>& names) {
  html.paragraph("Command: " + in.command);
  html.paragraph("Calibration records: " + [&] {
    std::string s;
    for (const auto& r : names) s += (s.empty() ? "" : ", ") + r;
    return s;
  }());
  html.paragraph("Truth: " + in.truth_note);
  html.paragraph("Chosen model: " + in.chosen);
  {
    HtmlTable t{"Oven-run quality gate on the calibration records", {"severity", "finding", "what was measured"}};
    for (const auto& f : in.gate) t.rows.push_back({calibration::to_string(f.severity), f.code, f.message});
    if (t.rows.empty())
      t.rows.push_back({std::string("–"), std::string("none"), std::string("the run passes every check")});
    t.note = "Errors stop the fit; warnings become errors with --strict (models/calibration/oven_run.hpp).";
    html.table(t);
  }
  for (const auto& n : in.notes) html.paragraph("Note: " + n);
  {
    HtmlTable t{"Competing models, all fitted on the calibration records",
                {"name", "kind", "order", "terms", "valid range (°C)", "extrapolation", "fitted on",
                 "held-out CV residual (°/h)"}};
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
    t.note =
        "Held-out CV residual: pooled RMS of fitting-bin residuals on the held-out legs, runs or time blocks "
        "of the calibration records (each model's fit.holdout_design).";
    html.table(t);
  }
}

// Every model (and every method run outside, e.g. the paper pipeline) on held-out record e.
std::vector<MethodScore> score_methods(const ReportInput& in, std::size_t e, const RecordBlocks& blocks) {
  const auto& r = in.evaluations[e];
  std::vector<MethodScore> scores;
  for (const auto& m : in.models) {
    if (!m.model) {
      scores.push_back(score(m.name, m.description, r, blocks, r.rate_rad_s, nullptr, in.gmwm));
    } else {
      const auto c = calibration::compensate(*m.model, r.time_s, r.rate_rad_s, r.temp_c);
      scores.push_back(score(m.name, m.description, r, blocks, c.rate_rad_s, &c, in.gmwm));
    }
    scores.back().bandwidth = "fs/2 (unchanged: the correction is a slow bias)";
  }
  for (const auto& x : in.external) {
    if (x.record == e) {
      scores.push_back(score(x.name, x.description, r, blocks, x.rate_rad_s, nullptr, in.gmwm));
      scores.back().bandwidth = x.bandwidth;
    }
  }
  return scores;
}

// The GMWM parameters of every method's residual on record r, one column per parameter.
HtmlTable gmwm_table(const GmwmRequest& request, const calibration::Record& r, const std::vector<MethodScore>& scores) {
  const std::string model = allan::gmwm::to_string(request.model);
  const MethodScore* fitted = nullptr;
  for (const auto& s : scores)
    if (s.gmwm && fitted == nullptr) fitted = &s;
  HtmlTable t{"GMWM " + model + " of every method's residual on " + r.name, {"method"}};
  if (fitted != nullptr) {
    for (const auto& c : fitted->gmwm->components)
      for (const auto& p : c.parameters)
        t.header.push_back(allan::gmwm::to_string(c.process) + " " + p.name + " (" + gmwm_unit(p, true, "rad/s").first +
                           ")");
    t.header.push_back("χ²/dof");
  } else {
    t.header.push_back("GMWM");
  }
  for (const auto& s : scores) {
    std::vector<HtmlCell> row{s.name};
    if (s.gmwm) {
      for (const auto& c : s.gmwm->components)
        for (const auto& p : c.parameters) row.push_back(gmwm_value_text(c, p, gmwm_unit(p, true, "rad/s").second));
      row.push_back(s.gmwm->reduced_chi2());
    } else {
      row.push_back("not fitted: " + s.gmwm_failure);
      while (row.size() < t.header.size()) row.push_back(std::string("–"));
    }
    t.rows.push_back(std::move(row));
  }
  t.note =
      "GMWM (Guerrier et al. 2013; models/allan/gmwm.hpp) fitted to the same OADEV curve of (output - true "
      "rate) that B and N are read from; value [one-sigma interval, " +
      (fitted != nullptr ? fitted->gmwm->intervals : std::string("-")) +
      "]; '< x': not resolved, only the bound; 'not determined': the component is below what the curve "
      "resolves. N in deg/sqrt(h) is N in °/h/√Hz divided by 60.";
  return t;
}

// The section of held-out record e: its evaluations[] entry (returned), its tables and figures
// (into html), and its scores (into held_out).
nlohmann::json held_out_section(const ReportInput& in, std::size_t e,
                                const std::vector<RecordBlocks>& calibration_blocks, HtmlReport& html,
                                std::vector<HeldOutScores>& held_out) {
  const auto& r = in.evaluations[e];
  const RecordBlocks blocks = blocks_of(r);
  auto scores = score_methods(in, e, blocks);
  nlohmann::json ej{{"record", r.name},
                    {"samples", r.time_s.size()},
                    {"duration_s", r.time_s[r.time_s.size() - 1] - r.time_s[0]},
                    {"temperature_range_c", {r.temp_c.minCoeff(), r.temp_c.maxCoeff()}}};
  ej["legs"] = nlohmann::json::array();
  for (const auto& leg : blocks.legs)
    ej["legs"].push_back({{"direction", leg.name()},
                          {"from_c", leg.from_c},
                          {"to_c", leg.to_c},
                          {"start_s", leg.start_s},
                          {"end_s", leg.end_s}});
  std::optional<double> floor_dph;
  if (r.systematic_rad_s.size()) {
    floor_dph = evaluation::block_mean_rms(r.time_s, evaluation::intrinsic_noise(r.rate_rad_s, r.systematic_rad_s)) *
                kDphPerRadPerSec;
    ej["intrinsic_floor_drift_dph"] = *floor_dph;
  }
  const auto number_or_null = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
  ej["methods"] = nlohmann::json::array();
  HtmlTable t{"Held-out record " + r.name,
              {"method", "residual drift (°/h)", "B (°/h)", "N (°/h/√Hz)", "output bandwidth", "extrapolated (%)"}};
  std::vector<std::string> leg_header{"method"};
  for (const auto& leg : blocks.legs) leg_header.push_back(leg_text(leg) + " (°/h)");
  HtmlTable by_leg{"Residual drift of every method on each leg of " + r.name, leg_header};
  for (const auto& s : scores) {
    nlohmann::json by_leg_json = nlohmann::json::array();
    std::vector<HtmlCell> leg_row{s.name};
    for (const double v : s.leg_drift_dph) {
      by_leg_json.push_back(number_or_null(v));
      leg_row.push_back(v);
    }
    by_leg.rows.push_back(std::move(leg_row));
    ej["methods"].push_back({{"name", s.name},
                             {"description", s.description},
                             {"residual_drift_dph", s.drift_dph},
                             {"residual_drift_by_leg_dph", by_leg_json},
                             {"B_dph", s.b_resolved ? number_or_null(s.b_dph) : nlohmann::json()},
                             {"B_resolved", s.b_resolved},
                             {"B_upper_dph", !s.b_resolved ? number_or_null(s.b_dph) : nlohmann::json()},
                             {"N_dph_rthz", number_or_null(s.n_dph_rthz)},
                             {"output_bandwidth", s.bandwidth},
                             {"extrapolated_fraction", s.extrapolated}});
    if (s.gmwm) ej["methods"].back()["gmwm"] = gmwm_json(*s.gmwm, true, "rad/s");
    if (!s.gmwm_failure.empty()) {
      ej["methods"].back()["gmwm"] = nullptr;
      ej["methods"].back()["gmwm_failure"] = s.gmwm_failure;
    }
    evaluation::BDegH b_reading;
    b_reading.resolved = s.b_resolved;
    b_reading.value = b_reading.high = s.b_dph;  // B, or the bound when not resolved
    b_reading.longest_tau_s = s.b_within_tau_s;
    const HtmlCell b = !std::isfinite(s.b_dph) ? HtmlCell(std::string("–"))
                       : s.b_resolved          ? HtmlCell(s.b_dph)
                                      : HtmlCell(evaluation::b_text(b_reading, evaluation::BStyle::BoundWithin));
    t.rows.push_back({s.name, s.drift_dph, b, s.n_dph_rthz, s.bandwidth, 100.0 * s.extrapolated});
  }
  t.note =
      "Residual drift: rms of 60-s block means of (output - true rate). B and N need an evenly sampled "
      "record (none for burst records); B is a value only where the Allan deviation has a floor, otherwise "
      "the bound '< x'. " +
      (r.systematic_rad_s.size()
           ? "Intrinsic floor (measured - true systematic rate): " + format_number(*floor_dph) + " °/h."
           : std::string("No systematic-rate column: no intrinsic floor."));
  by_leg.note =
      "Legs as the quality gate finds them (zig-zag reversals of the 60-s temperature means); – where "
      "a leg is shorter than one 60-s block.";
  html.section("Held-out record " + r.name + " (" + std::to_string(r.time_s.size()) + " samples)");
  html.table(t);
  if (!in.gmwm.model.empty()) html.table(gmwm_table(in.gmwm, r, scores));
  if (!blocks.legs.empty()) html.table(by_leg);
  add_figures(html, in, calibration_blocks, r, blocks, scores);
  held_out.push_back({r.name, std::move(scores), floor_dph});
  return ej;
}

}  // namespace

std::vector<HeldOutScores> write_calibration_report(const ReportInput& in, const ReportFiles& files,
                                                    OutputSet& outputs) {
  std::vector<std::string> names;
  for (const auto& r : in.calibration) names.push_back(r.name);
  nlohmann::json j = report_head_json(in, names);
  HtmlReport html("driftlab calibrate: held-out evidence");
  add_overview(html, in, names);

  std::vector<RecordBlocks> calibration_blocks;
  for (const auto& c : in.calibration) calibration_blocks.push_back(blocks_of(c));
  std::vector<HeldOutScores> held_out;
  j["evaluations"] = nlohmann::json::array();
  for (std::size_t e = 0; e < in.evaluations.size(); ++e)
    j["evaluations"].push_back(held_out_section(in, e, calibration_blocks, html, held_out));
  outputs.write(files.json, j.dump(2) + "\n");
  outputs.write(files.html, html.html());
  return held_out;
}

}  // namespace driftlab::cli
