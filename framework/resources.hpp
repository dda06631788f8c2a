// Resource needs estimated from parameters before the work starts, refused above a stated limit
// (issue 17: absurd parameters must not pass validation and die later in std::bad_alloc; issue 28:
// nor run for days).
//
// Memory: the limit is half of the machine's physical memory, or DRIFTLAB_MEMORY_LIMIT_MB when set.
// Time: the budget is kDefaultTimeBudgetS (4 h) of one core, or DRIFTLAB_TIME_LIMIT_S when set; a
// larger run is allowed by raising it. Either variable, when set, must be a finite number > 0
// (ConfigError otherwise, naming it). Estimates are coarse bounds of what a command holds at once
// and of its single-core run time, from per-sample costs measured on the development machine (see
// each caller).
#pragma once

#include <string>

#include "framework/error.hpp"
#include "framework/units.hpp"

namespace driftlab {

inline constexpr double kDefaultTimeBudgetS = 4.0 * kSecondsPerHour;

// The memory budget in bytes.
double memory_limit_bytes();
// The time budget in s.
double time_limit_s();

// Throws ConfigError at `where` ("1e+13 samples at 250 bytes each: about 2.4e+09 MB needed, above
// the limit of 7900 MB (half the physical memory; DRIFTLAB_MEMORY_LIMIT_MB changes it)") when
// `bytes` is not finite or above the limit. `what` says what needs the memory.
void check_memory_estimate(double bytes, const Location& where, const std::string& what);

// Throws ConfigError at `where` ("--population, --generations: 1e+15 evaluations at 2e-05 s each:
// about 2e+10 s (6e+06 h) of computing, above the budget of 4 h (DRIFTLAB_TIME_LIMIT_S changes it)")
// when `seconds` is not finite or above the budget. `what` says what takes the time.
void check_time_estimate(double seconds, const Location& where, const std::string& what);

}  // namespace driftlab
