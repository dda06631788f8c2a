// filter/rate_of_change: adapter of plugins/rate_of_change/rate_of_change.hpp. Turns a signal into
// its slope per second (unit: the input's unit per second), e.g. the heating/cooling rate of a
// temperature trend as an input of a drift regressor.
#include <stdexcept>

#include "framework/error.hpp"
#include "framework/registry.hpp"
#include "plugins/rate_of_change/rate_of_change.hpp"

namespace driftlab {
namespace {

class RateOfChange final : public Filter {
 public:
  explicit RateOfChange(const ParamValues& p) : window_s_(p.real("window_s")) {}

  Eigen::VectorXd filter(const Eigen::VectorXd& z, RunContext& ctx) override {
    try {
      return rate_of_change::centred_slope(ctx.time_s, z, window_s_);
    } catch (const std::invalid_argument& e) {
      throw DataError({"", 0, "signal"}, std::string("filter/rate_of_change: ") + e.what());
    }
  }

  std::string output_unit(const std::string& input_unit) const override { return input_unit + "/s"; }

 private:
  double window_s_;
};

}  // namespace

void register_rate_of_change_plugins(Registry& registry) {
  registry.add({.name = "filter/rate_of_change",
                .summary = "slope per second over a centred window (e.g. the heating/cooling rate of a temperature)",
                .reference = "central difference over a window",
                .params = ParamTable{{param::real("window_s", 60.0, "s",
                                                  "width of the centred window the slope is taken over; "
                                                  "at least two samples")
                                          .at_least(0)}},
                .make = [](const ParamValues& p, const Registry&) { return std::make_unique<RateOfChange>(p); }});
}

}  // namespace driftlab
