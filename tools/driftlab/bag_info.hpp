// `driftlab log info` on a ROS bag (framework/rosbag.hpp): the container, every topic (type,
// encoding, messages, rate in Hz, time span in s since the epoch of the bag's message times), the
// IMU instances (framework/ros_imu.hpp: topic, messages and rate by header stamps, the paired
// temperature topic and its span in degC), unpaired temperature topics and the reader's notes.
#pragma once

#include <ostream>
#include <string>

namespace driftlab::cli {

void print_bag_info(const std::string& path, std::ostream& out);

}  // namespace driftlab::cli
