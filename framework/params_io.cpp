#include "framework/params_io.hpp"

#include <cmath>
#include <set>

#include "framework/registry.hpp"
#include "framework/yaml_io.hpp"

namespace driftlab {
namespace {

int line_of(const YAML::Node& node) { return yaml_line(node); }

std::string joined(const std::vector<std::string>& items) {
  std::string s;
  for (const auto& i : items) s += (s.empty() ? "" : ", ") + i;
  return s;
}

// Converts one YAML value to the declared type; empty message on success.
std::string convert(const ParamSpec& spec, const YAML::Node& node, ParamValue& out) {
  try {
    switch (spec.type) {
      case ParamType::Integer: {
        if (!node.IsScalar()) return "expected an integer, got " + yaml_shape(node);
        const double d = node.as<double>();
        if (std::floor(d) != d || std::abs(d) > 9.0e15) return "expected an integer, got '" + node.Scalar() + "'";
        out = static_cast<std::int64_t>(d);
        return "";
      }
      case ParamType::Real: {
        if (!node.IsScalar()) return "expected a real number, got " + yaml_shape(node);
        const double d = node.as<double>();
        if (!std::isfinite(d)) return "expected a finite real number, got " + yaml_shape(node);
        out = d;
        return "";
      }
      case ParamType::Boolean:
        if (!node.IsScalar()) return "expected true or false, got " + yaml_shape(node);
        out = node.as<bool>();
        return "";
      case ParamType::Text:
      case ParamType::Choice:
        if (!node.IsScalar()) return "expected text, got " + yaml_shape(node);
        out = node.as<std::string>();
        return "";
      case ParamType::RealList: {
        std::vector<double> v;
        if (node.IsScalar()) {
          v.push_back(node.as<double>());
        } else if (node.IsSequence()) {
          for (const auto& e : node) {
            if (!e.IsScalar()) return "expected a list of real numbers, got " + yaml_shape(e) + " in it";
            v.push_back(e.as<double>());
          }
        } else {
          return "expected a list of real numbers, got " + yaml_shape(node);
        }
        for (const double d : v)
          if (!std::isfinite(d)) return "expected finite real numbers, got " + yaml_shape(node);
        out = std::move(v);
        return "";
      }
      case ParamType::Plugin:
        return "nested plugins are converted separately";
    }
  } catch (const YAML::Exception&) {
    return "expected " + to_string(spec.type) + ", got " + yaml_shape(node);
  }
  return "unsupported type";
}

ParamValue resolve_nested(const Registry& registry, const ParamSpec& spec, const YAML::Node& node,
                          const std::string& file, const std::string& path, std::vector<Diagnostic>& problems) {
  std::string name = std::get<std::shared_ptr<const PluginSpec>>(spec.default_value)->name;
  YAML::Node params;
  if (node && !node.IsNull()) {
    if (node.IsScalar()) {
      name = node.Scalar();
    } else if (node.IsMap()) {
      for (const auto& kv : node) {
        const auto k = scalar_text(kv.first).value_or("?");
        if (k == "plugin") {
          if (const auto text = scalar_text(kv.second)) {
            name = *text;
          } else {
            problems.push_back(
                {{file, line_of(kv.second), path + ".plugin"},
                 "expected a plugin name (" + spec.plugin_kind + "/NAME), got " + yaml_shape(kv.second)});
            return std::make_shared<const PluginSpec>(PluginSpec{name, {}});
          }
        } else if (k == "params") {
          params = kv.second;
        } else
          problems.push_back({{file, line_of(kv.first), path + "." + k}, "unknown key (expected plugin, params)"});
      }
    } else {
      problems.push_back(
          {{file, line_of(node), path}, "expected {plugin: " + spec.plugin_kind + "/NAME, params: {...}}"});
    }
  }
  const int line = node ? line_of(node) : 0;
  if (!registry.contains(name)) {
    std::string known;
    for (const auto* info : registry.list(spec.plugin_kind)) known += (known.empty() ? "" : ", ") + info->name;
    problems.push_back({{file, line, path},
                        "unknown plugin '" + name + "' (known " + spec.plugin_kind +
                            " plugins: " + (known.empty() ? "none" : known) + ")"});
    return std::make_shared<const PluginSpec>(PluginSpec{name, {}});
  }
  if (registry.info(name).kind() != spec.plugin_kind) {
    problems.push_back({{file, line, path}, "plugin '" + name + "' is not a " + spec.plugin_kind + " plugin"});
  }
  auto values = resolve_params(registry, name, params, file, path + ".params", problems);
  return std::make_shared<const PluginSpec>(PluginSpec{name, std::move(values)});
}

}  // namespace

ParamValues resolve_params(const Registry& registry, const std::string& plugin, const YAML::Node& node,
                           const std::string& file, const std::string& key_prefix, std::vector<Diagnostic>& problems) {
  const auto& table = registry.info(plugin).params;
  const auto path_of = [&](const std::string& key) { return key_prefix.empty() ? key : key_prefix + "." + key; };
  ParamValues values;
  const std::size_t problems_before = problems.size();

  if (node && !node.IsNull() && !node.IsMap()) {
    problems.push_back({{file, line_of(node), key_prefix}, "expected a map of parameters"});
  } else if (node) {
    for (const auto& kv : node) {
      const auto key = scalar_text(kv.first).value_or(yaml_shape(kv.first));
      if (!table.find(key))
        problems.push_back({{file, line_of(kv.first), path_of(key)},
                            "unknown parameter of " + plugin + " (valid: " + joined(table.keys()) + ")"});
    }
  }
  for (const auto& spec : table.params) {
    const YAML::Node given = (node && node.IsMap()) ? node[spec.key] : YAML::Node();
    const int line = given ? line_of(given) : (node ? line_of(node) : 0);
    ParamValue value = spec.default_value;
    if (spec.type == ParamType::Plugin) {
      value = resolve_nested(registry, spec, given, file, path_of(spec.key), problems);
    } else if (given && !given.IsNull()) {
      if (auto msg = convert(spec, given, value); !msg.empty()) {
        problems.push_back({{file, line, path_of(spec.key)}, msg});
        continue;
      }
    }
    if (auto msg = spec.check(value); !msg.empty()) problems.push_back({{file, line, path_of(spec.key)}, msg});
    values.set(spec.key, std::move(value));
  }
  if (problems.size() == problems_before) {
    for (const auto& rule : table.rules)
      if (!rule.holds(values)) {
        std::string keys;
        for (const auto& k : rule.keys) keys += (keys.empty() ? "" : ",") + path_of(k);
        problems.push_back({{file, node ? line_of(node) : 0, keys}, "violates rule: " + rule.description});
      }
  }
  return values;
}

ParamValues params_from_assignments(const Registry& registry, const std::string& plugin,
                                    const std::vector<std::string>& assignments) {
  YAML::Node node(YAML::NodeType::Map);
  std::vector<Diagnostic> problems;
  std::set<std::string> given;
  for (const auto& a : assignments) {
    const auto eq = a.find('=');
    if (eq == std::string::npos || eq == 0) {
      problems.push_back({{"--set", 0, a}, "expected key=value"});
      continue;
    }
    const std::string key = a.substr(0, eq);
    if (!given.insert(key).second) {
      problems.push_back({{"--set", 0, key}, "given twice; each parameter may be set once"});
      continue;
    }
    try {
      node[key] = load_yaml_checked(a.substr(eq + 1), "--set " + key);
    } catch (const ConfigError& e) {
      for (const auto& p : e.problems()) problems.push_back(p);
    }
  }
  auto values = resolve_params(registry, plugin, node, "--set", "", problems);
  if (!problems.empty()) throw ConfigError(problems);
  return values;
}

YAML::Node params_to_yaml(const Registry& registry, const std::string& plugin, const ParamValues& values) {
  YAML::Node out(YAML::NodeType::Map);
  for (const auto& spec : registry.info(plugin).params.params) {
    if (!values.has(spec.key)) continue;
    const auto& v = values.at(spec.key);
    if (const auto* nested = std::get_if<std::shared_ptr<const PluginSpec>>(&v)) {
      YAML::Node n(YAML::NodeType::Map);
      n["plugin"] = (*nested)->name;
      n["params"] = params_to_yaml(registry, (*nested)->name, (*nested)->params);
      out[spec.key] = n;
    } else if (const auto* s = std::get_if<std::string>(&v)) {
      out[spec.key] = *s;
    } else {
      out[spec.key] = YAML::Load(format_value(v));
    }
  }
  return out;
}

}  // namespace driftlab
