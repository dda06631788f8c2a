#include "devices/yaml_fields.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>

#include "framework/yaml_io.hpp"

namespace driftlab::devices {
namespace {

std::string joined(const std::vector<std::string>& items) {
  std::string s;
  for (const auto& i : items) s += (s.empty() ? "" : ", ") + i;
  return s;
}

std::string bounds_text(const Bounds& b) {
  std::ostringstream out;
  if (b.min && b.max)
    out << "in " << (b.min_exclusive ? "(" : "[") << *b.min << ", " << *b.max << "]";
  else if (b.min)
    out << (b.min_exclusive ? "> " : ">= ") << *b.min;
  else if (b.max)
    out << "<= " << *b.max;
  return out.str();
}

bool within(const Bounds& b, double v) {
  if (b.min && (b.min_exclusive ? !(v > *b.min) : !(v >= *b.min))) return false;
  if (b.max && !(v <= *b.max)) return false;
  return true;
}

}  // namespace

int YamlFields::line_of(const YAML::Node& node) {
  return node.IsDefined() && node.Mark().line >= 0 ? node.Mark().line + 1 : 0;
}

std::string YamlFields::join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

void YamlFields::problem(const YAML::Node& at, const std::string& field, const std::string& message) {
  problems_.push_back({{file_, line_of(at), field}, message});
}

bool YamlFields::map(const YAML::Node& node, const std::string& path, const std::vector<std::string>& allowed) {
  if (!node.IsMap()) {
    problem(node, path, "expected a mapping of keys (" + joined(allowed) + ")");
    return false;
  }
  for (const auto& kv : node) {
    const std::string key = kv.first.Scalar();
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end())
      problem(kv.first, join(path, key), "unknown key; expected one of: " + joined(allowed));
  }
  return true;
}

YAML::Node YamlFields::child(const YAML::Node& parent, const std::string& path, const std::string& key, bool required) {
  if (!parent.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
  for (const auto& kv : parent)
    if (kv.first.Scalar() == key) return kv.second;
  if (required) problem(parent, join(path, key), "missing required key");
  return YAML::Node(YAML::NodeType::Undefined);
}

std::optional<double> YamlFields::number(const YAML::Node& parent, const std::string& path, const std::string& key,
                                         bool required, Bounds bounds) {
  const YAML::Node node = child(parent, path, key, required);
  if (!node.IsDefined()) return std::nullopt;
  const std::string field = join(path, key);
  double value = 0.0;
  try {
    if (!node.IsScalar()) throw YAML::BadConversion(node.Mark());
    value = node.as<double>();
  } catch (const YAML::BadConversion&) {
    problem(node, field, "expected a number, got " + yaml_shape(node));
    return std::nullopt;
  }
  if (!std::isfinite(value)) {
    problem(node, field, "must be finite, got " + yaml_shape(node));
    return std::nullopt;
  }
  if (!within(bounds, value)) {
    problem(node, field, "must be " + bounds_text(bounds) + ", got " + quoted_excerpt(node.Scalar(), 40));
    return std::nullopt;
  }
  return value;
}

double YamlFields::number_or(const YAML::Node& parent, const std::string& path, const std::string& key, double fallback,
                             Bounds bounds) {
  return number(parent, path, key, false, bounds).value_or(fallback);
}

std::optional<std::uint64_t> YamlFields::whole_number(const YAML::Node& parent, const std::string& path,
                                                      const std::string& key, bool required, std::uint64_t max) {
  const YAML::Node node = child(parent, path, key, required);
  if (!node.IsDefined()) return std::nullopt;
  const std::string expected = "expected a whole number from 0 to " + std::to_string(max) + ", got ";
  if (!node.IsScalar()) {
    problem(node, join(path, key), expected + yaml_shape(node));
    return std::nullopt;
  }
  const std::string& text = node.Scalar();
  std::uint64_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  const bool digits = !text.empty() && text.find_first_not_of("0123456789") == std::string::npos;
  if (!digits || error != std::errc() || end != text.data() + text.size() || value > max) {
    problem(node, join(path, key), expected + quoted_excerpt(text, 40));
    return std::nullopt;
  }
  return value;
}

std::uint64_t YamlFields::whole_number_or(const YAML::Node& parent, const std::string& path, const std::string& key,
                                          std::uint64_t fallback, std::uint64_t max) {
  return whole_number(parent, path, key, false, max).value_or(fallback);
}

std::optional<std::string> YamlFields::text(const YAML::Node& parent, const std::string& path, const std::string& key,
                                            bool required) {
  const YAML::Node node = child(parent, path, key, required);
  if (!node.IsDefined()) return std::nullopt;
  if (!node.IsScalar() || node.Scalar().empty()) {
    problem(node, join(path, key), "expected non-empty text, got " + yaml_shape(node));
    return std::nullopt;
  }
  return node.Scalar();
}

std::optional<std::vector<double>> YamlFields::numbers(const YAML::Node& parent, const std::string& path,
                                                       const std::string& key, bool required) {
  const YAML::Node node = child(parent, path, key, required);
  if (!node.IsDefined()) return std::nullopt;
  const std::string field = join(path, key);
  std::vector<double> values;
  auto add = [&](const YAML::Node& item) {
    try {
      if (!item.IsScalar()) throw YAML::BadConversion(item.Mark());
      const double v = item.as<double>();
      if (!std::isfinite(v)) throw YAML::BadConversion(item.Mark());
      values.push_back(v);
      return true;
    } catch (const YAML::BadConversion&) {
      problem(item, field, "expected a list of finite numbers, got " + yaml_shape(item));
      return false;
    }
  };
  if (node.IsSequence()) {
    for (const auto& item : node)
      if (!add(item)) return std::nullopt;
  } else if (!add(node)) {
    return std::nullopt;
  }
  return values;
}

}  // namespace driftlab::devices
