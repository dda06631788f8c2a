// Resource needs estimated from parameters before the work starts, refused above a stated limit
// (issue 17: absurd parameters must not pass validation and die later in std::bad_alloc).
//
// The limit is half of the machine's physical memory, or DRIFTLAB_MEMORY_LIMIT_MB when set.
// Estimates are coarse upper bounds of what a command holds at once (see each caller).
#pragma once

#include <string>

#include "framework/error.hpp"

namespace driftlab {

// The memory budget in bytes.
double memory_limit_bytes();

// Throws ConfigError at `where` ("1e+13 samples at 250 bytes each: about 2.4e+09 MB needed, above
// the limit of 7900 MB (half the physical memory; DRIFTLAB_MEMORY_LIMIT_MB changes it)") when
// `bytes` is not finite or above the limit. `what` says what needs the memory.
void check_memory_estimate(double bytes, const Location& where, const std::string& what);

}  // namespace driftlab
