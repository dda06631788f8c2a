#include "framework/resources.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace driftlab {

double memory_limit_bytes() {
  if (const char* env = std::getenv("DRIFTLAB_MEMORY_LIMIT_MB")) {
    char* end = nullptr;
    const double mb = std::strtod(env, &end);
    if (end != env && *end == '\0' && std::isfinite(mb) && mb > 0.0) return mb * 1048576.0;
  }
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  if (pages > 0 && page > 0) return 0.5 * static_cast<double>(pages) * static_cast<double>(page);
  return 4096.0 * 1048576.0;
}

void check_memory_estimate(double bytes, const Location& where, const std::string& what) {
  const double limit = memory_limit_bytes();
  if (std::isfinite(bytes) && bytes <= limit) return;
  char text[256];
  std::snprintf(text, sizeof text, "%s: about %.3g MB needed, above the limit of %.0f MB (%s)", what.c_str(),
                bytes / 1048576.0, limit / 1048576.0,
                std::getenv("DRIFTLAB_MEMORY_LIMIT_MB") ? "DRIFTLAB_MEMORY_LIMIT_MB"
                                                        : "half the physical memory; DRIFTLAB_MEMORY_LIMIT_MB changes it");
  throw ConfigError(where, text);
}

}  // namespace driftlab
