// Parameters between YAML / command lines and validated ParamValues, driven by each plugin's
// ParamTable. Nested plugins are written `key: {plugin: kind/name, params: {...}}` (or just
// `key: kind/name`) and resolved recursively through the registry.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "framework/error.hpp"
#include "framework/params.hpp"

namespace driftlab {

class Registry;

// Converts, fills defaults and validates `node` (a map, or null for all defaults) against the
// table of `plugin`. Every problem is appended to `problems` (file, 1-based line, key path under
// `key_prefix`); unknown keys list the valid ones. Returns the values that could be resolved.
ParamValues resolve_params(const Registry& registry, const std::string& plugin, const YAML::Node& node,
                           const std::string& file, const std::string& key_prefix, std::vector<Diagnostic>& problems);

// Resolves `key=value` assignments (value parsed as YAML, so `optimizer={plugin: optimizer/ga}`
// works). Throws ConfigError listing every problem.
ParamValues params_from_assignments(const Registry& registry, const std::string& plugin,
                                    const std::vector<std::string>& assignments);

// The effective parameters as YAML: every key, defaults included, nested plugins expanded.
YAML::Node params_to_yaml(const Registry& registry, const std::string& plugin, const ParamValues& values);

}  // namespace driftlab
