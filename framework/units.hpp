// Units at the I/O boundary. Inside the library everything is SI: angular rate in rad/s, time in
// s, frequency in Hz, temperature differences in K and absolute temperature in degC.
// A unit converts to its quantity's internal unit by  internal = value * scale + offset.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace driftlab {

enum class Quantity { AngularRate, Acceleration, Temperature, Time, Frequency, Dimensionless };

struct Unit {
  std::string symbol;  // canonical spelling, e.g. "deg/s"
  Quantity quantity;
  double scale;  // internal = value * scale + offset
  double offset;
};

// Looks a unit up by any accepted spelling ("deg/s", "dps", "°/s", "mdps", "rad/s", "mrad/s",
// "deg/h", "m/s^2", "g", "mg", "degC", "C", "°C", "K", "s", "ms", "us", "ns", "h", "Hz", "kHz",
// "1"). Raw sensor counts are a scaled unit: "lsb*0.061*mdps" (or "0.061*mdps") is 0.061 mdps per
// count. Empty optional when unknown or when the scale is not a finite number > 0.
std::optional<Unit> find_unit(std::string_view spelling);

// Every accepted spelling, for error messages.
std::vector<std::string> known_unit_spellings();

// Internal unit symbol of a quantity ("rad/s", "degC", "s", "Hz", "1").
std::string internal_unit_symbol(Quantity q);

inline double to_internal(double value, const Unit& u) { return value * u.scale + u.offset; }
inline double from_internal(double value, const Unit& u) { return (value - u.offset) / u.scale; }
// Differences (deviations, IMFs, standard deviations) convert by the scale only: an offset applies
// to absolute values alone (a 1 K difference is a 1 degC difference).
inline double difference_from_internal(double value, const Unit& u) { return value / u.scale; }

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegPerRad = 180.0 / kPi;
constexpr double kRadPerDeg = kPi / 180.0;
constexpr double kSecondsPerHour = 3600.0;
constexpr double kHoursPerSecond = 1.0 / kSecondsPerHour;
constexpr double kSqrtSecondsPerHour = 60.0;  // sqrt(3600 s): x/sqrt(h) = x/(60 sqrt(s)) (angle random walk)
constexpr double kRadPerSecPerDph = kRadPerDeg / kSecondsPerHour;  // rad/s per deg/h (gyro bias unit)
constexpr double kDphPerRadPerSec = 1.0 / kRadPerSecPerDph;        // deg/h per rad/s
constexpr double kPpm = 1e-6;                                      // parts per million
constexpr double kStandardGravity = 9.80665;                       // m/s^2 per g (CGPM 1901)
// The physical range of an absolute temperature a file may give, degC: absolute zero to 1000 degC,
// far beyond any sensor (calibration models, simulator chamber and nav cabin profiles).
constexpr double kMinTemperatureC = -273.15, kMaxTemperatureC = 1000.0;

}  // namespace driftlab
