// ROS bags, whatever their container: the catalogue (topics with type, encoding, message count and
// time span) and the messages of chosen topics as serialized bytes (framework/ros_messages.hpp
// decodes them; framework/ros_imu.hpp makes the IMU record). Containers, chosen by content:
//   ROS 1 bag v2.0    first bytes "#ROSBAG V2.0"; read through Debian's librosbag-storage
//                     (rosbag::Bag, rosbag::View: chunk compression none, bz2, lz4 as the library
//                     reads them). Message time: the bag's receive time. Messages in time order.
//                     The md5sum of every connection is kept (ros1 encoding).
//   ROS 2 sqlite3     first bytes "SQLite format 3\0" (.db3, rosbag2's sqlite3 storage): tables
//                     topics(id, name, type, serialization_format) and messages(id, topic_id,
//                     timestamp (ns, receive time), data); through libsqlite3, opened read only.
//                     Messages in row order.
//   MCAP              first bytes 0x89 "MCAP0\r\n" (framework/mcap.hpp): a channel is a topic, its
//                     schema name the type, its message encoding the encoding ("cdr", "ros1"),
//                     the log time the message time. Messages in file order.
//   rosbag2 directory a directory with metadata.yaml (rosbag2_bagfile_information:
//                     storage_identifier sqlite3 or mcap, relative_file_paths, compression_format,
//                     compression_mode): its files, one after the other, as one bag. Compression
//                     mode MESSAGE (each message zstd-compressed) is undone message by message;
//                     mode FILE (whole files compressed) is refused with how to undo it
//                     (zstd -d), as is a storage other than sqlite3 and mcap.
// A container whose library driftlab was built without (CMake reports which) is a DataError naming
// the Debian package.
//
// Errors: DataError naming the file, and the byte, row or message where it was found: whatever the
// container's reader finds wrong (truncated, corrupt, not that container after all), a topic of one
// name with two types, a metadata.yaml that is not rosbag2's or names missing files.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace driftlab::rosbag {

enum class Format { Ros1, Sqlite3, Mcap, Directory };
// The container `path` holds, by content (a directory: by its metadata.yaml); nullopt: not a bag.
std::optional<Format> sniff(const std::filesystem::path& path);

struct Topic {
  std::string name;
  std::string type;      // "sensor_msgs/Imu" (ROS 1), "sensor_msgs/msg/Imu" (ROS 2)
  std::string encoding;  // "ros1", "cdr", or what an MCAP channel states
  std::string md5;       // ROS 1 only: md5sum of the message definition
  std::uint64_t count = 0;
  std::int64_t first_ns = 0, last_ns = 0;  // earliest / latest message time, ns
};

struct Bag {
  std::string file;
  Format format = Format::Ros1;
  std::string container;           // "ROS 1 bag v2.0, bz2 chunks", "MCAP (profile ros2, zstd chunks, summary)", ...
  std::uint64_t bytes = 0;         // of every file read
  std::vector<std::string> files;  // the files read (one, or a directory's)
  std::vector<Topic> topics;       // sorted by name
  const Topic* find(std::string_view name) const;
};

struct Message {
  const Topic* topic = nullptr;
  std::int64_t time_ns = 0;  // the container's message time (receive / log time)
  std::string_view data;     // serialized message, valid during the visit only
  // "byte N", "row N", "message N" (after the file's name in a directory): built only when asked,
  // valid during the visit.
  std::function<std::string()> where;
};
using Visitor = std::function<void(const Message&)>;
// Whose messages to visit: asked once per topic as its container declares it (name, type, encoding
// and md5 known; count and span not yet).
using Wanted = std::function<bool(const Topic&)>;

// Reads the catalogue of `path` in one pass, visiting the messages of the wanted topics (none
// without `wanted`).
Bag read(const std::filesystem::path& path, const Wanted& wanted = {}, const Visitor& visit = {});

}  // namespace driftlab::rosbag
