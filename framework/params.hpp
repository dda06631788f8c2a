// Plugin parameters, declared once as data.
//
// Each plugin declares a ParamTable: one ParamSpec per parameter (key = YAML key, type, default,
// unit, constraint, one-line doc) plus cross-parameter rules. Everything else is derived from the
// table: YAML loading and validation (params_io.hpp), `driftlab plugins describe`, docs/plugins.md's
// plugin table and the generated invalid-value tests (invalid_examples()).
//
//   ParamTable table{{
//       param::real("sd_threshold", 0.2, "1", "Cauchy SD stopping threshold").greater_than(0),
//       param::integer("max_sifts", 50, "1", "cap on sifting iterations per IMF").at_least(1),
//       param::choice("end_policy", "mirror", {"mirror", "linear"}, "envelope end treatment"),
//       param::nested("optimizer", "optimizer", "optimizer/ga", "tunes sigma and centres"),
//   }};
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace driftlab {

enum class ParamType { Integer, Real, Boolean, Text, Choice, RealList, Plugin };
std::string to_string(ParamType type);

struct PluginSpec;
class ParamValues;

// A parameter value. Integer parameters hold int64, Real hold double, Text and Choice hold string,
// RealList holds a vector, Plugin holds a nested plugin spec.
using ParamValue =
    std::variant<std::int64_t, double, bool, std::string, std::vector<double>, std::shared_ptr<const PluginSpec>>;

// Validated values of one plugin's parameters, every declared key present.
class ParamValues {
 public:
  void set(const std::string& key, ParamValue value) { values_[key] = std::move(value); }
  bool has(const std::string& key) const { return values_.count(key) != 0; }
  const ParamValue& at(const std::string& key) const;  // throws ConfigError when absent

  std::int64_t integer(const std::string& key) const;
  double real(const std::string& key) const;  // Integer values convert
  bool boolean(const std::string& key) const;
  const std::string& text(const std::string& key) const;  // Text and Choice
  const std::vector<double>& reals(const std::string& key) const;
  const PluginSpec& plugin(const std::string& key) const;

  const std::map<std::string, ParamValue>& all() const { return values_; }

 private:
  std::map<std::string, ParamValue> values_;
};

// A nested plugin: `{plugin: optimizer/ga, params: {...}}`.
struct PluginSpec {
  std::string name;
  ParamValues params;
};

// A cross-parameter rule: `holds` returns false when the combination is invalid.
struct CrossRule {
  std::string description;        // e.g. "min_imfs <= max_imfs"
  std::vector<std::string> keys;  // parameters it involves, named in the error
  std::function<bool(const ParamValues&)> holds;
};

struct ParamSpec {
  std::string key;
  ParamType type = ParamType::Real;
  ParamValue default_value;
  std::string unit = "1";
  std::string doc;
  std::optional<double> min, max;  // numeric bounds (Integer, Real, each RealList element)
  bool min_exclusive = false, max_exclusive = false;
  std::vector<std::string> choices;  // Choice
  std::string plugin_kind;           // Plugin: required kind of the nested plugin
  // Extra predicate; returns an error message or empty string when the value is fine.
  std::function<std::string(const ParamValue&)> predicate;
  std::string predicate_doc;  // what the predicate demands, for describe
  // A value that breaks the predicate (used by the generated invalid-value test).
  std::optional<ParamValue> predicate_counterexample;

  // Fluent constraint setters.
  ParamSpec& at_least(double v) {
    min = v;
    min_exclusive = false;
    return *this;
  }
  ParamSpec& greater_than(double v) {
    min = v;
    min_exclusive = true;
    return *this;
  }
  ParamSpec& at_most(double v) {
    max = v;
    max_exclusive = false;
    return *this;
  }
  ParamSpec& less_than(double v) {
    max = v;
    max_exclusive = true;
    return *this;
  }
  ParamSpec& must(std::string doc_text, std::function<std::string(const ParamValue&)> check, ParamValue counterexample);

  // Human-readable constraint, e.g. "> 0", "in [1, 50]", "one of: mirror, linear".
  std::string constraint_text() const;
  // Returns an error message, or empty when the value satisfies type and constraint.
  std::string check(const ParamValue& value) const;
};

namespace param {
ParamSpec integer(std::string key, std::int64_t def, std::string unit, std::string doc);
ParamSpec real(std::string key, double def, std::string unit, std::string doc);
ParamSpec boolean(std::string key, bool def, std::string doc);
ParamSpec text(std::string key, std::string def, std::string doc);
ParamSpec choice(std::string key, std::string def, std::vector<std::string> choices, std::string doc);
ParamSpec reals(std::string key, std::vector<double> def, std::string unit, std::string doc);
// A nested plugin of `kind`, defaulting to `default_plugin` with its own defaults.
ParamSpec nested(std::string key, std::string kind, std::string default_plugin, std::string doc);
// The conventional seed parameter. Pipelines fill it from the pipeline seed when it is absent.
ParamSpec seed();
}  // namespace param

struct ParamTable {
  std::vector<ParamSpec> params;
  std::vector<CrossRule> rules;

  const ParamSpec* find(const std::string& key) const;
  std::vector<std::string> keys() const;
};

// Renders a value for messages, describe and effective pipelines (YAML flow style).
std::string format_value(const ParamValue& value);

// Values that must be rejected for this parameter, with a short reason each; at least one for
// every declared constraint and one of the wrong type. Drives the conformance test.
struct InvalidExample {
  ParamValue value;
  std::string why;
};
std::vector<InvalidExample> invalid_examples(const ParamSpec& spec);

}  // namespace driftlab
