#include "framework/yaml_io.hpp"

#include <set>

#include "framework/regular_file.hpp"

namespace driftlab {
namespace {

struct DuplicateFinder {
  const std::string& file;
  std::vector<Diagnostic>& problems;
  std::size_t visited = 0;

  void walk(const YAML::Node& node, const std::string& path) {
    if (++visited > kMaxYamlNodes)
      throw ConfigError({file, yaml_line(node), path}, "document too large: more than " +
                                                           std::to_string(kMaxYamlNodes) +
                                                           " YAML nodes (after expanding aliases); refused");
    if (node.IsMap()) {
      std::set<std::string> seen;
      for (const auto& kv : node) {
        const auto key = scalar_text(kv.first);
        const std::string label = key ? *key : "?";
        const std::string child = path.empty() ? label : path + "." + label;
        if (key && !seen.insert(*key).second)
          problems.push_back(
              {{file, yaml_line(kv.first), child}, "duplicate key (each key may appear once in a mapping)"});
        walk(kv.second, child);
      }
    } else if (node.IsSequence()) {
      std::size_t i = 0;
      for (const auto& item : node) walk(item, path + "[" + std::to_string(i++) + "]");
    }
  }
};

}  // namespace

int yaml_line(const YAML::Node& node) { return node.IsDefined() && node.Mark().line >= 0 ? node.Mark().line + 1 : 0; }

void find_duplicate_keys(const YAML::Node& node, const std::string& file, std::vector<Diagnostic>& problems) {
  DuplicateFinder finder{file, problems};
  finder.walk(node, "");
}

YAML::Node load_yaml_checked(const std::string& text, const std::string& file, std::vector<Diagnostic>* problems) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw ConfigError({file, e.mark.line >= 0 ? e.mark.line + 1 : 0, ""}, "YAML syntax error: " + e.msg);
  } catch (const YAML::Exception& e) {
    throw ConfigError({file, e.mark.line >= 0 ? e.mark.line + 1 : 0, ""}, "YAML syntax error: " + e.msg);
  }
  std::vector<Diagnostic> found;
  find_duplicate_keys(root, file, found);
  if (problems)
    problems->insert(problems->end(), found.begin(), found.end());
  else if (!found.empty())
    throw ConfigError(found);
  return root;
}

YAML::Node load_yaml_file(const std::filesystem::path& path, const std::string& what) {
  return load_yaml_checked(read_config_text(path, what), input_name(path));
}

std::optional<std::string> scalar_text(const YAML::Node& node) {
  if (!node.IsDefined() || !node.IsScalar()) return std::nullopt;
  return node.Scalar();
}

std::string yaml_shape(const YAML::Node& node) {
  if (!node.IsDefined()) return "nothing";
  if (node.IsMap()) return "a map";
  if (node.IsSequence()) return "a list";
  if (node.IsNull()) return "null";
  return quoted_excerpt(node.Scalar());
}

}  // namespace driftlab
