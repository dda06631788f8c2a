// libFuzzer harness: the device-file and chamber/rate-profile parsers (devices/). The first byte
// picks the parser. Property oracle for an accepted device: its model responds finitely over its
// temperature range (frequencies and Q positive); for an accepted profile: a finite, non-negative
// duration. Rejections must be ConfigError; anything else is a finding.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "devices/device_file.hpp"
#include "devices/device_model.hpp"
#include "devices/simulator.hpp"
#include "framework/error.hpp"

namespace {

void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "property violated: %s\n", what);
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  using namespace driftlab;
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  try {
    if (data[0] & 1) {
      const auto profile = devices::parse_profile(text, "fuzz-profile.yaml");
      check(std::isfinite(profile.duration_s()) && profile.duration_s() >= 0.0, "profile duration");
    } else {
      const auto device = devices::parse_device(text, "fuzz-device.yaml");
      const devices::DeviceModel model(device.physics);
      for (double t = -40.0; t <= 85.0; t += 5.0) {
        const auto r = model.response(t);
        check(std::isfinite(r.scale_factor) && std::isfinite(r.bias_rad_s), "device response not finite");
      }
    }
  } catch (const ConfigError&) {
  }
  return 0;
}
