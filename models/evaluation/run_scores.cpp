#include "models/evaluation/run_scores.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "framework/error.hpp"
#include "framework/number_text.hpp"
#include "framework/units.hpp"
#include "models/calibration/fit.hpp"
#include "models/calibration/oven_run.hpp"

namespace driftlab::evaluation {
namespace {

nlohmann::json curve_json(const allan::Analysis& a) {
  nlohmann::json c = nlohmann::json::array();
  for (const auto& e : a.curve)
    c.push_back({{"tau_s", e.tau},
                 {"dev_deg_h", e.dev * kDphPerRadPerSec},
                 {"lo_deg_h", e.dev_lo * kDphPerRadPerSec},
                 {"hi_deg_h", e.dev_hi * kDphPerRadPerSec}});
  return c;
}

nlohmann::json fit_json(const allan::Analysis& a) {
  if (!a.fit) return nullptr;
  nlohmann::json j{{"label", "least-squares fit of the five IEEE 952 terms (not the paper's reading)"},
                   {"chi2_per_dof", a.fit->reduced_chi2()},
                   {"dof", a.fit->dof}};
  for (const auto& c : allan::kIeee952Units) {
    const auto& t = (*a.fit)[c.term];
    nlohmann::json term{{"resolved", t.resolved}, {"unit", std::string(c.unit)}};
    if (t.resolved) {
      term["value"] = t.value * c.factor;
      term["sigma"] = t.sigma * c.factor;
      term["interval"] = {t.low * c.factor, t.high * c.factor};
    } else {
      term["value"] = nullptr;
      term["upper"] = t.high * c.factor;
    }
    j[std::string(c.key)] = term;
  }
  return j;
}

}  // namespace

const PipelineReference::Row* reference_row(const RunScores& s, const std::string& stage) {
  if (!s.reference) return nullptr;
  const auto it = s.reference->rows.find(stage);
  return it == s.reference->rows.end() ? nullptr : &it->second;
}

std::vector<PipelineStage> rate_stages(const Pipeline& pipeline, const std::map<std::string, Signal>& outputs) {
  const auto is_rate = [&](const std::string& name) {
    const auto it = outputs.find(name);
    return it != outputs.end() && it->second.unit == "rad/s" && it->second.columns.cols() == 1;
  };
  if (!pipeline.stages.empty()) {
    for (const auto& stage : pipeline.stages)
      if (!is_rate(stage.output))
        throw DataError({pipeline.file, 0, "stages." + stage.output},
                        "a stage must be one rad/s column (a compensated rate)");
    return pipeline.stages;
  }
  std::vector<PipelineStage> stages;
  for (const auto& name : pipeline.output_order)
    if (is_rate(name)) stages.push_back({name, name});
  return stages;
}

std::string reference_mismatch(const TimeSeries& record, const PipelineReference& reference) {
  if (!reference.record || record.size() < 2) return "";
  const auto& want = *reference.record;
  const double rate = record.sample_rate_hz(), duration = record.time()[record.size() - 1] - record.time()[0];
  std::string differs;
  const auto add = [&](const std::string& what) { differs += (differs.empty() ? "" : ", ") + what; };
  if (std::abs(rate - want.sample_rate_hz) > kReferenceRateTolerance * want.sample_rate_hz)
    add(format_number(rate) + " Hz, not " + format_number(want.sample_rate_hz));
  if (std::abs(duration - want.duration_s) > kReferenceDurationTolerance * want.duration_s)
    add(format_number(duration) + " s, not " + format_number(want.duration_s));
  if (record.has(role::kTemperature)) {
    const Eigen::VectorXd& temp = record.channel(role::kTemperature).values;
    if (std::abs(temp.minCoeff() - want.temperature_min_c) > kReferenceTemperatureToleranceC ||
        std::abs(temp.maxCoeff() - want.temperature_max_c) > kReferenceTemperatureToleranceC)
      add(format_number(temp.minCoeff()) + " to " + format_number(temp.maxCoeff()) + " degC, not " +
          format_number(want.temperature_min_c) + " to " + format_number(want.temperature_max_c));
  } else {
    add("no temperature");
  }
  return differs.empty() ? "" : "this record is not the one " + reference.source + " reports on (" + differs + ")";
}

RunScores score_run(const TimeSeries& record, const Pipeline& pipeline, const std::map<std::string, Signal>& outputs) {
  RunScores s;
  if (pipeline.reference) {
    s.reference_not_shown = reference_mismatch(record, *pipeline.reference);
    if (s.reference_not_shown.empty()) s.reference = pipeline.reference;
  }
  const double fs = record.sample_rate_hz();
  const Eigen::VectorXd& rate = record.channel(role::kRate).values;
  std::optional<Truth> truth;
  if (record.has(role::kTrueRate)) {
    truth = Truth{record.channel(role::kTrueRate).values, std::nullopt};
    if (record.has(role::kSystematic))
      truth->intrinsic_noise_rad_s = intrinsic_noise(rate, record.channel(role::kSystematic).values);
  }
  const Truth* t = truth ? &*truth : nullptr;
  // The record's Allan curve, estimated once: its N is the reference of every bandwidth, and the
  // original stage reads its B from the same curve.
  const auto raw = allan::analyze_rate(rate, fs, {.fit_terms = false});
  const double reference_n = raw.arw_rad_sqrt_s;

  const Eigen::VectorXd& time = record.time();
  s.stages.push_back(score_stage(kOriginalStage, rate, time, fs, reference_n, t, &raw));
  s.stages.back().source = StageScore::Source::Record;
  for (const auto& stage : rate_stages(pipeline, outputs)) {
    s.stages.push_back(score_stage(stage.output, outputs.at(stage.output).columns.col(0), time, fs, reference_n, t));
    s.stages.back().label = stage.label;
  }
  // The baselines need an oven run the calibration quality gate does not refuse.
  const auto fittable = [&](const Eigen::VectorXd& temp) {
    const auto gate = calibration::quality_gate(
        {calibration::analyse_oven_run("the record", time, temp, calibration::FitOptions{}.bin_s)});
    return std::none_of(gate.begin(), gate.end(),
                        [](const auto& f) { return f.severity == calibration::Finding::Severity::Error; });
  };
  if (record.has(role::kTemperature) && fittable(record.channel(role::kTemperature).values)) {
    const Eigen::VectorXd& temp = record.channel(role::kTemperature).values;
    const std::vector<calibration::Record> fitted_on{{"the record", time, rate, temp, {}, {}}};
    for (auto& [stage, model] : {std::pair{kPx4BaselineStage, calibration::fit_px4_style(fitted_on, {})},
                                 std::pair{kCubicBaselineStage, calibration::fit_cubic_all_bins(fitted_on, {})}}) {
      Eigen::VectorXd compensated = calibration::compensate(model, time, rate, temp).rate_rad_s;
      s.stages.push_back(score_stage(stage, compensated, time, fs, reference_n, t));
      s.stages.back().source = StageScore::Source::Baseline;
      s.baselines.push_back({stage, model, std::move(compensated)});
    }
  }
  if (truth && truth->intrinsic_noise_rad_s) {
    s.intrinsic = intrinsic_floor(*truth->intrinsic_noise_rad_s, fs);
    for (const auto& stage : s.stages)
      if (stage.error) s.against_floor[stage.stage] = compare_to_floor(*stage.error, *s.intrinsic, kFloorFactor);
  }
  return s;
}

nlohmann::json b_json(const allan::FloorReading& b) {
  const double f = kDphPerRadPerSec;
  nlohmann::json j{{"B_resolved", b.resolved},
                   {"B_deg_h", nullptr},
                   {"B_upper_deg_h", b.high * f},
                   {"B_tau_s", b.tau_s},
                   {"B_within_tau_s", b.longest_tau_s}};
  if (b.resolved) {
    j["B_deg_h"] = b.value * f;
    j["B_ci"] = {b.low * f, b.high * f};
  }
  return j;
}

BDegH b_deg_h(const allan::FloorReading& b) {
  const double f = kDphPerRadPerSec;
  return {b.resolved, b.value * f, b.low * f, b.high * f, b.tau_s, b.longest_tau_s};
}

std::string b_text(const BDegH& b, BStyle style) {
  const auto n4 = [](double v) { return format_number(v); };
  switch (style) {
    case BStyle::Table2Text:
      if (b.resolved)
        return number_text(b.value, "%.3g") + " [" + number_text(b.low, "%.2g") + "," + number_text(b.high, "%.2g") +
               "]";
      return "< " + number_text(b.high, "%.3g") + " (tau<=" + number_text(b.longest_tau_s, "%.0f") + "s)";
    case BStyle::AllanLine: {
      char line[320];
      if (b.resolved)
        std::snprintf(line, sizeof line,
                      "B = %.4g deg/h (flat floor of the OADEV / 0.664, IEEE 952) at tau = %g s, 68.3 %% interval "
                      "[%.3g, %.3g]",
                      b.value, b.tau_s, b.low, b.high);
      else
        std::snprintf(line, sizeof line,
                      "B < %.3g deg/h (not resolved within tau <= %g s: the OADEV has no floor there, its minimum is "
                      "at tau = %g s; 68.3 %% bound)",
                      b.high, b.longest_tau_s, b.tau_s);
      return line;
    }
    case BStyle::Bound:
      return b.resolved ? n4(b.value) : "< " + number_text(b.high, "%.3g");
    case BStyle::BoundFourDigits:
      return b.resolved ? n4(b.value) : "< " + n4(b.high);
    case BStyle::BoundWithin:
      return b.resolved ? n4(b.value)
                        : "< " + n4(b.high) + " (not resolved within tau ≤ " + n4(b.longest_tau_s) + " s)";
    case BStyle::Interval:
      if (b.resolved) return number_text(b.low, "%.3g") + " – " + number_text(b.high, "%.3g");
      return "not resolved within tau ≤ " + number_text(b.longest_tau_s, "%.0f") + " s";
    case BStyle::IntervalBracketed:
      if (b.resolved) return "[" + n4(b.low) + ", " + n4(b.high) + "]";
      return "not resolved within tau ≤ " + n4(b.longest_tau_s) + " s";
  }
  return "";
}

std::string b_text(const allan::FloorReading& b) { return b_text(b_deg_h(b), BStyle::Table2Text); }

nlohmann::json stage_json(const RunScores& s, const StageScore& st) {
  const auto& a = st.analysis;
  nlohmann::json row{{"stage", st.stage},
                     {"label", st.label},
                     {"N_deg_h_rtHz", a.arw_rad_sqrt_s * kDphPerRadPerSec},
                     {"bandwidth_hz", st.bandwidth_hz},
                     {"correlation_time_s", st.correlation_time_s},
                     {"fit", fit_json(a)}};
  row.update(b_json(a.bias_instability));
  if (st.residual_drift_rad_s) row["residual_drift_deg_h"] = *st.residual_drift_rad_s * kDphPerRadPerSec;
  if (st.systematic_error_rad_s) row["systematic_error_deg_h"] = *st.systematic_error_rad_s * kDphPerRadPerSec;
  if (const auto it = s.against_floor.find(st.stage); it != s.against_floor.end()) {
    row["error_vs_floor"] = {{"max_ratio", it->second.max_ratio},
                             {"tau_of_max_s", it->second.tau_of_max_s},
                             {"within_1_5x", it->second.within}};
  }
  if (const auto* p = reference_row(s, st.stage))
    row["reference"] = {{"B_deg_h", p->b_deg_h}, {"N_deg_h_rtHz", p->n_deg_h_rthz}};
  return row;
}

nlohmann::json intrinsic_floor_json(const allan::Analysis& a) {
  nlohmann::json j{{"what", "Allan analysis of measured - true systematic rate: the gyro's own noise"},
                   {"N_deg_h_rtHz", a.arw_rad_sqrt_s * kDphPerRadPerSec}};
  j.update(b_json(a.bias_instability));
  return j;
}

nlohmann::json scores_json(const RunScores& s) {
  nlohmann::json j;
  auto& rows = j["table2"] = nlohmann::json::array();
  auto& curves = j["allan"] = nlohmann::json::object();
  if (s.reference) j["reference"] = {{"source", s.reference->source}};
  if (!s.reference_not_shown.empty()) j["reference_not_shown"] = s.reference_not_shown;
  for (const auto& st : s.stages) {
    rows.push_back(stage_json(s, st));
    curves[st.stage] = curve_json(st.analysis);
    if (st.error) curves[st.stage + "_minus_truth"] = curve_json(*st.error);
  }
  if (s.intrinsic) {
    j["intrinsic_floor"] = intrinsic_floor_json(*s.intrinsic);
    curves["intrinsic_floor"] = curve_json(*s.intrinsic);
  }
  for (const auto& b : s.baselines) {
    const auto& m = b.model;
    nlohmann::json c = nlohmann::json::array();
    for (double v : m.bias_rad_s) c.push_back(v * kDphPerRadPerSec);
    const std::string bins = b.stage == kPx4BaselineStage
                                 ? (m.fit.heating_only ? "the heating bins (PX4 practice)"
                                                       : "all bins (PX4 practice, but too few heating bins)")
                                 : "all bins, both directions";
    j["baselines"][b.stage] = {
        {"what", "third-order polynomial in T - T0 fitted on this record's " + bins + ", T clamped to their range"},
        {"coefficients_deg_h_per_c_pow_i", c},
        {"reference_temp_c", m.reference_temp_c},
        {"fit_range_c", {m.valid_min_c, m.valid_max_c}},
        {"heating_only", m.fit.heating_only},
        {"bin_s", m.fit.bin_s}};
  }
  j["units"] = {{"B", "deg/h"},
                {"N", "deg/h/sqrt(Hz)"},
                {"bandwidth", "Hz (one-sided equivalent noise bandwidth)"},
                {"residual_drift", "deg/h, rms of 60-s block means of output - true rate"},
                {"systematic_error", "deg/h, rms of 60-s block means of output - true rate - intrinsic noise"},
                {"allan", "deg/h"}};
  j["readings"] = {{"B",
                    "flat floor of the overlapping Allan deviation / 0.664 (IEEE 952 Annex C), at tau >= the "
                    "output's correlation time (1 / bandwidth); a value only where the deviation has a floor (a "
                    "minimum with rising or flat neighbours within the intervals), otherwise B_deg_h is null and "
                    "B_upper_deg_h bounds B within tau <= B_within_tau_s"},
                   {"N", "-1/2 slope line at tau = 1 s"}};
  return j;
}

std::string table2_text(const RunScores& s) {
  std::string out;
  // The reference's two columns only for a pipeline that has one; the systematic error only for a
  // record with its true systematic rate.
  const bool ref = s.reference.has_value();
  const bool syst = std::any_of(s.stages.begin(), s.stages.end(),
                                [](const StageScore& st) { return st.systematic_error_rad_s.has_value(); });
  out += "Table 2 (B in deg/h, N in deg/h/sqrt(Hz), noise bandwidth in Hz, residual drift" +
         std::string(syst ? " and systematic error" : "") +
         " in deg/h; B is a value [68% CI] only where the Allan deviation has a floor, otherwise a bound '< x' "
         "within the taus read)\n";
  const auto row_text = [&](const std::string& stage, const std::string& ref_b, const std::string& ref_n,
                            const std::string& b, const std::string& n, const std::string& bandwidth,
                            const std::string& drift, const std::string& systematic) {
    char line[256];
    std::snprintf(line, sizeof line, "%-18s", stage.c_str());
    out += line;
    if (ref) {
      std::snprintf(line, sizeof line, " %10s %10s ", ref_b.c_str(), ref_n.c_str());
      out += line;
    }
    std::snprintf(line, sizeof line, " %20s %12s %10s %14s", b.c_str(), n.c_str(), bandwidth.c_str(), drift.c_str());
    out += line;
    if (syst) {
      std::snprintf(line, sizeof line, " %12s", systematic.c_str());
      out += line;
    }
    out += "\n";
  };
  row_text("stage", "paper B", "paper N", "B", "N", "bandwidth", "resid. drift", "syst. error");
  const auto cell = [](std::optional<double> v, const char* fmt) {
    return v ? number_text(*v, fmt) : std::string("-");
  };
  const auto deg_h = [](std::optional<double> rad_s) {
    return rad_s ? std::optional<double>(*rad_s * kDphPerRadPerSec) : std::nullopt;
  };
  for (const auto& st : s.stages) {
    const auto* p = reference_row(s, st.stage);
    const auto& a = st.analysis;
    row_text(st.stage, p ? cell(p->b_deg_h, "%.4g") : "-", p ? cell(p->n_deg_h_rthz, "%.4g") : "-",
             b_text(a.bias_instability), cell(a.arw_rad_sqrt_s * kDphPerRadPerSec, "%.4g"),
             cell(st.bandwidth_hz, "%.3g"), cell(deg_h(st.residual_drift_rad_s), "%.3g"),
             cell(deg_h(st.systematic_error_rad_s), "%.3g"));
  }
  if (s.intrinsic) {
    const auto& a = *s.intrinsic;
    row_text("intrinsic floor", "-", "-", b_text(a.bias_instability), cell(a.arw_rad_sqrt_s * kDphPerRadPerSec, "%.4g"),
             "-", "-", "-");
  }
  if (ref) out += "paper: " + s.reference->source + "\n";
  if (!s.reference_not_shown.empty()) out += "paper columns not shown: " + s.reference_not_shown + "\n";
  return out;
}

}  // namespace driftlab::evaluation
