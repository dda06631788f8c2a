#include "framework/imu.hpp"

#include <algorithm>
#include <cctype>
#include <regex>

#include "framework/error.hpp"
#include "framework/units.hpp"

namespace driftlab::imu {
namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return std::tolower(c); });
  return out;
}

struct UnitSuffix {
  std::string_view suffix, unit;
};
// Longest first: "_mdps" before "_dps", "_mg" before "_g".
constexpr UnitSuffix kRateSuffixes[] = {{"_rad_s", "rad/s"}, {"_rads", "rad/s"}, {"_rps", "rad/s"}, {"_mdps", "mdps"},
                                        {"_deg_s", "deg/s"}, {"_dps", "deg/s"},  {"_dph", "deg/h"}};
constexpr UnitSuffix kAccelSuffixes[] = {
    {"_m_s2", "m/s^2"}, {"_mps2", "m/s^2"}, {"_ms2", "m/s^2"}, {"_mg", "mg"}, {"_g", "g"}};
constexpr UnitSuffix kTempSuffixes[] = {{"_degc", "degC"}, {"_c", "degC"}, {"_k", "K"}};

// Splits a known unit suffix off `stem`; the unit, or `fallback` when there is none.
template <std::size_t N>
std::string strip_suffix(std::string& stem, const UnitSuffix (&table)[N], std::string_view fallback) {
  for (const auto& s : table) {
    if (stem.size() > s.suffix.size() && stem.ends_with(s.suffix)) {
      stem.resize(stem.size() - s.suffix.size());
      return std::string(s.unit);
    }
  }
  return std::string(fallback);
}

std::string with_instance(std::string_view stem, int instance) {
  return instance == 0 ? std::string(stem) : std::string(stem) + std::to_string(instance);
}

}  // namespace

std::string to_string(Sensor sensor) { return sensor == Sensor::Gyro ? "gyro" : "accel"; }

DisplayUnit display_unit(Sensor sensor) {
  return sensor == Sensor::Gyro ? DisplayUnit{kDphPerRadPerSec, "deg/h"} : DisplayUnit{1e3 / kStandardGravity, "mg"};
}

std::string internal_unit(Sensor sensor) { return sensor == Sensor::Gyro ? "rad/s" : "m/s^2"; }

std::string ChannelId::role() const { return with_instance(to_string(sensor), instance) + "_" + axis; }

std::optional<ChannelId> parse_role(std::string_view role, std::string_view prefix) {
  if (!role.starts_with(prefix)) return std::nullopt;
  role.remove_prefix(prefix.size());
  static const std::regex pattern("^(gyro|accel)([1-9][0-9]?)?_([xyz])$");
  std::cmatch m;
  if (!std::regex_match(role.data(), role.data() + role.size(), m, pattern)) return std::nullopt;
  ChannelId id;
  id.sensor = m[1].str() == "gyro" ? Sensor::Gyro : Sensor::Accel;
  id.instance = m[2].matched ? std::stoi(m[2].str()) : 0;
  id.axis = m[3].str()[0];
  return id;
}

std::string temperature_role(int instance) { return with_instance("temperature", instance); }

std::optional<int> parse_temperature_role(std::string_view role) {
  static const std::regex pattern("^temperature([1-9][0-9]?)?$");
  std::cmatch m;
  if (!std::regex_match(role.data(), role.data() + role.size(), m, pattern)) return std::nullopt;
  return m[1].matched ? std::stoi(m[1].str()) : 0;
}

std::string truth_role(const ChannelId& id) { return "true_" + id.role(); }
std::string systematic_role(const ChannelId& id) { return "systematic_" + id.role(); }

std::optional<ColumnMatch> recognize_imu_column(std::string_view header) {
  std::string stem = lower(header);
  // Instance digits may sit after the sensor (gyro1_x, accel_2_z) or after the axis (GyrX1, gx_1);
  // a second instance number is not a recognised name.
  static const std::regex sensor_axis("^(gyro|gyr|g|accel|acc|a)(?:_?([0-9]))?_?([xyz])(?:_?([0-9]))?$");
  for (const bool gyro : {true, false}) {
    std::string s = stem;
    const std::string unit = gyro ? strip_suffix(s, kRateSuffixes, "rad/s") : strip_suffix(s, kAccelSuffixes, "m/s^2");
    std::smatch m;
    if (!std::regex_match(s, m, sensor_axis)) continue;
    const std::string sensor = m[1].str();
    const bool is_gyro = sensor[0] == 'g';
    if (is_gyro != gyro) continue;
    if (m[2].matched && m[4].matched) return std::nullopt;
    ChannelId id;
    id.sensor = is_gyro ? Sensor::Gyro : Sensor::Accel;
    id.axis = m[3].str()[0];
    id.instance = m[2].matched ? std::stoi(m[2].str()) : m[4].matched ? std::stoi(m[4].str()) : 0;
    return ColumnMatch{id.role(), unit};
  }
  // Temperatures: temp, temp_c, temperature, tmp, imu_temp, imu1_temp, temp1, temp_1, and ArduPilot's
  // upper-case "T" (a lower-case "t" is a time column).
  if (header == "T") return ColumnMatch{temperature_role(0), "degC"};
  std::string s = stem;
  const std::string unit = strip_suffix(s, kTempSuffixes, "degC");
  static const std::regex temp("^(?:imu_?([0-9])_?)?(?:temp|temperature|tmp)(?:_?([0-9]))?$");
  std::smatch m;
  if (std::regex_match(s, m, temp)) {
    if (m[1].matched && m[2].matched) return std::nullopt;
    const int instance = m[1].matched ? std::stoi(m[1].str()) : m[2].matched ? std::stoi(m[2].str()) : 0;
    return ColumnMatch{temperature_role(instance), unit};
  }
  return std::nullopt;
}

bool Selection::selects(const ChannelId& id) const {
  if (items.empty()) return true;
  for (const auto& item : items) {
    if (item == "all" || item == to_string(id.sensor) || item == with_instance(to_string(id.sensor), id.instance) ||
        item == id.role())
      return true;
  }
  return false;
}

Selection parse_selection(const std::string& text, const std::string& option) {
  static const std::regex item_pattern("^(all|(gyro|accel)([1-9][0-9]?)?(_[xyz])?)$");
  Selection sel;
  std::size_t start = 0;
  while (start <= text.size()) {
    const auto comma = text.find(',', start);
    std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    item.erase(0, item.find_first_not_of(' '));
    item.erase(item.find_last_not_of(' ') + 1);
    if (!std::regex_match(item, item_pattern))
      throw ConfigError({"", 0, option}, "'" + item +
                                             "' names no channel (expected e.g. gyro, accel, gyro1, gyro_x, "
                                             "accel1_z or all, comma-separated)");
    sel.items.push_back(item);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return sel;
}

}  // namespace driftlab::imu
