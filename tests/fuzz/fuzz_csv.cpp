// libFuzzer harness: the CSV time-series reader (framework/csv.hpp).
// The first byte picks the read options (default columns, an explicit mapping, --fs, gaps); the
// rest is the file. Property oracle on every accepted input: at least one sample; time finite and
// strictly increasing with steps >= kMinTimeStep; every channel as long as the time vector, finite
// and within kMaxMagnitude. Rejections must be ConfigError or DataError; anything else (another
// exception, a crash, a sanitizer report) is a finding.
#include <cmath>
#include <cstdint>
#include <string>

#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "tests/fuzz/fuzz_oracle.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  using namespace driftlab;
  using fuzz::require;
  const std::uint8_t mode = data[0];
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  CsvReadOptions options;
  options.required_roles = (mode & 1) ? std::vector<std::string>{} : std::vector<std::string>{"rate"};
  if (mode & 2) options.columns = {{"rate", "g", "rad/s"}, {"temperature", "T", "K"}};
  if (mode & 4) options.sample_rate_hz = 100.0;
  if (mode & 8) options.max_gap_factor = 0.0;
  if ((mode & 6) == 2) options.columns.push_back({"time", "ts", "ms"});
  try {
    const TimeSeries series = parse_csv(text, "fuzz.csv", options);
    const auto& t = series.time();
    require(t.size() > 0, "no samples");
    for (Eigen::Index i = 0; i < t.size(); ++i) {
      require(std::isfinite(t[i]), "time not finite");
      if (i > 0) require(t[i] - t[i - 1] >= kMinTimeStep, "time not strictly increasing by >= 1 ns");
    }
    for (const auto& c : series.channels()) {
      require(c.values.size() == t.size(), "channel length differs from time");
      for (const double v : c.values) require(std::isfinite(v) && std::abs(v) <= kMaxMagnitude, "value out of range");
    }
  } catch (const ConfigError&) {
  } catch (const DataError&) {
  }
  return 0;
}
