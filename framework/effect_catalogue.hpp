// The effect vocabulary, in one place: the physical effects that the simulator can switch on and
// that the discrepancy workflow can name, with their parameters as a device file's `effects:`
// section writes them (key, unit, factor to SI, doc). Read by the device-file reader and
// `driftlab simulate --effect` (devices/device_file.hpp), `driftlab devices describe`, the effect
// plugins' reports (plugins/effects) and `driftlab discrepancy --update-device`, so that a named
// effect pasted into a device file means the same thing to the simulator.
//
// SI values: s, K (temperature differences), rad/s, rad/s per K/s, rad, 1/K^i.
// Effects that the workflow can name but a device file cannot hold (effect/mode_split_drift: the
// device file's physics already is the resonator's temperature response) are not listed.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "framework/plugin.hpp"

namespace driftlab {

struct EffectKeyInfo {
  std::string key;     // device-file key, e.g. "height_dph"
  std::string unit;    // its unit, e.g. "deg/h"
  double to_si = 1.0;  // SI value = file value * to_si
  std::string doc;
  bool list = false;      // a list of numbers (one per polynomial power)
  bool positive = false;  // must be > 0
};

struct EffectInfo {
  std::string name;                 // e.g. "thermal_lag"; the plugin is effect/<name>
  std::string doc;                  // one line: what it adds to the model
  std::vector<EffectKeyInfo> keys;  // all required in a device file
};

const std::vector<EffectInfo>& effect_catalogue();

// nullptr when `name` is not in the catalogue.
const EffectInfo* find_effect_info(std::string_view name);

// The entry of `name`; throws std::logic_error when absent (a programming error, not bad input).
const EffectInfo& effect_info(std::string_view name);

// Key `key` of effect `effect` with SI values converted to the file unit (for Effect::describe).
// Throws std::logic_error when the effect or the key is not in the catalogue.
EffectValue effect_value(std::string_view effect, std::string_view key, std::vector<double> si_values);

}  // namespace driftlab
