// filter/wavelet: adapter around plugins/wavelet/wavelet.hpp (padding, level numbering, noise
// estimates and threshold rules are documented there).
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "framework/error.hpp"
#include "framework/registry.hpp"
#include "plugins/wavelet/wavelet.hpp"

namespace driftlab {
namespace {

wavelet::Family family_of(const std::string& name) {
  if (name == "daubechies") return wavelet::Family::Daubechies;
  if (name == "daubechies_centered") return wavelet::Family::DaubechiesCentered;
  if (name == "haar") return wavelet::Family::Haar;
  if (name == "haar_centered") return wavelet::Family::HaarCentered;
  if (name == "bspline") return wavelet::Family::Bspline;
  return wavelet::Family::BsplineCentered;
}

class WaveletFilter final : public Filter {
 public:
  explicit WaveletFilter(const ParamValues& p) {
    const std::string& rule = p.text("threshold");
    config_ = {.family = family_of(p.text("wavelet")),
               .order = static_cast<int>(p.integer("order")),
               .levels = static_cast<int>(p.integer("levels")),
               .rule = rule == "universal" ? wavelet::ThresholdRule::Universal
                       : rule == "sure"    ? wavelet::ThresholdRule::Sure
                                           : wavelet::ThresholdRule::SureHybrid,
               .shrink = p.text("mode") == "soft" ? wavelet::Shrink::Soft : wavelet::Shrink::Hard,
               .noise = p.text("noise_estimate") == "finest_level" ? wavelet::NoiseEstimate::FinestLevel
                                                                   : wavelet::NoiseEstimate::PerLevel};
  }

  Eigen::VectorXd filter(const Eigen::VectorXd& z, RunContext& ctx) override {
    wavelet::Result r;
    try {
      wavelet::Config config = config_;
      config.progress = ctx.progress;
      r = wavelet::denoise(z, config);
    } catch (const std::domain_error& e) {
      throw DataError({"", 0, "signal"}, std::string("filter/wavelet: ") + e.what());
    } catch (const std::invalid_argument& e) {
      throw ConfigError({"", 0, ""}, std::string("filter/wavelet: ") + e.what());
    }
    ctx.diagnostics["levels"] = r.levels;
    ctx.diagnostics["noise_sigma_per_level"] = r.sigma;  // finest level first, signal units
    ctx.diagnostics["threshold_per_level"] = r.thresholds;
    ctx.diagnostics["coefficients_kept_per_level"] = r.kept;
    return std::move(r.denoised);
  }

 private:
  wavelet::Config config_;
};

}  // namespace

void register_wavelet_plugins(Registry& registry) {
  registry.add(
      {.name = "filter/wavelet",
       .summary = "wavelet-threshold denoising (GSL DWT; soft/hard; universal, SURE or hybrid SURE thresholds)",
       .reference = "Donoho & Johnstone 1994 (VisuShrink); Donoho & Johnstone 1995 (SureShrink); "
                    "Johnstone & Silverman 1997 (level-dependent noise)",
       .params =
           ParamTable{
               {
                   param::choice(
                       "wavelet", "daubechies",
                       {"daubechies", "daubechies_centered", "haar", "haar_centered", "bspline", "bspline_centered"},
                       "wavelet family (GSL)"),
                   param::integer("order", 8, "1",
                                  "GSL's k: daubechies 4, 6, ..., 20 (k/2 vanishing moments; 8 = db4), haar 2, "
                                  "bspline 103 105 202 204 206 208 301 303 305 307 309"),
                   param::integer("levels", 5, "1", "detail levels thresholded, finest first (coarser levels kept)")
                       .at_least(1)
                       .at_most(30),
                   param::choice("threshold", "universal", {"universal", "sure", "sure_hybrid"},
                                 "universal sigma sqrt(2 ln N) (VisuShrink); sure: per-level SURE minimizer; "
                                 "sure_hybrid: universal on sparse levels, else SURE (SureShrink)"),
                   param::choice("mode", "soft", {"soft", "hard"}, "shrinkage rule"),
                   param::choice("noise_estimate", "finest_level", {"finest_level", "per_level"},
                                 "sigma = median(|d|)/0.6745 of the finest details for all levels (white noise) or of "
                                 "each level's own details (coloured noise)"),
               },
               {
                   {"order is one GSL implements for the wavelet family",
                    {"wavelet", "order"},
                    [](const ParamValues& v) {
                      return wavelet::valid_order(family_of(v.text("wavelet")), static_cast<int>(v.integer("order")));
                    }},
               }},
       .make = [](const ParamValues& p, const Registry&) { return std::make_unique<WaveletFilter>(p); }});
}

}  // namespace driftlab
