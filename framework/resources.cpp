#include "framework/resources.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>

#include "framework/units.hpp"

namespace driftlab {

namespace {

// The value of a limit variable in its unit; nullopt when unset; ConfigError naming it when malformed.
std::optional<double> limit_variable(const char* name) {
  const char* env = std::getenv(name);
  if (!env) return std::nullopt;
  char* end = nullptr;
  const double value = std::strtod(env, &end);
  if (end == env || *end != '\0' || !std::isfinite(value) || !(value > 0.0))
    throw ConfigError({"", 0, name}, "expected a finite number > 0, got " + quoted_excerpt(env, 40));
  return value;
}

}  // namespace

double memory_limit_bytes() {
  if (const auto mb = limit_variable("DRIFTLAB_MEMORY_LIMIT_MB")) return *mb * 1048576.0;
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  if (pages > 0 && page > 0) return 0.5 * static_cast<double>(pages) * static_cast<double>(page);
  return 4096.0 * 1048576.0;
}

double time_limit_s() { return limit_variable("DRIFTLAB_TIME_LIMIT_S").value_or(kDefaultTimeBudgetS); }

void check_memory_estimate(double bytes, const Location& where, const std::string& what) {
  const double limit = memory_limit_bytes();
  if (std::isfinite(bytes) && bytes <= limit) return;
  char text[320];
  std::snprintf(text, sizeof text, "%s: about %.3g MB needed, above the limit of %.0f MB (%s)", what.c_str(),
                bytes / 1048576.0, limit / 1048576.0,
                std::getenv("DRIFTLAB_MEMORY_LIMIT_MB")
                    ? "DRIFTLAB_MEMORY_LIMIT_MB"
                    : "half the physical memory; DRIFTLAB_MEMORY_LIMIT_MB changes it");
  throw ConfigError(where, text);
}

void check_time_estimate(double seconds, const Location& where, const std::string& what) {
  const double limit = time_limit_s();
  if (std::isfinite(seconds) && seconds <= limit) return;
  char text[320];
  std::snprintf(
      text, sizeof text, "%s: about %.3g s (%.3g h) of computing, above the budget of %.3g h (%s)", what.c_str(),
      seconds, seconds / kSecondsPerHour, limit / kSecondsPerHour,
      std::getenv("DRIFTLAB_TIME_LIMIT_S") ? "DRIFTLAB_TIME_LIMIT_S" : "the default; DRIFTLAB_TIME_LIMIT_S raises it");
  throw ConfigError(where, text);
}

}  // namespace driftlab
