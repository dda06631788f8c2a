// Reading the small YAML formats (pipelines, parameters, device files, profiles) safely: the rules
// every loader shares live here, once.
//   - a syntax error is a ConfigError with file and line;
//   - a key repeated in one mapping is a ConfigError naming file, line and key (yaml-cpp would
//     silently keep the first value);
//   - a document that expands (through aliases) to more than kMaxYamlNodes nodes is refused;
//   - values of the wrong shape (a list or map where text belongs) are reported by the loaders
//     through scalar_text(), never by an escaping yaml-cpp conversion exception.
#pragma once

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "framework/error.hpp"

namespace driftlab {

inline constexpr std::size_t kMaxYamlNodes = 200000;

// 1-based line of a node, 0 when unknown.
int yaml_line(const YAML::Node& node);

// Parses and checks the text (rules above). Throws ConfigError; with `problems`, repeated keys are
// appended there instead, so a loader can report them together with its own findings.
YAML::Node load_yaml_checked(const std::string& text, const std::string& file,
                             std::vector<Diagnostic>* problems = nullptr);
// Reads a YAML file (framework/regular_file.hpp read_config_text: a regular file or "-", size-capped;
// `what` names it in errors, e.g. "device file") and parses and checks it.
YAML::Node load_yaml_file(const std::filesystem::path& path, const std::string& what);

// Appends a problem for every repeated key in every mapping under `node`.
void find_duplicate_keys(const YAML::Node& node, const std::string& file, std::vector<Diagnostic>& problems);

// The text of a scalar node; nullopt for a sequence, a map, null or undefined.
std::optional<std::string> scalar_text(const YAML::Node& node);

// "a map", "a list", "null", or the scalar quoted (at most 80 bytes): for "expected X, got Y".
std::string yaml_shape(const YAML::Node& node);

}  // namespace driftlab
