#include "tools/driftlab/noise_report.hpp"

#include "tools/driftlab/cli.hpp"

#include <cmath>
#include <cstdio>

namespace driftlab::cli {

std::string generic_unit(allan::Term term, const std::string& u) {
  switch (term) {
    case allan::Term::Q:
      return u + "*s";
    case allan::Term::N:
      return u + "*sqrt(s)";
    case allan::Term::B:
      return u;
    case allan::Term::K:
      return u + "/sqrt(s)";
    case allan::Term::R:
      return u + "/s";
  }
  return u;
}

std::pair<std::string, double> gmwm_unit(const allan::gmwm::Parameter& p, bool angular, const std::string& u) {
  const auto ieee = [](allan::Term t) {
    for (const auto& c : allan::kIeee952Units)
      if (c.term == t) return std::pair<std::string, double>(std::string(c.unit), c.factor);
    return std::pair<std::string, double>("", 1.0);
  };
  if (p.name == "T") return {"s", 1.0};
  if (p.name == "sigma") return angular ? ieee(allan::Term::B) : std::pair<std::string, double>(u, 1.0);
  const allan::Term t = p.name == "N"   ? allan::Term::N
                        : p.name == "Q" ? allan::Term::Q
                        : p.name == "K" ? allan::Term::K
                                        : allan::Term::R;
  return angular ? ieee(t) : std::pair<std::string, double>(generic_unit(t, u), 1.0);
}

nlohmann::json gmwm_json(const allan::gmwm::Fit& f, bool angular, const std::string& u) {
  nlohmann::json components = nlohmann::json::array();
  for (const auto& c : f.components) {
    nlohmann::json parameters = nlohmann::json::array();
    for (const auto& p : c.parameters) {
      const auto [unit, factor] = gmwm_unit(p, angular, u);
      nlohmann::json j{{"name", p.name}, {"unit", unit}, {"resolved", p.resolved}};
      if (p.resolved) {
        j["value"] = p.value * factor;
        j["interval"] = {p.low * factor, p.high * factor};
      } else {
        j["value"] = nullptr;
        j["upper"] = std::isfinite(p.high) ? nlohmann::json(p.high * factor) : nlohmann::json();
      }
      parameters.push_back(j);
    }
    components.push_back(
        {{"process", allan::gmwm::to_string(c.process)}, {"observable", c.observable}, {"parameters", parameters}});
  }
  std::vector<allan::gmwm::Process> model;
  for (const auto& c : f.components) model.push_back(c.process);
  return {{"model", allan::gmwm::to_string(model)},
          {"method", "GMWM (Guerrier et al. 2013) on the OADEV curve's variances; models/allan/gmwm.hpp"},
          {"intervals", f.intervals},
          {"confidence", 0.683},
          {"points", f.points},
          {"dof", f.dof},
          {"chi2_per_dof", f.reduced_chi2()},
          {"components", components}};
}

std::string gmwm_value_text(const allan::gmwm::Component& c, const allan::gmwm::Parameter& p, double factor) {
  char text[96];
  if (p.resolved)
    std::snprintf(text, sizeof text, "%.4g [%.3g, %.3g]", p.value * factor, p.low * factor, p.high * factor);
  else if (!c.observable && !std::isfinite(p.high))
    return "not determined";
  else
    std::snprintf(text, sizeof text, "< %.3g", p.high * factor);
  return text;
}

void print_gmwm(std::ostream& out, const allan::gmwm::Fit& fit, bool angular, const std::string& u,
                const std::string& indent) {
  std::vector<allan::gmwm::Process> model;
  for (const auto& c : fit.components) model.push_back(c.process);
  char head[256];
  std::snprintf(head, sizeof head,
                "GMWM %s (Guerrier et al. 2013; one-sigma intervals: %s; chi2/dof = %.3g, %zu points):",
                allan::gmwm::to_string(model).c_str(), fit.intervals.c_str(), fit.reduced_chi2(), fit.points);
  out << indent << head << "\n";
  for (const auto& c : fit.components)
    for (const auto& p : c.parameters) {
      const auto [unit, factor] = gmwm_unit(p, angular, u);
      const std::string value = gmwm_value_text(c, p, factor);
      out << indent << "  " << allan::gmwm::to_string(c.process) << " " << p.name;
      if (p.resolved)
        out << " = " << value << " " << unit << "\n";
      else if (!c.observable && !std::isfinite(p.high))
        out << " " << value << " (the component is below what the curve resolves)\n";
      else
        out << " " << value << " " << unit << "  (not resolved: "
            << (c.observable ? "its interval spans more than a factor e^0.5 either way"
                             : "below what the curve resolves; the bound is where it would show")
            << ")\n";
    }
  out.flush();
}

allan::gmwm::Fit fit_gmwm(std::span<const allan::Estimate> curve, double sample_rate_hz,
                          const std::vector<allan::gmwm::Process>& model, std::size_t samples, std::size_t replicates,
                          std::uint64_t seed, unsigned threads) {
  auto fit = allan::gmwm::fit(curve, sample_rate_hz, model);
  if (replicates > 0) fit = allan::gmwm::bootstrap(fit, static_cast<Eigen::Index>(samples), replicates, seed, threads);
  return fit;
}

void add_gmwm_bootstrap_option(CLI::App* command, std::size_t& replicates) {
  command
      ->add_option("--gmwm-bootstrap", replicates,
                   "replicates of the parametric bootstrap for the GMWM intervals (0: asymptotic intervals, "
                   "which are optimistic; otherwise at least 2)")
      ->check(whole_number(0, 10000))
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            return text == "1" ? "one replicate gives no interval: 0 (asymptotic intervals) or at least 2" : "";
          },
          "0 or 2..10000"))
      ->capture_default_str();
}

}  // namespace driftlab::cli
