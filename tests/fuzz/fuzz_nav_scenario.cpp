// libFuzzer harness: the nav scenario reader (tools/mrpt/nav_scenario.hpp, driftlab-nav-scenario/1
// YAML). Property oracle on every accepted scenario: a finite sample rate > 0 and a finite duration
// > 0; every profile's breakpoints finite, their times non-decreasing, its values finite at the
// start, the middle and the end; the cabin within [kMinTemperatureC, kMaxTemperatureC]; the noise
// and fix settings finite and in their ranges. Rejections must be ConfigError; anything else (another
// exception, a crash, a sanitizer report) is a finding.
#include <cmath>
#include <cstdint>
#include <string>

#include "framework/error.hpp"
#include "framework/units.hpp"
#include "tests/fuzz/fuzz_oracle.hpp"
#include "tools/mrpt/nav_scenario.hpp"

namespace {

void check_profile(const driftlab::devices::Profile& p, double low, double high, const char* name) {
  using driftlab::fuzz::require;
  const auto& t = p.breakpoint_times();
  const auto& v = p.breakpoint_values();
  require(t.size() == v.size() && !t.empty(), "a profile has one value per breakpoint", name);
  for (std::size_t i = 0; i < t.size(); ++i) {
    require(std::isfinite(t[i]) && (i == 0 || t[i] >= t[i - 1]), "profile times finite and non-decreasing", name);
    require(std::isfinite(v[i]) && v[i] >= low && v[i] <= high, "profile values finite and in range", name);
  }
  for (const double at : {0.0, 0.5 * p.duration_s(), p.duration_s()})
    require(std::isfinite(p.value_at(at)), "a profile's value finite", name);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace driftlab;
  using fuzz::require;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto s = mrpt_bridge::parse_nav_scenario(text, "fuzz.yaml");
    require(std::isfinite(s.sample_rate_hz) && s.sample_rate_hz > 0.0, "a finite sample rate > 0", text);
    require(std::isfinite(s.duration_s()) && s.duration_s() > 0.0, "a finite duration > 0", text);
    check_profile(s.cabin_c, kMinTemperatureC, kMaxTemperatureC, "cabin");
    check_profile(s.yaw_rate_rad_s, -HUGE_VAL, HUGE_VAL, "yaw_rate");
    check_profile(s.speed_mps, -HUGE_VAL, HUGE_VAL, "speed");
    require(std::isfinite(s.odometry_speed_sigma_mps) && s.odometry_speed_sigma_mps >= 0.0, "odometry sigma", text);
    require(std::isfinite(s.fix_period_s) && s.fix_period_s >= 0.0, "fix period", text);
    require(std::isfinite(s.fix_sigma_m) && s.fix_sigma_m > 0.0, "fix sigma", text);
  } catch (const ConfigError&) {
  }
  return 0;
}
