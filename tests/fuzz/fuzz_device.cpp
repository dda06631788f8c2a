// libFuzzer harness: the device-file and chamber/rate-profile parsers (devices/). The first byte
// picks the parser. Property oracle for an accepted device: its model responds finitely over its
// temperature range; for an accepted profile: a finite, non-negative duration. Rejections must be ConfigError; anything
// else is a finding.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "devices/device_file.hpp"
#include "devices/device_model.hpp"
#include "devices/simulator.hpp"
#include "framework/error.hpp"
#include "tests/fuzz/fuzz_oracle.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  using namespace driftlab;
  using fuzz::require;
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  try {
    if (data[0] & 1) {
      const auto profile = devices::parse_profile(text, "fuzz-profile.yaml");
      require(std::isfinite(profile.duration_s()) && profile.duration_s() >= 0.0, "profile duration");
    } else {
      const auto device = devices::parse_device(text, "fuzz-device.yaml");
      const devices::DeviceModel model(device.physics);
      double lo = -55.0, hi = 125.0;  // the range the loader checks: the temperature channel's, else this
      for (const auto& c : device.channels)
        if (c.role == "temperature" && std::isfinite(c.range_min) && std::isfinite(c.range_max)) {
          lo = std::max(c.range_min, -273.0);
          hi = c.range_max;
        }
      for (double t = lo; t <= hi; t += (hi - lo) / 16.0) {
        const auto r = model.response(t);
        require(std::isfinite(r.scale_factor) && std::isfinite(r.bias_rad_s), "device response not finite");
      }
    }
  } catch (const ConfigError&) {
  }
  return 0;
}
