// Rate of change of a sampled signal: the slope over a centred window,
//
//   r_k = (x_{k+h} - x_{k-h}) / (t_{k+h} - t_{k-h}),   h = max(1, round(window_s / (2 dt))),
//
// dt the median sample interval; near the ends the window is cut to what the record has (one-sided
// at the first and last sample). A window of two samples is the central difference; a wider window
// averages the quantization and sensor noise of a slowly moving signal (a temperature ramp read to
// 0.01 degC) down by its length. Unit: the signal's unit per second. Cost O(n), no allocation but
// the result.
#pragma once

#include <Eigen/Core>

namespace driftlab::rate_of_change {

// time_s strictly increasing, same length as x (>= 2). Throws std::invalid_argument otherwise.
Eigen::VectorXd centred_slope(const Eigen::VectorXd& time_s, const Eigen::VectorXd& x, double window_s);

}  // namespace driftlab::rate_of_change
