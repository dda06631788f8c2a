// A minimal ArduPilot DataFlash writer for the tests: structure and bad-input cases the real
// fixtures (tests/data/logs) do not cover. It encodes each value by its FMT's format character
// (framework/dataflash.hpp's table); c C e E are given scaled (1.5 -> 150), L in degrees.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

namespace driftlab::testing_dataflash {

using Value = std::variant<double, std::string>;

inline std::size_t size_of(char c) {
  switch (c) {
    case 'b':
    case 'B':
    case 'M':
      return 1;
    case 'h':
    case 'H':
    case 'c':
    case 'C':
    case 'g':
      return 2;
    case 'i':
    case 'I':
    case 'f':
    case 'e':
    case 'E':
    case 'L':
    case 'n':
      return 4;
    case 'd':
    case 'q':
    case 'Q':
      return 8;
    case 'N':
      return 16;
    case 'Z':
    case 'a':
      return 64;
  }
  throw std::invalid_argument(std::string("format character ") + c);
}

class Writer {
 public:
  static constexpr std::uint8_t kFmt = 0x80;
  static constexpr const char* kFmtFormat = "BBnNZ";

  // The FMT message that defines FMT, as ArduPilot writes it first.
  Writer() { fmt(kFmt, "FMT", kFmtFormat, "Type,Length,Name,Format,Columns"); }

  // An FMT message; the type is then writable with message(). `length` overrides the computed one.
  Writer& fmt(std::uint8_t type, const std::string& name, const std::string& format, const std::string& columns,
              int length = -1) {
    std::size_t size = 3;
    if (length < 0)
      for (const char c : format) size += size_of(c);
    write(kFmtFormat, kFmt,
          {double(type), double(length < 0 ? size : static_cast<std::size_t>(length)), name, format, columns});
    if (type != kFmt) formats_[type] = format;
    return *this;
  }

  Writer& message(std::uint8_t type, const std::vector<Value>& values) {
    return write(formats_.at(type), type, values);
  }

  Writer& raw(const std::string& bytes) {
    bytes_ += bytes;
    return *this;
  }

  const std::string& bytes() const { return bytes_; }

 private:
  Writer& write(const std::string& format, std::uint8_t type, const std::vector<Value>& values) {
    if (values.size() != format.size()) throw std::invalid_argument("value count differs from the format");
    bytes_ += '\xA3';
    bytes_ += '\x95';
    bytes_ += static_cast<char>(type);
    for (std::size_t i = 0; i < format.size(); ++i) encode(format[i], values[i]);
    return *this;
  }

  template <typename T>
  void put(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof v);  // the tests run on little-endian hosts, as ArduPilot logs are
    bytes_.append(b, sizeof b);
  }

  void text(const std::string& s, std::size_t n) {
    std::string padded = s.substr(0, n);
    padded.resize(n, '\0');
    bytes_ += padded;
  }

  static std::uint16_t half(double v) {  // exact for the values the tests use (normal halves)
    if (v == 0.0) return 0;
    int exponent = 0;
    const double m = std::frexp(std::abs(v), &exponent);  // v = m 2^e, m in [0.5, 1)
    const auto mantissa = static_cast<std::uint16_t>(std::lround((m * 2 - 1) * 1024));
    return static_cast<std::uint16_t>((v < 0 ? 0x8000 : 0) | ((exponent + 14) << 10) | mantissa);
  }

  void encode(char c, const Value& value) {
    if (c == 'n' || c == 'N' || c == 'Z') return text(std::get<std::string>(value), size_of(c));
    if (c == 'a') return text("", 64);
    const double v = std::get<double>(value);
    switch (c) {
      case 'b':
        return put(static_cast<std::int8_t>(v));
      case 'B':
      case 'M':
        return put(static_cast<std::uint8_t>(v));
      case 'h':
        return put(static_cast<std::int16_t>(v));
      case 'H':
        return put(static_cast<std::uint16_t>(v));
      case 'i':
        return put(static_cast<std::int32_t>(v));
      case 'I':
        return put(static_cast<std::uint32_t>(v));
      case 'q':
        return put(static_cast<std::int64_t>(v));
      case 'Q':
        return put(static_cast<std::uint64_t>(v));
      case 'f':
        return put(static_cast<float>(v));
      case 'd':
        return put(v);
      case 'g':
        return put(half(v));
      case 'c':
        return put(static_cast<std::int16_t>(std::lround(v)));
      case 'C':
        return put(static_cast<std::uint16_t>(std::lround(v)));
      case 'e':
        return put(static_cast<std::int32_t>(std::lround(v)));
      case 'E':
        return put(static_cast<std::uint32_t>(std::lround(v)));
      case 'L':
        return put(static_cast<std::int32_t>(std::lround(v * 1e7)));
    }
    throw std::invalid_argument(std::string("format character ") + c);
  }

  std::map<std::uint8_t, std::string> formats_;
  std::string bytes_;
};

// Type numbers and definitions as ArduPilot 4.x logs them (AP_Logger/LogStructure.h).
inline constexpr std::uint8_t kParm = 64, kImu = 65, kUnit = 177, kFmtu = 178, kMult = 179;

inline Writer& define_imu_log(Writer& w) {
  return w.fmt(kUnit, "UNIT", "QbZ", "TimeUS,Id,Label")
      .fmt(kMult, "MULT", "Qbd", "TimeUS,Id,Mult")
      .fmt(kFmtu, "FMTU", "QBNN", "TimeUS,FmtType,UnitIds,MultIds")
      .fmt(kParm, "PARM", "QNff", "TimeUS,Name,Value,Default")
      .fmt(kImu, "IMU", "QBffffffIIfBBHH", "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,EG,EA,T,GH,AH,GHz,AHz");
}

// One IMU message of instance `instance`.
inline Writer& imu(Writer& w, double time_us, int instance, double gx, double gy, double gz, double ax, double ay,
                   double az, double temperature) {
  return w.message(
      kImu, {time_us, double(instance), gx, gy, gz, ax, ay, az, 0.0, 0.0, temperature, 1.0, 1.0, 1000.0, 1000.0});
}

inline Writer& parm(Writer& w, double time_us, const std::string& name, double value) {
  return w.message(kParm, {time_us, name, value, value});
}

}  // namespace driftlab::testing_dataflash
