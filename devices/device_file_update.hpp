// Adds effects to a device file's text, keeping everything else as it was (comments, order,
// spacing): `driftlab discrepancy --update-device` writes what it named back into a device file.
//
// The effects go under the top-level `effects:` key, one flow-style line per effect
// (`  hysteresis: {height_dph: 214.7, width_c: 2.09}`) in the catalogue's keys and units
// (framework/effect_catalogue.hpp). An effect the file already lists is replaced in place; others
// are appended to the section. Without an `effects:` section, one is appended at the end of the
// file after a comment line `note`. An `effects:` section written in flow style on one line
// (`effects: {thermal_lag: {tau_s: 400}}`) is rewritten in block style with its entries kept.
// The result is parsed as a device file before it is returned (ConfigError naming `file` if not).
#pragma once

#include <string>
#include <vector>

#include "framework/plugin.hpp"

namespace driftlab::devices {

struct NamedEffect {
  std::string name;                 // catalogue name, e.g. "hysteresis"
  std::vector<EffectValue> values;  // every catalogue key of the effect, in its unit
};

// Throws ConfigError when an effect is not in the catalogue or lacks a key, or when the result
// does not load as a device file.
std::string add_effects_to_device_text(const std::string& text, const std::string& file,
                                       const std::vector<NamedEffect>& effects, const std::string& note);

}  // namespace driftlab::devices
