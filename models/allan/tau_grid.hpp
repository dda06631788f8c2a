// Averaging-time grids for the Allan-family deviations: tau = m * tau0 with integer factor m.
//
//   octave   m = 1, 2, 4, 8, ...                   (Stable32 "octave")
//   decade   m = 1, 2, 4, 10, 20, 40, 100, ...     (Stable32 "decade")
//   dense    m = round(10^(j/p)), j = 0, 1, ...   p points per decade, duplicates dropped
//   explicit the given taus, each rounded to the nearest multiple of tau0
// Generated grids stop at Stable32's longest factor, beyond which an estimate rests on too few
// independent samples to be useful: floor((n-1)/5) for ADEV and HDEV, floor((n-1)/4) for OADEV,
// MDEV and OHDEV, floor((n-1)/2) for TOTDEV (n = number of angle samples). An explicit tau may go
// up to max_factor() of deviation.hpp (at least one term). The number of terms behind each value is
// term_count() of deviation.hpp. Cost O(number of factors).
#pragma once

#include "models/allan/deviation.hpp"

#include <cstddef>
#include <string_view>
#include <vector>

namespace driftlab::allan {

enum class GridKind { Octave, Decade, Dense, Explicit };

struct TauGrid {
  GridKind kind = GridKind::Octave;
  int points_per_decade = 10;  // Dense only
  std::vector<double> taus_s;  // Explicit only, s
};

// "octave", "decade", "dense", "dense:P" (P points per decade) or a comma-separated list of taus
// in s ("0.1,1,10"). Throws driftlab::ConfigError on anything else.
TauGrid parse_tau_grid(std::string_view text);

// Longest averaging factor a generated grid uses (Stable32's convention, see above).
std::size_t grid_limit(Kind kind, std::size_t n_angle);

// Increasing, distinct averaging factors of the grid for n angle samples spaced tau0 s. Throws
// driftlab::ConfigError for an explicit tau shorter than tau0/2 or longer than the record supports,
// and driftlab::DataError when the record is too short for any factor.
std::vector<std::size_t> averaging_factors(const TauGrid& grid, Kind kind, std::size_t n_angle, double tau0);

}  // namespace driftlab::allan
