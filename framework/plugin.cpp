#include "framework/plugin.hpp"

#include <limits>

#include "framework/error.hpp"

namespace driftlab {
namespace {

constexpr const char* kImfDecisionsKey = "imfs";  // a classifier step's diagnostics entry

const Signal& input(const SignalMap& inputs, const std::string& port) {
  auto it = inputs.find(port);
  if (it == inputs.end()) throw ConfigError({"", 0, port}, "required input is not connected");
  return it->second;
}

}  // namespace

const std::vector<std::string>& plugin_kinds() {
  static const std::vector<std::string> kinds{"decomposition", "classifier", "regressor",
                                              "optimizer",     "filter",     "effect"};
  return kinds;
}

const KindPorts& ports_of_kind(const std::string& kind) {
  static const std::map<std::string, KindPorts> ports{
      {"decomposition", {{{"signal", true, false, "signal to decompose"}}, {"imfs", "residue"}}},
      {"classifier",
       {{{"imfs", true, false, "IMFs to group"}, {"residue", false, false, "added to the drift group"}},
        {"noise", "mixed", "drift"}}},
      {"regressor",
       {{{"target", true, false, "signal to model"}, {"features", true, true, "explanatory signals"}},
        {"fitted", "residual"}}},
      {"filter", {{{"signal", true, false, "signal to filter"}}, {"signal"}}},
      {"optimizer", {{}, {}}},
      {"effect", {{}, {}}},
  };
  auto it = ports.find(kind);
  if (it == ports.end()) throw ConfigError({"", 0, kind}, "unknown plugin kind");
  return it->second;
}

Signal Signal::single(Eigen::VectorXd values, std::string label, std::string unit) {
  Signal s;
  s.columns = std::move(values);
  s.labels = {std::move(label)};
  s.unit = std::move(unit);
  return s;
}

std::string to_string(ImfGroup group) {
  switch (group) {
    case ImfGroup::Noise:
      return "noise";
    case ImfGroup::Mixed:
      return "mixed";
    case ImfGroup::Drift:
      return "drift";
  }
  return "?";
}

SignalMap Decomposer::run(const SignalMap& inputs, RunContext& ctx) {
  const auto& x = input(inputs, "signal");
  auto d = decompose(x.sum(), ctx);
  Signal imfs;
  imfs.columns = std::move(d.imfs);
  imfs.unit = x.unit;
  for (Eigen::Index k = 0; k < imfs.columns.cols(); ++k) imfs.labels.push_back("imf" + std::to_string(k + 1));
  ctx.diagnostics["imf_count"] = imfs.columns.cols();
  return {{"imfs", std::move(imfs)}, {"residue", Signal::single(std::move(d.residue), "residue", x.unit)}};
}

nlohmann::json imf_decisions_json(const std::vector<ImfDecision>& decisions) {
  nlohmann::json log = nlohmann::json::array();
  for (const auto& d : decisions)
    log.push_back({{"imf", d.imf}, {"group", to_string(d.group)}, {"score", d.score}, {"reason", d.reason}});
  return log;
}

std::vector<ImfDecision> imf_decisions(const nlohmann::json& diagnostics) {
  std::vector<ImfDecision> decisions;
  if (!diagnostics.is_object() || !diagnostics.contains(kImfDecisionsKey)) return decisions;
  for (const auto& e : diagnostics.at(kImfDecisionsKey)) {
    ImfDecision d;
    d.imf = e.at("imf").get<std::size_t>();
    const auto group = e.at("group").get<std::string>();
    for (const auto g : kImfGroups)
      if (to_string(g) == group) d.group = g;
    // A score written to a file and read back: infinity is stored as null.
    d.score = e.at("score").is_number() ? e.at("score").get<double>() : std::numeric_limits<double>::infinity();
    d.reason = e.at("reason").get<std::string>();
    decisions.push_back(std::move(d));
  }
  return decisions;
}

SignalMap Classifier::run(const SignalMap& inputs, RunContext& ctx) {
  const auto& imfs = input(inputs, "imfs");
  const auto c = classify(imfs.columns, ctx);
  const Eigen::Index n = imfs.columns.rows();
  Eigen::VectorXd noise = Eigen::VectorXd::Zero(n), mixed = noise, drift = noise;
  std::vector<ImfDecision> decisions;
  for (std::size_t k = 0; k < c.groups.size(); ++k) {
    const auto col = imfs.columns.col(static_cast<Eigen::Index>(k));
    (c.groups[k] == ImfGroup::Noise ? noise : c.groups[k] == ImfGroup::Mixed ? mixed : drift) += col;
    decisions.push_back(
        {k + 1, c.groups[k], k < c.scores.size() ? c.scores[k] : 0.0, k < c.reasons.size() ? c.reasons[k] : ""});
  }
  ctx.diagnostics[kImfDecisionsKey] = imf_decisions_json(decisions);
  if (auto it = inputs.find("residue"); it != inputs.end()) drift += it->second.sum();
  return {{"noise", Signal::single(std::move(noise), "noise", imfs.unit)},
          {"mixed", Signal::single(std::move(mixed), "mixed", imfs.unit)},
          {"drift", Signal::single(std::move(drift), "drift", imfs.unit)}};
}

SignalMap Regressor::run(const SignalMap& inputs, RunContext& ctx) {
  const auto& target = input(inputs, "target");
  const Eigen::VectorXd y = target.sum();
  const auto& X = input(inputs, "features").columns;
  fit(X, y, ctx);
  Eigen::VectorXd fitted = predict(X);
  Eigen::VectorXd residual = y - fitted;
  ctx.diagnostics["rms_residual"] =
      std::sqrt(residual.squaredNorm() / static_cast<double>(std::max<Eigen::Index>(1, y.size())));
  return {{"fitted", Signal::single(std::move(fitted), "fitted", target.unit)},
          {"residual", Signal::single(std::move(residual), "residual", target.unit)}};
}

OptimizationResult Optimizer::minimize_objectives(const VectorObjective& f, std::size_t objectives,
                                                  const std::vector<Bound>& bounds, RunContext& ctx) {
  if (objectives != 1) {
    throw ConfigError({"", 0, "optimizer"},
                      "this optimizer minimizes one objective; " + std::to_string(objectives) +
                          " were asked for (use a multi-objective optimizer, e.g. optimizer/pagmo with "
                          "algorithm nsga2)");
  }
  OptimizationResult r = minimize([&](const Eigen::VectorXd& x) { return f(x)[0]; }, bounds, ctx);
  r.best_values = Eigen::VectorXd::Constant(1, r.best_value);
  return r;
}

SignalMap Optimizer::run(const SignalMap&, RunContext&) {
  throw ConfigError({"", 0, "plugin"}, "optimizer plugins run nested inside another plugin, not as steps");
}

SignalMap Effect::run(const SignalMap&, RunContext&) {
  throw ConfigError({"", 0, "plugin"}, "effect plugins run inside `driftlab discrepancy`, not as pipeline steps");
}

SignalMap Filter::run(const SignalMap& inputs, RunContext& ctx) {
  const auto& x = input(inputs, "signal");
  return {{"signal", Signal::single(filter(x.sum(), ctx), "signal", output_unit(x.unit))}};
}

}  // namespace driftlab
