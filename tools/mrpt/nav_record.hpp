// `driftlab nav` on a user's record (issue 20): an IMU record with odometry, as the bridge reads
// it from a rawlog (import_rawlog: CObservationIMU plus CActionRobotMovement2D actions) or from
// its CSV (read_imu_csv: t_s, rate_rps | rate_dps, temp_c, odom_dx_m, odom_dy_m, odom_dphi_rad
// [, odom_speed_mps]; the columns `driftlab mrpt import` writes), turned into the EKF's input.
//
// Reference: the odometry pose, composed from the increments (pose_k = pose_{k-1} (+) (dx, dy,
// dphi), MRPT's CPose2D composition) from (0, 0, 0) at the first IMU sample; odometry before the
// first sample is not used. It is wheel odometry, not ground truth: the errors it gives are
// differences from what the odometry says.
// EKF speed over step k: the mean of odom_speed_mps at k-1 and k when the record has it, else the
// chord of the increment: sign(dx) hypot(dx, dy) / dt, m/s (the EKF's midpoint rule then moves by
// exactly the chord).
// No position fixes. Errors: DataError naming the missing columns, or fewer than two samples.
#pragma once

#include <string>

#include "tools/mrpt/nav_scenario.hpp"
#include "tools/mrpt/rawlog_io.hpp"

namespace driftlab::mrpt_bridge {

struct RecordNavInput {
  NavInput input;
  std::string speed_source;  // "odom_speed_mps" or "odometry increments"
};
// `source` names the record in errors (its file).
RecordNavInput record_nav_input(const ImuTable& table, const std::string& source);

}  // namespace driftlab::mrpt_bridge
