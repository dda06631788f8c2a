#include "devices/fleet_simulator.hpp"

#include <algorithm>
#include <cstdio>
#include <numeric>

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
    case FaultKind::Hysteresis: return "hysteresis";
    case FaultKind::BiasStep: return "bias_step";
    case FaultKind::Noisy: return "noisy";
    case FaultKind::Truncated: return "truncated";
  }
  return "";
}

ExpectedFinding expected_finding(FaultKind kind) {
  switch (kind) {
    case FaultKind::Hysteresis: return {"gyro_x", "hysteresis"};
    case FaultKind::BiasStep: return {"gyro_y", "holdout"};
    case FaultKind::Noisy: return {"gyro1_x", "N"};
    case FaultKind::Truncated: return {"", "failed"};
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
                    kBiasStepDps, kBiasStepDps * 3600.0);
      break;
    case FaultKind::Noisy:
      std::snprintf(text, sizeof text, "instance 1 gyro angle random walk N x %g", kNoisyFactor);
      break;
    case FaultKind::Truncated:
      std::snprintf(text, sizeof text, "log cut to %g %% of its bytes, mid-row", 100.0 * kTruncatedFraction);
      break;
  }
  return text;
}

std::vector<FleetUnit> plan_fleet(const ImuDefinition& nominal, std::size_t units, std::uint64_t seed,
                                  const FleetSpread& s) {
  if (units < kFaultKinds + 1)
    throw ConfigError({"", 0, "--fleet"}, "a fleet needs at least " + std::to_string(kFaultKinds + 1) +
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
  for (std::size_t f = 0; f < kFaultKinds; ++f) {
    FleetUnit& unit = fleet[order[f]];
    unit.fault = static_cast<FaultKind>(f);
    if (*unit.fault == FaultKind::Noisy) {
      if (unit.imu.instances.size() < 2)
        throw ConfigError({"", 0, "--device"}, "the planted noisy-instance fault needs a device with 2 IMU instances");
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
    const double step = kBiasStepDps * 3600.0 * kRadPerSecPerDph;
    axis.measured.tail(n - n / 2).array() += step;
    axis.systematic.tail(n - n / 2).array() += step;
  }
  return r;
}

}  // namespace driftlab::devices
