// effect/*: candidate terms of the discrepancy workflow (kernels and formulas in effects.hpp).
// Reported parameters use the keys and units of the effect catalogue (framework/effect_catalogue.hpp),
// which a device file's `effects:` section also reads, so a named effect can be pasted into a
// device file; the catalogue's one-line doc is each plugin's summary.
#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <type_traits>

#include "framework/effect_catalogue.hpp"
#include "framework/error.hpp"
#include "framework/registry.hpp"
#include "framework/units.hpp"
#include "plugins/effects/effects.hpp"

namespace driftlab {
namespace {

const Eigen::VectorXd& channel(const TimeSeries& record, const char* role) { return record.channel(role).values; }

CrossRule lower_below_upper(const std::string& lower, const std::string& upper) {
  return {lower + " < " + upper, {lower, upper}, [lower, upper](const ParamValues& v) {
            return v.real(lower) < v.real(upper);
          }};
}

class ThermalLag final : public Effect {
 public:
  explicit ThermalLag(const ParamValues& p) : lower_(p.real("tau_min_s")), upper_(p.real("tau_max_s")) {}
  std::vector<std::string> required_roles() const override { return {role::kTemperature}; }
  std::vector<EffectParameter> nonlinear_parameters() const override { return {{"tau_s", "s", lower_, upper_}}; }
  std::vector<std::string> coefficient_names() const override { return {}; }
  bool moves_model_temperature() const override { return true; }
  EffectTerm evaluate(const TimeSeries& r, const EffectContext&, const Eigen::VectorXd& theta) const override {
    return {Eigen::MatrixXd(r.size(), 0),
            effects::lagged_temperature(r.time(), channel(r, role::kTemperature), theta[0])};
  }
  std::vector<EffectValue> describe(const TimeSeries&, const EffectContext&, const Eigen::VectorXd& theta,
                                    const Eigen::VectorXd&) const override {
    return {effect_value("thermal_lag", "tau_s", {theta[0]})};
  }

 private:
  double lower_, upper_;
};

class TemperatureRate final : public Effect {
 public:
  std::vector<std::string> required_roles() const override { return {role::kTemperature}; }
  std::vector<EffectParameter> nonlinear_parameters() const override { return {}; }
  std::vector<std::string> coefficient_names() const override { return {"coefficient_rad_s_per_k_s"}; }
  EffectTerm evaluate(const TimeSeries& r, const EffectContext&, const Eigen::VectorXd&) const override {
    return {effects::temperature_rate(r.time(), channel(r, role::kTemperature)), {}};
  }
  std::vector<EffectValue> describe(const TimeSeries&, const EffectContext&, const Eigen::VectorXd&,
                                    const Eigen::VectorXd& c) const override {
    return {effect_value("temperature_rate", "coefficient_dph_per_c_per_min", {c[0]})};
  }
};

class Hysteresis final : public Effect {
 public:
  explicit Hysteresis(const ParamValues& p)
      : lower_(p.real("width_min_c")), upper_(p.real("width_max_c")), deadband_(p.real("deadband_c")) {}
  std::vector<std::string> required_roles() const override { return {role::kTemperature}; }
  std::vector<EffectParameter> nonlinear_parameters() const override { return {{"width_c", "degC", lower_, upper_}}; }
  std::vector<std::string> coefficient_names() const override { return {"height_rad_s"}; }
  EffectTerm evaluate(const TimeSeries& r, const EffectContext&, const Eigen::VectorXd& theta) const override {
    return {effects::hysteresis_basis(channel(r, role::kTemperature), theta[0], deadband_), {}};
  }
  std::vector<EffectValue> describe(const TimeSeries&, const EffectContext&, const Eigen::VectorXd& theta,
                                    const Eigen::VectorXd& c) const override {
    return {effect_value("hysteresis", "height_dph", {c[0]}), effect_value("hysteresis", "width_c", {theta[0]})};
  }

 private:
  double lower_, upper_, deadband_;
};

class WarmupTransient final : public Effect {
 public:
  explicit WarmupTransient(const ParamValues& p) : lower_(p.real("tau_min_s")), upper_(p.real("tau_max_s")) {}
  std::vector<std::string> required_roles() const override { return {}; }
  std::vector<EffectParameter> nonlinear_parameters() const override { return {{"tau_s", "s", lower_, upper_}}; }
  std::vector<std::string> coefficient_names() const override { return {"amplitude_rad_s"}; }
  EffectTerm evaluate(const TimeSeries& r, const EffectContext& context, const Eigen::VectorXd& theta) const override {
    return {effects::warmup_basis(r.time(), context.start_time_s, theta[0]), {}};
  }
  std::vector<EffectValue> describe(const TimeSeries&, const EffectContext&, const Eigen::VectorXd& theta,
                                    const Eigen::VectorXd& c) const override {
    return {effect_value("warmup_transient", "amplitude_dph", {c[0]}),
            effect_value("warmup_transient", "tau_s", {theta[0]})};
  }

 private:
  double lower_, upper_;
};

class PeriodicDisturbance final : public Effect {
 public:
  explicit PeriodicDisturbance(const ParamValues& p) : lower_(p.real("period_min_s")), upper_(p.real("period_max_s")) {}
  std::vector<std::string> required_roles() const override { return {}; }
  std::vector<EffectParameter> nonlinear_parameters() const override {
    return {{"period_s", "s", lower_, upper_, EffectParameter::Scale::Period}};
  }
  std::vector<std::string> coefficient_names() const override { return {"sin_rad_s", "cos_rad_s"}; }
  EffectTerm evaluate(const TimeSeries& r, const EffectContext&, const Eigen::VectorXd& theta) const override {
    return {effects::periodic_basis(r.time(), theta[0]), {}};
  }
  std::vector<EffectValue> describe(const TimeSeries&, const EffectContext&, const Eigen::VectorXd& theta,
                                    const Eigen::VectorXd& c) const override {
    const auto s = effects::sinusoid_from_coefficients(c[0], c[1]);
    return {effect_value("periodic_disturbance", "amplitude_dph", {s.amplitude}),
            effect_value("periodic_disturbance", "period_s", {theta[0]}),
            effect_value("periodic_disturbance", "phase_deg", {s.phase_rad})};
  }

 private:
  double lower_, upper_;
};

class ScaleFactorTemperature final : public Effect {
 public:
  explicit ScaleFactorTemperature(const ParamValues& p) : degree_(static_cast<int>(p.integer("degree"))) {}
  std::vector<std::string> required_roles() const override { return {role::kTemperature, role::kTrueRate}; }
  std::vector<EffectParameter> nonlinear_parameters() const override { return {}; }
  std::vector<std::string> coefficient_names() const override {
    std::vector<std::string> names;
    for (int i = 1; i <= degree_; ++i) names.push_back("c" + std::to_string(i) + "_per_k" + std::to_string(i));
    return names;
  }
  EffectTerm evaluate(const TimeSeries& r, const EffectContext& context, const Eigen::VectorXd&) const override {
    return {effects::scale_factor_basis(channel(r, role::kTemperature), channel(r, role::kTrueRate),
                                        context.reference_temp_c, degree_),
            {}};
  }
  std::vector<EffectValue> describe(const TimeSeries&, const EffectContext&, const Eigen::VectorXd&,
                                    const Eigen::VectorXd& c) const override {
    return {effect_value("scale_factor_temperature", "coefficients_ppm", {c.data(), c.data() + c.size()})};
  }

 private:
  int degree_;
};

class ModeSplitDrift final : public Effect {
 public:
  std::vector<std::string> required_roles() const override { return {role::kTemperature, role::kDriveFrequency}; }
  std::vector<EffectParameter> nonlinear_parameters() const override { return {}; }
  std::vector<std::string> coefficient_names() const override { return {}; }
  bool moves_model_temperature() const override { return true; }
  EffectTerm evaluate(const TimeSeries& r, const EffectContext& context, const Eigen::VectorXd&) const override {
    return {Eigen::MatrixXd(r.size(), 0), thermometer(r, context).temperature_c};
  }
  std::vector<EffectValue> describe(const TimeSeries& r, const EffectContext& context, const Eigen::VectorXd&,
                                    const Eigen::VectorXd&) const override {
    const auto t = thermometer(r, context);
    const Eigen::VectorXd difference = t.temperature_c - channel(r, role::kTemperature);
    return {
        {"drive_frequency_at_reference_hz", "Hz", {t.frequency_at_reference_hz}},
        {"drive_frequency_tc_ppm_per_k", "ppm/K", {t.slope_hz_per_k / t.frequency_at_reference_hz / kPpm}},
        {"resonator_minus_sensor_rms_c",
         "degC",
         {std::sqrt(difference.squaredNorm() / static_cast<double>(std::max<Eigen::Index>(1, difference.size())))}}};
  }

 private:
  static effects::ResonatorThermometer thermometer(const TimeSeries& r, const EffectContext& context) {
    try {
      return effects::resonator_temperature(channel(r, role::kTemperature), channel(r, role::kDriveFrequency),
                                            context.reference_temp_c, context.drive_frequency_at_reference_hz,
                                            context.drive_frequency_slope_hz_per_k);
    } catch (const std::invalid_argument& e) {
      throw DataError({"", 0, "drive_frequency"}, std::string("effect/mode_split_drift: ") + e.what());
    }
  }
};

template <class T>
decltype(PluginInfo::make) make() {
  return [](const ParamValues& p, const Registry&) -> std::unique_ptr<Plugin> {
    if constexpr (std::is_constructible_v<T, const ParamValues&>)
      return std::make_unique<T>(p);
    else
      return std::make_unique<T>();
  };
}

}  // namespace

void register_effect_plugins(Registry& registry) {
  const std::string workflow = "; fitted by the discrepancy workflow (models/discrepancy)";
  registry.add(
      {.name = "effect/thermal_lag",
       .summary = effect_info("thermal_lag").doc,
       .reference = "first-order thermal lag (Newton cooling), exact for piecewise-linear input: "
                    "signal::first_order_lag" +
                    workflow,
       .params = ParamTable{{param::real("tau_min_s", 10.0, "s", "shortest time constant searched").greater_than(0),
                             param::real("tau_max_s", 5000.0, "s", "longest time constant searched").greater_than(0)},
                            {lower_below_upper("tau_min_s", "tau_max_s")}},
       .make = make<ThermalLag>()});
  registry.add({.name = "effect/temperature_rate",
                .summary = effect_info("temperature_rate").doc,
                .reference = "temperature-rate bias sensitivity; signal::time_derivative" + workflow,
                .params = ParamTable{},
                .make = make<TemperatureRate>()});
  registry.add(
      {.name = "effect/hysteresis",
       .summary = effect_info("hysteresis").doc,
       .reference = "branch state signal::hysteresis_state on the play operator (Visintin 1994, "
                    "Differential Models of Hysteresis, ch. III)" +
                    workflow,
       .params =
           ParamTable{{param::real("width_min_c", 0.2, "degC", "narrowest switching width searched").greater_than(0),
                       param::real("width_max_c", 20.0, "degC", "widest switching width searched").greater_than(0),
                       param::real("deadband_c", 0.05, "degC",
                                   "play half-width: temperature reversals smaller than this "
                                   "(sensor noise) do not switch the branch")
                           .at_least(0)},
                      {lower_below_upper("width_min_c", "width_max_c")}},
       .make = make<Hysteresis>()});
  registry.add(
      {.name = "effect/warmup_transient",
       .summary = effect_info("warmup_transient").doc,
       .reference = "exponential warm-up drift (power-on transient)" + workflow,
       .params = ParamTable{{param::real("tau_min_s", 30.0, "s", "shortest decay time searched").greater_than(0),
                             param::real("tau_max_s", 20000.0, "s", "longest decay time searched").greater_than(0)},
                            {lower_below_upper("tau_min_s", "tau_max_s")}},
       .make = make<WarmupTransient>()});
  registry.add(
      {.name = "effect/periodic_disturbance",
       .summary = effect_info("periodic_disturbance").doc,
       .reference = "least-squares sinusoid (Lomb 1976; Scargle 1982)" + workflow,
       .params =
           ParamTable{{param::real("period_min_s", 20.0, "s",
                                   "shortest period searched (raised to 4 block spacings of the workflow)")
                           .greater_than(0),
                       param::real("period_max_s", 1e5, "s", "longest period searched (lowered to half the record)")
                           .greater_than(0)},
                      {lower_below_upper("period_min_s", "period_max_s")}},
       .make = make<PeriodicDisturbance>()});
  registry.add(
      {.name = "effect/scale_factor_temperature",
       .summary = effect_info("scale_factor_temperature").doc,
       .reference = "scale-factor temperature sensitivity (IEEE Std 952-1997 model equation)" + workflow,
       .params = ParamTable{{param::integer("degree", 1, "1", "polynomial degree in T - T0").at_least(1).at_most(3)}},
       .make = make<ScaleFactorTemperature>()});
  registry.add({.name = "effect/mode_split_drift",
                .summary = "the bias follows the mode split seen by the drive frequency (resonator temperature), "
                           "not the case sensor (needs a drive-frequency channel)",
                .reference = "open-loop sense response b = g W_q sin(theta), devices/device_model.hpp "
                             "(Li et al., Micromachines 2023, 14, 971, Fig. 1b)" +
                             workflow,
                .params = ParamTable{},
                .make = make<ModeSplitDrift>()});
}

}  // namespace driftlab
