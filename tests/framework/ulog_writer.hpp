// A minimal ULog writer for tests: byte-exact messages as PX4's format documentation lays them
// out, so the reader's features and bad-input handling can be tried on files small enough to read
// in a test. The counts and values the reader is checked against come from pyulog's outputs on
// real logs (ulog_test.cpp); these files only exercise structure.
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace driftlab::testing_ulog {

class Writer {
 public:
  explicit Writer(std::uint64_t start_us = 1000, std::uint8_t version = 1) {
    bytes_ = std::string("ULog\x01\x12\x35", 7);
    bytes_ += static_cast<char>(version);
    put(start_us, 8);
  }
  // 'B' with the given incompatible byte 0 and appended offsets.
  Writer& flag_bits(std::uint8_t incompat0 = 0, std::vector<std::uint64_t> appended = {}) {
    std::string p(16, '\0');
    p[8] = static_cast<char>(incompat0);
    appended.resize(3, 0);
    for (const auto o : appended) p += le(o, 8);
    return message('B', p);
  }
  Writer& format(const std::string& text) { return message('F', text); }
  Writer& info(const std::string& key, const std::string& value) {
    return message('I', std::string(1, static_cast<char>(key.size())) + key + value);
  }
  Writer& parameter_float(const std::string& name, float v) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, 4);
    const std::string key = "float " + name;
    return message('P', std::string(1, static_cast<char>(key.size())) + key + le(bits, 4));
  }
  Writer& add(std::uint8_t multi_id, std::uint16_t msg_id, const std::string& name) {
    return message('A', std::string(1, static_cast<char>(multi_id)) + le(msg_id, 2) + name);
  }
  Writer& data(std::uint16_t msg_id, const std::string& payload) { return message('D', le(msg_id, 2) + payload); }
  Writer& dropout(std::uint16_t ms) { return message('O', le(ms, 2)); }
  Writer& logged(char level, std::uint64_t t_us, const std::string& text) {
    return message('L', std::string(1, level) + le(t_us, 8) + text);
  }
  Writer& message(char type, const std::string& payload) {
    put(payload.size(), 2);
    bytes_ += type;
    bytes_ += payload;
    return *this;
  }
  Writer& raw(const std::string& bytes) {
    bytes_ += bytes;
    return *this;
  }
  const std::string& bytes() const { return bytes_; }

  static std::string le(std::uint64_t v, int n) {
    std::string out;
    for (int i = 0; i < n; ++i) out += static_cast<char>((v >> (8 * i)) & 0xff);
    return out;
  }
  static std::string f32(float v) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, 4);
    return le(bits, 4);
  }

 private:
  void put(std::uint64_t v, int n) { bytes_ += le(v, n); }
  std::string bytes_;
};

// The sensor_gyro format of PX4 v1.11 (as in pyulog's sample_log_small.ulg) and one message of it.
inline const char* kSensorGyroFormat =
    "sensor_gyro:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float x;float y;float z;"
    "float temperature;uint32_t error_count;";
inline std::string sensor_gyro(std::uint64_t t_us, std::uint32_t device, float x, float y, float z, float temp) {
  return Writer::le(t_us, 8) + Writer::le(t_us, 8) + Writer::le(device, 4) + Writer::f32(x) + Writer::f32(y) +
         Writer::f32(z) + Writer::f32(temp) + Writer::le(0, 4);
}

// FIFO formats with the fields of PX4's msg/SensorGyroFifo.msg (is_external included) and
// msg/SensorAccelFifo.msg (without it), ordered by element size as PX4's generated formats are (the
// reader goes by name, not order), and one message of either.
inline const char* kSensorGyroFifoFormat =
    "sensor_gyro_fifo:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float dt;float scale;"
    "int16_t[32] x;int16_t[32] y;int16_t[32] z;bool is_external;uint8_t samples;uint8_t[2] _padding0;";
inline const char* kSensorAccelFifoFormat =
    "sensor_accel_fifo:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float dt;float scale;"
    "int16_t[32] x;int16_t[32] y;int16_t[32] z;uint8_t samples;uint8_t[3] _padding0;";
struct FifoMessage {
  std::uint64_t timestamp_sample = 0;  // us, of the last sample; `timestamp` is 50 us later
  std::uint32_t device_id = 0;
  float dt_us = 0.f, scale = 0.f;
  std::vector<std::array<std::int16_t, 3>> counts;    // x, y, z of each sample, at most `capacity`
  int samples = -1;                                   // the samples field; -1: counts.size()
  std::size_t capacity = 32;                          // the format's array length
  std::string before_samples = std::string(1, '\0');  // the fields between z and samples (is_external)
  std::string after_samples;                          // and after samples
};
// The payload without trailing padding, as PX4 writes it.
inline std::string sensor_fifo(const FifoMessage& m) {
  std::string out = Writer::le(m.timestamp_sample + 50, 8) + Writer::le(m.timestamp_sample, 8) +
                    Writer::le(m.device_id, 4) + Writer::f32(m.dt_us) + Writer::f32(m.scale);
  for (int a = 0; a < 3; ++a)
    for (std::size_t i = 0; i < m.capacity; ++i)
      out += Writer::le(static_cast<std::uint16_t>(i < m.counts.size() ? m.counts[i][a] : 0), 2);
  out += m.before_samples;
  out += static_cast<char>(m.samples < 0 ? m.counts.size() : static_cast<std::size_t>(m.samples));
  return out + m.after_samples;
}

}  // namespace driftlab::testing_ulog
