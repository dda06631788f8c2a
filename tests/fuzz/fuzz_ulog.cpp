// libFuzzer harness: the PX4 ULog parser (framework/ulog.hpp) and its IMU adapter
// (framework/ulog_imu.hpp). The first byte picks the options (bit 0: keep every topic's values, else
// only the IMU topics; bit 1: read instance 0 only; bit 2: gyros only; bit 3: --topic
// sensor_gyro_fifo); the rest is the file.
// Property oracle on every accepted log: each kept topic has one time stamp and one value per column
// per message, its columns lie inside its format, and the counts are consistent; on every IMU record:
// at least 2 samples, time finite and strictly increasing, channels as long as time and finite.
// Rejections must be DataError or ConfigError; anything else (another exception, a crash, a
// sanitizer report, a hang) is a finding.
// Seed corpus (tests/fuzz/corpus/ulog): pyulog's sample logs cut down to a few kilobytes (header,
// flag bits, the formats and subscriptions of the IMU topics, their first data messages, an info,
// parameter, dropout and logged string; one with an appended-data boundary after a cut-off message),
// each with mode bytes 0 and 1; two FIFO logs written for it (a short script, in the layout of
// tests/framework/ulog_writer.hpp): sensor_gyro_fifo multi_id 0 and 1 with 3, 5 and 8 samples per
// message, sensor_accel_fifo without is_external; one alone (mode 0), one with sensor_gyro of the
// same device ids carrying temperatures (mode 8, so the FIFO is read and matched to it).
#include <cmath>
#include <cstdint>
#include <string_view>

#include "framework/error.hpp"
#include "framework/ulog.hpp"
#include "framework/ulog_imu.hpp"
#include "tests/fuzz/fuzz_oracle.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  using namespace driftlab;
  using fuzz::require;
  const std::uint8_t mode = data[0];
  const std::string_view bytes(reinterpret_cast<const char*>(data + 1), size - 1);
  ulog::ReadOptions options;
  options.keep_all = (mode & 1) != 0;
  options.keep_topics = ulog::imu_topics();
  LogSelection selection;
  if (mode & 2) selection.instance = 0;
  if (mode & 4) selection.sensor = "gyro";
  if (mode & 8) selection.topic = "sensor_gyro_fifo";
  try {
    const ulog::Log log = ulog::parse(bytes, "fuzz.ulg", options);
    for (const auto& t : log.topics) {
      if (!t.kept) {
        require(t.timestamp_us.empty() && t.values.empty(), "values kept for a topic not asked for");
        continue;
      }
      require(t.timestamp_us.size() == t.count, "kept time stamps differ from the message count");
      require(t.values.size() == t.columns.size(), "one value vector per column");
      for (std::size_t c = 0; c < t.columns.size(); ++c) {
        require(t.values[c].size() == t.count, "a column's values differ from the message count");
        require(t.columns[c].offset < t.message_size, "a column lies outside its format");
      }
      require(t.data_bytes <= t.count * t.message_size, "more payload bytes than the format allows");
    }
    const TimeSeries record = ulog::imu_record(log, selection);
    const auto& time = record.time();
    require(time.size() >= 2, "an IMU record of fewer than 2 samples");
    for (Eigen::Index i = 0; i < time.size(); ++i) {
      require(std::isfinite(time[i]), "time not finite");
      if (i > 0) require(time[i] > time[i - 1], "time not strictly increasing");
    }
    for (const auto& c : record.channels()) {
      require(c.values.size() == time.size(), "channel length differs from time");
      for (const double v : c.values) require(std::isfinite(v), "value not finite");
    }
  } catch (const DataError&) {
  } catch (const ConfigError&) {
  }
  return 0;
}
