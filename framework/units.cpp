#include "framework/units.hpp"


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
        {"rad/s", rad_s}, {"rps", rad_s},   {"deg/s", deg_s}, {"dps", deg_s},  {"°/s", deg_s},
        {"deg/h", deg_h}, {"°/h", deg_h},   {"dph", deg_h},   {"mrad/s", mrad_s},
        {"degC", deg_c},  {"C", deg_c},     {"°C", deg_c},    {"celsius", deg_c}, {"K", kelvin},
        {"s", sec},       {"ms", msec},     {"us", usec},     {"ns", nsec},    {"h", hour},
        {"Hz", hz},       {"kHz", khz},     {"1", one},
    };
  }();
  return table;
}

}  // namespace

std::optional<Unit> find_unit(std::string_view spelling) {
  for (const auto& s : spellings())
    if (s.text == spelling) return s.unit;
  return std::nullopt;
}

std::vector<std::string> known_unit_spellings() {
  std::vector<std::string> out;
  for (const auto& s : spellings()) out.emplace_back(s.text);
  return out;
}

std::string internal_unit_symbol(Quantity q) {
  switch (q) {
    case Quantity::AngularRate: return "rad/s";
    case Quantity::Temperature: return "degC";
    case Quantity::Time: return "s";
    case Quantity::Frequency: return "Hz";
    case Quantity::Dimensionless: return "1";
  }
  return "1";
}

}  // namespace driftlab
