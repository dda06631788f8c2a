#include "models/allan/deviation.hpp"

#include "framework/error.hpp"
#include "framework/simd.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <string>
#include <utility>

namespace driftlab::allan {
namespace {

constexpr std::array<std::string_view, 6> kKindNames = {"adev", "oadev", "mdev", "hdev", "ohdev", "totdev"};

// Second (kOrder 2) or third (kOrder 3) difference of x at lag m, starting at x[0].
template <int kOrder>
[[gnu::always_inline]] inline double difference(const double* x, std::size_t m) {
  if constexpr (kOrder == 2)
    return x[2 * m] - 2.0 * x[m] + x[0];
  else
    return x[3 * m] - 3.0 * x[2 * m] + 3.0 * x[m] - x[0];
}

// Partial sums of one overlapping estimate, kept apart so that the additions of consecutive
// terms do not wait for each other (four AVX2 vectors of four lanes in flight).
constexpr std::size_t kLanes = 16;
using Lanes = std::array<double, kLanes>;

// lanes[j] += D(x + i, m)^2 for i < count, i = j mod kLanes. Compiled once per target clone; the
// lane loop is vectorized and the lane assignment does not depend on the clone, so every clone
// gives the same bits.
template <int kOrder>
DRIFTLAB_SIMD_CLONES void accumulate_squares(const double* x, std::size_t count, std::size_t m, Lanes& lanes) {
  Lanes sums = lanes;
  std::size_t i = 0;
  for (; i + kLanes <= count; i += kLanes) {
    for (std::size_t j = 0; j < kLanes; ++j) {
      const double d = difference<kOrder>(x + i + j, m);
      sums[j] += d * d;
    }
  }
  for (std::size_t j = 0; i < count; ++i, ++j) {
    const double d = difference<kOrder>(x + i, m);
    sums[j] += d * d;
  }
  lanes = sums;
}

// One overlapping estimate: the sum of D(e + p, m)^2 over the starts p in [begin, end).
struct OverlappingSum {
  std::size_t m, begin, end;
};

// Cache plan of the overlapping sums. The record e is viewed as rows of `row` samples (a power of
// two, at least L / kMaxRows for a record of L samples):
//   - a sum whose lag is a multiple of the row width combines samples in the same column of rows
//     k, k + m/row, ...: the record is copied one column strip (kStrip samples of every row) at a
//     time into a contiguous buffer (at most kMaxRows * kStrip * 8 bytes, so it stays in L2; the
//     copy also keeps the power-of-two row stride from mapping every row to the same cache set),
//     and all such lags are summed on the buffer, so together they read the record from memory once;
//   - every other sum (the short lags, and long lags that are no multiple of the row width) is
//     swept along the record in blocks of kBlock starts; for lags under the row width the blocks
//     of all lags lie within 2 rows plus a block and are reused from cache.
// For the octave grid this reads the record from memory twice whatever its length, instead of
// once per long lag.
constexpr std::size_t kBlock = 4096;
constexpr std::size_t kStrip = 128;
constexpr std::size_t kMaxRows = 512;
constexpr std::size_t kMinRow = 2048;

template <int kOrder>
std::vector<double> overlapping_sums(const double* e, std::size_t length, std::span<const OverlappingSum> sums) {
  const std::size_t row = std::max(kMinRow, std::bit_ceil(length / kMaxRows + 1));
  std::vector<Lanes> lanes(sums.size(), Lanes{});
  std::vector<std::size_t> swept, striped;
  for (std::size_t k = 0; k < sums.size(); ++k) {
    (sums[k].m % row == 0 ? striped : swept).push_back(k);
  }

  std::size_t last_end = 0;
  for (const std::size_t k : swept) last_end = std::max(last_end, sums[k].end);
  for (std::size_t start = 0; start < last_end; start += kBlock) {
    for (const std::size_t k : swept) {
      const std::size_t lo = std::max(start, sums[k].begin);
      const std::size_t hi = std::min(start + kBlock, sums[k].end);
      if (lo < hi) accumulate_squares<kOrder>(e + lo, hi - lo, sums[k].m, lanes[k]);
    }
  }

  if (!striped.empty()) {
    const std::size_t rows = (length + row - 1) / row;
    std::vector<double> strip(rows * kStrip);
    for (std::size_t column = 0; column < row; column += kStrip) {
      for (std::size_t r = 0; r < rows; ++r) {
        const std::size_t from = r * row + column;
        const std::size_t count = from < length ? std::min(kStrip, length - from) : 0;
        std::copy_n(e + from, count, strip.data() + r * kStrip);
      }
      for (const std::size_t k : striped) {
        // Starts p = r * row + column + t (t < kStrip) sit at strip[r * kStrip + t]: the starts of
        // rows first..last are one run of the strip, clipped at both ends to [begin, end).
        const auto& [m, begin, end] = sums[k];
        if (begin >= end) continue;
        const std::size_t first = begin / row, last = (end - 1) / row;
        const std::size_t lo = std::clamp(begin, first * row + column, first * row + column + kStrip);
        const std::size_t hi = std::clamp(end, last * row + column, last * row + column + kStrip);
        const std::size_t from = first * kStrip + (lo - first * row - column);
        const std::size_t to = last * kStrip + (hi - last * row - column);
        if (from < to) accumulate_squares<kOrder>(strip.data() + from, to - from, m / row * kStrip, lanes[k]);
      }
    }
  }

  std::vector<double> totals(sums.size(), 0.0);
  for (std::size_t k = 0; k < sums.size(); ++k) {
    for (const double lane : lanes[k]) totals[k] += lane;
  }
  return totals;
}

double strided_sum(const double* x, std::size_t terms, std::size_t m, int order) {
  double sum = 0.0;
  for (std::size_t k = 0; k < terms; ++k) {
    const double d = order == 2 ? difference<2>(x + k * m, m) : difference<3>(x + k * m, m);
    sum += d * d;
  }
  return sum;
}

double modified_sum(const double* x, std::size_t terms, std::size_t m) {
  const auto d = [x, m](std::size_t i) { return difference<2>(x + i, m); };
  double window = 0.0;
  for (std::size_t i = 0; i < m; ++i) window += d(i);
  double sum = window * window;
  for (std::size_t j = 1; j < terms; ++j) {
    window += d(j + m - 1) - d(j - 1);
    sum += window * window;
  }
  return sum;
}

Eigen::VectorXd reflected(const Eigen::Ref<const Eigen::VectorXd>& x) {
  const Eigen::Index n = x.size();
  Eigen::VectorXd e(3 * n - 4);
  const Eigen::Index c = n - 2;
  e.segment(c, n) = x;
  for (Eigen::Index j = 1; j <= n - 2; ++j) {
    e(c - j) = 2.0 * x(0) - x(j);
    e(c + n - 1 + j) = 2.0 * x(n - 1) - x(n - 1 - j);
  }
  return e;
}

}  // namespace

std::string_view kind_name(Kind kind) { return kKindNames[static_cast<std::size_t>(kind)]; }

std::optional<Kind> parse_kind(std::string_view name) {
  for (std::size_t i = 0; i < kKindNames.size(); ++i) {
    if (kKindNames[i] == name) return static_cast<Kind>(i);
  }
  return std::nullopt;
}

bool is_hadamard(Kind kind) { return kind == Kind::Hdev || kind == Kind::Ohdev; }

Eigen::VectorXd angle_from_rate(const Eigen::Ref<const Eigen::VectorXd>& rate, double tau0) {
  return angle_from_rate(Eigen::VectorXd(rate), tau0);
}

Eigen::VectorXd angle_from_rate(Eigen::VectorXd&& rate, double tau0) {
  Eigen::VectorXd x = std::move(rate);
  const Eigen::Index n = x.size();
  const double mean = n > 0 ? x.mean() : 0.0;
  x.conservativeResize(n + 1);
  double next_rate = n > 0 ? x(0) : 0.0, angle = 0.0;
  x(0) = 0.0;
  for (Eigen::Index i = 1; i <= n; ++i) {
    const double y = next_rate;
    if (i < n) next_rate = x(i);
    angle += tau0 * (y - mean);
    x(i) = angle;
  }
  return x;
}

std::size_t term_count(Kind kind, std::size_t n, std::size_t m) {
  if (m == 0 || n < 2) return 0;
  const auto positive = [](std::ptrdiff_t v) { return v > 0 ? static_cast<std::size_t>(v) : 0; };
  const auto sn = static_cast<std::ptrdiff_t>(n);
  const auto sm = static_cast<std::ptrdiff_t>(m);
  switch (kind) {
    case Kind::Adev:
      return positive((sn - 1) / sm - 1);
    case Kind::Oadev:
      return positive(sn - 2 * sm);
    case Kind::Mdev:
      return positive(sn - 3 * sm + 1);
    case Kind::Hdev:
      return positive((sn - 1) / sm - 2);
    case Kind::Ohdev:
      return positive(sn - 3 * sm);
    case Kind::Totdev:
      return m <= n - 1 && n >= 3 ? n - 2 : 0;
  }
  return 0;
}

std::size_t max_factor(Kind kind, std::size_t n) {
  switch (kind) {
    case Kind::Adev:
    case Kind::Oadev:
      return n >= 3 ? (n - 1) / 2 : 0;
    case Kind::Mdev:
      return n >= 3 ? n / 3 : 0;
    case Kind::Ohdev:
    case Kind::Hdev:
      return n >= 4 ? (n - 1) / 3 : 0;
    case Kind::Totdev:
      return n >= 3 ? n - 1 : 0;
  }
  return 0;
}

std::vector<Deviation> deviations(Kind kind, const Eigen::Ref<const Eigen::VectorXd>& angle, double tau0,
                                  std::span<const std::size_t> factors) {
  const auto n = static_cast<std::size_t>(angle.size());
  const std::size_t needed = is_hadamard(kind) ? 4 : 3;
  if (n < needed) {
    throw DataError({}, std::string(kind_name(kind)) + " needs at least " + std::to_string(needed) +
                            " angle samples, got " + std::to_string(n));
  }
  if (!(tau0 > 0.0)) throw DataError({}, "sample interval tau0 must be positive");
  const std::size_t limit = max_factor(kind, n);
  std::vector<std::size_t> counts(factors.size());
  for (std::size_t k = 0; k < factors.size(); ++k) {
    if (factors[k] == 0 || factors[k] > limit) {
      throw DataError({}, std::string(kind_name(kind)) + ": averaging factor " + std::to_string(factors[k]) +
                              " outside 1.." + std::to_string(limit) + " for " + std::to_string(n) + " angle samples");
    }
    counts[k] = term_count(kind, n, factors[k]);
  }

  const double* x = angle.data();
  std::vector<double> sums(factors.size(), 0.0);
  Eigen::VectorXd extended;
  if (kind == Kind::Oadev || kind == Kind::Ohdev) {
    std::vector<OverlappingSum> overlapping(factors.size());
    for (std::size_t k = 0; k < factors.size(); ++k) overlapping[k] = {factors[k], 0, counts[k]};
    sums = kind == Kind::Oadev ? overlapping_sums<2>(x, n, overlapping) : overlapping_sums<3>(x, n, overlapping);
  } else if (kind == Kind::Totdev) {
    extended = reflected(angle);
    std::vector<OverlappingSum> overlapping(factors.size());
    for (std::size_t k = 0; k < factors.size(); ++k) {
      const std::size_t begin = (n - 2) + 1 - factors[k];
      overlapping[k] = {factors[k], begin, begin + counts[k]};
    }
    sums = overlapping_sums<2>(extended.data(), static_cast<std::size_t>(extended.size()), overlapping);
  } else {
    for (std::size_t k = 0; k < factors.size(); ++k) {
      if (kind == Kind::Mdev)
        sums[k] = modified_sum(x, counts[k], factors[k]);
      else
        sums[k] = strided_sum(x, counts[k], factors[k], kind == Kind::Hdev ? 3 : 2);
    }
  }

  std::vector<Deviation> out(factors.size());
  for (std::size_t k = 0; k < factors.size(); ++k) {
    const auto m = static_cast<double>(factors[k]);
    const double tau = m * tau0;
    const auto terms = static_cast<double>(counts[k]);
    double variance = 0.0;
    switch (kind) {
      case Kind::Adev:
      case Kind::Oadev:
      case Kind::Totdev:
        variance = sums[k] / (2.0 * terms * tau * tau);
        break;
      case Kind::Mdev:
        variance = sums[k] / (2.0 * m * m * tau * tau * terms);
        break;
      case Kind::Hdev:
      case Kind::Ohdev:
        variance = sums[k] / (6.0 * terms * tau * tau);
        break;
    }
    out[k] = {factors[k], tau, std::sqrt(variance), counts[k]};
  }
  return out;
}

}  // namespace driftlab::allan
