// decomposition/emd, decomposition/eemd, decomposition/ceemdan: adapters around plugins/emd/emd.hpp
// (stopping rules, spline end conditions, end-effect policies, ensemble alignment and determinism
// are documented there). Ensemble members run on ctx.threads threads; results do not depend on it.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "framework/error.hpp"
#include "framework/registry.hpp"
#include "framework/resources.hpp"
#include "plugins/emd/emd.hpp"

namespace driftlab {
namespace {

enum class Method { Emd, Eemd, Ceemdan };

emd::SiftConfig sift_config(const ParamValues& p) {
  const std::string& rule = p.text("stop_rule");
  return {.stop_rule = rule == "s_number"          ? emd::StopRule::SNumber
                       : rule == "s_number_steady" ? emd::StopRule::SNumberSteady
                       : rule == "cauchy_sd"       ? emd::StopRule::CauchySd
                                                   : emd::StopRule::FixedSifts,
          .s_number = static_cast<int>(p.integer("s_number")),
          .sd_threshold = p.real("sd_threshold"),
          .fixed_sifts = static_cast<int>(p.integer("fixed_sifts")),
          .max_sifts = static_cast<int>(p.integer("max_sifts")),
          .end_policy = p.text("end_policy") == "mirror" ? emd::EndPolicy::Mirror : emd::EndPolicy::Linear};
}

// One member's sifting per sample, rounded up from the benchmarks (docs/performance.md): BM_Emd/1000000 1.8 s,
// BM_Ceemdan/10000 (100 members) 1.9 s, i.e. 1.8e-6 and 1.9e-6 s per sample and member.
constexpr double kSecondsPerSampleMember = 2e-6;

class EmdDecomposer final : public Decomposer {
 public:
  EmdDecomposer(Method method, const ParamValues& p) : method_(method), sift_(sift_config(p)) {
    max_imfs_ = static_cast<int>(p.integer("max_imfs"));
    if (method_ == Method::Emd) return;
    ensemble_size_ = static_cast<int>(p.integer("ensemble_size"));
    noise_strength_ = p.real("noise_strength");
    seed_ = static_cast<std::uint64_t>(p.integer("seed"));
    if (method_ == Method::Ceemdan)
      variant_ =
          p.text("variant") == "torres2011" ? emd::CeemdanVariant::Torres2011 : emd::CeemdanVariant::Colominas2014;
  }

  Decomposition decompose(const Eigen::VectorXd& x, RunContext& ctx) override {
    if (method_ != Method::Emd) {  // the run time before the work (framework/resources.hpp)
      const double sample_members = static_cast<double>(ensemble_size_) * static_cast<double>(x.size());
      char what[160];
      std::snprintf(what, sizeof what, "%d members x %td samples at %.2g s per sample and member", ensemble_size_,
                    x.size(), kSecondsPerSampleMember);
      check_time_estimate(sample_members * kSecondsPerSampleMember, {"", 0, "ensemble_size"}, what);
    }
    emd::Result result;
    try {
      result = run_kernel(x, ctx);
    } catch (const std::domain_error& e) {
      throw DataError({"", 0, "signal"}, e.what());
    } catch (const std::invalid_argument& e) {
      throw ConfigError({"", 0, ""}, e.what());
    }
    ctx.diagnostics["sifts_per_imf"] = result.sifts;
    if (x.squaredNorm() > 0.0)
      ctx.diagnostics["orthogonality_index"] = emd::orthogonality_index(x, result.imfs, result.residue);
    return {std::move(result.imfs), std::move(result.residue)};
  }

 private:
  emd::Result run_kernel(const Eigen::VectorXd& x, const RunContext& ctx) const {
    if (method_ == Method::Emd) return emd::emd(x, {.sift = sift_, .max_imfs = max_imfs_, .progress = ctx.progress});
    const emd::EnsembleConfig ensemble{.sift = sift_,
                                       .max_imfs = max_imfs_,
                                       .ensemble_size = ensemble_size_,
                                       .noise_strength = noise_strength_,
                                       .seed = seed_,
                                       .threads = std::max(1u, ctx.threads),
                                       .progress = ctx.progress};
    if (method_ == Method::Eemd) return emd::eemd(x, ensemble);
    return emd::ceemdan(x, {.ensemble = ensemble, .variant = variant_});
  }

  Method method_;
  emd::SiftConfig sift_;
  int max_imfs_ = 0;
  int ensemble_size_ = 1;
  double noise_strength_ = 0.0;
  std::uint64_t seed_ = 1;
  emd::CeemdanVariant variant_ = emd::CeemdanVariant::Torres2011;
};

std::vector<ParamSpec> sift_params(const std::string& max_imfs_doc) {
  return {
      param::choice("stop_rule", "s_number", {"s_number", "s_number_steady", "cauchy_sd", "fixed_sifts"},
                    "when sifting one IMF stops: s_number (Huang 2003, S consecutive sifts with "
                    "#extrema and #zero crossings differing by <= 1), s_number_steady (libeemd's rule: "
                    "also the counts changing by <= 1 in total from the sift before), cauchy_sd (Huang "
                    "1998 eq. 5.5, aggregated SD < sd_threshold), fixed_sifts (exactly fixed_sifts)"),
      param::integer("s_number", 4, "1", "S for stop_rules s_number and s_number_steady").at_least(1),
      param::real("sd_threshold", 0.2, "1", "threshold for stop_rule cauchy_sd: sum (h_prev - h)^2 / sum h_prev^2")
          .greater_than(0),
      param::integer("fixed_sifts", 10, "1", "sifts per IMF for stop_rule fixed_sifts").at_least(1),
      param::integer("max_sifts", 50, "1", "cap on sifts per IMF, for every stop rule").at_least(1),
      param::choice("end_policy", "mirror", {"mirror", "linear"},
                    "envelope ends: mirror (Rilling 2003, two extrema reflected per end) or linear "
                    "(extrapolated from the two nearest extrema, not inside the signal)"),
      param::integer("max_imfs", 0, "1", max_imfs_doc).at_least(0),
  };
}

std::vector<ParamSpec> ensemble_params(double noise_strength) {
  return {
      param::integer("ensemble_size", 100, "1", "number of noise realizations I").at_least(1).at_most(1e5),
      param::real("noise_strength", noise_strength, "1",
                  "added white-noise standard deviation as a multiple of the signal's population "
                  "standard deviation (eps0)")
          .at_least(0),
      param::seed(),
  };
}

std::vector<CrossRule> sift_rules() {
  return {
      {"stop_rule fixed_sifts needs fixed_sifts <= max_sifts", {"fixed_sifts", "max_sifts"}, [](const ParamValues& v) {
         return v.text("stop_rule") != "fixed_sifts" || v.integer("fixed_sifts") <= v.integer("max_sifts");
       }}};
}

template <class... Lists>
std::vector<ParamSpec> concat(Lists... lists) {
  std::vector<ParamSpec> all;
  (all.insert(all.end(), lists.begin(), lists.end()), ...);
  return all;
}

}  // namespace

void register_emd_plugins(Registry& registry) {
  auto make = [](Method method) {
    return [method](const ParamValues& p, const Registry&) -> std::unique_ptr<Plugin> {
      return std::make_unique<EmdDecomposer>(method, p);
    };
  };
  registry.add({.name = "decomposition/emd",
                .summary = "empirical mode decomposition into IMFs and a residue",
                .reference = "Huang et al. 1998 Sec. 5 (sifting, eqs. 5.1-5.5); Huang et al. 2003 "
                             "(S-number); Rilling et al. 2003 (mirror ends)",
                .params = ParamTable{sift_params("maximum number of IMFs; 0: until the residue has "
                                                 "fewer than 3 extrema, at most floor(log2 N)"),
                                     sift_rules()},
                .make = make(Method::Emd)});
  registry.add({.name = "decomposition/eemd",
                .summary = "ensemble EMD: IMFs averaged over noise-added copies",
                .reference = "Wu & Huang 2009 Sec. 3 (steps 1-4)",
                .params = ParamTable{concat(sift_params("number of IMFs K; 0: the largest member "
                                                        "count (members with fewer pad zeros)"),
                                            ensemble_params(0.2)),
                                     sift_rules()},
                .make = make(Method::Eemd)});
  registry.add({.name = "decomposition/ceemdan",
                .summary = "complete ensemble EMD with adaptive noise, one averaged mode per stage",
                .reference = "Torres et al. 2011 Sec. 3 (steps 1-6); Colominas et al. 2014 Sec. 3 "
                             "(improved variant, eqs. 4-7)",
                .params = ParamTable{concat(sift_params("maximum number of IMFs; 0: until the residue has fewer "
                                                        "than 3 extrema, at most floor(log2 N)"),
                                            ensemble_params(0.2),
                                            std::vector<ParamSpec>{param::choice(
                                                "variant", "torres2011", {"torres2011", "colominas2014"},
                                                "torres2011: averaged first modes of residue + scaled noise modes; "
                                                "colominas2014: averaged local means (improved CEEMDAN)")}),
                                     sift_rules()},
                .make = make(Method::Ceemdan)});
}

}  // namespace driftlab
