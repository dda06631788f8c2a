// Planar navigation EKF on MRPT's mrpt::bayes::CKalmanFilterCapable (issue 14).
//
// State (4): x, y (m, world frame), heading psi (rad, wrapped to (-pi, pi]), gyro bias b (rad/s).
// Input per step: measured yaw rate w_m (rad/s), odometry forward speed v (m/s), step dt (s).
// Transition (midpoint rule):
//   dpsi = (w_m - b) dt,  psi_mid = psi + dpsi / 2
//   x += v dt cos(psi_mid),  y += v dt sin(psi_mid),  psi = wrap(psi + dpsi),  b unchanged
// Observation (optional, 2): an absolute position fix (x, y) with standard deviation fix_sigma_m.
// Process noise Q per step, from the device's IEEE-952 terms (error_model::NoiseTerms):
//   heading   N^2 dt                          (angle random walk N, rad/sqrt(s))
//   bias      (K^2 + 2 B^2 / tau_b) dt         (rate random walk K, rad/s/sqrt(s); bias instability
//                                              B, rad/s, as a Gauss-Markov bias of variance B^2 and
//                                              correlation time tau_b, the device's longest flicker
//                                              correlation time; driving noise 2 B^2 / tau_b)
//   position  (sigma_v dt)^2 along the heading (odometry speed white noise sigma_v, m/s per sample)
// Jacobians are analytic (MRPT's numeric ones fail without a map). MRPT 2.5.8 notes: kfEKFNaive
// (kfIKF throws), feature size 0, a 2-element observation (a 1-element one does not link).
// Cost: O(1) per step (4x4 matrices); no output, no exceptions on normal data.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>

namespace driftlab::mrpt_bridge {

struct NavNoise {
  double arw_rad_sqrt_s = 0.0;                 // N
  double bias_instability_rad_s = 0.0;         // B
  double rate_random_walk_rad_s_sqrt_s = 0.0;  // K
  double bias_correlation_time_s = 5000.0;     // tau_b for the B term
  double speed_sigma_mps = 0.0;                // odometry speed noise, per sample
  double fix_sigma_m = 3.0;                    // position-fix standard deviation, per axis
};

struct NavState {
  double x_m = 0.0, y_m = 0.0, heading_rad = 0.0, bias_rad_s = 0.0;
  Eigen::Matrix4d covariance = Eigen::Matrix4d::Zero();  // order x, y, heading, bias (SI)
};

class NavEkf {
 public:
  // `initial.covariance` is the prior (e.g. diag(0, 0, 0, sigma_b^2) for a known start pose).
  NavEkf(const NavNoise& noise, const NavState& initial);
  ~NavEkf();
  NavEkf(const NavEkf&) = delete;
  NavEkf& operator=(const NavEkf&) = delete;

  // One prediction with the inputs, then an update when a fix (x, y in m) is given.
  void step(double dt_s, double rate_rad_s, double speed_mps, std::optional<Eigen::Vector2d> fix_m = std::nullopt);
  NavState state() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

// Wraps an angle to (-pi, pi].
double wrap_angle(double rad);

}  // namespace driftlab::mrpt_bridge
