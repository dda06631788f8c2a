#include "framework/params.hpp"

#include <cmath>
#include <limits>
#include <charconv>

#include "framework/error.hpp"

namespace driftlab {
namespace {

// Shortest text that reads back to the same double.
std::string format_number(double v) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, res.ptr);
}

template <class T>
const T& get_as(const ParamValues& values, const std::string& key, const char* expected) {
  const auto& v = values.at(key);
  if (const auto* p = std::get_if<T>(&v)) return *p;
  throw ConfigError({"", 0, key}, std::string("parameter is not ") + expected);
}

std::string type_mismatch(const ParamSpec& spec, const ParamValue& value) {
  const bool ok = [&] {
    switch (spec.type) {
      case ParamType::Integer:
        return std::holds_alternative<std::int64_t>(value);
      case ParamType::Real:
        return std::holds_alternative<double>(value) || std::holds_alternative<std::int64_t>(value);
      case ParamType::Boolean:
        return std::holds_alternative<bool>(value);
      case ParamType::Text:
      case ParamType::Choice:
        return std::holds_alternative<std::string>(value);
      case ParamType::RealList:
        return std::holds_alternative<std::vector<double>>(value);
      case ParamType::Plugin:
        return std::holds_alternative<std::shared_ptr<const PluginSpec>>(value);
    }
    return false;
  }();
  return ok ? "" : "expected " + to_string(spec.type) + ", got " + format_value(value);
}

std::string bound_violation(const ParamSpec& spec, double v) {
  if (!std::isfinite(v)) return "expected a finite number, got " + format_number(v);
  const bool below = spec.min && (spec.min_exclusive ? v <= *spec.min : v < *spec.min);
  const bool above = spec.max && (spec.max_exclusive ? v >= *spec.max : v > *spec.max);
  if (below || above) return "value " + format_number(v) + " is out of range: must be " + spec.constraint_text();
  return "";
}

}  // namespace

std::string to_string(ParamType type) {
  switch (type) {
    case ParamType::Integer:
      return "integer";
    case ParamType::Real:
      return "real";
    case ParamType::Boolean:
      return "boolean";
    case ParamType::Text:
      return "text";
    case ParamType::Choice:
      return "choice";
    case ParamType::RealList:
      return "list of reals";
    case ParamType::Plugin:
      return "plugin";
  }
  return "?";
}

const ParamValue& ParamValues::at(const std::string& key) const {
  auto it = values_.find(key);
  if (it == values_.end()) throw ConfigError({"", 0, key}, "parameter has no value");
  return it->second;
}

std::int64_t ParamValues::integer(const std::string& key) const {
  return get_as<std::int64_t>(*this, key, "an integer");
}

double ParamValues::real(const std::string& key) const {
  const auto& v = at(key);
  if (const auto* i = std::get_if<std::int64_t>(&v)) return static_cast<double>(*i);
  return get_as<double>(*this, key, "a real number");
}

bool ParamValues::boolean(const std::string& key) const { return get_as<bool>(*this, key, "a boolean"); }

const std::string& ParamValues::text(const std::string& key) const { return get_as<std::string>(*this, key, "text"); }

const std::vector<double>& ParamValues::reals(const std::string& key) const {
  return get_as<std::vector<double>>(*this, key, "a list of reals");
}

const PluginSpec& ParamValues::plugin(const std::string& key) const {
  return *get_as<std::shared_ptr<const PluginSpec>>(*this, key, "a nested plugin");
}

ParamSpec& ParamSpec::must(std::string doc_text, std::function<std::string(const ParamValue&)> check_fn,
                           ParamValue counterexample) {
  predicate_doc = std::move(doc_text);
  predicate = std::move(check_fn);
  predicate_counterexample = std::move(counterexample);
  return *this;
}

std::string ParamSpec::constraint_text() const {
  std::string text;
  if (type == ParamType::Choice) {
    text = "one of:";
    for (const auto& c : choices) text += " " + c;
  } else if (type == ParamType::Plugin) {
    text = "a " + plugin_kind + " plugin";
  } else if (min && max) {
    text = std::string(min_exclusive ? "(" : "[") + format_number(*min) + ", " + format_number(*max) +
           (max_exclusive ? ")" : "]");
  } else if (min) {
    text = std::string(min_exclusive ? "> " : ">= ") + format_number(*min);
  } else if (max) {
    text = std::string(max_exclusive ? "< " : "<= ") + format_number(*max);
  }
  if (!predicate_doc.empty()) text += (text.empty() ? "" : "; ") + predicate_doc;
  return text.empty() ? "any" : text;
}

std::string ParamSpec::check(const ParamValue& value) const {
  if (auto msg = type_mismatch(*this, value); !msg.empty()) return msg;
  switch (type) {
    case ParamType::Integer:
      if (auto msg = bound_violation(*this, static_cast<double>(std::get<std::int64_t>(value))); !msg.empty())
        return msg;
      break;
    case ParamType::Real: {
      const double v = std::holds_alternative<double>(value) ? std::get<double>(value)
                                                             : static_cast<double>(std::get<std::int64_t>(value));
      if (auto msg = bound_violation(*this, v); !msg.empty()) return msg;
      break;
    }
    case ParamType::RealList:
      for (double v : std::get<std::vector<double>>(value))
        if (auto msg = bound_violation(*this, v); !msg.empty()) return "list element: " + msg;
      break;
    case ParamType::Choice: {
      const auto& s = std::get<std::string>(value);
      bool found = false;
      for (const auto& c : choices) found = found || c == s;
      if (!found) return "'" + s + "' is not " + constraint_text();
      break;
    }
    default:
      break;
  }
  if (predicate)
    if (auto msg = predicate(value); !msg.empty()) return msg;
  return "";
}

namespace param {

ParamSpec integer(std::string key, std::int64_t def, std::string unit, std::string doc) {
  ParamSpec s;
  s.key = std::move(key), s.type = ParamType::Integer, s.default_value = def, s.unit = std::move(unit);
  s.doc = std::move(doc);
  return s;
}

ParamSpec real(std::string key, double def, std::string unit, std::string doc) {
  ParamSpec s;
  s.key = std::move(key), s.type = ParamType::Real, s.default_value = def, s.unit = std::move(unit);
  s.doc = std::move(doc);
  return s;
}

ParamSpec boolean(std::string key, bool def, std::string doc) {
  ParamSpec s;
  s.key = std::move(key), s.type = ParamType::Boolean, s.default_value = def, s.doc = std::move(doc);
  return s;
}

ParamSpec text(std::string key, std::string def, std::string doc) {
  ParamSpec s;
  s.key = std::move(key), s.type = ParamType::Text, s.default_value = std::move(def), s.doc = std::move(doc);
  return s;
}

ParamSpec choice(std::string key, std::string def, std::vector<std::string> choices, std::string doc) {
  ParamSpec s;
  s.key = std::move(key), s.type = ParamType::Choice, s.default_value = std::move(def);
  s.choices = std::move(choices), s.doc = std::move(doc);
  return s;
}

ParamSpec reals(std::string key, std::vector<double> def, std::string unit, std::string doc) {
  ParamSpec s;
  s.key = std::move(key), s.type = ParamType::RealList, s.default_value = std::move(def);
  s.unit = std::move(unit), s.doc = std::move(doc);
  return s;
}

ParamSpec nested(std::string key, std::string kind, std::string default_plugin, std::string doc) {
  ParamSpec s;
  s.key = std::move(key), s.type = ParamType::Plugin, s.plugin_kind = std::move(kind);
  s.default_value = std::make_shared<const PluginSpec>(PluginSpec{std::move(default_plugin), {}});
  s.unit = "", s.doc = std::move(doc);
  return s;
}

ParamSpec seed() {
  return integer("seed", 1, "1", "random seed; pipelines fill it from the pipeline seed when absent").at_least(0);
}

}  // namespace param

const ParamSpec* ParamTable::find(const std::string& key) const {
  for (const auto& p : params)
    if (p.key == key) return &p;
  return nullptr;
}

std::vector<std::string> ParamTable::keys() const {
  std::vector<std::string> out;
  for (const auto& p : params) out.push_back(p.key);
  return out;
}

std::string format_value(const ParamValue& value) {
  struct Visitor {
    std::string operator()(std::int64_t v) const { return std::to_string(v); }
    std::string operator()(double v) const { return format_number(v); }
    std::string operator()(bool v) const { return v ? "true" : "false"; }
    std::string operator()(const std::string& v) const { return v.empty() ? "\"\"" : v; }
    std::string operator()(const std::vector<double>& v) const {
      std::string s = "[";
      for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + format_number(v[i]);
      return s + "]";
    }
    std::string operator()(const std::shared_ptr<const PluginSpec>& v) const {
      return v ? "{plugin: " + v->name + "}" : "{}";
    }
  };
  return std::visit(Visitor{}, value);
}

std::vector<InvalidExample> invalid_examples(const ParamSpec& spec) {
  std::vector<InvalidExample> out;
  const auto numeric = [&](double v) -> ParamValue {
    if (spec.type == ParamType::Integer) return static_cast<std::int64_t>(std::floor(v));
    if (spec.type == ParamType::RealList) return std::vector<double>{v};
    return v;
  };
  const bool is_numeric =
      spec.type == ParamType::Integer || spec.type == ParamType::Real || spec.type == ParamType::RealList;
  if (is_numeric && spec.min) {
    const double below = spec.min_exclusive ? *spec.min : *spec.min - 1.0;
    out.push_back({numeric(below), "below the minimum"});
  }
  if (is_numeric && spec.max) {
    const double above = spec.max_exclusive ? *spec.max : *spec.max + 1.0;
    out.push_back({numeric(spec.type == ParamType::Integer ? std::ceil(above) : above), "above the maximum"});
  }
  if (spec.type == ParamType::Real) out.push_back({std::numeric_limits<double>::quiet_NaN(), "not finite"});
  if (spec.type == ParamType::Choice) out.push_back({std::string("no_such_choice"), "not a listed choice"});
  if (spec.predicate_counterexample) out.push_back({*spec.predicate_counterexample, "breaks: " + spec.predicate_doc});
  if (spec.type == ParamType::Text || spec.type == ParamType::Choice)
    out.push_back({std::int64_t{7}, "wrong type"});
  else
    out.push_back({std::string("not_a_value"), "wrong type"});
  return out;
}

}  // namespace driftlab
