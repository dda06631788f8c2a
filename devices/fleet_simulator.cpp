#include "devices/fleet_simulator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <set>
#include <sstream>

#include "framework/error.hpp"
#include "framework/seeded_random.hpp"
#include "framework/signal.hpp"
#include "framework/units.hpp"
#include "models/error_model/error_model.hpp"

namespace driftlab::devices {
namespace {

constexpr std::uint64_t kSpreadStream = 0x464C454554ULL;  // "FLEET": apart from the simulators' streams

double spread(double value, double sigma, error_model::NormalStream& z) {
  return std::max(0.0, value * (1.0 + sigma * z.next()));
}

void spread_axis(ImuAxis& axis, const FleetSpread& s, error_model::NormalStream& z) {
  for (double& c : axis.bias_polynomial) c *= 1.0 + s.bias * z.next();
  for (double& k : axis.scale_factor_polynomial) k *= 1.0 + s.scale_factor * z.next();
  axis.noise.arw_rad_sqrt_s = spread(axis.noise.arw_rad_sqrt_s, s.noise, z);
  axis.noise.bias_instability_rad_s = spread(axis.noise.bias_instability_rad_s, s.noise, z);
  axis.noise.rate_random_walk_rad_s_sqrt_s = spread(axis.noise.rate_random_walk_rad_s_sqrt_s, s.noise, z);
}

}  // namespace

std::string to_string(FaultKind kind) {
  switch (kind) {
    case FaultKind::Hysteresis:
      return "hysteresis";
    case FaultKind::BiasStep:
      return "bias_step";
    case FaultKind::Noisy:
      return "noisy";
    case FaultKind::Truncated:
      return "truncated";
    case FaultKind::Lag:
      return "lag";
    case FaultKind::DeadAxis:
      return "dead_axis";
    case FaultKind::Lsb:
      return "lsb";
  }
  return "";
}

namespace {

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(text);
  while (std::getline(in, item, ',')) out.push_back(item);
  return out;
}

// A whole text as a number, or nothing.
std::optional<double> parse_number(const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

}  // namespace

FleetSpread parse_fleet_spread(const std::string& spec) {
  const Location where{"", 0, "--spread"};
  FleetSpread s;
  if (const auto all = parse_number(spec)) {
    if (*all < 0) throw ConfigError(where, "relative sigma '" + spec + "' must be >= 0");
    return {*all, *all, *all, *all};
  }
  for (const auto& item : split_list(spec)) {
    const auto eq = item.find('=');
    const std::string group = item.substr(0, eq);
    const auto value = eq == std::string::npos ? std::nullopt : parse_number(item.substr(eq + 1));
    double* target = group == "bias"            ? &s.bias
                     : group == "scale_factor"  ? &s.scale_factor
                     : group == "noise"         ? &s.noise
                     : group == "time_constant" ? &s.time_constant
                                                : nullptr;
    if (!target || !value || *value < 0)
      throw ConfigError(where, "'" + item +
                                   "': expected a relative sigma >= 0 for every group (e.g. 0.1) or group=sigma,... "
                                   "with groups bias, scale_factor, noise, time_constant");
    *target = *value;
  }
  return s;
}

std::vector<FaultCount> parse_fault_plan(const std::string& spec) {
  const Location where{"", 0, "--outliers"};
  std::vector<FaultCount> plan;
  if (spec.empty() || spec == "none") return plan;
  std::string kinds;
  for (const FaultKind k : kFaultKindList) kinds += (kinds.empty() ? "" : ", ") + to_string(k);
  std::set<std::string> seen;
  for (const auto& item : split_list(spec)) {
    const auto colon = item.find(':');
    const std::string name = item.substr(0, colon);
    const auto count = colon == std::string::npos ? std::nullopt : parse_number(item.substr(colon + 1));
    const FaultKind* kind = nullptr;
    for (const FaultKind& k : kFaultKindList)
      if (to_string(k) == name) kind = &k;
    if (!kind || !count || *count < 0 || *count != std::floor(*count) || *count > 1e6)
      throw ConfigError(where, "'" + item + "': expected kind:count (a whole count >= 0) with kind one of " + kinds);
    if (!seen.insert(name).second) throw ConfigError(where, "fault kind '" + name + "' given twice");
    plan.push_back({*kind, static_cast<std::size_t>(*count)});
  }
  return plan;
}

ExpectedFinding expected_finding(FaultKind kind) {
  switch (kind) {
    case FaultKind::Hysteresis:
      return {"gyro_x", "hysteresis"};
    case FaultKind::BiasStep:
      return {"gyro_y", "holdout"};
    case FaultKind::Noisy:
      return {"gyro1_x", "N"};
    case FaultKind::Truncated:
      return {"", "failed"};
    case FaultKind::Lag:
      return {"gyro_z", "hysteresis"};
    case FaultKind::DeadAxis:
      return {"gyro1_z", "N"};
    case FaultKind::Lsb:
      return {"gyro1_x", "quantisation"};
  }
  return {};
}

std::string describe(FaultKind kind) {
  char text[160];
  switch (kind) {
    case FaultKind::Hysteresis:
      std::snprintf(text, sizeof text, "gyro_x hysteresis %g deg/h (branch state of width %g K)", kHysteresisDph,
                    kHysteresisWidthK);
      break;
    case FaultKind::BiasStep:
      std::snprintf(text, sizeof text, "gyro_y bias step of %g deg/s (%g deg/h) at the middle of the record",
                    kBiasStepDps, kBiasStepDps * kSecondsPerHour);
      break;
    case FaultKind::Noisy:
      std::snprintf(text, sizeof text, "instance 1 gyro angle random walk N x %g", kNoisyFactor);
      break;
    case FaultKind::Truncated:
      std::snprintf(text, sizeof text, "log cut to %g %% of its bytes, mid-row", 100.0 * kTruncatedFraction);
      break;
    case FaultKind::Lag:
      std::snprintf(text, sizeof text, "gyro_z bias %g deg/h/K of its sensing element's lag (tau %g s) behind the die",
                    kLagSlopeDphPerK, kLagTauS);
      break;
    case FaultKind::DeadAxis:
      std::snprintf(text, sizeof text, "instance 1 gyro_z dead: constant output");
      break;
    case FaultKind::Lsb:
      std::snprintf(text, sizeof text, "instance 1 gyro_x quantised to an LSB of %g deg/s (%g deg/h)", kLsbDps,
                    kLsbDps * kSecondsPerHour);
      break;
  }
  return text;
}

std::vector<FleetUnit> plan_fleet(const ImuDefinition& nominal, std::size_t units, std::uint64_t seed,
                                  const FleetSpread& s, const std::vector<FaultCount>& faults) {
  std::size_t planted = 0;
  for (const auto& f : faults) planted += f.count;
  if (units < planted + 1)
    throw ConfigError({"", 0, "--fleet"}, "a fleet needs at least " + std::to_string(planted + 1) +
                                              " units (one per planted fault and a normal one), got " +
                                              std::to_string(units));
  const std::size_t width = std::max<std::size_t>(3, std::to_string(units).size());
  std::vector<std::size_t> order(units);
  std::iota(order.begin(), order.end(), 0);
  SeededRandom pick(splitmix64(seed ^ kSpreadStream));
  for (std::size_t i = units - 1; i > 0; --i) std::swap(order[i], order[pick.index(i + 1)]);  // Fisher-Yates

  std::vector<FleetUnit> fleet(units);
  for (std::size_t u = 0; u < units; ++u) {
    FleetUnit& unit = fleet[u];
    const std::string number = std::to_string(u + 1);
    unit.id = "unit" + std::string(width - number.size(), '0') + number;
    unit.seed = splitmix64(seed ^ splitmix64(u + 1));
    unit.imu = nominal;
    error_model::NormalStream z(splitmix64(seed ^ kSpreadStream), u + 1);
    for (std::size_t i = 0; i < unit.imu.instances.size(); ++i) {
      ImuInstance& instance = unit.imu.instances[i];
      instance.device_id = 1000.0 * static_cast<double>(u + 1) + static_cast<double>(i);
      instance.die_time_constant_s = spread(instance.die_time_constant_s, s.time_constant, z);
      instance.sensor_time_constant_s = spread(instance.sensor_time_constant_s, s.time_constant, z);
      for (auto& axis : instance.gyro.axes) spread_axis(axis, s, z);
      for (auto& axis : instance.accel.axes) spread_axis(axis, s, z);
    }
  }
  std::size_t next = 0;
  for (const auto& f : faults) {
    const bool second_instance =
        f.kind == FaultKind::Noisy || f.kind == FaultKind::DeadAxis || f.kind == FaultKind::Lsb;
    if (f.count > 0 && second_instance && nominal.instances.size() < 2)
      throw ConfigError({"", 0, "--device"},
                        "the planted " + to_string(f.kind) + " fault needs a device with 2 IMU instances");
    for (std::size_t c = 0; c < f.count; ++c) {
      FleetUnit& unit = fleet[order[next++]];
      unit.fault = f.kind;
      if (f.kind == FaultKind::Noisy)
        for (auto& axis : unit.imu.instances[1].gyro.axes) axis.noise.arw_rad_sqrt_s *= kNoisyFactor;
    }
  }
  return fleet;
}

ImuSimulationRecord simulate_unit(const FleetUnit& unit, const SimulationProfile& profile, SimulationOptions options) {
  options.seed = unit.seed;
  ImuSimulationRecord r = simulate_imu(unit.imu, profile, options);
  if (unit.fault == FaultKind::Hysteresis) {
    ImuInstanceRecord& instance = r.instances.front();
    const Eigen::VectorXd s = signal::hysteresis_state(instance.die_temp_c, kHysteresisWidthK);
    const Eigen::VectorXd offset = s * (kHysteresisDph * kRadPerSecPerDph);
    instance.gyro[0].measured += offset;
    instance.gyro[0].systematic += offset;
  } else if (unit.fault == FaultKind::BiasStep) {
    ImuAxisRecord& axis = r.instances.front().gyro[1];
    const Eigen::Index n = r.time_s.size();
    const double step = kBiasStepDps * kSecondsPerHour * kRadPerSecPerDph;
    axis.measured.tail(n - n / 2).array() += step;
    axis.systematic.tail(n - n / 2).array() += step;
  } else if (unit.fault == FaultKind::Lag) {
    ImuInstanceRecord& instance = r.instances.front();
    const Eigen::VectorXd lagged = signal::first_order_lag(r.time_s, instance.die_temp_c, kLagTauS);
    const Eigen::VectorXd offset = (lagged - instance.die_temp_c) * (kLagSlopeDphPerK * kRadPerSecPerDph);
    instance.gyro[2].measured += offset;
    instance.gyro[2].systematic += offset;
  } else if (unit.fault == FaultKind::DeadAxis) {
    ImuAxisRecord& axis = r.instances[1].gyro[2];
    axis.measured.setConstant(axis.measured[0]);
    axis.systematic.setConstant(axis.measured[0]);
  } else if (unit.fault == FaultKind::Lsb) {
    ImuAxisRecord& axis = r.instances[1].gyro[0];
    const double lsb = kLsbDps * kSecondsPerHour * kRadPerSecPerDph;
    axis.measured = (axis.measured / lsb).array().round() * lsb;
  }
  return r;
}

}  // namespace driftlab::devices
