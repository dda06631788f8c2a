#include "tools/mrpt/nav_record.hpp"

#include <mrpt/poses/CPose2D.h>

#include <cmath>

#include "framework/error.hpp"

namespace driftlab::mrpt_bridge {

RecordNavInput record_nav_input(const ImuTable& table, const std::string& source) {
  if (!table.has_odometry())
    throw DataError(Location{source, 0, "odom_dx_m"},
                    "nav needs odometry: the record has no odom_dx_m, odom_dy_m, odom_dphi_rad (in a rawlog, "
                    "CActionRobotMovement2D actions)");
  const Eigen::Index n = table.time_s.size();
  if (n < 2) throw DataError(Location{source, 0, "t_s"}, "nav needs at least two IMU samples");
  const auto& dx = table.values("odom_dx_m");
  const auto& dy = table.values("odom_dy_m");
  const auto& dphi = table.values("odom_dphi_rad");
  const bool speed = table.has("odom_speed_mps");

  RecordNavInput out;
  out.speed_source = speed ? "odom_speed_mps" : "odometry increments";
  NavInput& in = out.input;
  in.time_s = table.time_s;
  in.step_speed_mps = Eigen::VectorXd::Zero(n);
  in.x_m = Eigen::VectorXd::Zero(n);
  in.y_m = Eigen::VectorXd::Zero(n);
  in.heading_rad = Eigen::VectorXd::Zero(n);
  mrpt::poses::CPose2D pose;
  for (Eigen::Index k = 1; k < n; ++k) {
    pose = pose + mrpt::poses::CPose2D(dx[k], dy[k], dphi[k]);
    in.x_m[k] = pose.x();
    in.y_m[k] = pose.y();
    in.heading_rad[k] = pose.phi();
    const double dt = table.time_s[k] - table.time_s[k - 1];
    in.step_speed_mps[k] = speed ? 0.5 * (table.values("odom_speed_mps")[k - 1] + table.values("odom_speed_mps")[k])
                                 : std::copysign(std::hypot(dx[k], dy[k]), dx[k]) / dt;
  }
  return out;
}

}  // namespace driftlab::mrpt_bridge
