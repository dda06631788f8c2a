// `driftlab allan`: Allan-family deviation of one channel on a tau grid, with the identified noise
// type, 68.3 % chi-square intervals and the number of terms per tau (allan.csv), the IEEE 952
// noise terms fitted to the OADEV curve (summary.json) and a log-log plot (allan.svg); with --gmwm
// a composite model fitted to the same curve by GMWM (models/allan/gmwm.hpp) beside them.
//
// --input angle: the column holds the integrated angle. Angles have no unit of their own in the
// CSV reader, so the column is mapped with the matching rate unit (deg/s for an angle in deg,
// rad/s for rad); the deviations then come out in that rate unit.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <nlohmann/json.hpp>

#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/output_set.hpp"
#include "framework/sampling.hpp"
#include "framework/units.hpp"
#include "models/allan/confidence.hpp"
#include "models/allan/deviation.hpp"
#include "models/allan/gmwm.hpp"
#include "models/allan/analysis.hpp"
#include "models/allan/noise_fit.hpp"
#include "models/allan/tau_grid.hpp"
#include "models/evaluation/run_scores.hpp"
#include "tools/driftlab/cli.hpp"
#include "tools/driftlab/noise_report.hpp"
#include "tools/driftlab/plot.hpp"

namespace driftlab::cli {
namespace {

struct AllanOptions {
  DataOptions data;
  std::string input = "rate";
  std::string kind = "oadev";
  std::string taus = "octave";
  double confidence = allan::kDefaultConfidence;
  std::string out;
  std::string json;
  std::string plot;
  std::string gmwm;                 // composite model, e.g. "wn+rw+gm"; empty: none
  std::size_t gmwm_bootstrap = 50;  // replicates of the parametric bootstrap; 0: asymptotic intervals
  std::uint64_t seed = 1;           // of the bootstrap's simulations
  unsigned threads = 1;
};

// A fitted term with its resolution (models/allan/noise_fit.hpp): an unresolved term has no value,
// only its bound `upper`.
nlohmann::json term_json(const allan::TermEstimate& t, double factor, std::string_view unit) {
  nlohmann::json j{{"resolved", t.resolved}, {"fitted", t.fitted}, {"unit", std::string(unit)}};
  if (t.resolved) {
    j["value"] = t.value * factor;
    j["sigma"] = t.sigma * factor;
    j["interval"] = {t.low * factor, t.high * factor};
  } else {
    j["value"] = nullptr;
    j["upper"] = t.high * factor;
  }
  return j;
}

nlohmann::json summary_json(const AllanOptions& o, const allan::NoiseFit& fit, bool angular,
                            const std::string& channel_unit, std::size_t samples, double tau0,
                            const nlohmann::json& sampling) {
  nlohmann::json j;
  if (angular) {
    for (const auto& c : allan::kIeee952Units) j[std::string(c.key)] = term_json(fit[c.term], c.factor, c.unit);
    const auto& d = allan::kNoiseDensityDegPerHour;
    j[std::string(d.key)] = term_json(fit[d.term], d.factor, d.unit);
    for (const auto& c : allan::kKalibrUnits)
      j["kalibr"][std::string(c.key)] = term_json(fit[c.term], c.factor, c.unit);
    for (const auto& c : allan::kIeee952Units) {
      j["si"][std::string(c.key)] = term_json(fit[c.term], 1.0, generic_unit(c.term, "rad/s"));
    }
  } else {
    for (const auto& c : allan::kIeee952Units) {
      j[std::string(c.key)] = term_json(fit[c.term], 1.0, generic_unit(c.term, channel_unit));
    }
  }
  j["record_length_s"] = static_cast<double>(samples) * tau0;  // sampled time (bursts: their sum)
  j["samples"] = samples;
  j["sample_rate_hz"] = 1.0 / tau0;
  j["sampling"] = sampling;
  j["input"] = o.input;
  j["kind"] = o.kind;
  j["confidence"] = o.confidence;
  j["fit"] = {
      {"curve", "oadev"},
      {"points", fit.points},
      {"dof", fit.dof},
      {"chi2", fit.chi2},
      {"chi2_per_dof", fit.reduced_chi2()},
      {"covariance_scale", fit.scale},
      {"resolved", "kept by the fit and c = term^2 more than one sigma above 0; otherwise only the bound 'upper'"},
      {"model", "sigma^2 = 3Q^2/tau^2 + N^2/tau + (2 ln2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2"}};
  return j;
}

// The paper's and data sheets' readings (models/allan/analysis.hpp), in deg/h for a rate channel.
nlohmann::json readings_json(const allan::Analysis& a, bool angular, const std::string& channel_unit) {
  const double f = angular ? kDphPerRadPerSec : 1.0;
  const std::string unit = angular ? "deg/h" : channel_unit;
  const auto& b = a.bias_instability;
  nlohmann::json floor{{"resolved", b.resolved},
                       {"tau_s", b.tau_s},
                       {"longest_tau_s", b.longest_tau_s},
                       {"unit", unit},
                       {"how",
                        "min OADEV / 0.664 (IEEE 952 Annex C), a value only where the curve has a floor "
                        "(models/allan/analysis.hpp); otherwise the bound 'upper'"}};
  if (b.resolved) {
    floor["value"] = b.value * f;
    floor["interval"] = {b.low * f, b.high * f};
  } else {
    floor["value"] = nullptr;
    floor["upper"] = b.high * f;
  }
  return {{"B_flat_floor", floor},
          {"N_at_1s",
           {{"value", a.arw_rad_sqrt_s * f},
            {"unit", angular ? "deg/h/sqrt(Hz)" : channel_unit + "*sqrt(s)"},
            {"how", "-1/2 slope line at tau = 1 s"}}}};
}

// The plot in the printed text's unit: deg/h for a rate in rad/s (`factor` from SI), else the
// channel's display unit (factor 1 / scale). The readings' guides (allan_guides) and the fitted
// models are guides: the axes follow the measured curve.
Figure allan_figure(const AllanOptions& o, const std::vector<allan::Estimate>& curve, const allan::Analysis* analysis,
                    const allan::gmwm::Fit* gmwm, double factor, const std::string& unit) {
  PlotPanel panel;
  panel.title = o.kind + " of " + std::filesystem::path(o.data.path).filename().string();
  panel.x_label = "tau (s)";
  panel.y_label = o.kind + " (" + unit + ")";
  panel.log_x = panel.log_y = true;
  panel.series.push_back(
      allan_series(o.kind + " with " + std::to_string(o.confidence * 100.0).substr(0, 4) + " % interval", curve, factor,
                   PlotSeries::Style::Markers, PlotSeries::Interval::Bars));
  const allan::NoiseFit* fit = analysis && analysis->fit ? &*analysis->fit : nullptr;
  if ((fit != nullptr || gmwm != nullptr) && !curve.empty()) {
    const double first = curve.front().tau;
    const double last = curve.back().tau;
    std::vector<double> taus;
    for (double t = first; t <= last * 1.0001; t *= std::pow(10.0, 0.05)) taus.push_back(t);
    const auto add_line = [&](const std::string& label, PlotSeries::Style style, auto dev) {
      PlotSeries line;
      line.label = label;
      line.style = style;
      line.guide = true;
      for (const double t : taus) {
        line.x.push_back(t);
        line.y.push_back(dev(t) * factor);
      }
      panel.series.push_back(line);
    };
    if (fit)
      add_line("fitted model (IEEE 952 terms)", PlotSeries::Style::Line,
               [&](double t) { return fit->model_deviation(t); });
    if (gmwm) {
      std::vector<allan::gmwm::Process> model;
      for (const auto& c : gmwm->components) model.push_back(c.process);
      add_line("GMWM " + allan::gmwm::to_string(model), PlotSeries::Style::Line,
               [&](double t) { return std::sqrt(gmwm->model_variance(t)); });
    }
  }
  if (analysis)
    for (auto& g : allan_guides(*analysis, factor, unit)) panel.series.push_back(std::move(g));
  Figure figure;
  figure.panels.push_back(panel);
  figure.width = 1000;
  figure.panel_height = 480;
  return figure;
}

// One angle series per burst (one for an evenly sampled record); no difference spans a gap.
struct BurstAngles {
  std::vector<Eigen::VectorXd> angles;
  std::size_t samples = 0;        // rate samples of every burst
  std::size_t median_length = 0;  // angle samples of the median burst (of the record when even)
};

BurstAngles burst_angles(const Channel& channel, const sampling::Facts& facts, allan::InputType input, double tau0) {
  BurstAngles b;
  for (const auto& segment : facts.segments) {
    const auto values = channel.values.segment(segment.first, segment.samples);
    b.angles.push_back(input == allan::InputType::Rate
                           ? allan::angle_from_rate(Eigen::Ref<const Eigen::VectorXd>(values), tau0)
                           : Eigen::VectorXd(values));
    b.samples += static_cast<std::size_t>(segment.samples);
  }
  std::vector<std::size_t> lengths;
  for (const auto& a : b.angles) lengths.push_back(static_cast<std::size_t>(a.size()));
  std::nth_element(lengths.begin(), lengths.begin() + static_cast<std::ptrdiff_t>(lengths.size() / 2), lengths.end());
  b.median_length = lengths[lengths.size() / 2];
  return b;
}

// allan.csv: tau, the deviation and its interval (display unit), the number of terms.
void write_curve_csv(OutputSet& outputs, const std::string& path, const std::vector<allan::Estimate>& curve,
                     const std::string& unit) {
  // Deviations are differences: a unit with an offset (K) converts them by its scale only.
  std::vector<CsvColumn> columns{{"tau_s", {}, "s"},
                                 {"dev", {}, unit, false},
                                 {"dev_lo", {}, unit, false},
                                 {"dev_hi", {}, unit, false},
                                 {"n", {}, "1"}};
  for (auto& c : columns) c.values.resize(static_cast<Eigen::Index>(curve.size()));
  for (std::size_t i = 0; i < curve.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    columns[0].values(k) = curve[i].tau;
    columns[1].values(k) = curve[i].dev;
    columns[2].values(k) = curve[i].dev_lo;
    columns[3].values(k) = curve[i].dev_hi;
    columns[4].values(k) = static_cast<double>(curve[i].terms);
  }
  outputs.write_csv(path, columns);
}

// The OADEV readings (B, N) and the noise-term fit of the channel; none (a note on stderr) when the
// record is too short for them, unless --json asks for them (then DataError).
std::optional<allan::Analysis> channel_analysis(const AllanOptions& o, const Channel& channel,
                                                const sampling::Facts& facts, const BurstAngles& b, bool bursts,
                                                allan::InputType input, double fs, const std::string& why) {
  const double tau0 = 1.0 / fs;
  std::optional<allan::Analysis> analysis;
  try {
    if (bursts && input == allan::InputType::Rate) {
      analysis = allan::analyze_segments(channel.values, facts.segments, fs, {.confidence = o.confidence});
    } else if (bursts) {  // an angle record: each burst's rate is its angle's differences / tau0
      Eigen::VectorXd rate(static_cast<Eigen::Index>(b.samples - b.angles.size()));
      std::vector<sampling::Segment> rate_segments;
      Eigen::Index at = 0;
      for (const auto& a : b.angles) {
        const Eigen::Index k = a.size() - 1;
        rate.segment(at, k) = (a.tail(k) - a.head(k)) / tau0;
        rate_segments.push_back({at, k});
        at += k;
      }
      analysis = allan::analyze_segments(rate, rate_segments, fs, {.confidence = o.confidence});
    } else {
      analysis = allan::analyze_angle(b.angles.front(), tau0, {.confidence = o.confidence});
    }
  } catch (const DataError& e) {
    if (!o.json.empty()) throw DataError({o.data.path, 0, channel.source}, std::string(e.what()) + why);
    std::cerr << "note: no Allan readings: " << e.what() << why << "\n";
  }
  return analysis;
}

// The --gmwm composite model fitted to the curve (with the bootstrap's intervals unless
// --gmwm-bootstrap 0); none without --gmwm.
std::optional<allan::gmwm::Fit> gmwm_fit(const AllanOptions& o, const std::optional<allan::Analysis>& analysis,
                                         const std::string& role, const sampling::Facts& facts, bool bursts,
                                         std::size_t samples, double fs, const std::string& why) {
  if (o.gmwm.empty()) return std::nullopt;
  const auto model = allan::gmwm::parse_model(o.gmwm, "--gmwm");
  if (!analysis) throw DataError({o.data.path, 0, role}, "no Allan curve for the GMWM fit" + why);
  if (bursts && o.gmwm_bootstrap > 0)
    throw ConfigError({"", 0, "--gmwm-bootstrap"}, "the bootstrap simulates a contiguous record and this one is " +
                                                       std::to_string(facts.segments.size()) +
                                                       " bursts; give --gmwm-bootstrap 0 for the asymptotic intervals");
  return fit_gmwm(analysis->curve, fs, model, samples, o.gmwm_bootstrap, o.seed, o.threads);
}

// ---- the console summary ----

void print_readings(const allan::Analysis& analysis) {
  std::printf(
      "%s\n",
      evaluation::b_text(evaluation::b_deg_h(analysis.bias_instability), evaluation::BStyle::AllanLine).c_str());
  std::printf("N = %.4g deg/h/sqrt(Hz) (-1/2 slope line at tau = 1 s)\n", analysis.arw_rad_sqrt_s * kDphPerRadPerSec);
  std::fflush(stdout);
}

void print_fit(const allan::NoiseFit& fit) {
  char head[160];
  std::snprintf(head, sizeof head,
                "least-squares fit of the five IEEE 952 terms (chi2/dof = %.3g, %zu points, %zu dof; "
                "one-sigma intervals):\n",
                fit.reduced_chi2(), fit.points, fit.dof);
  std::cout << head;
  for (const auto& c : allan::kIeee952Units) {
    const auto& t = fit[c.term];
    const std::string key(c.key), term_unit(c.unit);
    char line[200];
    if (t.resolved) {
      std::snprintf(line, sizeof line, "%s = %.4g +- %.2g %s [%.3g, %.3g]\n", key.c_str(), t.value * c.factor,
                    t.sigma * c.factor, term_unit.c_str(), t.low * c.factor, t.high * c.factor);
    } else {
      std::snprintf(line, sizeof line, "%s < %.3g %s  (not resolved%s)\n", key.c_str(), t.high * c.factor,
                    term_unit.c_str(),
                    t.fitted ? ": kept by the fit, but within one sigma of 0" : ": set to 0 by the fit");
    }
    std::cout << line;
  }
}

void allan_command(const AllanOptions& o) {
  OutputSet outputs({o.data.path});
  outputs.plan(o.out, "--out");
  outputs.plan(o.json, "--json");
  outputs.plan(o.plot, "--plot");
  const auto kind = allan::parse_kind(o.kind);
  if (!kind) throw ConfigError({"", 0, "--kind"}, "unknown kind '" + o.kind + "'");
  const auto input = o.input == "angle" ? allan::InputType::Angle : allan::InputType::Rate;
  const allan::TauGrid grid = allan::parse_tau_grid(o.taus);

  const TimeSeries record = load_record_with_gaps(o.data);
  const auto& facts = record.sampling_facts();
  const bool bursts = facts.layout() == sampling::Layout::RegularBursts;
  if (facts.layout() == sampling::Layout::Irregular)
    throw sampling::uneven_sampling_error(facts, record.time(), o.data.path, "an Allan analysis",
                                          "driftlab allan analyses a record of regular bursts per burst");
  const std::string role = primary_role(o.data);
  const auto& channel = record.channel(role);
  const bool constant_record = (channel.values.array() == channel.values[0]).all();
  const std::string why =
      constant_record ? " (the record is constant: every deviation is 0, there is no noise to fit)" : "";
  const double fs = sampling::rate_within_segments_hz(record.time(), facts);
  if (!(fs > 0.0)) throw DataError({o.data.path, 0, "t_s"}, "cannot derive a sample interval");
  const double tau0 = 1.0 / fs;
  const auto b = burst_angles(channel, facts, input, tau0);
  const auto factors = allan::averaging_factors(grid, *kind, b.median_length, tau0);
  const auto curve = bursts ? allan::estimate_bursts(*kind, b.angles, tau0, input, factors, o.confidence)
                            : allan::estimate(*kind, b.angles.front(), tau0, input, factors, o.confidence);

  const std::string unit = display_unit(record, role, o.data);
  const auto display = find_unit(unit);
  const double scale = display ? display->scale : 1.0;
  write_curve_csv(outputs, o.out, curve, unit);

  const auto analysis = channel_analysis(o, channel, facts, b, bursts, input, fs, why);
  const allan::NoiseFit* fit = analysis && analysis->fit ? &*analysis->fit : nullptr;
  if (analysis && !fit) {
    if (!o.json.empty()) throw DataError({o.data.path, 0, role}, "too few Allan points for the noise-term fit" + why);
    std::cerr << "note: no noise-term fit: too few Allan points" << why << "\n";
  }
  const bool angular = channel.unit == "rad/s";
  const auto gmwm = gmwm_fit(o, analysis, role, facts, bursts, b.samples, fs, why);
  const std::string sampled = sampling::describe(facts, record.time());
  const nlohmann::json sampling_json{
      {"layout", bursts ? "regular_bursts" : "even"},
      {"bursts", bursts ? facts.segments.size() : 1},
      {"description", sampled},
      {"how", bursts ? "overlapping Allan variance of every burst pooled (no difference spans a gap), edf of all "
                       "bursts summed, tau up to the grid of the median burst"
                     : "one contiguous record"}};
  if (!o.json.empty()) {
    auto summary = summary_json(o, *fit, angular, channel.unit, b.samples, tau0, sampling_json);
    summary["readings"] = readings_json(*analysis, angular, channel.unit);
    if (gmwm) summary["gmwm"] = gmwm_json(*gmwm, angular, channel.unit);
    outputs.write(o.json, summary.dump(2) + "\n");
  }
  if (!o.plot.empty())
    outputs.write(o.plot, render_svg(allan_figure(o, curve, analysis ? &*analysis : nullptr, gmwm ? &*gmwm : nullptr,
                                                  angular ? kDphPerRadPerSec : 1.0 / scale, angular ? "°/h" : unit)));
  outputs.commit();

  std::cout << o.kind << " of " << role << ": " << curve.size() << " taus from " << curve.front().tau << " s to "
            << curve.back().tau << " s, " << b.samples << " samples, " << sampled << "\n";
  if (bursts)
    std::cout << "per burst: the " << o.kind << " of every burst pooled (no difference spans a gap), the edf of all "
              << facts.segments.size() << " bursts summed; tau only up to " << curve.back().tau << " s\n";
  if (analysis && angular) print_readings(*analysis);
  if (fit && angular) print_fit(*fit);
  if (gmwm) print_gmwm(std::cout, *gmwm, angular, channel.unit);
}

}  // namespace

void add_allan_command(CLI::App& app, CommandEnv& env) {
  auto options = std::make_shared<AllanOptions>();
  auto* cmd = app.add_subcommand(
      "allan", "Allan-family deviation with confidence intervals and IEEE 952 noise terms (NIST SP 1065)");
  add_data_options(cmd, options->data, "column to analyse, role=column:unit (default rate_dps)");
  cmd->add_option("--input", options->input, "the column holds a rate or its integrated angle")
      ->check(CLI::IsMember({"rate", "angle"}))
      ->capture_default_str();
  cmd->add_option("--kind", options->kind, "deviation")
      ->check(CLI::IsMember({"oadev", "adev", "mdev", "hdev", "ohdev", "totdev"}))
      ->capture_default_str();
  cmd->add_option("--taus", options->taus, "tau grid: octave, decade, dense, dense:P or a list of taus in s")
      ->capture_default_str();
  cmd->add_option("--confidence", options->confidence, "confidence level of the intervals")
      ->check(finite_number(0.01, 0.999))
      ->capture_default_str();
  cmd->add_option("--out", options->out, "output CSV: tau_s,dev,dev_lo,dev_hi,n")->required();
  cmd->add_option("--json", options->json, "summary JSON with the fitted noise terms");
  cmd->add_option(
      "--plot", options->plot,
      "log-log SVG plot (deg/h for a rate) with intervals, the slopes N, B and K are read from and the fitted model");
  cmd->add_option("--gmwm", options->gmwm,
                  "also fit a composite noise model by GMWM, processes joined by '+': wn (white), qn (quantization), "
                  "rw (rate random walk), dr (rate ramp), gm (Gauss-Markov, may repeat); e.g. wn+rw+gm");
  add_gmwm_bootstrap_option(cmd, options->gmwm_bootstrap);
  cmd->add_option("--seed", options->seed, "seed of the bootstrap's simulated records; same seed, same intervals")
      ->check(whole_number(0, kMaxSeed))
      ->capture_default_str();
  cmd->callback([options, &env] {
    options->threads = env.threads;
    allan_command(*options);
  });
}

}  // namespace driftlab::cli
