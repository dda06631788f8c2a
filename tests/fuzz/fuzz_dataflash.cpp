// libFuzzer harness: the ArduPilot DataFlash parser (framework/dataflash.hpp) and its IMU adapter
// (framework/dataflash_imu.hpp). The first byte picks the options (bit 0: keep every type's values,
// else only the IMU types; bit 1: read instance 0 only; bit 2: gyros only); the rest is the file.
// Property oracle on every accepted log: every byte is accounted for (messages x their lengths +
// skipped garbage + a cut-off end = the file size), each kept type has one time stamp (when timed)
// and one value per numeric column per message, columns lie inside their message, the per-type
// counts add up to the message count; on every IMU record: at least 2 samples, time finite and
// strictly increasing, channels as long as time and finite.
// Rejections must be DataError or ConfigError; anything else (another exception, a crash, a
// sanitizer report, a hang) is a finding.
// Seed corpus (tests/fuzz/corpus/dataflash): messages cut from the real fixtures of
// tests/data/logs (the FMT, FMTU, UNIT, MULT definitions, parameters with INS_TCAL1 switched on,
// IMU messages of two instances; the old IMU/IMU2 message set; one with garbage between messages
// and a cut-off end), each with mode bytes 0 and 1.
#include <cmath>
#include <cstdint>
#include <string_view>

#include "framework/dataflash.hpp"
#include "framework/dataflash_imu.hpp"
#include "framework/error.hpp"
#include "tests/fuzz/fuzz_oracle.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  using namespace driftlab;
  using fuzz::require;
  const std::uint8_t mode = data[0];
  const std::string_view bytes(reinterpret_cast<const char*>(data + 1), size - 1);
  dataflash::ReadOptions options;
  options.keep_all = (mode & 1) != 0;
  options.keep_types = dataflash::imu_types();
  LogSelection selection;
  if (mode & 2) selection.instance = 0;
  if (mode & 4) selection.sensor = "gyro";
  try {
    const dataflash::Log log = dataflash::parse(bytes, "fuzz.bin", options);
    std::uint64_t message_bytes = 0, messages = 0;
    for (const auto& t : log.types) {
      message_bytes += t.count * t.length;
      messages += t.count;
      for (const auto& c : t.columns) require(c.offset + c.size + 3 <= t.length, "a column lies outside its message");
      if (!t.kept) {
        require(t.time_us.empty() && t.values.empty(), "values kept for a type not asked for");
        continue;
      }
      require(t.time_us.size() == (t.timed ? t.count : 0), "kept time stamps differ from the message count");
      require(t.values.size() == t.columns.size(), "one value vector per column");
      for (std::size_t c = 0; c < t.columns.size(); ++c)
        require(t.values[c].size() == (t.columns[c].numeric() ? t.count : 0),
                "a column's values differ from the message count");
    }
    require(messages == log.messages, "the types' counts do not add up to the message count");
    require(message_bytes + log.skipped_bytes + log.truncated_bytes == bytes.size(), "bytes not accounted for");
    const TimeSeries record = dataflash::imu_record(log, selection);
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
