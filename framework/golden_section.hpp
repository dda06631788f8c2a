// Golden-section search for the minimum of a one-dimensional function on [a, b] (Kiefer 1953):
// each iteration shrinks the bracket by 0.618 with one new evaluation. Used where a grid has found
// the best cell and a smooth criterion is refined inside it (the discrepancy workflow's nonlinear
// parameters, the calibration's lag and hysteresis width). Header-only, std only.
#pragma once

#include <algorithm>
#include <functional>

namespace driftlab {

struct GoldenSectionMinimum {
  double x = 0.0;      // the better of the two last interior points
  double value = 0.0;  // f(x)
};

// `iterations` bracket reductions after two initial evaluations (iterations + 2 evaluations).
// The end points themselves are never evaluated.
inline GoldenSectionMinimum golden_section_minimize(const std::function<double(double)>& f, double a, double b,
                                                    int iterations) {
  constexpr double kRatio = 0.6180339887498949;  // (sqrt(5) - 1) / 2
  double c = b - kRatio * (b - a), d = a + kRatio * (b - a);
  double fc = f(c), fd = f(d);
  for (int i = 0; i < iterations; ++i) {
    if (fc < fd) {
      b = d, d = c, fd = fc;
      c = b - kRatio * (b - a);
      fc = f(c);
    } else {
      a = c, c = d, fc = fd;
      d = a + kRatio * (b - a);
      fd = f(d);
    }
  }
  return fc < fd ? GoldenSectionMinimum{c, fc} : GoldenSectionMinimum{d, fd};
}

}  // namespace driftlab
