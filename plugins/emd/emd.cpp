#include "plugins/emd/emd.hpp"

#include "framework/parallel.hpp"
#include "framework/seeded_random.hpp"
#include "framework/simd.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <memory>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#ifdef DRIFTLAB_AVX2_INTRINSICS
#include <immintrin.h>
#endif

namespace driftlab::emd {
namespace {

using Index = std::ptrdiff_t;

constexpr int kNearest = 3;
constexpr int kMaxEndKnots = 2;
constexpr Index kPad = kMaxEndKnots;
constexpr Index kWrittenPast = 3;  // extrema slots written past the last extremum by a scan

// Sifting storage, written before it is read: allocated without zeroing, so that pages never
// written (the capacity is sized for the densest possible extrema) are never touched. reserve()
// does not keep the contents.
class Buffer {
 public:
  void reserve(std::size_t capacity) {
    if (capacity <= capacity_) return;
    values_ = std::make_unique_for_overwrite<double[]>(capacity);
    capacity_ = capacity;
  }
  std::size_t capacity() const { return capacity_; }
  double* data() const { return values_.get(); }
  double& operator[](Index i) const { return values_[i]; }

 private:
  std::unique_ptr<double[]> values_;
  std::size_t capacity_ = 0;
};

struct Extrema {
  Buffer pos, val;  // interior extrema at [kPad, kPad + count), end knots around them
  Index count = 0;
};

struct ExtremaSet {
  Extrema max, min;
  Index zero_crossings = 0;

  bool siftable() const { return max.count >= 1 && min.count >= 1 && max.count + min.count >= 3; }
};

std::uint64_t bits(double v) { return std::bit_cast<std::uint64_t>(v); }

// Smallest i in [from, to) with x[i] < x[i-1] (kFalling) or x[i] > x[i-1], else `to`. Chunks are
// skipped when no difference in them has its sign bit set (exact for finite samples:
// x[i] < x[i-1] implies x[i] - x[i-1] < 0), and the exact test runs from the first chunk that may
// hold the turn.
template <bool kFalling>
Index next_turn(const double* x, Index from, Index to) {
  constexpr Index kChunk = 8;
  Index i = from;
  for (; i + kChunk <= to; i += kChunk) {
    std::uint64_t signs = 0;
    for (Index k = i; k < i + kChunk; ++k) signs |= bits(kFalling ? x[k] - x[k - 1] : x[k - 1] - x[k]);
    if (signs >> 63) break;
  }
  while (i < to && !(kFalling ? x[i] < x[i - 1] : x[i] > x[i - 1])) ++i;
  return i;
}

// Number of i in [from, to) where the sign bits of x[i] and x[i-1] differ.
DRIFTLAB_SIMD_CLONES Index count_sign_changes(const double* x, Index from, Index to) {
  std::uint64_t changes = 0;
  for (Index k = from; k < to; ++k) changes += (bits(x[k]) ^ bits(x[k - 1])) >> 63;
  return static_cast<Index>(changes);
}

// True when x[i] == x[i - 1] for some i in [from, to).
DRIFTLAB_SIMD_CLONES bool has_equal_neighbours(const double* x, Index from, Index to) {
  Index equal = 0;
  for (Index i = from; i < to; ++i) equal += x[i] == x[i - 1];
  return equal > 0;
}

// Write cursor into the extrema arrays of one kind: the next extremum goes to pos[count], val[count].
struct Appender {
  double *pos, *val;
  Index count;
};

// Appends the strict extrema x[j], j in [lo, hi) (1 <= lo, hi + 1 <= length of x), to `max`
// (x[j] > x[j-1] and x[j] > x[j+1]) and `min` (both <), in order. Every candidate is written and
// the count advances only at an extremum, so there is no branch on the data; up to kWrittenPast
// slots past the last extremum are written.
void append_strict_extrema(const double* x, Index lo, Index hi, Appender& max, Appender& min) {
  Index max_count = max.count, min_count = min.count;
  for (Index j = lo; j < hi; ++j) {
    const double value = x[j], position = static_cast<double>(j);
    max.pos[max_count] = position;
    max.val[max_count] = value;
    max_count += (value > x[j - 1]) & (value > x[j + 1]);
    min.pos[min_count] = position;
    min.val[min_count] = value;
    min_count += (value < x[j - 1]) & (value < x[j + 1]);
  }
  max.count = max_count;
  min.count = min_count;
}

// scan_strict (below) is a head, a vectorized body over the pairs [head, i) and a tail over
// [i, to). The head checks the pair before `from` (or the first pair) for equality and counts the
// sign changes of the pairs it covers into `changes`; it returns the body's first pair, or 0 when
// two neighbours are equal.
Index strict_scan_head(const double* x, Index from, Index& changes) {
  const Index i = std::max<Index>(from, 2);
  if (has_equal_neighbours(x, std::max<Index>(from - 1, 1), i)) return 0;
  changes = count_sign_changes(x, from, i);
  return i;
}

// The tail: false when two neighbours of the pairs [i, to) are equal; otherwise adds `changes`
// and the tail's sign changes to sign_changes and appends the tail's extrema.
bool strict_scan_tail(const double* x, Index i, Index to, Index changes, Appender& max, Appender& min,
                      Index& sign_changes) {
  if (has_equal_neighbours(x, i, to)) return false;
  sign_changes += changes + count_sign_changes(x, i, to);
  append_strict_extrema(x, i - 1, to - 1, max, min);
  return true;
}

#ifdef DRIFTLAB_AVX2_INTRINSICS
// For each 4-bit mask, the 32-bit lane permutation that packs the selected doubles to the front.
struct CompressPermutations {
  alignas(32) std::array<std::array<std::int32_t, 8>, 16> lanes{};
};

constexpr CompressPermutations compress_permutations() {
  CompressPermutations p;
  for (int mask = 0; mask < 16; ++mask) {
    int packed = 0;
    for (int k = 0; k < 4; ++k) {
      if ((mask >> k & 1) == 0) continue;
      p.lanes[mask][2 * packed] = 2 * k;
      p.lanes[mask][2 * packed + 1] = 2 * k + 1;
      ++packed;
    }
  }
  return p;
}

constexpr CompressPermutations kPack = compress_permutations();

// The lanes of v selected by mask, packed to the front.
DRIFTLAB_AVX2_TARGET inline __m256d pack(__m256d v, int mask) {
  const __m256i lanes = _mm256_load_si256(reinterpret_cast<const __m256i*>(kPack.lanes[mask].data()));
  return _mm256_castps_pd(_mm256_permutevar8x32_ps(_mm256_castpd_ps(v), lanes));
}

// Extremum masks of the 4 candidates x[j, j + 4): bit k set when x[j + k] is a maximum (minimum).
// `equal` flags x[j + k] == x[j + k + 1]; `sign_changes` flags a sign-bit change between them.
struct GroupExtrema {
  __m256d value, equal;
  __m256i sign_changes;
  int max, min;
};

DRIFTLAB_AVX2_TARGET inline GroupExtrema group_extrema(const double* x, Index j) {
  const __m256d value = _mm256_loadu_pd(x + j), left = _mm256_loadu_pd(x + j - 1),
                right = _mm256_loadu_pd(x + j + 1);
  return {value, _mm256_cmp_pd(value, right, _CMP_EQ_OQ),
          _mm256_srli_epi64(_mm256_xor_si256(_mm256_castpd_si256(value), _mm256_castpd_si256(right)), 63),
          _mm256_movemask_pd(_mm256_and_pd(_mm256_cmp_pd(value, left, _CMP_GT_OQ),
                                           _mm256_cmp_pd(value, right, _CMP_GT_OQ))),
          _mm256_movemask_pd(_mm256_and_pd(_mm256_cmp_pd(value, left, _CMP_LT_OQ),
                                           _mm256_cmp_pd(value, right, _CMP_LT_OQ)))};
}

// scan_strict (below) for densely packed extrema, 8 pairs at a time: the extrema among each 4
// candidates are packed with one permutation per array and stored together; equalities and sign
// changes are accumulated in vectors.
DRIFTLAB_AVX2_TARGET bool scan_dense_avx2(const double* x, Index from, Index to, Appender& max,
                                          Appender& min, Index& sign_changes) {
  Index changes = 0, i = strict_scan_head(x, from, changes);
  if (i == 0) return false;
  Index max_count = max.count, min_count = min.count;
  const auto append = [&](const GroupExtrema& g, __m256d position) DRIFTLAB_AVX2_TARGET {
    _mm256_storeu_pd(max.pos + max_count, pack(position, g.max));
    _mm256_storeu_pd(max.val + max_count, pack(g.value, g.max));
    _mm256_storeu_pd(min.pos + min_count, pack(position, g.min));
    _mm256_storeu_pd(min.val + min_count, pack(g.value, g.min));
    max_count += _mm_popcnt_u32(static_cast<unsigned>(g.max));
    min_count += _mm_popcnt_u32(static_cast<unsigned>(g.min));
  };
  const __m256d offsets = _mm256_setr_pd(0.0, 1.0, 2.0, 3.0), four = _mm256_set1_pd(4.0);
  __m256d equal = _mm256_setzero_pd();
  __m256i lane_changes = _mm256_setzero_si256();
  for (; i + 8 <= to; i += 8) {
    const GroupExtrema a = group_extrema(x, i - 1), b = group_extrema(x, i + 3);
    equal = _mm256_or_pd(equal, _mm256_or_pd(a.equal, b.equal));
    lane_changes = _mm256_add_epi64(lane_changes, _mm256_add_epi64(a.sign_changes, b.sign_changes));
    const __m256d position = _mm256_add_pd(_mm256_set1_pd(static_cast<double>(i - 1)), offsets);
    append(a, position);
    append(b, _mm256_add_pd(position, four));
  }
  if (_mm256_movemask_pd(equal) != 0) return false;
  alignas(32) std::array<std::int64_t, 4> lanes;
  _mm256_store_si256(reinterpret_cast<__m256i*>(lanes.data()), lane_changes);
  max.count = max_count;
  min.count = min_count;
  return strict_scan_tail(x, i, to, changes + lanes[0] + lanes[1] + lanes[2] + lanes[3], max, min,
                          sign_changes);
}

// scan_strict (below) for sparse extrema, 64 candidates c[k] at a time as bit masks: F_k when
// c[k + 1] < c[k] (falling after c[k]), S_k the sign bit of c[k]. With no equal neighbours,
// c[k] is a maximum where F_k is set and F_{k-1} is not, a minimum where F_{k-1} is set and F_k is
// not, and the sign changes are the set bits of S xor (S >> 1); the few extrema are then taken one
// set bit at a time.
DRIFTLAB_AVX2_TARGET bool scan_sparse_avx2(const double* x, Index from, Index to, Appender& max,
                                           Appender& min, Index& sign_changes) {
  constexpr Index kWord = 64;
  Index changes = 0, i = strict_scan_head(x, from, changes);
  if (i == 0) return false;
  double *max_pos = max.pos, *max_val = max.val, *min_pos = min.pos, *min_val = min.val;
  Index max_count = max.count, min_count = min.count;
  __m256d equal = _mm256_setzero_pd();
  std::uint64_t falling_before = x[i - 1] < x[i - 2];
  for (; i + kWord <= to; i += kWord) {
    const double* c = x + (i - 1);
    std::uint64_t falling = 0, sign = 0;
    for (int g = 0; g < kWord / 4; ++g) {
      const __m256d value = _mm256_loadu_pd(c + 4 * g), right = _mm256_loadu_pd(c + 4 * g + 1);
      equal = _mm256_or_pd(equal, _mm256_cmp_pd(value, right, _CMP_EQ_OQ));
      falling |= static_cast<std::uint64_t>(_mm256_movemask_pd(_mm256_cmp_pd(right, value, _CMP_LT_OQ))) << (4 * g);
      sign |= static_cast<std::uint64_t>(_mm256_movemask_pd(value)) << (4 * g);
    }
    changes += std::popcount(sign ^ (sign >> 1 | (bits(c[kWord]) >> 63) << 63));
    const std::uint64_t before = falling << 1 | falling_before;
    falling_before = falling >> 63;
    for (std::uint64_t maxima = falling & ~before; maxima != 0; maxima &= maxima - 1) {
      const int k = std::countr_zero(maxima);
      max_pos[max_count] = static_cast<double>(i - 1 + k);
      max_val[max_count++] = c[k];
    }
    for (std::uint64_t minima = before & ~falling; minima != 0; minima &= minima - 1) {
      const int k = std::countr_zero(minima);
      min_pos[min_count] = static_cast<double>(i - 1 + k);
      min_val[min_count++] = c[k];
    }
  }
  if (_mm256_movemask_pd(equal) != 0) return false;
  max.count = max_count;
  min.count = min_count;
  return strict_scan_tail(x, i, to, changes, max, min, sign_changes);
}
#endif

// Extrema expected further apart than kSparseSpacing samples on average take the bit-mask scan.
constexpr Index kSparseSpacing = 4;

bool sparse_extrema(const ExtremaSet& e, Index n) { return (e.max.count + e.min.count) * kSparseSpacing < n; }

// For the pairs (x[i - 1], x[i]), i in [from, to), 1 <= from < to: appends the extrema x[i - 1]
// (i >= 2, as append_strict_extrema) and adds the number of sign-bit changes to sign_changes.
// Returns false, leaving sign_changes alone, when x[i - 1] == x[i] for some i in
// [max(from - 1, 1), to) (a flat run needs the turn search's bookkeeping); the appenders are then
// to be discarded.
bool scan_strict(const double* x, Index from, Index to, bool sparse, Appender& max, Appender& min,
                 Index& sign_changes) {
#ifdef DRIFTLAB_AVX2_INTRINSICS
  if (cpu_has_avx2()) {
    return sparse ? scan_sparse_avx2(x, from, to, max, min, sign_changes)
                  : scan_dense_avx2(x, from, to, max, min, sign_changes);
  }
#endif
  Index changes = 0;
  const Index i = strict_scan_head(x, from, changes);
  return i != 0 && strict_scan_tail(x, i, to, changes, max, min, sign_changes);
}

// Interior extrema and zero crossings of a signal scanned block by block, in order. A flat run of
// equal samples that is a peak or a trough counts once, at its middle sample.
class ExtremaScanner {
 public:
  // `sparse`: extrema expected more than kSparseSpacing samples apart (a hint for speed only).
  ExtremaScanner(ExtremaSet& out, bool sparse) : out_(out), sparse_(sparse) {}

  // Scans x[i] for i in [from, to), from >= 1; x[0, from) must be the samples scanned before.
  // Blocks without two equal neighbouring samples in x[from - 2, to) take the branch-free strict
  // test (scan_strict); the others search for each change of direction.
  void scan(const double* x, Index from, Index to) {
    if (to <= from) return;
    Appender max{out_.max.pos.data() + kPad, out_.max.val.data() + kPad, out_.max.count};
    Appender min{out_.min.pos.data() + kPad, out_.min.val.data() + kPad, out_.min.count};
    if (scan_strict(x, from, to, sparse_, max, min, out_.zero_crossings)) {
      out_.max.count = max.count;
      out_.min.count = min.count;
      direction_ = x[to - 1] > x[to - 2] ? 1 : -1;
    } else {
      search(x, from, to);
      out_.zero_crossings += count_sign_changes(x, from, to);
    }
  }

 private:
  void search(const double* x, Index from, Index to) {
    Index i = from;
    if (direction_ == 0) {
      while (i < to && x[i] == x[i - 1]) ++i;
      if (i < to) direction_ = x[i] > x[i - 1] ? 1 : -1;
    }
    while (i < to) {
      i = direction_ > 0 ? next_turn<true>(x, i, to) : next_turn<false>(x, i, to);
      if (i == to) break;
      Index run_start = i - 1;
      while (run_start > 0 && x[run_start - 1] == x[run_start]) --run_start;
      Extrema& e = direction_ > 0 ? out_.max : out_.min;
      e.pos[kPad + e.count] = static_cast<double>((run_start + i - 1) / 2);
      e.val[kPad + e.count] = x[i - 1];
      ++e.count;
      direction_ = -direction_;
    }
  }

  ExtremaSet& out_;
  bool sparse_;
  int direction_ = 0;
};

void find_extrema(const double* x, Index n, bool sparse, ExtremaSet& out) {
  out.max.count = out.min.count = out.zero_crossings = 0;
  ExtremaScanner(out, sparse).scan(x, 1, n);
}

// Extrema of one kind nearest to one end, nearest first; s = distance from the end sample.
struct NearEnd {
  std::array<double, kNearest> s{}, val{};
  int count = 0;
};

// Knots added beyond one end, nearest to the signal first; s <= 0.
struct EndKnots {
  std::array<double, kMaxEndKnots> s{}, val{};
  int count = 0;

  void add(double si, double vi) {
    s[count] = si;
    val[count] = vi;
    ++count;
  }
};

NearEnd near_start(const Extrema& e) {
  NearEnd near;
  near.count = static_cast<int>(std::min<Index>(kNearest, e.count));
  for (int k = 0; k < near.count; ++k) {
    near.s[k] = e.pos[kPad + k];
    near.val[k] = e.val[kPad + k];
  }
  return near;
}

NearEnd near_finish(const Extrema& e, Index n) {
  NearEnd near;
  near.count = static_cast<int>(std::min<Index>(kNearest, e.count));
  for (int k = 0; k < near.count; ++k) {
    near.s[k] = static_cast<double>(n - 1) - e.pos[kPad + e.count - 1 - k];
    near.val[k] = e.val[kPad + e.count - 1 - k];
  }
  return near;
}

EndKnots reflect(const NearEnd& near, int from, int to, double axis) {
  EndKnots knots;
  for (int k = from; k < std::min(to, near.count); ++k) knots.add(2.0 * axis - near.s[k], near.val[k]);
  return knots;
}

bool reaches_end(const EndKnots& knots) { return knots.count > 0 && knots.s[knots.count - 1] <= 0.0; }

void mirror_end(const NearEnd& max, const NearEnd& min, double end_value, EndKnots& max_knots,
                EndKnots& min_knots) {
  const bool max_nearest = max.s[0] < min.s[0];
  const NearEnd& nearest = max_nearest ? max : min;
  const NearEnd& other = max_nearest ? min : max;
  EndKnots& nearest_knots = max_nearest ? max_knots : min_knots;
  EndKnots& other_knots = max_nearest ? min_knots : max_knots;
  const bool end_beyond_other = max_nearest ? end_value <= other.val[0] : end_value >= other.val[0];
  if (end_beyond_other) {
    nearest_knots = reflect(nearest, 0, kMaxEndKnots, 0.0);
    other_knots = EndKnots{};
    other_knots.add(0.0, end_value);
    const EndKnots mirrored = reflect(other, 0, kMaxEndKnots - 1, 0.0);
    for (int k = 0; k < mirrored.count; ++k) other_knots.add(mirrored.s[k], mirrored.val[k]);
    return;
  }
  const double axis = nearest.s[0];
  nearest_knots = reflect(nearest, 1, kMaxEndKnots + 1, axis);
  other_knots = reflect(other, 0, kMaxEndKnots, axis);
  if (!reaches_end(nearest_knots) || !reaches_end(other_knots)) {
    max_knots = reflect(max, 0, kMaxEndKnots, 0.0);
    min_knots = reflect(min, 0, kMaxEndKnots, 0.0);
  }
}

EndKnots linear_end(const NearEnd& near, double end_value, bool upper) {
  double value = near.val[0];
  if (near.count >= 2) value -= near.s[0] * (near.val[1] - near.val[0]) / (near.s[1] - near.s[0]);
  value = upper ? std::max(value, end_value) : std::min(value, end_value);
  EndKnots knots;
  knots.add(0.0, value);
  return knots;
}

constexpr int kSmallSteps = 64;

constexpr std::array<double, kSmallSteps> small_step_inverses() {
  std::array<double, kSmallSteps> inverses{};
  for (int h = 1; h < kSmallSteps; ++h) inverses[h] = 1.0 / h;
  return inverses;
}

constexpr std::array<double, kSmallSteps> kSmallStepInverses = small_step_inverses();

// 1/h for a knot spacing h (a whole number of samples); small spacings from a table.
double inverse_step(Index h) {
  return h < kSmallSteps ? kSmallStepInverses[h] : 1.0 / static_cast<double>(h);
}

double inverse_step(double h) { return inverse_step(static_cast<Index>(h)); }

// A cubic spline in the second-derivative form: knots (x[k], y[k]) and second derivatives m[k],
// k < knots. On [x_j, x_{j+1}], with h = x_{j+1} - x_j and dt = t - x_j,
//   S(t) = y_j + dt (b + dt (c + dt d)),  b = (y_{j+1} - y_j)/h - h (2 m_j + m_{j+1})/6,
//   c = m_j / 2,  d = (m_{j+1} - m_j) / (6 h);
// the coefficients are formed when a piece is evaluated, so a fit writes one value per knot.
struct Spline {
  const double *x = nullptr, *y = nullptr, *m = nullptr;
  Index knots = 0;
};

struct SplineScratch {
  Buffer second, ratio;

  void reserve(std::size_t capacity) {
    second.reserve(capacity);
    ratio.reserve(capacity);
  }
};

constexpr Index kGroup = 4;
using Group = double __attribute__((vector_size(kGroup * sizeof(double))));  // GCC/Clang vector

using GroupBits = std::uint64_t __attribute__((vector_size(kGroup * sizeof(std::uint64_t))));

// One sweep of the homogeneous Thomas elimination through the rows of a spline's tridiagonal
// system, in either direction, for a scalar or for vector lanes (V = double or Group). A row i
// with neighbours i-1 and i+1 in the order of the sweep, multiplied through by h_{i-1} h_i (the
// spacings in sweep order, negative in a backward sweep, which scales the row by -1 and changes
// nothing), reads sub = h_{i-1}^2 h_i, diag = 2 (h_{i-1} + h_i) h_{i-1} h_i, super = h_i^2 h_{i-1},
// rhs = 6 (dy_i h_{i-1} - dy_{i-1} h_i). With pivot_i = Q_i / Q_{i-1}, the eliminated row is
// m_i + ratio_i m_next = second_i, ratio_i = P_i / Q_i, second_i = R_i / Q_i, where P, Q, R are
// linear recurrences: no division sits on the dependency chain. (P, Q, R) are rescaled by a power
// of two every kRescaleEvery rows (a plain row grows |Q| by at most 4 h^3, the first row, which is
// not multiplied through, by O(h^2), so 8 rows stay in range for spacings h < 2^40).
template <class V>
struct Sweep {
  V p, q, r;     // state after the last row
  V x, y;        // the knot of the next row
  V before, rise;  // spacing and rise from the last row's knot to it

  // Eliminates the next row, whose far neighbour is (next_x, next_y).
  void row(V next_x, V next_y, V& ratio, V& second) {
    const V after = next_x - x, next_rise = next_y - y, both = before * after, sum = before + after;
    const V sub = before * both, diag = (sum + sum) * both, super = after * both;
    const V rhs = 6.0 * (next_rise * before - rise * after);
    const V next_p = super * q, next_q = diag * q - sub * p, next_r = rhs * q - sub * r;
    const V inverse_q = 1.0 / next_q;
    ratio = next_p * inverse_q;
    second = next_r * inverse_q;
    p = next_p;
    q = next_q;
    r = next_r;
    x = next_x;
    y = next_y;
    before = after;
    rise = next_rise;
  }

  // Lane l of a vector sweep (V = Group), as a scalar sweep, and back.
  Sweep<double> lane(int l) const { return {p[l], q[l], r[l], x[l], y[l], before[l], rise[l]}; }
  void set_lane(int l, const Sweep<double>& s) {
    p[l] = s.p;
    q[l] = s.q;
    r[l] = s.r;
    x[l] = s.x;
    y[l] = s.y;
    before[l] = s.before;
    rise[l] = s.rise;
  }

  // Divides P, Q, R by 2^e for the binary exponent e of (each lane of) Q: exact, built from the
  // bits (Q normal), so no libm call sits in the elimination loop.
  void rescale() {
    using Bits = std::conditional_t<std::is_same_v<V, double>, std::uint64_t, GroupBits>;
    const Bits exponent_bits = __builtin_bit_cast(Bits, q) & 0x7ff0000000000000ULL;
    const V scale = __builtin_bit_cast(V, 0x7fe0000000000000ULL - exponent_bits);
    p *= scale;
    q *= scale;
    r *= scale;
  }
};

constexpr Index kRescaleEvery = 8;

// The first row of a sweep, next to an end knot e, with the not-a-knot condition folded in (the
// end's second derivative eliminated): row knot `at`, far neighbour `next`, all in sweep order.
Sweep<double> first_row(const double* x, const double* y, Index e, Index at, Index next, double& ratio,
                        double& second) {
  const double before = x[at] - x[e], after = x[next] - x[at];
  const double rise = y[at] - y[e], next_rise = y[next] - y[at];
  const double diag = 2.0 * (before + after) + before * (before + after) / after;
  const double super = after - before * before / after;
  const double rhs = 6.0 * (next_rise / after - rise / before);
  ratio = super / diag;
  second = rhs / diag;
  return {super, diag, rhs, x[next], y[next], after, next_rise};
}

// One spline's knots (x[k], y[k]), k < n, x strictly increasing whole numbers, and where its fit
// writes: the second derivatives m (n values) and, for the rows solved one at a time, ratio.
struct SplineSystem {
  const double *x, *y;
  Index n;
  double *m, *ratio;
};

// Rows eliminated in vector lanes: ratio and second of lane l at step t in [4 t + l].
struct LaneScratch {
  Buffer ratio, second;

  void reserve(std::size_t capacity) {
    ratio.reserve(2 * capacity);
    second.reserve(2 * capacity);
  }
};

// Not-a-knot cubic splines through two knot sets (n >= 2 each), fitted together: fills m. The
// tridiagonal system of each spline with n >= 4 (rows 1..R, R = n - 2, for M_1..M_R; M_0 and
// M_{n-1} eliminated by the not-a-knot conditions) is eliminated from both ends at once, forward
// from row 1 and backward from row R, the four sweeps of the two splines in the four lanes of a
// vector (each waits on its previous row, four chains in flight overlap). The sweeps meet at rows
// meet, meet + 1 (meet = R - common - 1; the rows between the lanes' common reach and meet are
// swept forward one at a time), whose two eliminated equations give M_meet and M_{meet+1}; the
// back substitution then runs from there towards both ends, again four chains in four lanes.
DRIFTLAB_SIMD_CLONES void fit_splines(const SplineSystem& a, const SplineSystem& b, LaneScratch& scratch) {
  double *lane_ratio = scratch.ratio.data(), *lane_second = scratch.second.data();
  const std::array<const SplineSystem*, 2> systems{&a, &b};
  for (const SplineSystem* s : systems) {
    if (s->n == 2) {
      s->m[0] = s->m[1] = 0.0;
    } else if (s->n == 3) {
      const double left = (s->y[1] - s->y[0]) / (s->x[1] - s->x[0]);
      const double right = (s->y[2] - s->y[1]) / (s->x[2] - s->x[1]);
      s->m[0] = s->m[1] = s->m[2] = 2.0 * (right - left) / (s->x[2] - s->x[0]);
    }
  }
  const Index common = a.n >= 4 && b.n >= 4 ? std::min(a.n - 4, b.n - 4) / 2 : 0;
  std::array<Sweep<double>, 4> sweeps;  // a forward, b forward, a backward, b backward
  for (int which = 0; which < 2; ++which) {
    const SplineSystem& s = *systems[which];
    if (s.n < 4) continue;
    const Index last = s.n - 2;
    sweeps[which] = first_row(s.x, s.y, 0, 1, 2, s.ratio[1], s.m[1]);
    sweeps[2 + which] = first_row(s.x, s.y, last + 1, last, last - 1, s.ratio[last], s.m[last]);
  }
  if (common > 0) {
    Sweep<Group> sweep;
    for (int l = 0; l < kGroup; ++l) sweep.set_lane(l, sweeps[l]);
    // Step t eliminates row t + 2 forward (far neighbour t + 3) and row R - 1 - t backward (far
    // neighbour R - 2 - t = n - 4 - t).
    const double *ax = a.x, *ay = a.y, *bx = b.x, *by = b.y;
    for (Index t = 0; t < common; ++t) {
      const Index f = t + 3, fa = a.n - 4 - t, fb = b.n - 4 - t;
      Group ratio, second;
      sweep.row(Group{ax[f], bx[f], ax[fa], bx[fb]}, Group{ay[f], by[f], ay[fa], by[fb]}, ratio, second);
      std::memcpy(lane_ratio + kGroup * t, &ratio, sizeof ratio);
      std::memcpy(lane_second + kGroup * t, &second, sizeof second);
      if (t % kRescaleEvery == 0) sweep.rescale();
    }
    for (int l = 0; l < kGroup; ++l) sweeps[l] = sweep.lane(l);
  }
  // The rows between the lanes' reach, forward; then the meeting, and the back substitution of
  // those rows. chain: M of the row next to the one substituted, per lane.
  Group chain{};
  for (int which = 0; which < 2; ++which) {
    const SplineSystem& s = *systems[which];
    if (s.n < 4) continue;
    Sweep<double>& forward = sweeps[which];
    const Sweep<double>& backward = sweeps[2 + which];
    const Index meet = s.n - 3 - common;
    for (Index i = common + 2; i <= meet; ++i) {
      forward.row(s.x[i + 1], s.y[i + 1], s.ratio[i], s.m[i]);
      forward.rescale();
    }
    const double ratio = forward.p / forward.q, second = forward.r / forward.q;
    const double back_ratio = backward.p / backward.q, back_second = backward.r / backward.q;
    const double m_meet = (second - ratio * back_second) / (1.0 - ratio * back_ratio);
    double down = back_second - back_ratio * m_meet;
    for (Index i = meet; i >= common + 2; --i) {
      down = s.m[i] - s.ratio[i] * down;
      s.m[i] = down;
    }
    chain[which] = down;
    chain[2 + which] = m_meet;
  }
  double *am = a.m, *bm = b.m, *am_back = a.m + a.n - 3, *bm_back = b.m + b.n - 3;
  for (Index t = common - 1; t >= 0; --t) {
    Group ratio, second;
    std::memcpy(&ratio, lane_ratio + kGroup * t, sizeof ratio);
    std::memcpy(&second, lane_second + kGroup * t, sizeof second);
    chain = second - ratio * chain;
    am[t + 2] = chain[0];
    bm[t + 2] = chain[1];
    am_back[-t] = chain[2];
    bm_back[-t] = chain[3];
  }
  for (int which = 0; which < 2; ++which) {
    const SplineSystem& s = *systems[which];
    if (s.n < 4) continue;
    const Index last = s.n - 2;
    s.m[1] -= s.ratio[1] * chain[which];
    s.m[last] -= s.ratio[last] * chain[2 + which];
    const double* x = s.x;
    const double ha = x[last] - x[last - 1], hb = x[last + 1] - x[last];
    s.m[last + 1] = ((ha + hb) * s.m[last] - hb * s.m[last - 1]) * inverse_step(ha);
    const double h0 = x[1] - x[0], h1 = x[2] - x[1];
    s.m[0] = ((h0 + h1) * s.m[1] - h0 * s.m[2]) * inverse_step(h1);
  }
}

// Values of a spline at the samples t in [from, to) into out[t - from], writing up to
// groups * kGroup - 1 values past `to`. Piece j serves t in [x_j, x_{j+1}) (the last piece also
// beyond its right knot); `piece` is the piece serving `from` on entry (or an earlier one) and the
// one serving `to` on return. Each piece is evaluated kGroup samples at a time (vectorized), at
// least `groups` groups whatever its length, overwriting the next piece's first samples when it is
// shorter: the densely packed knots of the first IMFs (pieces of 1 to 8 samples) then cost no
// mispredicted branch. Whole pieces inside the block go four at a time, their cubics formed in
// vector lanes and evaluated at the same offsets (groups = 2..6; a transpose turns the offsets'
// vectors into the pieces' groups).
constexpr Group kGroupOffsets = {0.0, 1.0, 2.0, 3.0};

// First sample past piece j of a spline: its right knot, or `beyond` for the last piece (which
// also serves the samples past its right knot).
[[gnu::always_inline]] inline Index piece_end(const Spline& spline, Index j, Index beyond) {
  return j + 2 >= spline.knots ? beyond : static_cast<Index>(spline.x[j + 1]);
}

// Piece j of a spline as y0 + dt (b + dt (c + dt d)), dt = t - x_j (of one piece, or of one piece
// per lane).
template <class V>
struct CubicOf {
  V y0, b, c, d;
};
using Cubic = CubicOf<double>;

// The piece of length `step` (inverse = 1 / step) between knots (y0, m0) and (y1, m1).
template <class V>
[[gnu::always_inline]] inline CubicOf<V> cubic(V step, V inverse, V y0, V y1, V m0, V m1) {
  constexpr double kSixth = 1.0 / 6.0;
  return {y0, (y1 - y0) * inverse - step * (2.0 * m0 + m1) * kSixth, 0.5 * m0, (m1 - m0) * inverse * kSixth};
}

// Piece j for the sparse path, whose pieces are too long for the table of 1/h (a division does
// not mispredict).
[[gnu::always_inline]] inline Cubic piece_of(const Spline& spline, Index j) {
  const double *x = spline.x, *y = spline.y, *m = spline.m;
  const double step = x[j + 1] - x[j];
  return cubic<double>(step, 1.0 / step, y[j], y[j + 1], m[j], m[j + 1]);
}

// The same cubic in s = t - (x_j + delta).
[[gnu::always_inline]] inline Cubic shifted(const Cubic& g, double delta) {
  return {g.y0 + delta * (g.b + delta * (g.c + delta * g.d)), g.b + delta * (2.0 * g.c + 3.0 * g.d * delta),
          g.c + 3.0 * g.d * delta, g.d};
}

// o[k] = y0 + t_k (b + t_k (c + t_k d)) for the kGroup positions t_k.
[[gnu::always_inline]] inline void store_cubic(double* o, Group t, double y0, double b, double c,
                                               double d) {
  const Group value = y0 + t * (b + t * (c + t * d));
  std::memcpy(o, &value, sizeof value);
}

// The 4x4 transpose of rows v[0..3]: lane i of v[k] becomes lane k of v[i].
[[gnu::always_inline]] inline void transpose(Group* v) {
  // __builtin_shufflevector (GCC >= 12 and clang) with constant lane indices: even, odd, low, high.
  const Group t0 = __builtin_shufflevector(v[0], v[1], 0, 4, 2, 6), t1 = __builtin_shufflevector(v[0], v[1], 1, 5, 3, 7);
  const Group t2 = __builtin_shufflevector(v[2], v[3], 0, 4, 2, 6), t3 = __builtin_shufflevector(v[2], v[3], 1, 5, 3, 7);
  v[0] = __builtin_shufflevector(t0, t2, 0, 1, 4, 5);
  v[1] = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
  v[2] = __builtin_shufflevector(t0, t2, 2, 3, 6, 7);
  v[3] = __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
}

// Pieces j .. j+3 of a spline, each starting at its left knot (out[0] is sample `from`), kGroups
// groups each, in order (a piece's first groups overwrite what the previous one wrote past its
// end). Their cubics are formed together, one lane each, and evaluated at the same offsets; a
// piece longer than kGroups groups gets the rest with its last group ending at its right knot.
template <int kGroups>
[[gnu::always_inline]] inline void evaluate_four(const Spline& spline, Index j, Index from, double* out) {
  Group x0, x1, y0, y1, m0, m1;
  std::memcpy(&x0, spline.x + j, sizeof x0);
  std::memcpy(&x1, spline.x + j + 1, sizeof x1);
  std::memcpy(&y0, spline.y + j, sizeof y0);
  std::memcpy(&y1, spline.y + j + 1, sizeof y1);
  std::memcpy(&m0, spline.m + j, sizeof m0);
  std::memcpy(&m1, spline.m + j + 1, sizeof m1);
  const Group step = x1 - x0;
  const CubicOf<Group> g = cubic(step, 1.0 / step, y0, y1, m0, m1);
  Group values[kGroups][kGroup];  // [group][offset in group] across the pieces, then transposed
  for (int k = 0; k < kGroups; ++k) {
    for (int i = 0; i < kGroup; ++i) {
      const double t = static_cast<double>(k * kGroup + i);
      values[k][i] = g.y0 + t * (g.b + t * (g.c + t * g.d));
    }
    transpose(values[k]);
  }
#pragma GCC unroll 4
  for (int lane = 0; lane < kGroup; ++lane) {
    double* o = out + (static_cast<Index>(x0[lane]) - from);
#pragma GCC unroll 8
    for (int k = 0; k < kGroups; ++k) std::memcpy(o + k * kGroup, &values[k][lane], sizeof(Group));
  }
  for (int lane = 0; lane < kGroup; ++lane) {
    const auto length = static_cast<Index>(step[lane]);
    if (length <= kGroups * kGroup) continue;
    double* o = out + (static_cast<Index>(x0[lane]) - from);
    const auto store = [&](Index offset) {
      const Group t = static_cast<double>(offset) + kGroupOffsets;
      store_cubic(o + offset, t, g.y0[lane], g.b[lane], g.c[lane], g.d[lane]);
    };
    for (Index offset = kGroups * kGroup; offset + kGroup < length; offset += kGroup) store(offset);
    store(length - kGroup);
  }
}

// Evaluates whole pieces j, j+1, ... four at a time while they end before `to` (and none is the
// last piece); returns the first piece not evaluated.
template <int kGroups>
[[gnu::always_inline]] inline Index evaluate_whole_pieces(const Spline& spline, Index j, Index from, Index to,
                                                          double* out) {
  for (; j + kGroup <= spline.knots - 2 && spline.x[j + kGroup] < static_cast<double>(to); j += kGroup)
    evaluate_four<kGroups>(spline, j, from, out);
  return j;
}

[[gnu::always_inline]] inline Index evaluate_whole_pieces(const Spline& spline, Index j, Index from, Index to,
                                                          Index groups, double* out) {
  switch (groups) {
    case 2: return evaluate_whole_pieces<2>(spline, j, from, to, out);
    case 3: return evaluate_whole_pieces<3>(spline, j, from, to, out);
    case 4: return evaluate_whole_pieces<4>(spline, j, from, to, out);
    case 5: return evaluate_whole_pieces<5>(spline, j, from, to, out);
    case 6: return evaluate_whole_pieces<6>(spline, j, from, to, out);
    default: return j;
  }
}

DRIFTLAB_SIMD_CLONES void evaluate_block(const Spline& spline, Index& piece, Index from, Index to,
                                         Index groups, double* out) {
  const double *x = spline.x, *y = spline.y, *m = spline.m;
  const Index last_piece = spline.knots - 2;
  Index j = piece;
  while (piece_end(spline, j, to) <= from) ++j;
  // One piece per pass, j advancing unconditionally (no data-dependent update on the loop's
  // critical path); the piece that reaches `to` ends the block and may serve the next one. Knot
  // positions are whole numbers, handled as integers.
  auto left = static_cast<Index>(x[j]);
  for (Index a = from;; ++j) {
    if (a == left) {
      j = evaluate_whole_pieces(spline, j, from, to, groups, out);
      a = left = static_cast<Index>(x[j]);
    }
    const auto right = static_cast<Index>(x[j + 1]);
    const Index next_knot = j >= last_piece ? to : right, end = std::min(next_knot, to);
    const Index step = right - left;
    const Cubic g =
        cubic<double>(static_cast<double>(step), inverse_step(step), y[j], y[j + 1], m[j], m[j + 1]);
    const auto store = [&g](double* o, Group t) { store_cubic(o, t, g.y0, g.b, g.c, g.d); };
    double* o = out + (a - from);
    Group t = static_cast<double>(a - left) + kGroupOffsets;
    store(o, t);
    store(o + kGroup, t + static_cast<double>(kGroup));
    t += static_cast<double>(2 * kGroup);
    Index k = 2;
    for (; k < groups; ++k, t += static_cast<double>(kGroup)) store(o + k * kGroup, t);
    for (; a + k * kGroup < end; ++k, t += static_cast<double>(kGroup)) store(o + k * kGroup, t);
    if (next_knot >= to) break;
    a = next_knot;
    left = right;
  }
  piece = j;
}

// h[i] -= (upper[i] + lower[i]) / 2 for i < count. With kWithChangeRatio, adds sum h^2 and
// sum mean^2 (before the subtraction) to sums[0] and sums[1].
template <bool kWithChangeRatio>
[[gnu::always_inline]] inline void subtract_mean(double* h, const double* upper,
                                                 const double* lower, Index count, double* sums) {
  for (Index i = 0; i < count; ++i) {
    const double mean = 0.5 * (upper[i] + lower[i]);
    if constexpr (kWithChangeRatio) {
      sums[0] += h[i] * h[i];
      sums[1] += mean * mean;
    }
    h[i] -= mean;
  }
}

DRIFTLAB_SIMD_CLONES void subtract_mean(double* h, const double* upper, const double* lower,
                                        Index count) {
  subtract_mean<false>(h, upper, lower, count, nullptr);
}

// h[t] -= (upper(t) + lower(t)) / 2 for t in [from, to), for sparse knots: one interval between
// consecutive knots of either spline at a time, the mean of the two pieces expanded about the
// interval's first sample, so each sample costs one cubic. `upper_piece` and `lower_piece` carry
// the pieces from block to block as in evaluate_block. With kWithChangeRatio, adds sum h^2 and
// sum mean^2 (before the subtraction) to sums[0] and sums[1].
template <bool kWithChangeRatio>
[[gnu::always_inline]] inline void subtract_mean_by_intervals(const Spline& upper, const Spline& lower,
                                                              Index& upper_piece, Index& lower_piece,
                                                              double* h, Index from, Index to, double* sums) {
  Index ju = upper_piece, jl = lower_piece;
  while (piece_end(upper, ju, to) <= from) ++ju;
  while (piece_end(lower, jl, to) <= from) ++jl;
  // The current piece of each spline and where it ends; each interval ends one of them.
  Cubic upper_cubic = piece_of(upper, ju), lower_cubic = piece_of(lower, jl);
  Index upper_end = piece_end(upper, ju, to), lower_end = piece_end(lower, jl, to);
  for (Index a = from;;) {
    const Index end = std::min({upper_end, lower_end, to});
    const double t0 = static_cast<double>(a);
    const Cubic u = shifted(upper_cubic, t0 - upper.x[ju]);
    const Cubic l = shifted(lower_cubic, t0 - lower.x[jl]);
    const Cubic mean{0.5 * (u.y0 + l.y0), 0.5 * (u.b + l.b), 0.5 * (u.c + l.c), 0.5 * (u.d + l.d)};
    double* piece = h + a;
    const Index length = end - a;
    Index k = 0;
    if constexpr (!kWithChangeRatio) {
      for (Group sk = kGroupOffsets; k + kGroup <= length; k += kGroup, sk += static_cast<double>(kGroup)) {
        Group values;
        std::memcpy(&values, piece + k, sizeof values);
        values -= mean.y0 + sk * (mean.b + sk * (mean.c + sk * mean.d));
        std::memcpy(piece + k, &values, sizeof values);
      }
    }
    for (; k < length; ++k) {
      const double sk = static_cast<double>(k);
      const double value = mean.y0 + sk * (mean.b + sk * (mean.c + sk * mean.d));
      if constexpr (kWithChangeRatio) {
        sums[0] += piece[k] * piece[k];
        sums[1] += value * value;
      }
      piece[k] -= value;
    }
    a = end;
    if (a >= to) break;
    if (upper_end == a) {
      ++ju;
      upper_cubic = piece_of(upper, ju);
      upper_end = piece_end(upper, ju, to);
    }
    if (lower_end == a) {
      ++jl;
      lower_cubic = piece_of(lower, jl);
      lower_end = piece_end(lower, jl, to);
    }
  }
  upper_piece = ju;
  lower_piece = jl;
}

DRIFTLAB_SIMD_CLONES void subtract_mean_by_intervals(const Spline& upper, const Spline& lower,
                                                     Index& upper_piece, Index& lower_piece,
                                                     double* h, Index from, Index to) {
  subtract_mean_by_intervals<false>(upper, lower, upper_piece, lower_piece, h, from, to, nullptr);
}

// Sifting workspace: buffers sized once per signal length, reused by every sift.
class Sifter {
  static constexpr Index kBlock = 2048;
  static constexpr Index kDenseSpacing = 9;
  static constexpr Index kMaxGroups = 16;

  // Groups evaluated for every piece of an envelope with `knots` knots over n samples: enough for
  // a piece 1.25 times as long as the average, so that the further groups of longer pieces are
  // seldom needed (and seldom mispredict); measured best on the dense IMFs of the benchmark record.
  static Index groups_per_piece(Index knots, Index n) {
    const Index average = n / std::max<Index>(knots, 1);
    return std::clamp<Index>((5 * average + 4 * kGroup - 1) / (4 * kGroup), 2, kMaxGroups);
  }

 public:
  explicit Sifter(const SiftConfig& config) : config_(config) {}

  // Copies r into h while finding its extrema; false when r has too few extrema to sift.
  bool load(const double* r, double* h, Index n) {
    if (n == 0) return false;
    reserve(n);
    current_ = 0;
    std::copy(r, r + n, h);
    find_extrema(h, n, sparse_residue_, sets_[current_]);
    return sets_[current_].siftable();
  }

  // Sifts the loaded candidate h into an IMF; returns the number of sifts.
  long sift(double* h, Index n) {
    long sifts = 0;
    int s_run = 0;
    for (;;) {
      build_envelopes(h, n);
      const double change_ratio = sift_pass(h, n);
      ++sifts;
      const ExtremaSet& e = sets_[current_];
      if (!e.siftable() || sifts >= config_.max_sifts) return sifts;
      switch (config_.stop_rule) {
        case StopRule::SNumber:
          s_run = std::abs(e.max.count + e.min.count - e.zero_crossings) <= 1 ? s_run + 1 : 0;
          if (s_run >= config_.s_number) return sifts;
          break;
        case StopRule::CauchySd:
          if (!(change_ratio >= config_.sd_threshold)) return sifts;
          break;
        case StopRule::FixedSifts:
          if (sifts >= config_.fixed_sifts) return sifts;
          break;
      }
    }
  }

 private:
  void reserve(Index n) {
    const auto capacity = static_cast<std::size_t>(n / 2 + 2 + 2 * kPad + kWrittenPast);
    if (upper_scratch_.ratio.capacity() >= capacity) return;
    for (ExtremaSet& set : sets_) {
      for (Extrema* e : {&set.max, &set.min}) {
        e->pos.reserve(capacity);
        e->val.reserve(capacity);
      }
    }
    upper_scratch_.reserve(capacity);
    lower_scratch_.reserve(capacity);
    lane_scratch_.reserve(capacity);
  }

  // Adds the end knots around the interior extrema; returns the index of the first knot.
  static Index add_end_knots(Extrema& e, const EndKnots& start, const EndKnots& finish, Index n) {
    for (int k = 0; k < start.count; ++k) {
      e.pos[kPad - 1 - k] = start.s[k];
      e.val[kPad - 1 - k] = start.val[k];
    }
    for (int k = 0; k < finish.count; ++k) {
      e.pos[kPad + e.count + k] = static_cast<double>(n - 1) - finish.s[k];
      e.val[kPad + e.count + k] = finish.val[k];
    }
    return kPad - start.count;
  }

  void build_envelopes(const double* h, Index n) {
    ExtremaSet& e = sets_[current_];
    EndKnots max_start, min_start, max_finish, min_finish;
    const NearEnd max_near_start = near_start(e.max), min_near_start = near_start(e.min);
    const NearEnd max_near_finish = near_finish(e.max, n), min_near_finish = near_finish(e.min, n);
    if (config_.end_policy == EndPolicy::Mirror) {
      mirror_end(max_near_start, min_near_start, h[0], max_start, min_start);
      mirror_end(max_near_finish, min_near_finish, h[n - 1], max_finish, min_finish);
    } else {
      max_start = linear_end(max_near_start, h[0], true);
      min_start = linear_end(min_near_start, h[0], false);
      max_finish = linear_end(max_near_finish, h[n - 1], true);
      min_finish = linear_end(min_near_finish, h[n - 1], false);
    }
    const Index upper_first = add_end_knots(e.max, max_start, max_finish, n);
    const Index lower_first = add_end_knots(e.min, min_start, min_finish, n);
    const Index upper_knots = max_start.count + e.max.count + max_finish.count;
    const Index lower_knots = min_start.count + e.min.count + min_finish.count;
    const SplineSystem upper{&e.max.pos[upper_first], &e.max.val[upper_first], upper_knots,
                             upper_scratch_.second.data(), upper_scratch_.ratio.data()};
    const SplineSystem lower{&e.min.pos[lower_first], &e.min.val[lower_first], lower_knots,
                             lower_scratch_.second.data(), lower_scratch_.ratio.data()};
    fit_splines(upper, lower, lane_scratch_);
    upper_ = {upper.x, upper.y, upper.m, upper.n};
    lower_ = {lower.x, lower.y, lower.m, lower.n};
  }

  // One sift: h <- h - (upper + lower) / 2, then the extrema of the new h, block by block so that
  // each block is still in cache when scanned. Returns the Cauchy SD (0 for the other rules).
  // Extrema closer than kDenseSpacing samples on average have their envelopes evaluated piece by
  // piece into block buffers; sparser ones subtract the mean interval by interval.
  double sift_pass(double* h, Index n) {
    const bool with_change_ratio = config_.stop_rule == StopRule::CauchySd;
    const ExtremaSet& e = sets_[current_];
    const bool dense = (e.max.count + e.min.count) * kDenseSpacing > n;
    const Index upper_groups = groups_per_piece(e.max.count, n);
    const Index lower_groups = groups_per_piece(e.min.count, n);
    ExtremaSet& next = sets_[1 - current_];
    next.max.count = next.min.count = next.zero_crossings = 0;
    ExtremaScanner scanner(next, sparse_extrema(e, n));
    double sums[2] = {0.0, 0.0};  // sum h^2, sum mean^2 (Cauchy SD only)
    Index upper_piece = 0, lower_piece = 0;
    for (Index from = 0; from < n; from += kBlock) {
      const Index to = std::min(n, from + kBlock);
      if (dense) {
        evaluate_block(upper_, upper_piece, from, to, upper_groups, upper_values_.data());
        evaluate_block(lower_, lower_piece, from, to, lower_groups, lower_values_.data());
        if (with_change_ratio)
          subtract_mean<true>(h + from, upper_values_.data(), lower_values_.data(), to - from, sums);
        else
          subtract_mean(h + from, upper_values_.data(), lower_values_.data(), to - from);
      } else {
        if (with_change_ratio)
          subtract_mean_by_intervals<true>(upper_, lower_, upper_piece, lower_piece, h, from, to, sums);
        else
          subtract_mean_by_intervals(upper_, lower_, upper_piece, lower_piece, h, from, to);
      }
      scanner.scan(h, std::max<Index>(from, 1), to);
    }
    current_ = 1 - current_;
    sparse_residue_ = sparse_extrema(next, n);
    return with_change_ratio ? sums[1] / sums[0] : 0.0;
  }

  SiftConfig config_;
  // Whether the last IMF's extrema were sparse: the residue left after it is no denser, so its
  // extrema search takes the bit-mask scan (a hint for speed only).
  bool sparse_residue_ = false;
  std::array<ExtremaSet, 2> sets_;
  int current_ = 0;
  SplineScratch upper_scratch_, lower_scratch_;
  LaneScratch lane_scratch_;
  Spline upper_, lower_;  // envelopes of the current candidate (knots in sets_[current_])
  std::vector<double> upper_values_ = std::vector<double>(kBlock + kMaxGroups * kGroup),
                      lower_values_ = std::vector<double>(kBlock + kMaxGroups * kGroup);  // one block each
};

void validate(const SiftConfig& c) {
  if (c.s_number < 1) throw std::invalid_argument("emd: s_number must be >= 1");
  if (!(c.sd_threshold > 0.0) || !std::isfinite(c.sd_threshold))
    throw std::invalid_argument("emd: sd_threshold must be a finite number > 0");
  if (c.fixed_sifts < 1) throw std::invalid_argument("emd: fixed_sifts must be >= 1");
  if (c.max_sifts < 1) throw std::invalid_argument("emd: max_sifts must be >= 1");
}

void validate(const EnsembleConfig& c) {
  validate(c.sift);
  if (c.max_imfs < 0) throw std::invalid_argument("emd: max_imfs must be >= 0");
  if (c.ensemble_size < 1) throw std::invalid_argument("emd: ensemble_size must be >= 1");
  if (!(c.noise_strength >= 0.0) || !std::isfinite(c.noise_strength))
    throw std::invalid_argument("emd: noise_strength must be a finite number >= 0");
  if (c.threads < 1) throw std::invalid_argument("emd: threads must be >= 1");
}

void check_finite(const Eigen::VectorXd& x) {
  for (Index i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i]))
      throw std::domain_error("emd: sample " + std::to_string(i) + " is not finite");
  }
}

int imf_cap(int max_imfs, Index n) {
  if (max_imfs > 0) return max_imfs;
  return n < 2 ? 0 : static_cast<int>(std::floor(std::log2(static_cast<double>(n))));
}

double population_std(const double* x, Index n) {
  if (n == 0) return 0.0;
  const Eigen::Map<const Eigen::VectorXd> v(x, n);
  return std::sqrt((v.array() - v.mean()).square().mean());
}

// One EMD: IMFs in the first `count` columns of imfs, residue in residue. Reuses its buffers
// across calls. The IMF matrix has room for `cap` columns; the pages of columns never written are
// never touched, and emd() hands the matrix over without copying it.
struct EmdWorkspace {
  explicit EmdWorkspace(const SiftConfig& sift) : sifter(sift) {}

  void decompose(const double* x, Index n, int cap) {
    residue = Eigen::Map<const Eigen::VectorXd>(x, n);
    if (imfs.rows() != n || imfs.cols() < cap) imfs.resize(n, cap);
    sifts.assign(static_cast<std::size_t>(cap), 0);
    count = 0;
    while (count < cap) {
      double* imf = imfs.col(count).data();
      if (!sifter.load(residue.data(), imf, n)) break;
      sifts[count] = sifter.sift(imf, n);
      residue -= imfs.col(count);
      ++count;
    }
  }

  Sifter sifter;
  Eigen::VectorXd residue;
  Eigen::MatrixXd imfs;
  std::vector<long> sifts;
  int count = 0;
};

void fill_gaussian(std::uint64_t seed, int member, double* out, Index n) {
  std::mt19937_64 rng(splitmix64(splitmix64(seed) + static_cast<std::uint64_t>(member)));
  constexpr double kTwoPow53 = 9007199254740992.0;
  for (Index i = 0; i < n; i += 2) {
    const double u1 = static_cast<double>((rng() >> 11) + 1) / kTwoPow53;
    const double u2 = static_cast<double>(rng() >> 11) / kTwoPow53;
    const double radius = std::sqrt(-2.0 * std::log(u1));
    const double angle = 2.0 * std::numbers::pi * u2;
    out[i] = radius * std::cos(angle);
    if (i + 1 < n) out[i + 1] = radius * std::sin(angle);
  }
}

// Runs work(member, slot) for every member and reduce(member, slot) in member order 0, 1, ...,
// members - 1. Members go in batches of `threads` (at most `members`) through parallel_for, member
// first + k of a batch in slot k < threads, and a batch is reduced before the next one starts, so
// a slot's buffers serve one member at a time.
template <class Work, class Reduce>
void for_members_in_order(int members, unsigned threads, Work work, Reduce reduce) {
  const int batch = static_cast<int>(std::min<unsigned>(std::max(threads, 1u), static_cast<unsigned>(members)));
  for (int first = 0; first < members; first += batch) {
    const int size = std::min(batch, members - first);
    parallel_for(static_cast<std::size_t>(size), threads, [&](std::size_t k) {
      work(first + static_cast<int>(k), static_cast<unsigned>(k));
    });
    for (int k = 0; k < size; ++k) reduce(first + k, static_cast<unsigned>(k));
  }
}

Eigen::MatrixXd stack(const std::vector<Eigen::VectorXd>& columns, int count, Index n) {
  Eigen::MatrixXd out(n, count);
  for (int k = 0; k < count; ++k) out.col(k) = columns[k];
  return out;
}

}  // namespace

Result emd(const Eigen::VectorXd& x, const EmdConfig& config) {
  validate(config.sift);
  if (config.max_imfs < 0) throw std::invalid_argument("emd: max_imfs must be >= 0");
  check_finite(x);
  const Index n = x.size();
  EmdWorkspace ws(config.sift);
  ws.decompose(x.data(), n, imf_cap(config.max_imfs, n));
  Result result;
  result.imfs = std::move(ws.imfs);
  result.imfs.conservativeResize(n, ws.count);  // drops the unused columns in place
  result.residue = std::move(ws.residue);
  result.sifts.assign(ws.sifts.begin(), ws.sifts.begin() + ws.count);
  return result;
}

Result eemd(const Eigen::VectorXd& x, const EnsembleConfig& config) {
  validate(config);
  check_finite(x);
  const Index n = x.size();
  const int cap = imf_cap(config.max_imfs, n);
  const double noise_std = config.noise_strength * population_std(x.data(), n);

  struct Worker {
    EmdWorkspace emd;
    Eigen::VectorXd member;
  };
  std::vector<Worker> workers;  // built in place: a sifter's buffers are not copied
  for (unsigned w = 0; w < std::max(1u, config.threads); ++w)
    workers.push_back({EmdWorkspace(config.sift), {}});
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(n, cap);
  std::vector<long> sifts(cap, 0);
  int widest = 0;

  for_members_in_order(
      config.ensemble_size, config.threads,
      [&](int i, unsigned w) {
        Worker& worker = workers[w];
        worker.member.resize(n);
        fill_gaussian(config.seed, i, worker.member.data(), n);
        worker.member = x + noise_std * worker.member;
        worker.emd.decompose(worker.member.data(), n, cap);
      },
      [&](int, unsigned w) {
        const EmdWorkspace& ws = workers[w].emd;
        for (int k = 0; k < ws.count; ++k) {
          sum.col(k) += ws.imfs.col(k);
          sifts[k] += ws.sifts[k];
        }
        widest = std::max(widest, ws.count);
      });

  const int count = config.max_imfs > 0 ? cap : widest;
  Result result;
  result.imfs = sum.leftCols(count) / static_cast<double>(config.ensemble_size);
  result.residue = x;
  for (int k = 0; k < count; ++k) result.residue -= result.imfs.col(k);
  result.sifts.assign(sifts.begin(), sifts.begin() + count);
  return result;
}

Result ceemdan(const Eigen::VectorXd& x, const CeemdanConfig& config) {
  const EnsembleConfig& ens = config.ensemble;
  validate(ens);
  check_finite(x);
  const Index n = x.size();
  const int members = ens.ensemble_size;
  const int cap = imf_cap(ens.max_imfs, n);
  const bool torres = config.variant == CeemdanVariant::Torres2011;

  Eigen::MatrixXd noise(n, members);  // per member: w_i minus the modes extracted so far
  std::vector<char> noise_left(members, 1);

  struct Worker {
    explicit Worker(const SiftConfig& sift) : sifter(sift) {}
    Sifter sifter;
    Eigen::VectorXd mode, y, first;
    long sifts = 0;
  };
  std::vector<Worker> workers;  // built in place: a sifter's buffers are not copied
  for (unsigned w = 0; w < std::max(1u, ens.threads); ++w) workers.emplace_back(ens.sift);
  Sifter residue_check(ens.sift);
  Eigen::VectorXd scratch(n);

  std::vector<Eigen::VectorXd> imfs;
  std::vector<long> sifts;
  Eigen::VectorXd residue = x;
  Eigen::VectorXd sum(n);

  for (int stage = 0; stage < cap; ++stage) {
    if (!residue_check.load(residue.data(), scratch.data(), n)) break;
    const double residue_std = population_std(residue.data(), n);
    sum.setZero();
    long stage_sifts = 0;

    for_members_in_order(
        members, ens.threads,
        [&](int i, unsigned w) {
          Worker& worker = workers[w];
          worker.mode.resize(n);
          worker.y.resize(n);
          worker.first.resize(n);
          double* w_i = noise.col(i).data();
          if (stage == 0) fill_gaussian(ens.seed, i, w_i, n);
          double scale = 0.0;
          if (torres && stage == 0) {
            worker.mode = noise.col(i);
            scale = ens.noise_strength * residue_std;
          } else if (noise_left[i] && worker.sifter.load(w_i, worker.mode.data(), n)) {
            worker.sifter.sift(worker.mode.data(), n);
            noise.col(i) -= worker.mode;
            const double mode_std = population_std(worker.mode.data(), n);
            if (torres || stage == 0)
              scale = mode_std > 0.0 ? ens.noise_strength * residue_std / mode_std : 0.0;
            else
              scale = ens.noise_strength * residue_std;
          } else {
            noise_left[i] = 0;
          }
          if (scale > 0.0)
            worker.y = residue + scale * worker.mode;
          else
            worker.y = residue;
          worker.sifts = 0;
          if (worker.sifter.load(worker.y.data(), worker.first.data(), n))
            worker.sifts = worker.sifter.sift(worker.first.data(), n);
          else
            worker.first.setZero();
          if (!torres) worker.first = worker.y - worker.first;
        },
        [&](int, unsigned w) {
          sum += workers[w].first;
          stage_sifts += workers[w].sifts;
        });

    sum /= static_cast<double>(members);
    if (torres) {
      imfs.push_back(sum);
      residue -= sum;
    } else {
      imfs.push_back(residue - sum);
      residue = sum;
    }
    sifts.push_back(stage_sifts);
  }

  Result result;
  result.imfs = stack(imfs, static_cast<int>(imfs.size()), n);
  result.residue = std::move(residue);
  result.sifts = std::move(sifts);
  return result;
}

double orthogonality_index(const Eigen::VectorXd& x, const Eigen::MatrixXd& imfs,
                           const Eigen::VectorXd& residue) {
  if (imfs.rows() != x.size() || residue.size() != x.size())
    throw std::invalid_argument("orthogonality_index: IMFs, residue and signal lengths differ");
  const double signal_energy = x.squaredNorm();
  if (!(signal_energy > 0.0))
    throw std::domain_error("orthogonality_index: the signal has zero energy");
  const double component_energy = imfs.colwise().squaredNorm().sum() + residue.squaredNorm();
  return (signal_energy - component_energy) / signal_energy;
}

}  // namespace driftlab::emd
