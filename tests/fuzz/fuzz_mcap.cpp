// libFuzzer harness: the MCAP parser (framework/mcap.hpp) with the ROS message decoders
// (framework/ros_messages.hpp) on what it visits. The first byte picks the options (bit 0: visit
// every channel's messages, else none; bit 1: decode each visited message as a sensor_msgs Imu,
// else by its schema name: Imu, Temperature or Float*); the rest is the file.
// Property oracle on every accepted file: the channel counts add up to the message count, every
// visit is of a counted channel and lies in its log-time span, the chunks of each compression add
// up to the chunk count, and a decoded header stamp has nanoseconds below 10^9 (ROS 2 stamps within
// the int32 seconds range). Rejections must be DataError; anything else (another exception, a
// crash, a sanitizer report, a hang, a property) is a finding.
// Seed corpus (tests/fuzz/corpus/mcap, made by tests/data/logs/ros2-robot-localization/
// make_fuzz_seeds.mjs): the first IMU and temperature messages of the ROS 2 fixtures in each
// layout (zstd, lz4, uncompressed chunks with summary; unchunked without; big-endian CDR; XCDR2),
// each with mode bytes 0 and 3.
#include <cstdint>
#include <map>
#include <string_view>

#include "framework/error.hpp"
#include "framework/mcap.hpp"
#include "framework/ros_messages.hpp"
#include "tests/fuzz/fuzz_oracle.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  using namespace driftlab;
  using fuzz::require;
  const std::uint8_t mode = data[0];
  const std::string_view bytes(reinterpret_cast<const char*>(data + 1), size - 1);
  std::uint64_t visits = 0;
  std::map<std::uint16_t, ros::MessageType> types;  // by channel id, from the schema name
  const mcap::Wanted wanted = [&](const mcap::Channel& c, const mcap::Schema* schema) {
    types[c.id] = schema ? ros::message_type(schema->name).value_or(ros::MessageType::Imu) : ros::MessageType::Imu;
    return (mode & 1) != 0;
  };
  const mcap::Visitor visit = [&](const mcap::Message& m) {
    ++visits;
    require(m.channel != nullptr && m.channel->count > 0, "a visit of a channel not counted");
    require(m.log_time >= m.channel->min_log_time && m.log_time <= m.channel->max_log_time,
            "a visit outside its channel's span");
    const auto type = (mode & 2) ? ros::MessageType::Imu : types.at(m.channel->id);
    const auto encoding = m.channel->message_encoding == "ros1" ? ros::Encoding::Ros1 : ros::Encoding::Cdr;
    try {
      if (type == ros::MessageType::Imu) {
        const auto imu =
            ros::decode_imu(m.data, encoding, {"fuzz.mcap", 0, m.channel->topic}, [&m] { return m.place.text(); });
        require(encoding == ros::Encoding::Ros1 ||
                    (imu.stamp_ns >= -2147483648LL * 1000000000 && imu.stamp_ns < 2147483648LL * 1000000000),
                "a CDR stamp outside int32 seconds");
      } else {
        ros::decode_temperature(m.data, type, encoding, {"fuzz.mcap", 0, m.channel->topic},
                                [&m] { return m.place.text(); });
      }
    } catch (const DataError&) {
    }
  };
  try {
    const mcap::File f = mcap::parse(bytes, "fuzz.mcap", wanted, visit);
    std::uint64_t counted = 0, wanted_count = 0, chunks = 0;
    for (const auto& c : f.channels) {
      counted += c.count;
      if (mode & 1) wanted_count += c.count;
      require(c.count == 0 || c.min_log_time <= c.max_log_time, "a channel's span is inverted");
    }
    require(counted == f.messages, "channel counts do not add up to the message count");
    require(visits == wanted_count, "visits differ from the wanted channels' counts");
    for (const auto& [codec, n] : f.chunk_compression) chunks += n;
    require(chunks == f.chunks, "chunks per compression do not add up");
  } catch (const DataError&) {
  }
  return 0;
}
