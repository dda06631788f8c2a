#include "models/allan/deviation.hpp"

#include "framework/error.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#if defined(__x86_64__) && defined(__GNUC__)
#define DRIFTLAB_SIMD_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define DRIFTLAB_SIMD_CLONES
#endif

namespace driftlab::allan {
namespace {

constexpr std::array<std::string_view, 6> kKindNames = {"adev", "oadev", "mdev",
                                                        "hdev", "ohdev", "totdev"};

// Block length of the cache-blocked sweeps (doubles): small enough that the blocks of every lag
// stay in L2, long enough that the per-block overhead vanishes.
constexpr std::size_t kBlock = 8192;

DRIFTLAB_SIMD_CLONES double second_difference_sum(const double* x, std::size_t count,
                                                  std::size_t m) {
  double sum = 0.0;
#pragma omp simd reduction(+ : sum)
  for (std::size_t i = 0; i < count; ++i) {
    const double d = x[i + 2 * m] - 2.0 * x[i + m] + x[i];
    sum += d * d;
  }
  return sum;
}

DRIFTLAB_SIMD_CLONES double third_difference_sum(const double* x, std::size_t count,
                                                 std::size_t m) {
  double sum = 0.0;
#pragma omp simd reduction(+ : sum)
  for (std::size_t i = 0; i < count; ++i) {
    const double d = x[i + 3 * m] - 3.0 * x[i + 2 * m] + 3.0 * x[i + m] - x[i];
    sum += d * d;
  }
  return sum;
}

// Sums difference(base[k] + i, ., factors[k]) over i < counts[k] for every k in one sweep over
// the record, block by block, so the blocks of all lags are reused from cache.
template <class DifferenceSum>
std::vector<double> blocked_sums(std::span<const double* const> bases,
                                 std::span<const std::size_t> factors,
                                 std::span<const std::size_t> counts, DifferenceSum difference) {
  std::vector<double> sums(factors.size(), 0.0);
  const std::size_t longest = *std::max_element(counts.begin(), counts.end());
  for (std::size_t start = 0; start < longest; start += kBlock) {
    for (std::size_t k = 0; k < factors.size(); ++k) {
      if (start >= counts[k]) continue;
      const std::size_t length = std::min(kBlock, counts[k] - start);
      sums[k] += difference(bases[k] + start, length, factors[k]);
    }
  }
  return sums;
}

double strided_sum(const double* x, std::size_t terms, std::size_t m, int order) {
  double sum = 0.0;
  for (std::size_t k = 0; k < terms; ++k) {
    const double* p = x + k * m;
    const double d = order == 2 ? p[2 * m] - 2.0 * p[m] + p[0]
                                : p[3 * m] - 3.0 * p[2 * m] + 3.0 * p[m] - p[0];
    sum += d * d;
  }
  return sum;
}

double modified_sum(const double* x, std::size_t terms, std::size_t m) {
  const auto d = [x, m](std::size_t i) { return x[i + 2 * m] - 2.0 * x[i + m] + x[i]; };
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
  Eigen::VectorXd x(rate.size() + 1);
  x(0) = 0.0;
  if (rate.size() == 0) return x;
  const double mean = rate.mean();
  for (Eigen::Index i = 0; i < rate.size(); ++i) x(i + 1) = x(i) + tau0 * (rate(i) - mean);
  return x;
}

std::size_t term_count(Kind kind, std::size_t n, std::size_t m) {
  if (m == 0 || n < 2) return 0;
  const auto positive = [](std::ptrdiff_t v) { return v > 0 ? static_cast<std::size_t>(v) : 0; };
  const auto sn = static_cast<std::ptrdiff_t>(n);
  const auto sm = static_cast<std::ptrdiff_t>(m);
  switch (kind) {
    case Kind::Adev: return positive((sn - 1) / sm - 1);
    case Kind::Oadev: return positive(sn - 2 * sm);
    case Kind::Mdev: return positive(sn - 3 * sm + 1);
    case Kind::Hdev: return positive((sn - 1) / sm - 2);
    case Kind::Ohdev: return positive(sn - 3 * sm);
    case Kind::Totdev: return m <= n - 1 && n >= 3 ? n - 2 : 0;
  }
  return 0;
}

std::size_t max_factor(Kind kind, std::size_t n) {
  switch (kind) {
    case Kind::Adev:
    case Kind::Oadev: return n >= 3 ? (n - 1) / 2 : 0;
    case Kind::Mdev: return n >= 3 ? n / 3 : 0;
    case Kind::Ohdev:
    case Kind::Hdev: return n >= 4 ? (n - 1) / 3 : 0;
    case Kind::Totdev: return n >= 3 ? n - 1 : 0;
  }
  return 0;
}

std::vector<Deviation> deviations(Kind kind, const Eigen::Ref<const Eigen::VectorXd>& angle,
                                  double tau0, std::span<const std::size_t> factors) {
  const auto n = static_cast<std::size_t>(angle.size());
  const std::size_t needed = is_hadamard(kind) ? 4 : 3;
  if (n < needed) {
    throw DataError({}, std::string(kind_name(kind)) + " needs at least " +
                            std::to_string(needed) + " angle samples, got " + std::to_string(n));
  }
  if (!(tau0 > 0.0)) throw DataError({}, "sample interval tau0 must be positive");
  const std::size_t limit = max_factor(kind, n);
  std::vector<std::size_t> counts(factors.size());
  for (std::size_t k = 0; k < factors.size(); ++k) {
    if (factors[k] == 0 || factors[k] > limit) {
      throw DataError({}, std::string(kind_name(kind)) + ": averaging factor " +
                              std::to_string(factors[k]) + " outside 1.." +
                              std::to_string(limit) + " for " + std::to_string(n) +
                              " angle samples");
    }
    counts[k] = term_count(kind, n, factors[k]);
  }

  const double* x = angle.data();
  std::vector<double> sums(factors.size(), 0.0);
  Eigen::VectorXd extended;
  if (kind == Kind::Oadev || kind == Kind::Ohdev) {
    std::vector<const double*> bases(factors.size(), x);
    sums = kind == Kind::Oadev ? blocked_sums(bases, factors, counts, second_difference_sum)
                               : blocked_sums(bases, factors, counts, third_difference_sum);
  } else if (kind == Kind::Totdev) {
    extended = reflected(angle);
    std::vector<const double*> bases(factors.size());
    for (std::size_t k = 0; k < factors.size(); ++k) {
      bases[k] = extended.data() + (n - 2) + 1 - factors[k];
    }
    sums = blocked_sums(bases, factors, counts, second_difference_sum);
  } else {
    for (std::size_t k = 0; k < factors.size(); ++k) {
      if (kind == Kind::Mdev) sums[k] = modified_sum(x, counts[k], factors[k]);
      else sums[k] = strided_sum(x, counts[k], factors[k], kind == Kind::Hdev ? 3 : 2);
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
      case Kind::Totdev: variance = sums[k] / (2.0 * terms * tau * tau); break;
      case Kind::Mdev: variance = sums[k] / (2.0 * m * m * tau * tau * terms); break;
      case Kind::Hdev:
      case Kind::Ohdev: variance = sums[k] / (6.0 * terms * tau * tau); break;
    }
    out[k] = {factors[k], tau, std::sqrt(variance), counts[k]};
  }
  return out;
}

}  // namespace driftlab::allan
