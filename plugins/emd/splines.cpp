#include "plugins/emd/emd_internal.hpp"

#include "framework/simd.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace driftlab::emd::detail {
namespace {

constexpr int kSmallSteps = 64;

constexpr std::array<double, kSmallSteps> small_step_inverses() {
  std::array<double, kSmallSteps> inverses{};
  for (int h = 1; h < kSmallSteps; ++h) inverses[h] = 1.0 / h;
  return inverses;
}

constexpr std::array<double, kSmallSteps> kSmallStepInverses = small_step_inverses();

// 1/h for a knot spacing h (a whole number of samples); small spacings from a table.
double inverse_step(Index h) { return h < kSmallSteps ? kSmallStepInverses[h] : 1.0 / static_cast<double>(h); }

double inverse_step(double h) { return inverse_step(static_cast<Index>(h)); }

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
  V p, q, r;       // state after the last row
  V x, y;          // the knot of the next row
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
[[gnu::always_inline]] inline void store_cubic(double* o, Group t, double y0, double b, double c, double d) {
  const Group value = y0 + t * (b + t * (c + t * d));
  std::memcpy(o, &value, sizeof value);
}

// The 4x4 transpose of rows v[0..3]: lane i of v[k] becomes lane k of v[i].
[[gnu::always_inline]] inline void transpose(Group* v) {
  // __builtin_shufflevector (GCC >= 12 and clang) with constant lane indices: even, odd, low, high.
  const Group t0 = __builtin_shufflevector(v[0], v[1], 0, 4, 2, 6),
              t1 = __builtin_shufflevector(v[0], v[1], 1, 5, 3, 7);
  const Group t2 = __builtin_shufflevector(v[2], v[3], 0, 4, 2, 6),
              t3 = __builtin_shufflevector(v[2], v[3], 1, 5, 3, 7);
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
    case 2:
      return evaluate_whole_pieces<2>(spline, j, from, to, out);
    case 3:
      return evaluate_whole_pieces<3>(spline, j, from, to, out);
    case 4:
      return evaluate_whole_pieces<4>(spline, j, from, to, out);
    case 5:
      return evaluate_whole_pieces<5>(spline, j, from, to, out);
    case 6:
      return evaluate_whole_pieces<6>(spline, j, from, to, out);
    default:
      return j;
  }
}

// The mean removal of subtract_mean and subtract_mean_by_intervals (emd_internal.hpp), with and
// without the Cauchy sums.
template <bool kWithChangeRatio>
[[gnu::always_inline]] inline void subtract_mean(double* h, const double* upper, const double* lower, Index count,
                                                 double* sums) {
  for (Index i = 0; i < count; ++i) {
    const double mean = 0.5 * (upper[i] + lower[i]);
    if constexpr (kWithChangeRatio) {
      sums[0] += h[i] * h[i];
      sums[1] += mean * mean;
    }
    h[i] -= mean;
  }
}

template <bool kWithChangeRatio>
[[gnu::always_inline]] inline void subtract_mean_by_intervals(const Spline& upper, const Spline& lower,
                                                              Index& upper_piece, Index& lower_piece, double* h,
                                                              Index from, Index to, double* sums) {
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

}  // namespace

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

DRIFTLAB_SIMD_CLONES void evaluate_block(const Spline& spline, Index& piece, Index from, Index to, Index groups,
                                         double* out) {
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
    const Cubic g = cubic<double>(static_cast<double>(step), inverse_step(step), y[j], y[j + 1], m[j], m[j + 1]);
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

DRIFTLAB_SIMD_CLONES void subtract_mean(double* h, const double* upper, const double* lower, Index count) {
  subtract_mean<false>(h, upper, lower, count, nullptr);
}

void subtract_mean(double* h, const double* upper, const double* lower, Index count, double* sums) {
  subtract_mean<true>(h, upper, lower, count, sums);
}

DRIFTLAB_SIMD_CLONES void subtract_mean_by_intervals(const Spline& upper, const Spline& lower, Index& upper_piece,
                                                     Index& lower_piece, double* h, Index from, Index to) {
  subtract_mean_by_intervals<false>(upper, lower, upper_piece, lower_piece, h, from, to, nullptr);
}

void subtract_mean_by_intervals(const Spline& upper, const Spline& lower, Index& upper_piece, Index& lower_piece,
                                double* h, Index from, Index to, double* sums) {
  subtract_mean_by_intervals<true>(upper, lower, upper_piece, lower_piece, h, from, to, sums);
}

}  // namespace driftlab::emd::detail
