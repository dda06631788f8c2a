// MCAP reader: the pure container parser (no ROS knowledge; framework/rosbag.hpp maps channels to
// topics and framework/ros_imu.hpp decodes the messages). Written from the MCAP format
// specification (https://mcap.dev/spec, version 0); no MCAP library code.
//
// The format, as read here. Little endian throughout.
//   Magic 0x89 "MCAP0" "\r\n" (8 bytes) at the start and at the end of the file.
//   Records: opcode (uint8), content length (uint64), content. Strings: uint32 length + bytes;
//   byte arrays: uint32 (uint64 in chunks) length + bytes; maps: uint32 byte length + entries.
//   0x01 Header: profile ("ros1", "ros2", ...), library.        0x02 Footer: summary_start,
//   summary_offset_start (uint64), summary_crc (uint32).         0x03 Schema: id (uint16), name,
//   encoding ("ros2msg", "ros1msg", ...), data.                  0x04 Channel: id (uint16),
//   schema_id (uint16), topic, message_encoding ("cdr", "ros1", ...), metadata map<string, string>.
//   0x05 Message: channel_id (uint16), sequence (uint32), log_time, publish_time (uint64, ns), data
//   (the rest of the record).                                    0x06 Chunk: message_start_time,
//   message_end_time, uncompressed_size (uint64), uncompressed_crc (uint32, CRC-32 of the
//   decompressed records; 0: none), compression ("", "zstd", "lz4"), records (uint64 length + bytes)
//   holding Schema, Channel and Message records.                0x0B Statistics: message_count
//   (uint64), schema_count (uint16), channel_count, attachment_count, metadata_count, chunk_count
//   (uint32), message_start_time, message_end_time (uint64), channel_message_counts
//   map<uint16, uint64>.                                         0x0F Data End: the data section ends.
//   Message Index 0x07, Chunk Index 0x08, Attachment 0x09, Attachment Index 0x0A, Metadata 0x0C,
//   Metadata Index 0x0D, Summary Offset 0x0E and opcodes above 0x0F (reserved) are skipped.
//
// Reading. The data section is streamed from the start record by record (a file without a summary
// section, e.g. one whose writer was stopped before it wrote one, reads the same way), every chunk
// decompressed (framework/decompress.hpp) and its CRC checked (zlib's crc32); every message of a wanted channel is
// handed to the visitor, every channel's messages counted. When the footer points at a summary
// section, its Schema and Channel records are read too (channels without messages are listed) and
// its Statistics are checked against the count: a summary that disagrees with the data is a
// DataError (one of the two is corrupt). Chunk indexes are not used to skip chunks: bags interleave
// every topic in every chunk by time, so an IMU topic is in nearly all of them.
//
// Contract. Every length is checked against the bytes that remain (in the file, the record, the
// chunk) before anything is read or allocated; a chunk's records are decompressed into memory
// growing only as the decompressor produces them (bounded by its stated uncompressed size). A
// truncated file (a record cut off by the end of the file, no footer and end magic), a bad magic, a
// corrupt record (lengths beyond their record, a message of an unknown channel, a channel of an
// unknown schema, a chunk whose CRC, size or compression is wrong), a summary that disagrees with
// the data: DataError naming the file and the byte offset of the record ("byte N"; inside a chunk,
// "chunk at byte N, record at byte M of its records"). Never a crash, never a loop without progress
// (every record advances the offset by at least its 9-byte opening).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace driftlab::mcap {

inline constexpr std::size_t kMagicSize = 8;
// True when `first_bytes` starts with the MCAP magic.
bool has_magic(std::string_view first_bytes);

struct Schema {
  std::uint16_t id = 0;
  std::string name;      // "sensor_msgs/msg/Imu"
  std::string encoding;  // "ros2msg", "ros1msg", ...
};

struct Channel {
  std::uint16_t id = 0;
  std::uint16_t schema_id = 0;  // 0: no schema
  std::string topic;
  std::string message_encoding;  // "cdr", "ros1", ...
  std::map<std::string, std::string> metadata;
  std::uint64_t count = 0;                              // messages in the data section
  std::uint64_t first_log_time = 0, last_log_time = 0;  // ns, of the first / last message in file order
  std::uint64_t min_log_time = 0, max_log_time = 0;     // ns, over all its messages
};

// Where a record lies, for messages: text() is "byte N" or, inside a chunk, "chunk at byte N,
// record at byte M of its records".
struct Place {
  static constexpr std::uint64_t kNoChunk = ~std::uint64_t{0};
  std::uint64_t chunk = kNoChunk;  // file offset of the Chunk record
  std::uint64_t record = 0;        // file offset, or offset in the chunk's decompressed records
  std::string text() const;
};

struct Message {
  const Channel* channel = nullptr;
  std::uint32_t sequence = 0;
  std::uint64_t log_time = 0;      // ns
  std::uint64_t publish_time = 0;  // ns
  std::string_view data;           // valid during the visit only
  Place place;
};

struct File {
  std::string file;
  std::uint64_t file_size = 0;
  std::string profile, library;  // Header
  std::vector<Schema> schemas;
  std::vector<Channel> channels;  // in order of their first record
  std::uint64_t messages = 0;
  std::uint64_t chunks = 0;
  std::map<std::string, std::uint64_t> chunk_compression;      // chunks per compression ("" = none)
  std::uint64_t compressed_bytes = 0, uncompressed_bytes = 0;  // of the chunks' records
  bool has_summary = false;
  bool has_statistics = false;

  const Schema* find_schema(std::uint16_t id) const;
};

using Visitor = std::function<void(const Message&)>;
// Which channels' messages the visitor gets (called once per channel, when it is first seen).
using Wanted = std::function<bool(const Channel&, const Schema*)>;

// Reads an MCAP file; DataError (see the contract above) for anything but a valid file.
File read(const std::filesystem::path& path, const Wanted& wanted = {}, const Visitor& visit = {});
// The same on bytes in memory; `file` names them in messages.
File parse(std::string_view bytes, const std::string& file, const Wanted& wanted = {}, const Visitor& visit = {});

}  // namespace driftlab::mcap
