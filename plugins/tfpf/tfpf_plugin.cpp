// filter/tfpf: adapter around plugins/tfpf/tfpf.hpp (FM encoding, the PWVD peak and the window
// rule are documented there).
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <variant>

#include "framework/error.hpp"
#include "framework/registry.hpp"
#include "plugins/tfpf/tfpf.hpp"

namespace driftlab {
namespace {

std::string odd_problem(const ParamValue& value) {
  const auto* v = std::get_if<std::int64_t>(&value);
  return v && *v % 2 == 1 ? "" : "must be odd";
}

ParamSpec odd_window(std::string key, std::int64_t def, std::string doc) {
  return param::integer(std::move(key), def, "samples", std::move(doc))
      .at_least(3)
      .at_most(100001)
      .must("odd", odd_problem, std::int64_t{4});
}

class TfpfFilter final : public Filter {
 public:
  explicit TfpfFilter(const ParamValues& p) {
    config_ = {.rule = p.text("window_rule") == "fixed" ? tfpf::WindowRule::Fixed : tfpf::WindowRule::NoiseLevel,
               .window = static_cast<int>(p.integer("window")),
               .short_window = static_cast<int>(p.integer("short_window")),
               .long_window = static_cast<int>(p.integer("long_window")),
               .lag_window = p.text("lag_window") == "hann" ? tfpf::LagWindow::Hann : tfpf::LagWindow::Rectangular};
  }

  Eigen::VectorXd filter(const Eigen::VectorXd& z, RunContext& ctx) override {
    tfpf::Result r;
    try {
      tfpf::Config config = config_;
      config.progress = ctx.progress;
      r = tfpf::filter(z, config);
    } catch (const std::domain_error& e) {
      throw DataError({"", 0, "signal"}, std::string("filter/tfpf: ") + e.what());
    } catch (const std::invalid_argument& e) {
      throw ConfigError({"", 0, ""}, std::string("filter/tfpf: ") + e.what());
    }
    ctx.diagnostics["window_samples"] = r.window;
    ctx.diagnostics["noise_sigma"] = r.noise_sigma;
    ctx.diagnostics["noise_share"] = r.noise_share;
    if (const double fs = ctx.rate_hz(); fs > 0.0) ctx.diagnostics["window_s"] = r.window / fs;
    return std::move(r.filtered);
  }

 private:
  tfpf::Config config_;
};

}  // namespace

void register_tfpf_plugins(Registry& registry) {
  registry.add(
      {.name = "filter/tfpf",
       .summary = "time-frequency peak filtering: PWVD peak of the FM-encoded signal, window chosen by noise level",
       .reference = "Boashash & Mesbah 2004 (TFPF); window rule after the SEEMD-TFPF / ICEEMDAN-TFPF gyro papers "
                    "(short window for signal-dominated, long for noise-dominated components)",
       .params =
           ParamTable{{
                          param::choice("window_rule", "noise_level", {"noise_level", "fixed"},
                                        "noise_level: short_window when the estimated noise share sigma^2/var <= 0.1, "
                                        "long_window when >= 0.9, geometric in between (sigma from the MAD of first "
                                        "differences); fixed: window"),
                          odd_window("window", 31, "PWVD lag-window length for window_rule fixed"),
                          odd_window("short_window", 9, "window for signal-dominated input (window_rule noise_level)"),
                          odd_window("long_window", 65, "window for noise-dominated input (window_rule noise_level)"),
                          param::choice("lag_window", "rectangular", {"rectangular", "hann"},
                                        "lag weighting of the pseudo Wigner-Ville distribution"),
                      },
                      {
                          {"short_window <= long_window",
                           {"short_window", "long_window"},
                           [](const ParamValues& v) { return v.integer("short_window") <= v.integer("long_window"); }},
                      }},
       .make = [](const ParamValues& p, const Registry&) { return std::make_unique<TfpfFilter>(p); }});
}

}  // namespace driftlab
