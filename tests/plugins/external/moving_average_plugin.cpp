// An external plugin library, built by the tests and loaded at run time with Boost.DLL:
// `filter/moving_average`, a centred moving average. It shows everything a third-party plugin
// needs: the two exported C symbols and a registration function.
#include <Eigen/Core>

#include "framework/registry.hpp"

namespace {

Eigen::VectorXd centred_moving_average(const Eigen::VectorXd& z, Eigen::Index window) {
  const Eigen::Index n = z.size(), half = window / 2;
  Eigen::VectorXd prefix(n + 1);
  prefix[0] = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) prefix[i + 1] = prefix[i] + z[i];
  Eigen::VectorXd out(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index lo = std::max<Eigen::Index>(0, i - half), hi = std::min<Eigen::Index>(n, i + half + 1);
    out[i] = (prefix[hi] - prefix[lo]) / static_cast<double>(hi - lo);
  }
  return out;
}

class MovingAverage final : public driftlab::Filter {
 public:
  explicit MovingAverage(const driftlab::ParamValues& p) : window_(p.integer("window")) {}
  Eigen::VectorXd filter(const Eigen::VectorXd& z, driftlab::RunContext&) override {
    return centred_moving_average(z, window_);
  }

 private:
  Eigen::Index window_;
};

}  // namespace

extern "C" int driftlab_plugin_interface_version() { return driftlab::kPluginInterfaceVersion; }

extern "C" void driftlab_register_plugins(driftlab::Registry& registry) {
  using namespace driftlab;
  registry.add({.name = "filter/moving_average",
                .summary = "centred moving average (external plugin example)",
                .reference = "",
                .params = ParamTable{{param::integer("window", 5, "samples", "odd window length")
                                          .at_least(1)
                                          .must(
                                              "odd",
                                              [](const ParamValue& v) {
                                                return std::get<std::int64_t>(v) % 2 ? "" : "window must be odd";
                                              },
                                              std::int64_t{4})}},
                .make = [](const ParamValues& p, const Registry&) { return std::make_unique<MovingAverage>(p); }});
}
