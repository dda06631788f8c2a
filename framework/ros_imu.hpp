// From a ROS bag (framework/rosbag.hpp: ROS 1, ROS 2 sqlite3, MCAP, rosbag2 directory) to the IMU
// record (framework/imu.hpp): the thin adapter between the containers, the message decoders
// (framework/ros_messages.hpp) and the record assembly (framework/imu_streams.hpp).
//
// Topics and instances.
//   IMU topics: type sensor_msgs/Imu (ROS 1) or sensor_msgs/msg/Imu (ROS 2). Each topic is one
//     instance: angular_velocity -> gyro (rad/s), linear_acceleration -> accel (m/s^2), both at
//     header.stamp (ns). Instances are numbered in the order of the topic names ("/imu0/data" is
//     instance 0, "/imu1/data" instance 1), or in the order --topic lists them. A sensor whose
//     covariance[0] is -1 in every message is "not provided" by the message's own convention and
//     left out with a note (e.g. an orientation-only Imu topic has neither).
//   Temperature topics: sensor_msgs/Temperature (at header.stamp), and std_msgs/Float32 / Float64
//     topics whose last name part contains "temp" (at the bag's message time: they carry no
//     header), in degC. Each pairs with the IMU topic of its namespace (the name without its last
//     part: /imu/data and /imu/temperature share /imu); one that matches no IMU topic, or several,
//     stays unpaired, and a note names it.
//   --topic (LogSelection::topic): a comma-separated list to read instead of every IMU topic. Its
//     IMU topics become instances 0, 1, ... in the order given; its temperature topics pair by
//     namespace, or with the only IMU topic listed.
//   Header stamps of 0 throughout a topic (drivers that leave the header empty): the bag's message
//   time is used instead, with a note.
//
// Checks: a ROS 1 topic whose md5sum is not that of the definition the decoders read is another
// version of the message (DataError naming both); an encoding other than ros1 / cdr, a message that
// does not decode, a non-finite rate or acceleration or one beyond kMaxMagnitude (csv.hpp), a
// temperature NaN only in part, a --topic that is not in the bag or not an IMU / temperature
// topic, a bag without IMU topics: DataError naming the file and the topic. Time base, repairs
// (sorting, repeated stamps) and their notes: imu_streams.hpp, ticks in ns.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "framework/imu_streams.hpp"
#include "framework/record_reader.hpp"
#include "framework/rosbag.hpp"
#include "framework/time_series.hpp"

namespace driftlab::ros {

struct ImuInstance {
  int instance = 0;
  std::string imu_topic;
  std::string temperature_topic;  // "" when none pairs with it
};

struct ImuLayout {
  std::vector<ImuInstance> instances;
  std::vector<std::string> unpaired_temperatures;
};

// The instances of `bag` as `topic_option` (LogSelection::topic: "" or a comma-separated list) picks
// them (none when the bag has no IMU topic); DataError for a listed topic that is missing or of
// another type, or a list without an IMU topic.
ImuLayout imu_layout(const rosbag::Bag& bag, const std::string& topic_option);

// The streams of those instances, decoded and repaired (notes), before the record is assembled.
struct ImuStreams {
  rosbag::Bag bag;
  ImuLayout layout;
  std::vector<imu::SensorStream> sensors;
  std::vector<imu::TemperatureStream> temperatures;
};
ImuStreams read_streams(const std::filesystem::path& path, const std::string& topic_option,
                        std::vector<std::string>* notes = nullptr);

// read_streams, then imu::assemble with `selection`'s instance and sensor; DataError when the bag
// has no IMU topic.
TimeSeries read_imu(const std::filesystem::path& path, const LogSelection& selection,
                    std::vector<std::string>* notes = nullptr);

}  // namespace driftlab::ros
