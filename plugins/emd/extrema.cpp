#include "plugins/emd/emd_internal.hpp"

#include "framework/simd.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>

#ifdef DRIFTLAB_AVX2_INTRINSICS
#include <immintrin.h>
#endif

namespace driftlab::emd::detail {
namespace {

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
  const __m256d value = _mm256_loadu_pd(x + j), left = _mm256_loadu_pd(x + j - 1), right = _mm256_loadu_pd(x + j + 1);
  return {value, _mm256_cmp_pd(value, right, _CMP_EQ_OQ),
          _mm256_srli_epi64(_mm256_xor_si256(_mm256_castpd_si256(value), _mm256_castpd_si256(right)), 63),
          _mm256_movemask_pd(
              _mm256_and_pd(_mm256_cmp_pd(value, left, _CMP_GT_OQ), _mm256_cmp_pd(value, right, _CMP_GT_OQ))),
          _mm256_movemask_pd(
              _mm256_and_pd(_mm256_cmp_pd(value, left, _CMP_LT_OQ), _mm256_cmp_pd(value, right, _CMP_LT_OQ)))};
}

// scan_strict (below) for densely packed extrema, 8 pairs at a time: the extrema among each 4
// candidates are packed with one permutation per array and stored together; equalities and sign
// changes are accumulated in vectors.
DRIFTLAB_AVX2_TARGET bool scan_dense_avx2(const double* x, Index from, Index to, Appender& max, Appender& min,
                                          Index& sign_changes) {
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
  return strict_scan_tail(x, i, to, changes + lanes[0] + lanes[1] + lanes[2] + lanes[3], max, min, sign_changes);
}

// scan_strict (below) for sparse extrema, 64 candidates c[k] at a time as bit masks: F_k when
// c[k + 1] < c[k] (falling after c[k]), S_k the sign bit of c[k]. With no equal neighbours,
// c[k] is a maximum where F_k is set and F_{k-1} is not, a minimum where F_{k-1} is set and F_k is
// not, and the sign changes are the set bits of S xor (S >> 1); the few extrema are then taken one
// set bit at a time.
DRIFTLAB_AVX2_TARGET bool scan_sparse_avx2(const double* x, Index from, Index to, Appender& max, Appender& min,
                                           Index& sign_changes) {
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

}  // namespace

bool sparse_extrema(const ExtremaSet& e, Index n) { return (e.max.count + e.min.count) * kSparseSpacing < n; }

void ExtremaScanner::scan(const double* x, Index from, Index to) {
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

void ExtremaScanner::search(const double* x, Index from, Index to) {
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

void find_extrema(const double* x, Index n, bool sparse, ExtremaSet& out) {
  out.max.count = out.min.count = out.zero_crossings = 0;
  ExtremaScanner(out, sparse).scan(x, 1, n);
}

}  // namespace driftlab::emd::detail
