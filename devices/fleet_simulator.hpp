// A simulated fleet of one whole-IMU device (issue 24): N units of the device file, each with its
// parameters spread unit to unit and some carrying one planted fault, so that a fleet report's
// findings can be scored against truth (`driftlab simulate --fleet`).
//
// Spread (FleetSpread; unit u draws z ~ N(0, 1) from its own stream (seed, u), in file order):
//   every bias-polynomial coefficient c_i of every gyro and accel axis   c_i (1 + bias z)
//   every scale-factor coefficient                                       k_j (1 + scale_factor z)
//   N, B, K of every axis                                                x (1 + noise z), at least 0
//   die and sensor time constants of every instance                      tau (1 + time_constant z), at least 0
// `--spread` (parse_fleet_spread): one relative sigma for every group ("0.1") or groups by name
// ("bias=0.2,noise=0.05", the others keep their default 0.10).
// Unit u's instance i gets device_id 1000 (u + 1) + i, so two units are two devices to `calibrate`.
//
// Faults (one per unit, FaultKind, sizes below), `--outliers` (parse_fault_plan) "kind:count,...",
// default kDefaultOutliers: planted, kind after kind in the plan's order, in the first units of a
// seeded permutation of the units; the rest are normal. The expected finding of each is what a
// fleet report should flag: the channel and the figure (tools/driftlab/fleet_report.hpp names).
//   hysteresis  gyro_x of instance 0: + kHysteresisDph * s(T_die), s the branch state
//               (framework/signal.hpp) with width kHysteresisWidthK     -> gyro_x hysteresis
//   bias_step   gyro_y of instance 0: + kBiasStepDps from the middle of the record -> gyro_y holdout
//   noisy       every gyro axis of instance 1: N times kNoisyFactor    -> gyro1_x N
//   truncated   the unit's CSV cut to kTruncatedFraction of its bytes (mid-row) -> a failed unit
//   lag         gyro_z of instance 0: + kLagSlopeDphPerK (T_lag - T_die), T_lag the die temperature
//               through a first-order lag of kLagTauS (its sensing element lags the die sensor:
//               a bias that differs between heating and cooling)          -> gyro_z hysteresis
//   dead_axis   gyro_z of instance 1: constant output (its first sample's) -> gyro1_z N
//   lsb         gyro_x of instance 1: output rounded to multiples of kLsbDps -> gyro1_x quantisation
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "devices/imu_definition.hpp"
#include "devices/imu_simulator.hpp"

namespace driftlab::devices {

struct FleetSpread {  // relative 1-sigma of a normal factor (1 + sigma z)
  double bias = 0.10;
  double scale_factor = 0.10;
  double noise = 0.10;
  double time_constant = 0.10;
};

// FleetSpread from `--spread`: "S" sets every group to S; "group=S,..." (groups bias,
// scale_factor, noise, time_constant) sets those. Each S finite and >= 0; ConfigError naming
// --spread otherwise.
FleetSpread parse_fleet_spread(const std::string& spec);

enum class FaultKind { Hysteresis, BiasStep, Noisy, Truncated, Lag, DeadAxis, Lsb };
inline constexpr FaultKind kFaultKindList[] = {FaultKind::Hysteresis, FaultKind::BiasStep, FaultKind::Noisy,
                                               FaultKind::Truncated,  FaultKind::Lag,      FaultKind::DeadAxis,
                                               FaultKind::Lsb};
// "hysteresis", "bias_step", "noisy", "truncated", "lag", "dead_axis", "lsb"
std::string to_string(FaultKind kind);

struct FaultCount {
  FaultKind kind;
  std::size_t count;
};
inline constexpr const char* kDefaultOutliers = "hysteresis:1,bias_step:1,noisy:1,truncated:1";
// The plan from `--outliers`: "kind:count,..." (count >= 0, each kind at most once; "" or "none":
// no fault). ConfigError naming --outliers and the kinds otherwise.
std::vector<FaultCount> parse_fault_plan(const std::string& spec);

inline constexpr double kHysteresisDph = 150.0;    // branch offset coefficient, deg/h
inline constexpr double kHysteresisWidthK = 2.0;   // saturation width, K
inline constexpr double kBiasStepDps = 0.05;       // 180 deg/h
inline constexpr double kNoisyFactor = 5.0;        // on N
inline constexpr double kTruncatedFraction = 0.4;  // of the CSV's bytes kept
inline constexpr double kLagSlopeDphPerK = 20.0;   // bias per K of (lagged - die) temperature, deg/h/K
inline constexpr double kLagTauS = 900.0;          // the sensing element's extra lag, s
inline constexpr double kLsbDps = 0.05;            // coarse output LSB (180 deg/h), deg/s

struct ExpectedFinding {
  std::string channel;  // "gyro_x"; empty for a failed unit
  std::string figure;   // "hysteresis", "holdout", "N", "quantisation"; "failed" for a failed unit
};
ExpectedFinding expected_finding(FaultKind kind);
std::string describe(FaultKind kind);  // the fault in words, with its size

struct FleetUnit {
  std::string id;      // "unit001": zero-padded to the width of the fleet size, at least 3 digits
  std::uint64_t seed;  // of its record's noise
  ImuDefinition imu;   // the spread device
  std::optional<FaultKind> fault;
};

// The fleet's units, planned from the nominal device. Throws ConfigError (naming --fleet) when
// `units` < the planted faults + 1, (naming --device) when a fault's instance is missing.
std::vector<FleetUnit> plan_fleet(const ImuDefinition& nominal, std::size_t units, std::uint64_t seed,
                                  const FleetSpread& spread = {},
                                  const std::vector<FaultCount>& faults = parse_fault_plan(kDefaultOutliers));

// The unit's oven run with its fault applied (a truncated unit's record is whole: the command cuts its file).
ImuSimulationRecord simulate_unit(const FleetUnit& unit, const SimulationProfile& profile, SimulationOptions options);

}  // namespace driftlab::devices
