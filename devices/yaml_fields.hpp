// Line-aware reading of the small YAML formats in devices/ (device files, chamber/rate profiles).
// Every problem is appended as a Diagnostic (file, 1-based line, dotted key path) so a loader can
// collect all of them and throw one ConfigError.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "framework/error.hpp"
#include "framework/units.hpp"
#include "framework/yaml_io.hpp"  // load_yaml_checked, load_yaml_file: parsing with the shared rules

namespace driftlab::devices {

struct Bounds {
  std::optional<double> min, max;
  bool min_exclusive = false;
  static Bounds positive() { return {0.0, std::nullopt, true}; }
  static Bounds non_negative() { return {0.0, std::nullopt, false}; }
  static Bounds between(double lo, double hi) { return {lo, hi, false}; }
  static Bounds absolute_temperature_c() { return between(kMinTemperatureC, kMaxTemperatureC); }
};

class YamlFields {
 public:
  YamlFields(std::string file, std::vector<Diagnostic>& problems) : file_(std::move(file)), problems_(problems) {}

  static int line_of(const YAML::Node& node);
  static std::string join(const std::string& path, const std::string& key);
  const std::string& file() const { return file_; }

  void problem(const YAML::Node& at, const std::string& field, const std::string& message);

  // True when `node` is a map; reports keys not in `allowed` (listing the allowed ones).
  bool map(const YAML::Node& node, const std::string& path, const std::vector<std::string>& allowed);
  // A map's child; reports "missing required key" at the parent's line when required and absent.
  YAML::Node child(const YAML::Node& parent, const std::string& path, const std::string& key, bool required);

  // A finite number within bounds; nullopt (with a problem when required or malformed) otherwise.
  std::optional<double> number(const YAML::Node& parent, const std::string& path, const std::string& key, bool required,
                               Bounds bounds = {});
  double number_or(const YAML::Node& parent, const std::string& path, const std::string& key, double fallback,
                   Bounds bounds = {});
  // A whole number written as digits, from 0 to `max` (a seed, a count): "1e30", "1.5" and "-1" are
  // refused (a cast would turn them into 0, 1 or 2^64 - 1 without a word).
  std::optional<std::uint64_t> whole_number(const YAML::Node& parent, const std::string& path, const std::string& key,
                                            bool required, std::uint64_t max = UINT64_MAX);
  std::uint64_t whole_number_or(const YAML::Node& parent, const std::string& path, const std::string& key,
                                std::uint64_t fallback, std::uint64_t max = UINT64_MAX);
  std::optional<std::string> text(const YAML::Node& parent, const std::string& path, const std::string& key,
                                  bool required);
  // A list of finite numbers (a single number is a list of one).
  std::optional<std::vector<double>> numbers(const YAML::Node& parent, const std::string& path, const std::string& key,
                                             bool required);

 private:
  std::string file_;
  std::vector<Diagnostic>& problems_;
};

}  // namespace driftlab::devices
