// classifier/sample_entropy: groups IMFs into noise / mixed / drift by their sample entropy.
// Each IMF's SampEn(m, r) uses r relative to that IMF's population standard deviation; the
// grouping rules are documented in sample_entropy.hpp. IMFs are processed on ctx.threads threads,
// each IMF by one thread, so results do not depend on the thread count. An IMF longer than
// max_samples is scored on kWindows evenly spaced windows of max_samples / kWindows samples: A and B
// are summed over the windows (pairs within a window), r is relative to the whole IMF's population
// SD, so the cost no longer grows with the record while every part of it is seen.
#include <cmath>
#include <limits>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>

#include "framework/error.hpp"
#include "framework/parallel.hpp"
#include "framework/registry.hpp"
#include "plugins/sample_entropy/sample_entropy.hpp"

namespace driftlab {
namespace {

ImfGroup to_imf_group(sampen::Group group) {
  switch (group) {
    case sampen::Group::Noise:
      return ImfGroup::Noise;
    case sampen::Group::Mixed:
      return ImfGroup::Mixed;
    case sampen::Group::Drift:
      return ImfGroup::Drift;
  }
  return ImfGroup::Mixed;
}

class SampleEntropyClassifier final : public Classifier {
 public:
  explicit SampleEntropyClassifier(const ParamValues& p)
      : m_(static_cast<int>(p.integer("m"))),
        r_(p.real("r")),
        rule_(p.text("rule")),
        noise_above_(p.real("noise_above")),
        drift_below_(p.real("drift_below")),
        max_samples_(static_cast<std::size_t>(p.integer("max_samples"))) {}

  Classification classify(const Eigen::MatrixXd& imfs, RunContext& ctx) override {
    const auto results = entropies(imfs, ctx.threads);
    std::vector<double> values;
    for (const auto& r : results) values.push_back(r.value);
    const auto decisions = rule_ == "thresholds" ? sampen::group_by_thresholds(values, noise_above_, drift_below_)
                                                 : sampen::group_by_gaps(values);

    Classification c;
    c.scores = values;
    auto& log = ctx.diagnostics["sample_entropy"] = nlohmann::json::array();
    for (std::size_t k = 0; k < results.size(); ++k) {
      const auto& r = results[k];
      c.groups.push_back(to_imf_group(decisions[k].group));
      c.reasons.push_back(decisions[k].reason);
      log.push_back({{"imf", k + 1},
                     {"sampen", r.finite() ? nlohmann::json(r.value) : nlohmann::json("Inf")},
                     {"a", r.a},
                     {"b", r.b},
                     {"n", r.n},
                     {"tolerance", r.tolerance},
                     {"status", sampen::to_string(r.status)},
                     {"group", sampen::to_string(decisions[k].group)},
                     {"reason", decisions[k].reason}});
    }
    ctx.diagnostics["rule"] = rule_;
    ctx.diagnostics["m"] = m_;
    ctx.diagnostics["r_relative_to_population_sd"] = r_;
    return c;
  }

 private:
  static constexpr std::size_t kWindows = 8;

  sampen::Result windowed_entropy(std::span<const double> x) const {
    if (max_samples_ / kWindows < 16 || x.size() <= max_samples_) return sampen::sample_entropy_relative(x, m_, r_);
    const double tolerance = r_ * sampen::population_sd(x);
    const std::size_t length = max_samples_ / kWindows;
    sampen::Result total;
    total.m = m_;
    total.tolerance = tolerance;
    for (std::size_t w = 0; w < kWindows; ++w) {
      const std::size_t start = w * (x.size() - length) / (kWindows - 1);
      const auto part = sampen::sample_entropy(x.subspan(start, length), m_, tolerance);
      total.n += part.n;
      total.a += part.a;
      total.b += part.b;
    }
    total.status = total.b == 0   ? sampen::Status::Undefined
                   : total.a == 0 ? sampen::Status::NoMatches
                                  : sampen::Status::Finite;
    total.value = total.finite() ? -std::log(static_cast<double>(total.a) / static_cast<double>(total.b))
                                 : std::numeric_limits<double>::infinity();
    return total;
  }

  std::vector<sampen::Result> entropies(const Eigen::MatrixXd& imfs, unsigned threads) const {
    std::vector<sampen::Result> results(static_cast<std::size_t>(imfs.cols()));
    parallel_for(results.size(), threads, [&](std::size_t k) {
      const auto column = imfs.col(static_cast<Eigen::Index>(k));
      try {
        results[k] = windowed_entropy(std::span<const double>(column.data(), static_cast<std::size_t>(column.size())));
      } catch (const std::invalid_argument& e) {
        throw DataError({"", 0, "imf" + std::to_string(k + 1)}, e.what());
      }
    });
    return results;
  }

  int m_;
  double r_;
  std::string rule_;
  double noise_above_;
  double drift_below_;
  std::size_t max_samples_;
};

}  // namespace

void register_sample_entropy_plugins(Registry& registry) {
  registry.add(
      {.name = "classifier/sample_entropy",
       .summary = "groups IMFs into noise / mixed / drift by sample entropy (largest gaps or thresholds)",
       .reference = "Richman & Moorman 2000 (SampEn; PhysioNet sampen.c counts); Li et al. 2023 "
                    "Sec. 3 (S1 noise, S2 mixed, S3 drift)",
       .params =
           ParamTable{
               {
                   param::integer("m", 2, "1", "template length (embedding dimension)").at_least(0).at_most(10),
                   param::real("r", 0.2, "1",
                               "tolerance as a multiple of the IMF's population standard deviation; "
                               "templates match when every |difference| < r * SD")
                       .greater_than(0),
                   param::choice("rule", "gaps", {"gaps", "thresholds"},
                                 "gaps: the two largest gaps in the decreasing SampEn sequence split "
                                 "noise | mixed | drift (one gap: no mixed; none: all mixed); "
                                 "thresholds: noise above noise_above, drift below drift_below"),
                   param::real("noise_above", 1.0, "1", "rule thresholds: SampEn above this (or Inf) -> noise")
                       .at_least(0),
                   param::real("drift_below", 0.2, "1", "rule thresholds: SampEn below this -> drift").at_least(0),
                   param::integer("max_samples", 40000, "1",
                                  "IMFs longer than this are scored on 8 evenly spaced windows of max_samples / 8 "
                                  "samples (pair counts summed); below 128: always the whole IMF")
                       .at_least(0),
               },
               {
                   {"noise_above > drift_below",
                    {"noise_above", "drift_below"},
                    [](const ParamValues& v) { return v.real("noise_above") > v.real("drift_below"); }},
               }},
       .make = [](const ParamValues& p, const Registry&) { return std::make_unique<SampleEntropyClassifier>(p); }});
}

}  // namespace driftlab
