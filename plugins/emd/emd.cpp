#include "plugins/emd/emd.hpp"

#include "framework/seeded_random.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <initializer_list>
#include <mutex>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace driftlab::emd {
namespace {

using Index = std::ptrdiff_t;

constexpr int kNearest = 3;
constexpr int kMaxEndKnots = 2;
constexpr Index kPad = kMaxEndKnots;

struct Extrema {
  std::vector<double> pos, val;  // interior extrema at [kPad, kPad + count), end knots around them
  Index count = 0;
};

struct ExtremaSet {
  Extrema max, min;
  Index zero_crossings = 0;

  bool siftable() const { return max.count >= 1 && min.count >= 1 && max.count + min.count >= 3; }
};

std::uint64_t bits(double v) { return std::bit_cast<std::uint64_t>(v); }

// Smallest i in [from, to) with x[i] < x[i-1] (kFalling) or x[i] > x[i-1], else `to`. Chunks are
// skipped when no difference in them has its sign bit set (vectorizable; exact for finite samples:
// x[i] < x[i-1] implies x[i] - x[i-1] < 0), and the exact test runs from the first chunk that may
// hold the turn.
template <bool kFalling>
Index next_turn(const double* x, Index from, Index to) {
  constexpr Index kChunk = 8;
  Index i = from;
  while (i + kChunk <= to) {
    std::uint64_t signs = 0;
    for (Index k = i; k < i + kChunk; ++k) signs |= bits(kFalling ? x[k] - x[k - 1] : x[k - 1] - x[k]);
    if (signs >> 63) break;
    i += kChunk;
  }
  while (i < to && !(kFalling ? x[i] < x[i - 1] : x[i] > x[i - 1])) ++i;
  return i;
}

// Interior extrema and zero crossings of a signal scanned block by block, in order: a search for
// the next change of direction, so the cost per sample is a few comparisons. A flat run of equal
// samples that is a peak or a trough counts once, at its middle sample.
class ExtremaScanner {
 public:
  explicit ExtremaScanner(ExtremaSet& out) : out_(out) {}

  // Scans x[i] for i in [from, to), from >= 1; x[0, from) must be the samples scanned before.
  void scan(const double* x, Index from, Index to) {
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
    count_zero_crossings(x, from, to);
  }

  // The same result without branches on the data: for densely packed extrema, where the search
  // would mispredict at almost every turn. Each step writes a candidate slot and advances a count
  // only at an extremum.
  void scan_dense(const double* x, Index from, Index to) {
    Index run_start = from - 1;
    while (run_start > 0 && x[run_start - 1] == x[run_start]) --run_start;
    double* max_pos = out_.max.pos.data() + kPad;
    double* max_val = out_.max.val.data() + kPad;
    double* min_pos = out_.min.pos.data() + kPad;
    double* min_val = out_.min.val.data() + kPad;
    Index max_count = out_.max.count, min_count = out_.min.count;
    Index direction = direction_;
    double prev = x[from - 1];
    for (Index i = from; i < to; ++i) {
      const double xi = x[i];
      const Index up = xi > prev, down = xi < prev, moved = up | down;
      const double middle = static_cast<double>((run_start + i - 1) >> 1);
      max_pos[max_count] = middle;
      max_val[max_count] = prev;
      max_count += down & (direction > 0);
      min_pos[min_count] = middle;
      min_val[min_count] = prev;
      min_count += up & (direction < 0);
      direction += moved * (up - down - direction);
      run_start += moved * (i - run_start);
      prev = xi;
    }
    out_.max.count = max_count;
    out_.min.count = min_count;
    direction_ = static_cast<int>(direction);
    count_zero_crossings(x, from, to);
  }

 private:
  void count_zero_crossings(const double* x, Index from, Index to) {
    std::uint64_t crossings = 0;
    for (Index k = from; k < to; ++k) crossings += (bits(x[k]) ^ bits(x[k - 1])) >> 63;
    out_.zero_crossings += static_cast<Index>(crossings);
  }

  ExtremaSet& out_;
  int direction_ = 0;
};

void find_extrema(const double* x, Index n, ExtremaSet& out) {
  out.max.count = out.min.count = out.zero_crossings = 0;
  ExtremaScanner(out).scan(x, 1, n);
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

// 1/h for a knot spacing h (a whole number of samples); small spacings from a table.
double inverse_step(double h) {
  static constexpr std::array<double, kSmallSteps> kInverses = small_step_inverses();
  return h < kSmallSteps ? kInverses[static_cast<int>(h)] : 1.0 / h;
}

// One piece of a cubic spline: S(t) = y + dt (b + dt (c + dt d)), dt = t - x, from knot x to the
// next piece's x.
struct Segment {
  double x, y, b, c, d;
};

struct SplineScratch {
  std::vector<double> slope, second, inverse_step, ratio;

  void reserve(std::size_t capacity) {
    for (auto* v : {&slope, &second, &inverse_step, &ratio}) v->resize(capacity);
  }
};

// 2^-e for the binary exponent e of a normal q (|q| in [2^e, 2^(e+1))): an exact rescaling to
// [1, 2) built from the bits, so no libm call sits in the elimination loop.
double power_of_two_below(double q) {
  const std::uint64_t exponent_bits = bits(q) & 0x7ff0000000000000ULL;
  return std::bit_cast<double>(0x7fe0000000000000ULL - exponent_bits);
}

// Not-a-knot cubic spline through (x[k], y[k]), k < n, n >= 2 (x strictly increasing whole
// numbers) into out[0, n): piece j covers [x[j], x[j+1]]; out[n-1] holds the last knot only.
// The tridiagonal system for the second derivatives M is eliminated with the Thomas recurrence in
// homogeneous form: pivot_i = Q_i / Q_{i-1}, ratio_i = P_i / Q_i, M'_i = R_i / Q_i with P, Q, R
// linear recurrences, so no division sits on the dependency chain. (P, Q, R) are rescaled by a
// power of two every kRescaleEvery rows (Q grows by at most 6n per row, so this holds for
// n < 2^40).
void fit_spline(const double* x, const double* y, Index n, SplineScratch& scratch, Segment* out) {
  constexpr Index kRescaleEvery = 8;
  double* slope = scratch.slope.data();
  double* m = scratch.second.data();
  double* inverse = scratch.inverse_step.data();
  double* ratio = scratch.ratio.data();
  auto chord = [&](Index j) {
    inverse[j] = inverse_step(x[j + 1] - x[j]);
    slope[j] = (y[j + 1] - y[j]) * inverse[j];
  };
  auto emit = [&](Index j) {
    const double step = x[j + 1] - x[j];
    out[j] = {x[j], y[j], slope[j] - step * (2.0 * m[j] + m[j + 1]) / 6.0, 0.5 * m[j],
              (m[j + 1] - m[j]) * inverse[j] / 6.0};
  };
  out[n - 1] = {x[n - 1], y[n - 1], 0.0, 0.0, 0.0};
  chord(0);
  if (n == 2) {
    m[0] = m[1] = 0.0;
    emit(0);
    return;
  }
  chord(1);
  if (n == 3) {
    m[0] = m[1] = m[2] = 2.0 * (slope[1] - slope[0]) / (x[2] - x[0]);
    emit(0);
    emit(1);
    return;
  }
  const Index last = n - 2;
  double p_prev = 0.0, q_prev = 1.0, r_prev = 0.0;
  for (Index i = 1; i <= last; ++i) {
    if (i > 1) chord(i);
    const double before = x[i] - x[i - 1], after = x[i + 1] - x[i];
    double sub = before, diag = 2.0 * (before + after), super = after;
    if (i == 1) {
      diag += before * (before + after) * inverse[1];
      super -= before * before * inverse[1];
    }
    if (i == last) {
      sub -= after * after * inverse[i - 1];
      diag += after * (before + after) * inverse[i - 1];
    }
    const double p = super * q_prev;
    double q = diag * q_prev - sub * p_prev;
    double r = 6.0 * (slope[i] - slope[i - 1]) * q_prev - sub * r_prev;
    const double inverse_q = 1.0 / q;
    ratio[i] = p * inverse_q;
    m[i] = r * inverse_q;
    p_prev = p;
    if (i % kRescaleEvery == 0) {
      const double scale = power_of_two_below(q);
      p_prev *= scale;
      q *= scale;
      r *= scale;
    }
    q_prev = q;
    r_prev = r;
  }
  for (Index i = last - 1; i >= 1; --i) {
    m[i] -= ratio[i] * m[i + 1];
    if (i == last - 1) {
      const double ha = x[n - 2] - x[n - 3], hb = x[n - 1] - x[n - 2];
      m[n - 1] = ((ha + hb) * m[n - 2] - hb * m[n - 3]) * inverse[n - 3];
      emit(n - 2);
    }
    emit(i);
  }
  const double h0 = x[1] - x[0], h1 = x[2] - x[1];
  m[0] = ((h0 + h1) * m[1] - h0 * m[2]) * inverse[1];
  emit(0);
}

// A spline piece re-expanded about a sample position t0: S(t0 + s) = p0 + s (p1 + s (p2 + s p3)).
struct LocalCubic {
  double p0, p1, p2, p3;
};

LocalCubic about(const Segment& g, double t0) {
  const double delta = t0 - g.x;
  return {g.y + delta * (g.b + delta * (g.c + delta * g.d)), g.b + delta * (2.0 * g.c + 3.0 * g.d * delta),
          g.c + 3.0 * g.d * delta, g.d};
}

double evaluate(const Segment& g, double t) {
  const double dt = t - g.x;
  return g.y + dt * (g.b + dt * (g.c + dt * g.d));
}

// Sifting workspace: buffers sized once per signal length, reused by every sift.
class Sifter {
  static constexpr Index kBlock = 2048;
  static constexpr Index kDenseSpacing = 5;

 public:
  explicit Sifter(const SiftConfig& config) : config_(config) {}

  // Copies r into h while finding its extrema; false when r has too few extrema to sift.
  bool load(const double* r, double* h, Index n) {
    if (n == 0) return false;
    reserve(n);
    current_ = 0;
    std::copy(r, r + n, h);
    find_extrema(h, n, sets_[current_]);
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
    const auto capacity = static_cast<std::size_t>(n / 2 + 2 + 2 * kPad);
    if (scratch_.ratio.size() >= capacity) return;
    for (ExtremaSet& set : sets_) {
      for (Extrema* e : {&set.max, &set.min}) {
        e->pos.resize(capacity);
        e->val.resize(capacity);
      }
    }
    upper_.resize(capacity);
    lower_.resize(capacity);
    scratch_.reserve(capacity);
  }

  // Adds the end knots around the interior extrema and fits the envelope through all of them.
  static Index fit(Extrema& e, const EndKnots& start, const EndKnots& finish, Index n,
                   SplineScratch& scratch, std::vector<Segment>& envelope) {
    for (int k = 0; k < start.count; ++k) {
      e.pos[kPad - 1 - k] = start.s[k];
      e.val[kPad - 1 - k] = start.val[k];
    }
    for (int k = 0; k < finish.count; ++k) {
      e.pos[kPad + e.count + k] = static_cast<double>(n - 1) - finish.s[k];
      e.val[kPad + e.count + k] = finish.val[k];
    }
    const Index first = kPad - start.count, count = start.count + e.count + finish.count;
    fit_spline(&e.pos[first], &e.val[first], count, scratch, envelope.data());
    return count;
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
    upper_knots_ = fit(e.max, max_start, max_finish, n, scratch_, upper_);
    lower_knots_ = fit(e.min, min_start, min_finish, n, scratch_, lower_);
  }

  // One sift: h <- h - (upper + lower) / 2, then the extrema of the new h, block by block so that
  // each block is still in cache when scanned. Returns the Cauchy SD (0 for the other rules).
  // Knots or extrema closer than kDenseSpacing samples on average take the branch-free paths.
  double sift_pass(double* h, Index n) {
    const bool with_change_ratio = config_.stop_rule == StopRule::CauchySd;
    const ExtremaSet& e = sets_[current_];
    const bool dense = (e.max.count + e.min.count) * kDenseSpacing > n;
    ExtremaSet& next = sets_[1 - current_];
    next.max.count = next.min.count = next.zero_crossings = 0;
    ExtremaScanner scanner(next);
    MeanSums sums;
    Index ju = 0, jl = 0;
    for (Index from = 0; from < n; from += kBlock) {
      const Index to = std::min(n, from + kBlock);
      if (dense) {
        if (with_change_ratio)
          remove_mean_dense<true>(h, from, to, ju, jl, sums);
        else
          remove_mean_dense<false>(h, from, to, ju, jl, sums);
        scanner.scan_dense(h, std::max<Index>(from, 1), to);
      } else {
        remove_mean(h, from, to, ju, jl, with_change_ratio, sums);
        scanner.scan(h, std::max<Index>(from, 1), to);
      }
    }
    current_ = 1 - current_;
    return with_change_ratio ? sums.mean_sq / sums.h_sq : 0.0;
  }

  struct MeanSums {
    double mean_sq = 0.0, h_sq = 0.0;
  };

  // h[i] -= (upper + lower) / 2 for i in [from, to), one merged knot interval at a time; ju, jl
  // carry the current pieces from block to block.
  void remove_mean(double* h, Index from, Index to, Index& ju, Index& jl, bool with_change_ratio,
                   MeanSums& sums) const {
    const Segment* upper = upper_.data();
    const Segment* lower = lower_.data();
    for (Index i = from; i < to;) {
      const double t0 = static_cast<double>(i);
      while (t0 > upper[ju + 1].x) ++ju;
      while (t0 > lower[jl + 1].x) ++jl;
      const Index end = std::min(to, static_cast<Index>(std::min(upper[ju + 1].x, lower[jl + 1].x)) + 1);
      const LocalCubic u = about(upper[ju], t0), l = about(lower[jl], t0);
      const double p0 = 0.5 * (u.p0 + l.p0), p1 = 0.5 * (u.p1 + l.p1);
      const double p2 = 0.5 * (u.p2 + l.p2), p3 = 0.5 * (u.p3 + l.p3);
      double* piece = h + i;
      const int length = static_cast<int>(end - i);
      if (with_change_ratio) {
        for (int k = 0; k < length; ++k) {
          const double s = k;
          const double mean = p0 + s * (p1 + s * (p2 + s * p3));
          sums.h_sq += piece[k] * piece[k];
          sums.mean_sq += mean * mean;
          piece[k] -= mean;
        }
      } else {
        for (int k = 0; k < length; ++k) {
          const double s = k;
          piece[k] -= p0 + s * (p1 + s * (p2 + s * p3));
        }
      }
      i = end;
    }
  }

  // remove_mean evaluating both splines at every sample. The piece index advances by a per-block
  // table of knot positions, so no branch and no load sits on its dependency chain.
  template <bool kWithChangeRatio>
  void remove_mean_dense(double* h, Index from, Index to, Index& ju, Index& jl, MeanSums& sums) {
    const Segment* upper = upper_.data();
    const Segment* lower = lower_.data();
    const double t0 = static_cast<double>(from);
    while (t0 > upper[ju + 1].x) ++ju;
    while (t0 > lower[jl + 1].x) ++jl;
    mark_knots(upper, upper_knots_, ju, from, to, upper_steps_.data());
    mark_knots(lower, lower_knots_, jl, from, to, lower_steps_.data());
    for (Index i = from; i < to; ++i) {
      ju += upper_steps_[i - from];
      jl += lower_steps_[i - from];
      const double t = static_cast<double>(i);
      const double mean = 0.5 * (evaluate(upper[ju], t) + evaluate(lower[jl], t));
      if constexpr (kWithChangeRatio) {
        sums.h_sq += h[i] * h[i];
        sums.mean_sq += mean * mean;
      }
      h[i] -= mean;
    }
  }

  // steps[i - from] = 1 when sample i - 1 is a knot, for i in (from, to): the piece of sample i is
  // the piece of sample i - 1 plus steps[i - from] (piece j holds (knot j, knot j+1]).
  static void mark_knots(const Segment* pieces, Index knots, Index j, Index from, Index to,
                         unsigned char* steps) {
    std::fill(steps, steps + (to - from), static_cast<unsigned char>(0));
    for (Index k = j + 1; k < knots && pieces[k].x < static_cast<double>(to - 1); ++k)
      steps[static_cast<Index>(pieces[k].x) + 1 - from] = 1;
  }

  SiftConfig config_;
  std::array<ExtremaSet, 2> sets_;
  int current_ = 0;
  SplineScratch scratch_;
  std::vector<Segment> upper_, lower_;  // envelope pieces, one per knot
  Index upper_knots_ = 0, lower_knots_ = 0;
  std::vector<unsigned char> upper_steps_ = std::vector<unsigned char>(kBlock),
                             lower_steps_ = std::vector<unsigned char>(kBlock);
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

// One EMD: IMFs in imfs[0, count), residue in residue. Reuses its buffers across calls.
struct EmdWorkspace {
  explicit EmdWorkspace(const SiftConfig& sift) : sifter(sift) {}

  void decompose(const double* x, Index n, int cap) {
    residue = Eigen::Map<const Eigen::VectorXd>(x, n);
    count = 0;
    while (count < cap) {
      if (static_cast<int>(imfs.size()) <= count) imfs.emplace_back(n);
      if (static_cast<int>(sifts.size()) <= count) sifts.push_back(0);
      Eigen::VectorXd& imf = imfs[count];
      imf.resize(n);
      if (!sifter.load(residue.data(), imf.data(), n)) break;
      sifts[count] = sifter.sift(imf.data(), n);
      residue -= imf;
      ++count;
    }
  }

  Sifter sifter;
  Eigen::VectorXd residue;
  std::vector<Eigen::VectorXd> imfs;
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

// Runs work(member, worker) for every member on `threads` workers and calls
// reduce(member, worker) in member order 0, 1, ..., members - 1.
template <class Work, class Reduce>
void for_members_in_order(int members, unsigned threads, Work work, Reduce reduce) {
  const unsigned workers = std::min<unsigned>(threads, static_cast<unsigned>(members));
  if (workers <= 1) {
    for (int i = 0; i < members; ++i) {
      work(i, 0u);
      reduce(i, 0u);
    }
    return;
  }
  std::atomic<int> next{0};
  int turn = 0;
  bool failed = false;
  std::exception_ptr error;
  std::mutex mutex;
  std::condition_variable turn_changed;
  auto run = [&](unsigned worker) {
    try {
      for (int i = next.fetch_add(1); i < members; i = next.fetch_add(1)) {
        work(i, worker);
        std::unique_lock lock(mutex);
        turn_changed.wait(lock, [&] { return turn == i || failed; });
        if (failed) return;
        reduce(i, worker);
        ++turn;
        turn_changed.notify_all();
      }
    } catch (...) {
      std::lock_guard lock(mutex);
      if (!error) error = std::current_exception();
      failed = true;
      turn_changed.notify_all();
    }
  };
  std::vector<std::thread> pool;
  for (unsigned w = 1; w < workers; ++w) pool.emplace_back(run, w);
  run(0);
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
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
  result.imfs = stack(ws.imfs, ws.count, n);
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
  std::vector<Worker> workers(std::max(1u, config.threads), Worker{EmdWorkspace(config.sift), {}});
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
          sum.col(k) += ws.imfs[k];
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
  std::vector<Worker> workers(std::max(1u, ens.threads), Worker(ens.sift));
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
