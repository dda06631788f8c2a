#include "framework/units.hpp"

#include <charconv>
#include <cmath>

namespace driftlab {
namespace {

struct Spelling {
  std::string_view text;
  Unit unit;
};

const std::vector<Spelling>& spellings() {
  static const std::vector<Spelling> table = [] {
    const Unit rad_s{"rad/s", Quantity::AngularRate, 1.0, 0.0};
    const Unit deg_s{"deg/s", Quantity::AngularRate, kRadPerDeg, 0.0};
    const Unit deg_h{"deg/h", Quantity::AngularRate, kRadPerSecPerDph, 0.0};
    const Unit mrad_s{"mrad/s", Quantity::AngularRate, 1e-3, 0.0};
    const Unit mdeg_s{"mdeg/s", Quantity::AngularRate, 1e-3 * kRadPerDeg, 0.0};
    const Unit m_s2{"m/s^2", Quantity::Acceleration, 1.0, 0.0};
    const Unit gee{"g", Quantity::Acceleration, kStandardGravity, 0.0};
    const Unit mgee{"mg", Quantity::Acceleration, 1e-3 * kStandardGravity, 0.0};
    const Unit deg_c{"degC", Quantity::Temperature, 1.0, 0.0};
    const Unit kelvin{"K", Quantity::Temperature, 1.0, -273.15};
    const Unit sec{"s", Quantity::Time, 1.0, 0.0};
    const Unit msec{"ms", Quantity::Time, 1e-3, 0.0};
    const Unit usec{"us", Quantity::Time, 1e-6, 0.0};
    const Unit nsec{"ns", Quantity::Time, 1e-9, 0.0};
    const Unit hour{"h", Quantity::Time, 3600.0, 0.0};
    const Unit hz{"Hz", Quantity::Frequency, 1.0, 0.0};
    const Unit khz{"kHz", Quantity::Frequency, 1e3, 0.0};
    const Unit one{"1", Quantity::Dimensionless, 1.0, 0.0};
    return std::vector<Spelling>{
        {"rad/s", rad_s}, {"rps", rad_s},  {"deg/s", deg_s}, {"dps", deg_s},     {"°/s", deg_s},
        {"deg/h", deg_h}, {"°/h", deg_h},  {"dph", deg_h},   {"mrad/s", mrad_s}, {"mdeg/s", mdeg_s},
        {"mdps", mdeg_s}, {"m/s^2", m_s2}, {"m/s2", m_s2},   {"mps2", m_s2},     {"g", gee},
        {"mg", mgee},     {"degC", deg_c}, {"C", deg_c},     {"°C", deg_c},      {"celsius", deg_c},
        {"K", kelvin},    {"s", sec},      {"ms", msec},     {"us", usec},       {"ns", nsec},
        {"h", hour},      {"Hz", hz},      {"kHz", khz},     {"1", one},
    };
  }();
  return table;
}

}  // namespace

std::optional<Unit> find_unit(std::string_view spelling) {
  for (const auto& s : spellings())
    if (s.text == spelling) return s.unit;
  // A scaled unit: [lsb*]<factor>*<unit>, e.g. raw counts of 0.061 mdps.
  if (spelling.starts_with("lsb*")) spelling.remove_prefix(4);
  const auto star = spelling.find('*');
  if (star == std::string_view::npos) return std::nullopt;
  double factor = 0.0;
  const auto factor_text = spelling.substr(0, star);
  const auto res = std::from_chars(factor_text.data(), factor_text.data() + factor_text.size(), factor);
  if (res.ec != std::errc() || res.ptr != factor_text.data() + factor_text.size() || !std::isfinite(factor) ||
      !(factor > 0.0))
    return std::nullopt;
  auto base = find_unit(spelling.substr(star + 1));
  if (!base || base->offset != 0.0) return std::nullopt;  // a scaled K would scale its offset too
  base->symbol = std::string(factor_text) + "*" + base->symbol;
  base->scale *= factor;
  if (!std::isfinite(base->scale) || !(base->scale > 0.0)) return std::nullopt;
  return base;
}

std::vector<std::string> known_unit_spellings() {
  std::vector<std::string> out;
  for (const auto& s : spellings()) out.emplace_back(s.text);
  return out;
}

std::string internal_unit_symbol(Quantity q) {
  switch (q) {
    case Quantity::AngularRate:
      return "rad/s";
    case Quantity::Acceleration:
      return "m/s^2";
    case Quantity::Temperature:
      return "degC";
    case Quantity::Time:
      return "s";
    case Quantity::Frequency:
      return "Hz";
    case Quantity::Dimensionless:
      return "1";
  }
  return "1";
}

}  // namespace driftlab
