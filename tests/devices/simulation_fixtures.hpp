// Simulation profiles and options shared by the single-axis and the whole-IMU simulator tests.
#pragma once

#include <cstdint>

#include "devices/simulator.hpp"

namespace driftlab::devices::testing {

// The chamber held at one temperature (degC) for the whole run.
inline SimulationProfile static_at(double temp_c) {
  SimulationProfile p;
  p.chamber_c = Profile(temp_c);
  return p;
}

// Sample rate fs (Hz), duration (s; <= 0 keeps the profile's own) and seed.
inline SimulationOptions options(double fs, double duration, std::uint64_t seed) {
  SimulationOptions o;
  o.sample_rate_hz = fs;
  if (duration > 0.0) o.duration_s = duration;
  o.seed = seed;
  return o;
}

}  // namespace driftlab::devices::testing
