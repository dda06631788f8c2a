#include "models/allan/confidence.hpp"

#include "framework/error.hpp"

#include <boost/math/distributions/chi_squared.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace driftlab::allan {
namespace {

constexpr std::size_t kMinLag1Points = 30;
constexpr double kJMax = 100.0;

Eigen::VectorXd differenced(const Eigen::VectorXd& z) { return z.tail(z.size() - 1) - z.head(z.size() - 1); }

Eigen::VectorXd averaged_rates(const Eigen::Ref<const Eigen::VectorXd>& x, std::size_t m) {
  const std::size_t count = (static_cast<std::size_t>(x.size()) - 1) / m;
  Eigen::VectorXd z(static_cast<Eigen::Index>(count));
  for (std::size_t k = 0; k < count; ++k) {
    z(static_cast<Eigen::Index>(k)) = x(static_cast<Eigen::Index>((k + 1) * m)) - x(static_cast<Eigen::Index>(k * m));
  }
  return z;
}

double b1_theory(double n, int mu) {
  if (mu == -1) return 1.0;
  if (mu == 0) return n * std::log(n) / (2.0 * (n - 1.0) * std::log(2.0));
  return n * (1.0 - std::pow(n, mu)) / (2.0 * (n - 1.0) * (1.0 - std::pow(2.0, mu)));
}

int alpha_from_b1_ratio(const Eigen::Ref<const Eigen::VectorXd>& x, std::size_t m) {
  const Eigen::VectorXd z = averaged_rates(x, m);
  const double count = static_cast<double>(z.size());
  if (z.size() < 3) return 0;
  const double standard = (z.array() - z.mean()).square().sum() / (count - 1.0);
  const double allan = differenced(z).squaredNorm() / (2.0 * (count - 1.0));
  if (!(allan > 0.0)) return 0;
  const double b1 = standard / allan;
  int mu = 1;
  while (mu > -2 && b1 < std::sqrt(b1_theory(count, mu) * b1_theory(count, mu - 1))) --mu;
  if (mu > -2) return -mu - 1;

  const auto n = static_cast<std::size_t>(x.size());
  if (m > max_factor(Kind::Mdev, n)) return 2;
  const std::array<std::size_t, 1> factor{m};
  const double adev = deviations(Kind::Adev, x, 1.0, factor)[0].dev;
  const double mdev = deviations(Kind::Mdev, x, 1.0, factor)[0].dev;
  if (!(adev > 0.0)) return 2;
  const double ratio = (mdev * mdev) / (adev * adev);
  const double white = 1.0 / static_cast<double>(m);
  const double flicker =
      1.5 * std::log(256.0 / 27.0) / (1.038 + 3.0 * std::log(std::numbers::pi * static_cast<double>(m)));
  return ratio < std::sqrt(white * flicker) ? 2 : 1;
}

// Greenhall & Riley eq. (7): generalized autocovariance of the power-law phase noise.
long double sw(long double t, int alpha) {
  const long double a = std::fabs(t);
  switch (alpha) {
    case 2:
      return -a;
    case 1:
      return a == 0 ? 0.0L : t * t * std::log(a);
    case 0:
      return a * a * a;
    case -1:
      return a == 0 ? 0.0L : t * t * t * t * std::log(a);
    case -2:
      return a * a * a * a * a;
    case -3:
      return a == 0 ? 0.0L : std::pow(t, 6) * std::log(a);
    case -4:
      return std::pow(a, 7);
  }
  throw ConfigError({}, "noise type alpha=" + std::to_string(alpha) + " outside -4..2");
}

constexpr long double kInfiniteF = std::numeric_limits<long double>::infinity();

// Eq. (8): filter with factor F (F = infinity: the phase-difference limit).
long double sx(long double t, long double f, int alpha) {
  if (std::isinf(f)) return sw(t, alpha + 2);
  return f * f * (2.0L * sw(t, alpha) - sw(t - 1.0L / f, alpha) - sw(t + 1.0L / f, alpha));
}

// Eq. (9): d-th difference, binomial weights (-1)^k C(2d, d+k).
long double sz(long double t, long double f, int alpha, int d) {
  static constexpr std::array<std::array<long double, 4>, 3> kWeights{
      {{2.0L, -1.0L, 0.0L, 0.0L}, {6.0L, -4.0L, 1.0L, 0.0L}, {20.0L, -15.0L, 6.0L, -1.0L}}};
  const auto& w = kWeights[static_cast<std::size_t>(d - 1)];
  long double sum = w[0] * sx(t, f, alpha);
  for (int k = 1; k <= d; ++k) {
    sum += w[static_cast<std::size_t>(k)] * (sx(t - k, f, alpha) + sx(t + k, f, alpha));
  }
  return sum;
}

// Eq. (10).
long double basic_sum(long double j_count, long double m_count, long double s, long double f, int alpha, int d) {
  const long double z0 = sz(0.0L, f, alpha, d);
  const long double zj = sz(j_count / s, f, alpha, d);
  long double sum = z0 * z0 + (1.0L - j_count / m_count) * zj * zj;
  for (long double j = 1.0L; j < j_count; j += 1.0L) {
    const long double z = sz(j / s, f, alpha, d);
    sum += 2.0L * (1.0L - j / m_count) * z * z;
  }
  return sum;
}

struct Coefficients {
  double a0;
  double a1;
};

// Table 1 (modified variances) and Table 2 (unmodified), rows alpha = 2..-4, columns d = 1..3;
// NaN where the variance does not converge.
constexpr double kNa = std::numeric_limits<double>::quiet_NaN();
constexpr std::array<std::array<Coefficients, 3>, 7> kTable1{{
    {{{2.0 / 3, 1.0 / 3}, {7.0 / 9, 1.0 / 2}, {22.0 / 25, 2.0 / 3}}},
    {{{0.840, 0.345}, {0.997, 0.616}, {1.141, 0.843}}},
    {{{1.079, 0.368}, {1.033, 0.607}, {1.184, 0.848}}},
    {{{kNa, kNa}, {1.048, 0.534}, {1.180, 0.816}}},
    {{{kNa, kNa}, {1.302, 0.535}, {1.175, 0.777}}},
    {{{kNa, kNa}, {kNa, kNa}, {1.194, 0.703}}},
    {{{kNa, kNa}, {kNa, kNa}, {1.489, 0.702}}},
}};
constexpr std::array<std::array<Coefficients, 3>, 7> kTable2{{
    {{{3.0 / 2, 1.0 / 2}, {35.0 / 18, 1.0}, {231.0 / 100, 3.0 / 2}}},
    {{{78.6, 25.2}, {790.0, 410.0}, {9950.0, 6520.0}}},
    {{{2.0 / 3, 1.0 / 6}, {2.0 / 3, 1.0 / 3}, {7.0 / 9, 1.0 / 2}}},
    {{{kNa, kNa}, {0.852, 0.375}, {0.997, 0.617}}},
    {{{kNa, kNa}, {1.079, 0.368}, {1.033, 0.607}}},
    {{{kNa, kNa}, {kNa, kNa}, {1.053, 0.553}}},
    {{{kNa, kNa}, {kNa, kNa}, {1.302, 0.535}}},
}};
// Table 3 (alpha = 1, unmodified): b0 + b1 ln m.
constexpr std::array<Coefficients, 3> kTable3{{{6.0, 4.0}, {15.23, 12.0}, {47.8, 40.0}}};

Coefficients table(const std::array<std::array<Coefficients, 3>, 7>& t, int alpha, int d) {
  return t[static_cast<std::size_t>(2 - alpha)][static_cast<std::size_t>(d - 1)];
}

double binomial(int n, int k) {
  double r = 1.0;
  for (int i = 1; i <= k; ++i) r = r * (n - k + i) / i;
  return r;
}

// The noise type at factor m, at most the type found at any shorter factor (see the header).
int held_from_rising(int alpha, std::size_t m, const std::vector<Estimate>& shorter) {
  for (const auto& e : shorter)
    if (e.m < m) alpha = std::min(alpha, e.alpha);
  return alpha;
}

}  // namespace

double lag1_autocorrelation(const Eigen::Ref<const Eigen::VectorXd>& z) {
  const Eigen::ArrayXd c = z.array() - z.mean();
  const double denominator = c.square().sum();
  if (!(denominator > 0.0)) return 0.0;
  return (c.head(c.size() - 1) * c.tail(c.size() - 1)).sum() / denominator;
}

int min_alpha(Kind kind) { return is_hadamard(kind) ? -4 : -2; }

NoiseEstimate identify_noise(const Eigen::Ref<const Eigen::VectorXd>& x, std::size_t m, Kind kind, InputType input) {
  if (m == 0 || static_cast<std::size_t>(x.size()) < 2 * m + 1) {
    throw DataError({}, "noise identification needs at least 2 averaging intervals");
  }
  Eigen::VectorXd z;
  int d = 0;
  if (input == InputType::Angle) {
    const Eigen::Index count = (x.size() - 1) / static_cast<Eigen::Index>(m) + 1;
    z.resize(count);
    for (Eigen::Index k = 0; k < count; ++k) z(k) = x(k * static_cast<Eigen::Index>(m));
  } else {
    z = averaged_rates(x, m);
    d = 1;
  }
  const int lowest = min_alpha(kind);
  NoiseEstimate result;
  if (static_cast<std::size_t>(z.size()) < kMinLag1Points) {
    result.method = NoiseMethod::B1Ratio;
    result.alpha = std::clamp(alpha_from_b1_ratio(x, m), lowest, kMaxAlpha);
    result.alpha_estimate = result.alpha;
    return result;
  }
  const int d_max = is_hadamard(kind) ? 3 : 2;
  while (true) {
    const double r1 = lag1_autocorrelation(z);
    const double delta = r1 / (1.0 + r1);
    if (delta < 0.25 || d >= d_max || z.size() < 3) {
      result.alpha_estimate = 2.0 - 2.0 * (delta + d);
      result.alpha = std::clamp(2 - 2 * d - static_cast<int>(std::lround(2.0 * delta)), lowest, kMaxAlpha);
      return result;
    }
    z = differenced(z);
    ++d;
  }
}

double greenhall_edf(int alpha, int d, std::size_t m_factor, std::size_t n_angle, bool overlapping, bool modified) {
  if (d < 1 || d > 3 || alpha + 2 * d <= 1 || alpha > 2) {
    throw ConfigError(
        {}, "edf undefined for alpha=" + std::to_string(alpha) + " with difference order " + std::to_string(d));
  }
  const auto m = static_cast<long double>(m_factor);
  const auto n = static_cast<long double>(n_angle);
  const long double f = modified ? 1.0L : m;
  const long double s = overlapping ? m : 1.0L;
  const long double length = m / f + m * d;
  const long double m_count = 1.0L + std::floor(s * (n - length) / m);
  if (m_count < 1.0L) throw DataError({}, "record too short for an edf at this tau");
  const long double j_count = std::min(m_count, (d + 1) * s);
  const long double r = m_count / s;
  const auto inverse_from_sum = [&](long double jj, long double mm, long double ss, long double ff) {
    const long double z0 = sz(0.0L, ff, alpha, d);
    return basic_sum(jj, mm, ss, ff, alpha, d) / (z0 * z0 * mm);
  };
  long double inverse = 0.0L;
  if (modified) {
    if (j_count <= kJMax) {
      inverse = inverse_from_sum(j_count, m_count, s, 1.0L);
    } else if (r > d + 1) {
      const auto [a0, a1] = table(kTable1, alpha, d);
      inverse = (a0 - a1 / r) / r;
    } else {
      inverse = inverse_from_sum(kJMax, kJMax, kJMax / r, 1.0L);
    }
  } else if (alpha <= 0) {
    if (j_count <= kJMax) {
      const long double ff = m * (d + 1) <= kJMax ? m : kInfiniteF;
      inverse = inverse_from_sum(j_count, m_count, s, ff);
    } else if (r > d + 1) {
      const auto [a0, a1] = table(kTable2, alpha, d);
      inverse = (a0 - a1 / r) / r;
    } else {
      inverse = inverse_from_sum(kJMax, kJMax, kJMax / r, kInfiniteF);
    }
  } else if (alpha == 1) {
    const auto [b0, b1] = kTable3[static_cast<std::size_t>(d - 1)];
    const long double scale = b0 + b1 * std::log(m);
    if (j_count <= kJMax) {
      inverse = inverse_from_sum(j_count, m_count, s, m);
    } else if (r > d + 1) {
      const auto [a0, a1] = table(kTable2, alpha, d);
      inverse = (a0 - a1 / r) / (scale * scale * r);
    } else {
      const long double mp = kJMax / r;
      inverse = basic_sum(kJMax, kJMax, mp, mp, alpha, d) / (scale * scale * kJMax);
    }
  } else {
    if (std::ceil(r) <= d) {
      inverse = inverse_from_sum(j_count, m_count, s, m);
    } else {
      const double a0 = binomial(4 * d, 2 * d) / std::pow(binomial(2 * d, d), 2);
      const double a1 = 0.5 * d;
      inverse = (a0 - a1 / r) / m_count;
    }
  }
  return static_cast<double>(1.0L / inverse);
}

double simple_edf(int alpha, std::size_t n_angle, std::size_t m_factor) {
  const auto n = static_cast<double>(n_angle);
  const auto m = static_cast<double>(m_factor);
  switch (alpha) {
    case 2:
      return (n + 1.0) * (n - 2.0 * m) / (2.0 * (n - m));
    case 1:
      return std::exp(std::sqrt(std::log((n - 1.0) / (2.0 * m)) * std::log((2.0 * m + 1.0) * (n - 1.0) / 4.0)));
    case 0:
      return (3.0 * (n - 1.0) / (2.0 * m) - 2.0 * (n - 2.0) / n) * (4.0 * m * m) / (4.0 * m * m + 5.0);
    case -1:
      return m_factor == 1 ? 2.0 * (n - 2.0) / (2.3 * n - 4.9) : 5.0 * n * n / (4.0 * m * (n + 3.0 * m));
    case -2:
      return (n - 2.0) / (m * (n - 3.0) * (n - 3.0)) * ((n - 1.0) * (n - 1.0) - 3.0 * m * (n - 1.0) + 4.0 * m * m);
  }
  throw ConfigError({}, "simple edf undefined for alpha=" + std::to_string(alpha));
}

double equivalent_dof(Kind kind, int alpha, std::size_t n, std::size_t m) {
  switch (kind) {
    case Kind::Adev:
      return greenhall_edf(alpha, 2, m, n, false, false);
    case Kind::Oadev:
      return greenhall_edf(alpha, 2, m, n, true, false);
    case Kind::Mdev:
      return greenhall_edf(alpha, 2, m, n, true, true);
    case Kind::Hdev:
      return greenhall_edf(alpha, 3, m, n, false, false);
    case Kind::Ohdev:
      return greenhall_edf(alpha, 3, m, n, true, false);
    case Kind::Totdev: {
      if (alpha > 0) return simple_edf(alpha, n, m);
      static constexpr std::array<Coefficients, 3> kHowe{{{1.50, 0.0}, {1.17, 0.22}, {0.93, 0.36}}};
      const auto [b, c] = kHowe[static_cast<std::size_t>(-std::max(alpha, -2))];
      return b * static_cast<double>(n) / static_cast<double>(m) - c;
    }
  }
  return 0.0;
}

Interval chi_square_interval(double dev, double edf, double confidence) {
  if (!(confidence > 0.0 && confidence < 1.0)) {
    throw ConfigError({}, "confidence must lie strictly between 0 and 1");
  }
  if (!(edf > 0.0) || !std::isfinite(edf)) return {0.0, std::numeric_limits<double>::infinity()};
  const boost::math::chi_squared distribution(edf);
  const double tail = 0.5 * (1.0 - confidence);
  const double chi2_lo = boost::math::quantile(distribution, tail);
  const double chi2_hi = boost::math::quantile(distribution, 1.0 - tail);
  return {dev * std::sqrt(edf / chi2_hi), dev * std::sqrt(edf / chi2_lo)};
}

std::vector<Estimate> estimate(Kind kind, const Eigen::Ref<const Eigen::VectorXd>& angle, double tau0, InputType input,
                               std::span<const std::size_t> factors, double confidence) {
  const auto devs = deviations(kind, angle, tau0, factors);
  const auto n = static_cast<std::size_t>(angle.size());
  std::vector<Estimate> out;
  out.reserve(devs.size());
  for (const auto& d : devs) {
    Estimate e{d.m, d.tau, d.dev, 0.0, 0.0, d.terms, 0, 0.0};
    e.alpha = held_from_rising(identify_noise(angle, d.m, kind, input).alpha, d.m, out);
    e.edf = equivalent_dof(kind, e.alpha, n, d.m);
    const Interval bounds = chi_square_interval(d.dev, e.edf, confidence);
    e.dev_lo = bounds.lo;
    e.dev_hi = bounds.hi;
    out.push_back(e);
  }
  return out;
}

std::vector<Estimate> estimate_bursts(Kind kind, std::span<const Eigen::VectorXd> angles, double tau0, InputType input,
                                      std::span<const std::size_t> factors, double confidence) {
  std::vector<Estimate> out;
  out.reserve(factors.size());
  for (const std::size_t m : factors) {
    const std::array<std::size_t, 1> factor{m};
    double sum = 0.0;  // sum over bursts of terms x variance
    std::size_t terms = 0;
    std::vector<int> alphas;
    std::vector<std::size_t> lengths;
    for (const auto& angle : angles) {
      const auto n = static_cast<std::size_t>(angle.size());
      if (n < 2 * m + 1 || term_count(kind, n, m) == 0) continue;
      const Deviation d = deviations(kind, angle, tau0, factor)[0];
      sum += static_cast<double>(d.terms) * d.dev * d.dev;
      terms += d.terms;
      alphas.push_back(identify_noise(angle, m, kind, input).alpha);
      lengths.push_back(n);
    }
    if (terms == 0) {
      throw DataError({}, "no burst is long enough for averaging factor " + std::to_string(m));
    }
    const auto middle = alphas.begin() + static_cast<std::ptrdiff_t>(alphas.size() / 2);
    std::nth_element(alphas.begin(), middle, alphas.end());
    Estimate e{m, static_cast<double>(m) * tau0, std::sqrt(sum / static_cast<double>(terms)), 0.0, 0.0, terms, 0, 0.0};
    e.alpha = held_from_rising(*middle, m, out);
    for (const std::size_t n : lengths) e.edf += equivalent_dof(kind, e.alpha, n, m);
    const Interval bounds = chi_square_interval(e.dev, e.edf, confidence);
    e.dev_lo = bounds.lo;
    e.dev_hi = bounds.hi;
    out.push_back(e);
  }
  return out;
}

}  // namespace driftlab::allan
