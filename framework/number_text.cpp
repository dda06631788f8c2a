#include "framework/number_text.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace driftlab {

std::string format_number(double v, int digits) {
  if (!std::isfinite(v)) return "–";
  char buf[48];
  if (v == std::floor(v) && std::abs(v) < 1e15)
    std::snprintf(buf, sizeof buf, "%.0f", v == 0.0 ? 0.0 : v);
  else
    std::snprintf(buf, sizeof buf, "%.*g", std::max(1, digits), v);
  return buf;
}

std::string number_text(double v, const char* printf_format) {
  char buf[64];
  std::snprintf(buf, sizeof buf, printf_format, v);
  return buf;
}

}  // namespace driftlab
