// `driftlab decompose`: splits one channel into IMFs and a residue with a decomposition plugin
// (decomposition/emd by default) and writes
//   --out   CSV  t_s,imf1,...,imfK,residue  in the channel's input unit;
//   --json  summary: per IMF its sample entropy, mean frequency, energy share and group, plus the
//           decomposition's diagnostics (sifts per IMF, orthogonality index);
//   --plot  SVG, one panel per component.
// Per-IMF statistics:
//   sample entropy   SampEn(m, r) with r relative to the IMF's population standard deviation, as
//                    computed by classifier/sample_entropy (plugins/sample_entropy), which also
//                    assigns the group (noise / mixed / drift) by its rule; --classifier-set
//                    key=value sets its parameters (m, r, rule, thresholds).
//   mean frequency   zero-crossing rate: (number of sign changes) / (2 T), T = N / fs, in Hz.
//   energy share     sum_t c_k(t)^2 / sum over all components (IMFs and residue) of sum_t c(t)^2.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/output_set.hpp"
#include "framework/params_io.hpp"
#include "framework/units.hpp"
#include "tools/driftlab/cli.hpp"
#include "tools/driftlab/plot.hpp"

namespace driftlab::cli {
namespace {

struct DecomposeOptions {
  DataOptions data;
  std::string plugin = "decomposition/emd";
  std::vector<std::string> sets;
  std::vector<std::string> classifier_sets;
  std::string out;
  std::string json;
  std::string plot;
};

constexpr const char* kClassifier = "classifier/sample_entropy";

double mean_frequency_hz(const Eigen::VectorXd& c, double sample_rate_hz) {
  Eigen::Index crossings = 0;
  for (Eigen::Index i = 1; i < c.size(); ++i) crossings += (c[i] < 0.0) != (c[i - 1] < 0.0);
  return static_cast<double>(crossings) / 2.0 / (static_cast<double>(c.size()) / sample_rate_hz);
}

nlohmann::json entropy_json(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json("Inf");
}

Figure component_figure(const DecomposeOptions& o, const Eigen::VectorXd& t, const Eigen::VectorXd& x,
                        const Eigen::MatrixXd& imfs, const Eigen::VectorXd& residue, double scale,
                        const std::string& unit, const std::vector<std::string>& groups) {
  Figure figure;
  figure.panel_height = 150;
  figure.shared_x = true;
  auto add = [&](const std::string& title, const Eigen::VectorXd& y) {
    PlotPanel panel;
    panel.title = title;
    panel.x_label = "t (s)";
    panel.y_label = "signal (" + unit + ")";
    PlotSeries series;
    series.label = title;
    series.x.assign(t.data(), t.data() + t.size());
    series.y.resize(static_cast<std::size_t>(y.size()));
    for (Eigen::Index i = 0; i < y.size(); ++i) series.y[static_cast<std::size_t>(i)] = y[i] / scale;
    panel.series.push_back(std::move(series));
    figure.panels.push_back(std::move(panel));
  };
  add("signal (" + std::filesystem::path(o.data.path).filename().string() + ")", x);
  for (Eigen::Index k = 0; k < imfs.cols(); ++k)
    add("imf" + std::to_string(k + 1) + " (" + groups[static_cast<std::size_t>(k)] + ")", imfs.col(k));
  add("residue", residue);
  return figure;
}

void decompose_command(const DecomposeOptions& o, CommandEnv& env) {
  OutputSet outputs({o.data.path});
  outputs.plan(o.out, "--out");
  outputs.plan(o.json, "--json");
  outputs.plan(o.plot, "--plot");
  const Registry& registry = env.registry();
  if (registry.info(o.plugin).kind() != "decomposition")
    throw ConfigError({"", 0, "--plugin"}, "'" + o.plugin + "' is not a decomposition plugin");
  const ParamValues params = params_from_assignments(registry, o.plugin, o.sets);
  const ParamValues classifier_params = params_from_assignments(registry, kClassifier, o.classifier_sets);
  auto decomposer = registry.create_as<Decomposer>({o.plugin, params});
  auto classifier = registry.create_as<Classifier>({kClassifier, classifier_params});

  const auto record = load_evenly_sampled_record(o.data, {role::kRate}, "A decomposition");
  const std::string role = primary_role(o.data);
  const Eigen::VectorXd& x = record.channel(role).values;
  const double fs = record.sample_rate_hz();
  if (!(fs > 0.0)) throw DataError({o.data.path, 0, "t_s"}, "cannot derive a sample rate from the time column");

  RunContext ctx;
  ctx.threads = env.threads;
  ctx.time_s = record.time();
  ctx.progress = [&env](double f) { env.progress("decompose", 0.7 * f); };  // the classifier takes the rest
  env.progress("decompose", 0.0);
  const Decomposition d = decomposer->decompose(x, ctx);
  env.progress("decompose", 0.7);
  RunContext classify_ctx;
  classify_ctx.threads = env.threads;
  const Classification c = d.imfs.cols() > 0 ? classifier->classify(d.imfs, classify_ctx) : Classification{};
  env.progress("decompose", 1.0);

  const std::string unit = display_unit(record, role, o.data);
  const auto display = find_unit(unit);
  const double scale = display ? display->scale : 1.0;
  // IMFs are differences (zero-mean oscillations): a unit with an offset (K) converts them by its
  // scale only; the residue carries the absolute level, so imf1 + ... + residue is the signal.
  std::vector<CsvColumn> columns{CsvColumn::view("t_s", record.time(), "s")};
  for (Eigen::Index k = 0; k < d.imfs.cols(); ++k)
    columns.push_back(CsvColumn::view("imf" + std::to_string(k + 1), d.imfs.col(k), unit, false));
  columns.push_back(CsvColumn::view("residue", d.residue, unit));
  outputs.write_csv(o.out, columns);

  const double total_energy = d.imfs.colwise().squaredNorm().sum() + d.residue.squaredNorm();
  auto share = [&](double energy) { return total_energy > 0.0 ? energy / total_energy : 0.0; };
  std::vector<std::string> groups;
  nlohmann::json imfs = nlohmann::json::array();
  std::printf("%-6s %12s %16s %13s  %s\n", "imf", "SampEn", "mean freq (Hz)", "energy share", "group");
  for (Eigen::Index k = 0; k < d.imfs.cols(); ++k) {
    const auto i = static_cast<std::size_t>(k);
    const double entropy = c.scores[i];
    const double frequency = mean_frequency_hz(d.imfs.col(k), fs);
    const double energy_share = share(d.imfs.col(k).squaredNorm());
    groups.push_back(to_string(c.groups[i]));
    imfs.push_back({{"imf", k + 1},
                    {"sample_entropy", entropy_json(entropy)},
                    {"mean_frequency_hz", frequency},
                    {"energy_share", energy_share},
                    {"group", groups.back()},
                    {"reason", c.reasons[i]}});
    std::printf("imf%-3td %12s %16.6g %13.4g  %s\n", k + 1,
                std::isfinite(entropy) ? std::to_string(entropy).c_str() : "Inf", frequency, energy_share,
                groups.back().c_str());
  }
  const double residue_share = share(d.residue.squaredNorm());
  std::printf("%-6s %12s %16s %13.4g\n", "residue", "", "", residue_share);

  if (!o.json.empty()) {
    nlohmann::json summary;
    summary["plugin"] = o.plugin;
    summary["params"] = o.sets;
    summary["channel"] = role;
    summary["unit"] = unit;
    summary["samples"] = x.size();
    summary["sample_rate_hz"] = fs;
    summary["imf_count"] = d.imfs.cols();
    summary["decomposition"] = ctx.diagnostics;
    summary["imfs"] = imfs;
    summary["residue"] = {{"energy_share", residue_share}};
    summary["sample_entropy"] = {{"classifier", kClassifier},
                                 {"params", o.classifier_sets},
                                 {"r_relative_to", "population standard deviation of each IMF"},
                                 {"log", classify_ctx.diagnostics}};
    summary["mean_frequency_method"] = "zero crossings / (2 N / fs)";
    summary["energy_share_definition"] = "sum of squares of the component / sum over IMFs and residue";
    outputs.write(o.json, summary.dump(2) + "\n");
  }
  if (!o.plot.empty())
    outputs.write(o.plot, render_svg(component_figure(o, record.time(), x, d.imfs, d.residue, scale, unit, groups)));
  outputs.commit();
}

}  // namespace

void add_decompose_command(CLI::App& app, CommandEnv& env) {
  auto options = std::make_shared<DecomposeOptions>();
  auto* cmd = app.add_subcommand(
      "decompose", "split one channel into IMFs and a residue (EMD, EEMD, CEEMDAN) with per-IMF statistics");
  add_data_options(cmd, options->data, "column to decompose, role=column:unit (default rate_dps)");
  cmd->add_option("--plugin", options->plugin, "decomposition plugin")->capture_default_str();
  cmd->add_option("--set", options->sets, "decomposition parameter key=value (repeatable)");
  cmd->add_option("--classifier-set", options->classifier_sets,
                  "classifier/sample_entropy parameter key=value (repeatable): m, r, rule, ...");
  cmd->add_option("--out", options->out, "output CSV: t_s,imf1,...,imfK,residue in the input unit")->required();
  cmd->add_option("--json", options->json, "summary JSON: per IMF sample entropy, mean frequency, energy share, group");
  cmd->add_option("--plot", options->plot, "SVG plot, one panel per component");
  cmd->callback([options, &env] { decompose_command(*options, env); });
}

}  // namespace driftlab::cli
