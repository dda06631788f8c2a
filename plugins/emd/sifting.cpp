#include "plugins/emd/emd_internal.hpp"

#include <algorithm>
#include <cstdlib>
#include <initializer_list>

namespace driftlab::emd::detail {

// Groups evaluated for every piece of an envelope with `knots` knots over n samples: enough for
// a piece 1.25 times as long as the average, so that the further groups of longer pieces are
// seldom needed (and seldom mispredict); measured best on the dense IMFs of the benchmark record.
Index Sifter::groups_per_piece(Index knots, Index n) {
  const Index average = n / std::max<Index>(knots, 1);
  return std::clamp<Index>((5 * average + 4 * kGroup - 1) / (4 * kGroup), 2, kMaxGroups);
}

bool Sifter::load(const double* r, double* h, Index n) {
  if (n == 0) return false;
  reserve(n);
  current_ = 0;
  std::copy(r, r + n, h);
  find_extrema(h, n, sparse_residue_, sets_[current_]);
  return sets_[current_].siftable();
}

long Sifter::sift(double* h, Index n) {
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
      case StopRule::SNumberSteady: {
        const ExtremaSet& before = sets_[1 - current_];
        const Index change = std::abs(e.max.count - before.max.count) + std::abs(e.min.count - before.min.count) +
                             std::abs(e.zero_crossings - before.zero_crossings);
        s_run = change <= 1 && std::abs(e.max.count + e.min.count - e.zero_crossings) <= 1 ? s_run + 1 : 0;
        if (s_run >= config_.s_number) return sifts;
        break;
      }
      case StopRule::CauchySd:
        if (!(change_ratio >= config_.sd_threshold)) return sifts;
        break;
      case StopRule::FixedSifts:
        if (sifts >= config_.fixed_sifts) return sifts;
        break;
    }
  }
}

void Sifter::reserve(Index n) {
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
Index Sifter::add_end_knots(Extrema& e, const EndKnots& start, const EndKnots& finish, Index n) {
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

void Sifter::build_envelopes(const double* h, Index n) {
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
  const SplineSystem upper{&e.max.pos[upper_first], &e.max.val[upper_first], upper_knots, upper_scratch_.second.data(),
                           upper_scratch_.ratio.data()};
  const SplineSystem lower{&e.min.pos[lower_first], &e.min.val[lower_first], lower_knots, lower_scratch_.second.data(),
                           lower_scratch_.ratio.data()};
  fit_splines(upper, lower, lane_scratch_);
  upper_ = {upper.x, upper.y, upper.m, upper.n};
  lower_ = {lower.x, lower.y, lower.m, lower.n};
}

// One sift: h <- h - (upper + lower) / 2, then the extrema of the new h, block by block so that
// each block is still in cache when scanned. Returns the Cauchy SD (0 for the other rules).
// Extrema closer than kDenseSpacing samples on average have their envelopes evaluated piece by
// piece into block buffers; sparser ones subtract the mean interval by interval.
double Sifter::sift_pass(double* h, Index n) {
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
        subtract_mean(h + from, upper_values_.data(), lower_values_.data(), to - from, sums);
      else
        subtract_mean(h + from, upper_values_.data(), lower_values_.data(), to - from);
    } else {
      if (with_change_ratio)
        subtract_mean_by_intervals(upper_, lower_, upper_piece, lower_piece, h, from, to, sums);
      else
        subtract_mean_by_intervals(upper_, lower_, upper_piece, lower_piece, h, from, to);
    }
    scanner.scan(h, std::max<Index>(from, 1), to);
  }
  current_ = 1 - current_;
  sparse_residue_ = sparse_extrema(next, n);
  return with_change_ratio ? sums[1] / sums[0] : 0.0;
}

}  // namespace driftlab::emd::detail
