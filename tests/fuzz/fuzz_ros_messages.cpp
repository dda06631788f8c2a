// libFuzzer harness: the decoders of ROS messages (framework/ros_messages.hpp) on arbitrary bytes.
// The first byte picks the message (bits 0-1: sensor_msgs Imu, Temperature, std_msgs Float32,
// Float64) and the serialization (bit 2: ROS 1, else CDR); the rest is the message.
// Property oracle on every accepted message: a header stamp is a whole number of ns built from
// nanoseconds below 10^9 (so stamp mod 10^9 is in [0, 10^9) for non-negative stamps); a std_msgs
// value has no stamp, a Temperature or Imu has one. Rejections must be DataError; anything else is
// a finding.
// Seed corpus (tests/fuzz/corpus/ros_messages, made by tests/data/logs/ros2-robot-localization/
// make_fuzz_seeds.mjs and make_fixtures.sh): the first Imu of the Jackal recording in CDR little
// and big endian, XCDR2 and ROS 1, a CDR Temperature and a ROS 1 Float64.
#include <cstdint>
#include <string_view>

#include "framework/error.hpp"
#include "framework/ros_messages.hpp"
#include "tests/fuzz/fuzz_oracle.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  using namespace driftlab;
  using fuzz::require;
  constexpr ros::MessageType kTypes[] = {ros::MessageType::Imu, ros::MessageType::Temperature,
                                         ros::MessageType::Float32, ros::MessageType::Float64};
  const ros::MessageType type = kTypes[data[0] & 3];
  const ros::Encoding encoding = (data[0] & 4) ? ros::Encoding::Ros1 : ros::Encoding::Cdr;
  const std::string_view bytes(reinterpret_cast<const char*>(data + 1), size - 1);
  const Location where{"fuzz", 0, "/topic"};
  const ros::Describe what = [] { return std::string("message"); };
  try {
    if (type == ros::MessageType::Imu) {
      const auto m = ros::decode_imu(bytes, encoding, where, what);
      require(m.stamp_ns < 0 || m.stamp_ns % 1000000000 < 1000000000, "stamp nanoseconds");
    } else {
      const auto m = ros::decode_temperature(bytes, type, encoding, where, what);
      require(m.stamp_ns.has_value() == (type == ros::MessageType::Temperature),
              "a stamp where the type has none, or none where it has one");
    }
  } catch (const DataError&) {
  }
  return 0;
}
