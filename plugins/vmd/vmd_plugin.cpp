// decomposition/vmd: adapter around plugins/vmd/vmd.hpp (the algorithm, its conventions and the
// stopping rule are documented there). Modes are the IMF columns (highest centre frequency first);
// the residue is the signal minus the modes.
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "framework/error.hpp"
#include "framework/registry.hpp"
#include "plugins/vmd/vmd.hpp"

namespace driftlab {
namespace {

class VmdDecomposer final : public Decomposer {
 public:
  explicit VmdDecomposer(const ParamValues& p) {
    const std::string& init = p.text("init");
    config_ = {.modes = static_cast<int>(p.integer("modes")),
               .alpha = p.real("alpha"),
               .tau = p.real("tau"),
               .dc = p.boolean("dc"),
               .init = init == "uniform" ? vmd::Init::Uniform
                       : init == "zero"  ? vmd::Init::Zero
                                         : vmd::Init::Random,
               .tolerance = p.real("tolerance"),
               .max_iterations = static_cast<int>(p.integer("max_iterations")),
               .seed = static_cast<std::uint64_t>(p.integer("seed"))};
  }

  Decomposition decompose(const Eigen::VectorXd& x, RunContext& ctx) override {
    vmd::Result result;
    try {
      vmd::Config config = config_;
      config.progress = ctx.progress;
      result = vmd::decompose(x, config);
    } catch (const std::domain_error& e) {
      throw DataError({"", 0, "signal"}, std::string("decomposition/vmd: ") + e.what());
    } catch (const std::invalid_argument& e) {
      throw ConfigError({"", 0, ""}, std::string("decomposition/vmd: ") + e.what());
    }
    ctx.diagnostics["iterations"] = result.iterations;
    ctx.diagnostics["converged"] = result.converged;
    ctx.diagnostics["final_change"] = result.final_change;
    const std::vector<double> cycles(result.centre_frequencies.data(),
                                     result.centre_frequencies.data() + result.centre_frequencies.size());
    ctx.diagnostics["centre_frequencies_cycles_per_sample"] = cycles;
    if (const double fs = ctx.rate_hz(); fs > 0.0) {
      std::vector<double> hz = cycles;
      for (double& f : hz) f *= fs;
      ctx.diagnostics["centre_frequencies_hz"] = hz;
    }
    return {std::move(result.modes), std::move(result.residue)};
  }

 private:
  vmd::Config config_;
};

}  // namespace

void register_vmd_plugins(Registry& registry) {
  registry.add({.name = "decomposition/vmd",
                .summary = "variational mode decomposition: K band-limited modes by ADMM in the Fourier domain",
                .reference = "Dragomiretskiy & Zosso 2014 Algorithm 2 (conventions of the authors' VMD.m: mirror "
                             "extension, alpha without the factor 2)",
                .params = ParamTable{{
                    param::integer("modes", 5, "1", "number of modes K").at_least(1).at_most(64),
                    param::real("alpha", 2000.0, "1",
                                "bandwidth penalty; mode filters are 1 / (1 + alpha (f - f_k)^2) with f in cycles per "
                                "sample (half width 1/sqrt(alpha) cycles per sample)")
                        .greater_than(0),
                    param::real("tau", 0.0, "1",
                                "dual-ascent step; 0 = no exact-reconstruction constraint (paper's choice for noisy "
                                "signals), > 0 enforces sum of modes = signal")
                        .at_least(0),
                    param::boolean("dc", false, "hold the first centre frequency at 0 (a trend mode)"),
                    param::choice("init", "uniform", {"uniform", "zero", "random"},
                                  "initial centre frequencies: uniform 0.5 (k-1)/K, all zero, or random log-uniform in "
                                  "[1/N, 0.5] (seeded)"),
                    param::real("tolerance", 1e-7, "1",
                                "stop when sum_k ||u_k^(n+1) - u_k^n||^2 / ||f||^2 (spectra) falls below this")
                        .greater_than(0),
                    param::integer("max_iterations", 500, "1", "cap on ADMM iterations").at_least(1),
                    param::seed(),
                }},
                .make = [](const ParamValues& p, const Registry&) { return std::make_unique<VmdDecomposer>(p); }});
}

}  // namespace driftlab
