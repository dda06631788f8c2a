// Property oracles of the libFuzzer harnesses: a violated property aborts, which libFuzzer reports
// as a finding (with the input saved) exactly like a crash or a sanitizer report.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>

namespace driftlab::fuzz {

inline void require(bool holds, const char* property, const std::string& detail = "") {
  if (holds) return;
  std::fprintf(stderr, "property violated: %s\n%s\n", property, detail.c_str());
  std::abort();
}

}  // namespace driftlab::fuzz
