// Decoders of the ROS messages driftlab reads from bags, in both serializations: ROS 1 (the
// "ROS serialization" of wiki.ros.org/roscpp/Overview/MessagesSerializationAndAdaptingTypes:
// little endian, no alignment, strings and variable arrays prefixed by a uint32 length) and ROS 2's
// CDR (OMG DDS-XTypes 1.3 section 7.4: a 4-byte encapsulation header, then the body with each
// primitive aligned to its size counted from the body's start; strings carry a uint32 length that
// includes their terminating NUL). Written from those specifications and the message definitions;
// no ROS code.
//
//   sensor_msgs/Imu          Header header; geometry_msgs/Quaternion orientation;
//   (ROS 2: .../msg/Imu)     float64[9] orientation_covariance; geometry_msgs/Vector3 angular_velocity
//                            (rad/s); float64[9] angular_velocity_covariance; geometry_msgs/Vector3
//                            linear_acceleration (m/s^2); float64[9] linear_acceleration_covariance
//   sensor_msgs/Temperature  Header header; float64 temperature (degC); float64 variance
//   std_msgs/Float32, Float64  float32/float64 data (no header; a temperature in degC by convention)
//   Header: ROS 1 uint32 seq, time stamp (uint32 sec, uint32 nsec), string frame_id;
//           ROS 2 builtin_interfaces/Time stamp (int32 sec, uint32 nanosec), string frame_id.
//
// CDR encapsulations read: CDR_BE 0x0000 and CDR_LE 0x0001 (XCDR1, alignment up to 8) and the
// plain XCDR2 forms CDR2_BE 0x0006 / CDR2_LE 0x0007 (alignment up to 4); parameter-list and
// delimited forms are refused. ROS 1 messages are identified by the md5sum of their definition
// (ros1_md5): a bag whose connection states another md5 for the same type name holds a different
// version of the message, which these decoders would misread.
//
// Contract: every read is checked against the bytes that remain; a message shorter than its type,
// one longer than its type by more than the CDR trailing alignment (3 bytes; 0 for ROS 1), a
// string longer than the message, a nanosecond field of 10^9 or more: DataError at `where` (file,
// topic) with what `what()` says (the message's place in the bag, asked only for the error) and
// the byte offset in the message. Never a read past the end.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include "framework/error.hpp"

namespace driftlab::ros {

enum class Encoding { Ros1, Cdr };
enum class MessageType { Imu, Temperature, Float32, Float64 };

// The type a ROS 1 ("sensor_msgs/Imu") or ROS 2 ("sensor_msgs/msg/Imu") name denotes; nullopt for
// any other type.
std::optional<MessageType> message_type(std::string_view type_name);
// md5sum of the ROS 1 definition (as in a ROS 1 bag's connection header).
std::string_view ros1_md5(MessageType type);

struct Imu {
  std::int64_t stamp_ns = 0;                    // header.stamp, ns since the epoch of the sender's clock
  std::array<double, 3> angular_velocity{};     // rad/s
  std::array<double, 3> linear_acceleration{};  // m/s^2
  // [0] of each covariance: -1 says "no such estimate" (the message's own convention).
  double angular_velocity_covariance0 = 0.0;
  double linear_acceleration_covariance0 = 0.0;
};

struct Temperature {
  std::optional<std::int64_t> stamp_ns;  // header.stamp; none for std_msgs/Float*
  double degc = 0.0;
};

using Describe = std::function<std::string()>;  // the message's place, for an error's text

Imu decode_imu(std::string_view bytes, Encoding encoding, const Location& where, const Describe& what);
// `type` is Temperature, Float32 or Float64.
Temperature decode_temperature(std::string_view bytes, MessageType type, Encoding encoding, const Location& where,
                               const Describe& what);

}  // namespace driftlab::ros
