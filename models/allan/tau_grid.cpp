#include "models/allan/tau_grid.hpp"

#include "framework/error.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>
#include <string>

namespace driftlab::allan {
namespace {

ConfigError grid_error(const std::string& message) { return ConfigError({{}, 0, "taus"}, message); }

double parse_positive(std::string_view token) {
  double value = 0.0;
  const auto* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, value);
  if (ec != std::errc() || ptr != end || !std::isfinite(value) || value <= 0.0) {
    throw grid_error("'" + std::string(token) +
                     "' is not a positive number; use octave, decade, dense, dense:P or a "
                     "comma-separated list of taus in s");
  }
  return value;
}

std::string seconds(double tau) {
  std::ostringstream out;
  out << tau << " s";
  return out.str();
}

}  // namespace

TauGrid parse_tau_grid(std::string_view text) {
  TauGrid grid;
  if (text == "octave") return grid;
  if (text == "decade") {
    grid.kind = GridKind::Decade;
    return grid;
  }
  if (text == "dense") {
    grid.kind = GridKind::Dense;
    return grid;
  }
  if (text.starts_with("dense:")) {
    grid.kind = GridKind::Dense;
    const double p = parse_positive(text.substr(6));
    if (p != std::floor(p) || p > 1000) throw grid_error("dense:P needs an integer P in 1..1000");
    grid.points_per_decade = static_cast<int>(p);
    return grid;
  }
  grid.kind = GridKind::Explicit;
  while (!text.empty()) {
    const auto comma = text.find(',');
    grid.taus_s.push_back(parse_positive(text.substr(0, comma)));
    if (comma == std::string_view::npos) break;
    text.remove_prefix(comma + 1);
  }
  if (grid.taus_s.empty()) throw grid_error("empty tau list");
  return grid;
}

std::size_t grid_limit(Kind kind, std::size_t n) {
  if (n < 2) return 0;
  switch (kind) {
    case Kind::Adev:
    case Kind::Hdev:
      return (n - 1) / 5;
    case Kind::Oadev:
    case Kind::Mdev:
    case Kind::Ohdev:
      return (n - 1) / 4;
    case Kind::Totdev:
      return (n - 1) / 2;
  }
  return 0;
}

std::vector<std::size_t> averaging_factors(const TauGrid& grid, Kind kind, std::size_t n, double tau0) {
  std::vector<std::size_t> factors;
  if (grid.kind == GridKind::Explicit) {
    const std::size_t limit = max_factor(kind, n);
    for (const double tau : grid.taus_s) {
      const double m = std::round(tau / tau0);
      if (m < 1.0) {
        throw grid_error("tau " + seconds(tau) + " is shorter than the sample interval " + seconds(tau0));
      }
      if (m > static_cast<double>(limit)) {
        throw grid_error("tau " + seconds(tau) + " is longer than this record supports for " +
                         std::string(kind_name(kind)) + " (at most " + seconds(static_cast<double>(limit) * tau0) +
                         ")");
      }
      factors.push_back(static_cast<std::size_t>(m));
    }
  } else {
    const std::size_t limit = std::max<std::size_t>(grid_limit(kind, n), 1);
    if (max_factor(kind, n) == 0) {
      throw DataError(
          {}, "record of " + std::to_string(n) + " angle samples is too short for " + std::string(kind_name(kind)));
    }
    if (grid.kind == GridKind::Octave) {
      for (std::size_t m = 1; m <= limit; m *= 2) factors.push_back(m);
    } else if (grid.kind == GridKind::Decade) {
      for (std::size_t decade = 1; decade <= limit; decade *= 10) {
        for (const std::size_t step : {1, 2, 4}) {
          if (decade * step <= limit) factors.push_back(decade * step);
        }
      }
    } else {
      if (grid.points_per_decade < 1) throw grid_error("dense grid needs points_per_decade >= 1");
      for (int j = 0;; ++j) {
        const double m = std::round(std::pow(10.0, static_cast<double>(j) / grid.points_per_decade));
        if (m > static_cast<double>(limit)) break;
        factors.push_back(static_cast<std::size_t>(m));
      }
    }
  }
  std::sort(factors.begin(), factors.end());
  factors.erase(std::unique(factors.begin(), factors.end()), factors.end());
  return factors;
}

}  // namespace driftlab::allan
