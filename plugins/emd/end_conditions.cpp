#include "plugins/emd/emd_internal.hpp"

#include <algorithm>

namespace driftlab::emd::detail {
namespace {

EndKnots reflect(const NearEnd& near, int from, int to, double axis) {
  EndKnots knots;
  for (int k = from; k < std::min(to, near.count); ++k) knots.add(2.0 * axis - near.s[k], near.val[k]);
  return knots;
}

bool reaches_end(const EndKnots& knots) { return knots.count > 0 && knots.s[knots.count - 1] <= 0.0; }

}  // namespace

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

void mirror_end(const NearEnd& max, const NearEnd& min, double end_value, EndKnots& max_knots, EndKnots& min_knots) {
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

}  // namespace driftlab::emd::detail
