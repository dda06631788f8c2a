// effect/*: candidate terms of the discrepancy workflow (kernels and formulas in effects.hpp).
// Reported parameters use the keys and units of a device file's `effects:` section
// (devices/device_file.hpp), so a named effect can be pasted into the device file.
#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <type_traits>

#include "framework/error.hpp"
#include "framework/registry.hpp"
#include "framework/units.hpp"
#include "plugins/effects/effects.hpp"

namespace driftlab {
namespace {

constexpr double kRadPerSecPerDph = kRadPerDeg / 3600.0;
constexpr double kPpm = 1e-6;

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
    return {{"tau_s", "s", {theta[0]}}};
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
    return {{"coefficient_dph_per_c_per_min", "deg/h per degC/min", {c[0] / (kRadPerSecPerDph * 60.0)}}};
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
    return {{"height_dph", "deg/h", {c[0] / kRadPerSecPerDph}}, {"width_c", "degC", {theta[0]}}};
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
    return {{"amplitude_dph", "deg/h", {c[0] / kRadPerSecPerDph}}, {"tau_s", "s", {theta[0]}}};
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
    return {{"amplitude_dph", "deg/h", {s.amplitude / kRadPerSecPerDph}},
            {"period_s", "s", {theta[0]}},
            {"phase_deg", "deg", {s.phase_rad / kRadPerDeg}}};
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
    EffectValue v{"coefficients_ppm", "ppm/K^i", {}};
    for (Eigen::Index i = 0; i < c.size(); ++i) v.values.push_back(c[i] / kPpm);
    return {v};
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
       .summary = "the resonator lags the temperature sensor: the model's bias(T) follows lag(T, tau)",
       .reference = "first-order thermal lag (Newton cooling), exact for piecewise-linear input: "
                    "error_model::first_order_lag" +
                    workflow,
       .params = ParamTable{{param::real("tau_min_s", 10.0, "s", "shortest time constant searched").greater_than(0),
                             param::real("tau_max_s", 5000.0, "s", "longest time constant searched").greater_than(0)},
                            {lower_below_upper("tau_min_s", "tau_max_s")}},
       .make = make<ThermalLag>()});
  registry.add({.name = "effect/temperature_rate",
                .summary = "bias proportional to the temperature rate dT/dt (thermal gradients across the die)",
                .reference = "temperature-rate bias sensitivity; error_model::time_derivative" + workflow,
                .params = ParamTable{},
                .make = make<TemperatureRate>()});
  registry.add(
      {.name = "effect/hysteresis",
       .summary = "heating/cooling branch offset that saturates a few degC after each reversal",
       .reference = "branch state error_model::hysteresis_state on the play operator (Visintin 1994, "
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
       .summary = "power-on exponential from the start of the record: amplitude, time constant",
       .reference = "exponential warm-up drift (power-on transient)" + workflow,
       .params = ParamTable{{param::real("tau_min_s", 30.0, "s", "shortest decay time searched").greater_than(0),
                             param::real("tau_max_s", 20000.0, "s", "longest decay time searched").greater_than(0)},
                            {lower_below_upper("tau_min_s", "tau_max_s")}},
       .make = make<WarmupTransient>()});
  registry.add(
      {.name = "effect/periodic_disturbance",
       .summary = "a sinusoid on the rate (HVAC, chamber control cycling): amplitude, period, phase",
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
       .summary = "scale-factor drift with temperature beyond the model: s *= 1 + sum c_i (T - T0)^i "
                  "(needs a true-rate channel)",
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
