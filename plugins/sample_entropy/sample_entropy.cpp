#include "plugins/sample_entropy/sample_entropy.hpp"

#include "framework/simd.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <utility>

namespace driftlab::sampen {
namespace {

void require_finite(std::span<const double> x) {
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i])) {
      throw std::invalid_argument("sample entropy: sample " + std::to_string(i) + " is not finite");
    }
  }
}

// Pairs i < j with |v[i] - v[j]| < r.
std::int64_t count_close_pairs(std::span<const double> v, double r) {
  std::vector<double> sorted(v.begin(), v.end());
  std::sort(sorted.begin(), sorted.end());
  std::int64_t count = 0;
  std::size_t hi = 0;
  for (std::size_t i = 0; i < sorted.size(); ++i) {
    hi = std::max(hi, i + 1);
    while (hi < sorted.size() && sorted[hi] - sorted[i] < r) ++hi;
    count += static_cast<std::int64_t>(hi - i - 1);
  }
  return count;
}

struct PairCounts {
  std::int64_t prefix = 0;  // pairs matching in coordinates 0 .. coords-2
  std::int64_t full = 0;    // pairs matching in every coordinate
};

constexpr int kMaxUnrolledCoords = 6;

// Counts matches among the candidates j in [a, b) of template i. Coordinate 1 is known to match.
// The 0/1 indicators are summed in double (exact below 2^53, so in any order): with
// -fopenmp-simd the loop becomes a vector reduction.
template <int kCoords>
[[gnu::always_inline]] inline void count_candidates(const std::vector<const double*>& c, std::size_t i, std::size_t a,
                                                    std::size_t b, double r, PairCounts& out) {
  const int coords = kCoords > 0 ? kCoords : static_cast<int>(c.size());
  const double* first = c[0];
  const double* last = c[coords - 1];
  const double first_i = first[i];
  const double last_i = last[i];
  double prefix = 0.0;
  double full = 0.0;
#pragma omp simd reduction(+ : prefix, full)
  for (std::size_t j = a; j < b; ++j) {
    double match = std::fabs(first[j] - first_i) < r ? 1.0 : 0.0;
    for (int k = 2; k < coords - 1; ++k) match = std::fabs(c[k][j] - c[k][i]) < r ? match : 0.0;
    prefix += match;
    full += (coords == 2 || std::fabs(last[j] - last_i) < r) ? match : 0.0;
  }
  out.prefix += static_cast<std::int64_t>(prefix);
  out.full += static_cast<std::int64_t>(full);
}

// Templates t = 0 .. count-1 with coordinates x[t + k], k = 0 .. coords-1 (coords >= 2).
// Compiled for AVX2 and baseline x86-64 (framework/simd.hpp): the candidate loops inlined here
// are the vector reductions.
template <int kCoords>
DRIFTLAB_SIMD_CLONES std::optional<PairCounts> count_template_pairs(std::span<const double> x, std::size_t count,
                                                                    int coords, double r, std::uint64_t budget) {
  std::vector<std::size_t> order(count);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t p, std::size_t q) { return x[p] < x[q]; });

  std::vector<std::size_t> strip_begin;
  for (std::size_t s = 0; s < count;) {
    strip_begin.push_back(s);
    std::size_t e = s + 1;
    while (e < count && x[order[e]] - x[order[s]] < r) ++e;
    std::sort(order.begin() + static_cast<std::ptrdiff_t>(s), order.begin() + static_cast<std::ptrdiff_t>(e),
              [&](std::size_t p, std::size_t q) { return x[p + 1] < x[q + 1]; });
    s = e;
  }
  strip_begin.push_back(count);

  std::vector<std::vector<double>> storage(static_cast<std::size_t>(coords), std::vector<double>(count));
  std::vector<const double*> c(static_cast<std::size_t>(coords));
  for (int k = 0; k < coords; ++k) {
    auto& column = storage[static_cast<std::size_t>(k)];
    for (std::size_t p = 0; p < count; ++p) column[p] = x[order[p] + static_cast<std::size_t>(k)];
    c[static_cast<std::size_t>(k)] = column.data();
  }
  const double* second = c[1];

  PairCounts counts;
  for (std::size_t strip = 0; strip + 1 < strip_begin.size(); ++strip) {
    const std::size_t begin = strip_begin[strip];
    const std::size_t end = strip_begin[strip + 1];
    const std::size_t next_end = strip + 2 < strip_begin.size() ? strip_begin[strip + 2] : end;
    std::size_t same_hi = begin;
    std::size_t next_lo = end;
    std::size_t next_hi = end;
    for (std::size_t i = begin; i < end; ++i) {
      const double s = second[i];
      same_hi = std::max(same_hi, i + 1);
      while (same_hi < end && second[same_hi] - s < r) ++same_hi;
      while (next_lo < next_end && second[next_lo] - s <= -r) ++next_lo;
      next_hi = std::max(next_hi, next_lo);
      while (next_hi < next_end && second[next_hi] - s < r) ++next_hi;
      const std::uint64_t candidates = (same_hi - i - 1) + (next_hi - next_lo);
      if (candidates > budget) return std::nullopt;
      budget -= candidates;
      count_candidates<kCoords>(c, i, i + 1, same_hi, r, counts);
      count_candidates<kCoords>(c, i, next_lo, next_hi, r, counts);
    }
  }
  return counts;
}

// Enumerated counts, or nothing once more than `budget` candidate pairs would be compared.
std::optional<PairCounts> count_template_pairs(std::span<const double> x, std::size_t count, int coords, double r,
                                               std::uint64_t budget) {
  switch (coords) {
    case 2:
      return count_template_pairs<2>(x, count, coords, r, budget);
    case 3:
      return count_template_pairs<3>(x, count, coords, r, budget);
    case 4:
      return count_template_pairs<4>(x, count, coords, r, budget);
    case 5:
      return count_template_pairs<5>(x, count, coords, r, budget);
    case kMaxUnrolledCoords:
      return count_template_pairs<kMaxUnrolledCoords>(x, count, coords, r, budget);
    default:
      return count_template_pairs<0>(x, count, coords, r, budget);
  }
}

// Fenwick (binary indexed) tree over slots 1 .. size of `tree` (slot 0 unused): a point at
// position p (0-based) is counted in slots p + 1, p + 1 + lowbit, ...
std::size_t lowest_bit(std::size_t k) { return k & (~k + 1); }

void fenwick_add(std::int32_t* tree, std::size_t size, std::size_t position, std::int32_t delta) {
  for (std::size_t k = position + 1; k <= size; k += lowest_bit(k)) tree[k] += delta;
}

// Points at positions [0, end).
std::int64_t fenwick_prefix(const std::int32_t* tree, std::size_t end) {
  std::int64_t sum = 0;
  for (std::size_t k = end; k > 0; k -= lowest_bit(k)) sum += tree[k];
  return sum;
}

// Counts of points at positions 0 .. n-1.
class Fenwick {
 public:
  explicit Fenwick(std::size_t n) : tree_(n + 1, 0) {}

  void add(std::size_t position, std::int32_t delta) { fenwick_add(tree_.data(), tree_.size() - 1, position, delta); }

  // Points at positions [lo, hi).
  std::int64_t count(std::size_t lo, std::size_t hi) const {
    return fenwick_prefix(tree_.data(), hi) - fenwick_prefix(tree_.data(), lo);
  }

 private:
  std::vector<std::int32_t> tree_;
};

// Counts of points (u, v) in rank space, for a set of points fixed in advance: node k of a Fenwick
// tree over u keeps the sorted v of the points it covers and a Fenwick tree over them.
class Fenwick2D {
 public:
  Fenwick2D(std::span<const std::uint32_t> u, std::span<const std::uint32_t> v) : n_(u.size()), begin_(n_ + 2, 0) {
    for (std::size_t p = 0; p < n_; ++p) {
      for (std::size_t k = u[p] + 1; k <= n_; k += lowest_bit(k)) ++begin_[k + 1];
    }
    for (std::size_t k = 1; k <= n_ + 1; ++k) begin_[k] += begin_[k - 1];
    values_.resize(begin_[n_ + 1]);
    tree_.assign(begin_[n_ + 1] + n_ + 1, 0);
    std::vector<std::size_t> fill(begin_.begin(), begin_.end() - 1);
    for (std::size_t p = 0; p < n_; ++p) {
      for (std::size_t k = u[p] + 1; k <= n_; k += lowest_bit(k)) values_[fill[k]++] = v[p];
    }
    for (std::size_t k = 1; k <= n_; ++k) {
      std::sort(values_.begin() + static_cast<std::ptrdiff_t>(begin_[k]),
                values_.begin() + static_cast<std::ptrdiff_t>(begin_[k + 1]));
    }
  }

  void add(std::uint32_t u, std::uint32_t v, std::int32_t delta) {
    for (std::size_t k = u + 1; k <= n_; k += lowest_bit(k)) {
      fenwick_add(inner(k), begin_[k + 1] - begin_[k], slot(k, v), delta);
    }
  }

  // Points with u in [u_lo, u_hi) and v in [v_lo, v_hi).
  std::int64_t count(std::size_t u_lo, std::size_t u_hi, std::uint32_t v_lo, std::uint32_t v_hi) const {
    return prefix(u_hi, v_lo, v_hi) - prefix(u_lo, v_lo, v_hi);
  }

 private:
  // Position of v among node k's sorted values (first not below v).
  std::size_t slot(std::size_t k, std::uint32_t v) const {
    const auto first = values_.begin() + static_cast<std::ptrdiff_t>(begin_[k]);
    const auto last = values_.begin() + static_cast<std::ptrdiff_t>(begin_[k + 1]);
    return static_cast<std::size_t>(std::lower_bound(first, last, v) - first);
  }

  // Node k's inner tree: size + 1 slots after the inner trees of nodes 1 .. k-1.
  std::int32_t* inner(std::size_t k) { return tree_.data() + begin_[k] + k; }
  const std::int32_t* inner(std::size_t k) const { return tree_.data() + begin_[k] + k; }

  std::int64_t prefix(std::size_t u_end, std::uint32_t v_lo, std::uint32_t v_hi) const {
    std::int64_t sum = 0;
    for (std::size_t k = u_end; k > 0; k -= lowest_bit(k)) {
      sum += fenwick_prefix(inner(k), slot(k, v_hi)) - fenwick_prefix(inner(k), slot(k, v_lo));
    }
    return sum;
  }

  std::size_t n_;
  std::vector<std::size_t> begin_;     // node k's values in [begin_[k], begin_[k + 1])
  std::vector<std::uint32_t> values_;  // sorted v per node
  std::vector<std::int32_t> tree_;     // per node a Fenwick tree of size + 1 slots
};

// One coordinate of the templates: its values sorted, each template's rank, and the rank interval
// of the values within r of a given value (the same fp test as the definition).
class RankedCoordinate {
 public:
  RankedCoordinate(std::span<const double> x, std::size_t offset, std::size_t count)
      : values_(x.subspan(offset, count)), order_(count), rank_(count), sorted_(count) {
    std::iota(order_.begin(), order_.end(), 0u);
    std::stable_sort(order_.begin(), order_.end(),
                     [&](std::uint32_t p, std::uint32_t q) { return values_[p] < values_[q]; });
    for (std::size_t k = 0; k < count; ++k) {
      rank_[order_[k]] = static_cast<std::uint32_t>(k);
      sorted_[k] = values_[order_[k]];
    }
  }

  double value(std::size_t t) const { return values_[t]; }
  std::uint32_t rank(std::size_t t) const { return rank_[t]; }
  std::span<const std::uint32_t> ranks() const { return rank_; }
  // Templates by increasing value (ties by index).
  std::span<const std::uint32_t> order() const { return order_; }

  // Ranks [lo, hi) of the values v with |value(t) - v| < r.
  std::pair<std::uint32_t, std::uint32_t> matching(std::size_t t, double r) const {
    const double c = values_[t];
    const auto lo = std::partition_point(sorted_.begin(), sorted_.end(), [&](double v) { return !(c - v < r); });
    const auto hi = std::partition_point(lo, sorted_.end(), [&](double v) { return v - c < r; });
    return {static_cast<std::uint32_t>(lo - sorted_.begin()), static_cast<std::uint32_t>(hi - sorted_.begin())};
  }

 private:
  std::span<const double> values_;
  std::vector<std::uint32_t> order_, rank_;
  std::vector<double> sorted_;
};

// Pairs of templates t = 0 .. count-1 (coordinates x[t], x[t+1], and x[t+2] when three) matching
// in the first two coordinates (prefix) and in all of them (full), by range counting.
PairCounts range_count_pairs(std::span<const double> x, std::size_t count, int coords, double r) {
  const RankedCoordinate first(x, 0, count), second(x, 1, count);
  const std::span<const std::uint32_t> order = first.order();
  std::optional<RankedCoordinate> third;
  std::optional<Fenwick2D> boxes;
  if (coords == 3) {
    third.emplace(x, 2, count);
    boxes.emplace(second.ranks(), third->ranks());
  }
  Fenwick strips(count);
  PairCounts counts;
  std::size_t window = 0;  // order[window .. p) are within r of order[p] in the first coordinate
  for (std::size_t p = 0; p < count; ++p) {
    const std::uint32_t t = order[p];
    for (; !(first.value(t) - first.value(order[window]) < r); ++window) {
      const std::uint32_t q = order[window];
      strips.add(second.rank(q), -1);
      if (boxes) boxes->add(second.rank(q), third->rank(q), -1);
    }
    const auto [lo, hi] = second.matching(t, r);
    counts.prefix += strips.count(lo, hi);
    if (boxes) {
      const auto [lo3, hi3] = third->matching(t, r);
      counts.full += boxes->count(lo, hi, lo3, hi3);
    }
    strips.add(second.rank(t), 1);
    if (boxes) boxes->add(second.rank(t), third->rank(t), 1);
  }
  if (coords == 2) counts.full = counts.prefix;
  return counts;
}

// Candidate pairs the enumeration may compare before range counting is cheaper. Measured on the
// reference machine (N = 162k): enumeration ~0.15 ns per candidate, range counting 2-10 us per
// template (the Fenwick tree of sorted lists is cache-unfriendly), so it pays beyond about
// 200 N log2(N)^2 candidates: smooth records of a few million samples.
std::uint64_t enumeration_budget(std::size_t templates) {
  const double n = static_cast<double>(std::max<std::size_t>(templates, 2));
  return static_cast<std::uint64_t>(200.0 * n * std::log2(n) * std::log2(n));
}

std::string format_entropy(double value) {
  if (std::isinf(value)) return "Inf";
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", value);
  return text;
}

void require_no_nan(std::span<const double> entropies) {
  for (const double v : entropies) {
    if (std::isnan(v)) throw std::invalid_argument("sample entropy grouping: NaN entropy");
  }
}

}  // namespace

std::string to_string(Status status) {
  switch (status) {
    case Status::Finite:
      return "finite";
    case Status::NoMatches:
      return "no matches of length m+1 (SampEn = Inf)";
    case Status::Undefined:
      return "no matches of length m (SampEn undefined, reported as Inf)";
  }
  return "unknown";
}

double population_sd(std::span<const double> x) {
  if (x.empty()) throw std::invalid_argument("sample entropy: empty signal");
  const double n = static_cast<double>(x.size());
  const double mean = std::accumulate(x.begin(), x.end(), 0.0) / n;
  double sum_sq = 0.0;
  for (const double v : x) sum_sq += (v - mean) * (v - mean);
  return std::sqrt(sum_sq / n);
}

Result sample_entropy(std::span<const double> x, int m, double tolerance, Counting counting) {
  if (m < 0) throw std::invalid_argument("sample entropy: m must be >= 0");
  if (!(tolerance >= 0.0) || !std::isfinite(tolerance)) {
    throw std::invalid_argument("sample entropy: r must be finite and >= 0");
  }
  require_finite(x);

  Result result;
  result.m = m;
  result.tolerance = tolerance;
  result.n = x.size();
  const std::size_t length = static_cast<std::size_t>(m);
  if (x.size() > length + 1) {
    const std::size_t templates = x.size() - length;
    if (m == 0) {
      const auto n = static_cast<std::int64_t>(x.size());
      result.b = n * (n - 1) / 2;
      result.a = count_close_pairs(x, tolerance);
    } else {
      const int coords = m + 1;
      const bool can_range_count = m <= 2 && tolerance > 0.0;
      std::optional<PairCounts> counts;
      if (counting != Counting::RangeCount || !can_range_count) {
        const std::uint64_t budget = counting == Counting::Automatic && can_range_count
                                         ? enumeration_budget(templates)
                                         : std::numeric_limits<std::uint64_t>::max();
        counts = count_template_pairs(x, templates, coords, tolerance, budget);
      }
      if (!counts) counts = range_count_pairs(x, templates, coords, tolerance);
      result.b = m == 1 ? count_close_pairs(x.first(templates), tolerance) : counts->prefix;
      result.a = counts->full;
    }
  }

  if (result.b == 0) {
    result.status = Status::Undefined;
    result.value = std::numeric_limits<double>::infinity();
  } else if (result.a == 0) {
    result.status = Status::NoMatches;
    result.value = std::numeric_limits<double>::infinity();
  } else {
    result.status = Status::Finite;
    result.value = -std::log(static_cast<double>(result.a) / static_cast<double>(result.b));
  }
  return result;
}

Result sample_entropy_relative(std::span<const double> x, int m, double r_relative) {
  if (!(r_relative >= 0.0) || !std::isfinite(r_relative)) {
    throw std::invalid_argument("sample entropy: r must be finite and >= 0");
  }
  require_finite(x);
  return sample_entropy(x, m, r_relative * population_sd(x));
}

std::vector<Result> sample_entropy_profile(std::span<const double> x, int max_m, double tolerance) {
  if (max_m < 0) throw std::invalid_argument("sample entropy: max_m must be >= 0");
  std::vector<Result> results;
  results.reserve(static_cast<std::size_t>(max_m) + 1);
  for (int m = 0; m <= max_m; ++m) results.push_back(sample_entropy(x, m, tolerance));
  return results;
}

std::string to_string(Group group) {
  switch (group) {
    case Group::Noise:
      return "noise";
    case Group::Mixed:
      return "mixed";
    case Group::Drift:
      return "drift";
  }
  return "unknown";
}

std::vector<GroupDecision> group_by_thresholds(std::span<const double> entropies, double noise_above,
                                               double drift_below) {
  if (!(noise_above > drift_below)) {
    throw std::invalid_argument("sample entropy grouping: noise_above must exceed drift_below");
  }
  require_no_nan(entropies);
  std::vector<GroupDecision> decisions;
  decisions.reserve(entropies.size());
  for (const double v : entropies) {
    const std::string se = "SampEn " + format_entropy(v);
    if (v > noise_above) {
      decisions.push_back({Group::Noise, se + " > noise_above " + format_entropy(noise_above) + " -> noise"});
    } else if (v < drift_below) {
      decisions.push_back({Group::Drift, se + " < drift_below " + format_entropy(drift_below) + " -> drift"});
    } else {
      decisions.push_back({Group::Mixed, "drift_below " + format_entropy(drift_below) + " <= " + se +
                                             " <= noise_above " + format_entropy(noise_above) + " -> mixed"});
    }
  }
  return decisions;
}

std::vector<GroupDecision> group_by_gaps(std::span<const double> entropies) {
  require_no_nan(entropies);
  const std::size_t count = entropies.size();
  std::vector<std::size_t> order(count);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t p, std::size_t q) { return entropies[p] > entropies[q]; });

  struct Gap {
    std::size_t after;  // position in `order` of the value above the gap
    double size;
  };
  std::vector<Gap> gaps;
  for (std::size_t p = 0; p + 1 < count; ++p) {
    const double above = entropies[order[p]];
    const double below = entropies[order[p + 1]];
    const double size = std::isinf(above) && std::isinf(below) ? 0.0 : above - below;
    if (size > 0.0) gaps.push_back({p, size});
  }
  std::stable_sort(gaps.begin(), gaps.end(), [](const Gap& g, const Gap& h) { return g.size > h.size; });
  if (gaps.size() > 2) gaps.resize(2);
  std::sort(gaps.begin(), gaps.end(), [](const Gap& g, const Gap& h) { return g.after < h.after; });

  auto describe_cut = [&](const Gap& gap) {
    return "(" + format_entropy(entropies[order[gap.after]]) + " | " + format_entropy(entropies[order[gap.after + 1]]) +
           ")";
  };

  std::vector<GroupDecision> decisions(count);
  for (std::size_t p = 0; p < count; ++p) {
    GroupDecision& d = decisions[order[p]];
    const std::string se = "SampEn " + format_entropy(entropies[order[p]]);
    if (gaps.empty()) {
      d = {Group::Mixed, se + ": no gap between the SampEn values (one IMF or all equal) -> mixed"};
    } else if (p <= gaps.front().after) {
      d = {Group::Noise, se + " is above the cut " + describe_cut(gaps.front()) + " -> noise"};
    } else if (p > gaps.back().after) {
      d = {Group::Drift, se + " is below the cut " + describe_cut(gaps.back()) + " -> drift"};
    } else {
      d = {Group::Mixed, se + " lies between the cuts " + describe_cut(gaps.front()) + " and " +
                             describe_cut(gaps.back()) + " -> mixed"};
    }
  }
  return decisions;
}

}  // namespace driftlab::sampen
