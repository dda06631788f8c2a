// PX4 ULog reader: the pure parser (no IMU knowledge; framework/ulog_imu.hpp maps topics to the
// IMU record). Written from PX4's "ULog File Format" documentation
// (https://docs.px4.io/main/en/dev_log/ulog_file_format.html); no PX4 or pyulog code.
//
// The format, as read here. Little endian throughout.
//   Header, 16 bytes: magic "ULog" 0x01 0x12 0x35, version (uint8, 0 or 1 accepted), timestamp
//   (uint64, us, start of logging).
//   Then messages: uint16 msg_size (bytes after this 3-byte header), uint8 msg_type, payload.
//   'B' flag bits (only as the first message, >= 40 bytes): compat_flags[8], incompat_flags[8],
//       appended_offsets[3] (uint64). incompat bit 0 of byte 0 = data appended; any other incompat
//       bit is a DataError (the log needs a newer reader).
//   'F' format "name:type field;type field;..." with types int8_t..uint64_t, float, double, bool,
//       char, another format's name (nested), each optionally an array "float[3]". Fields named
//       _padding* are alignment only: left out of the values; the data of a logged message may
//       omit its trailing padding (a nested one keeps it).
//   'I' info, 'M' info multiple (is_continued, appended to the previous value of the key),
//   'P' parameter, 'Q' default parameter (default_types bits): uint8 key_len, key "type name",
//       value bytes of that type (char[N] values are text).
//   'A' add logged message: multi_id (uint8), msg_id (uint16), format name. 'R' remove: msg_id.
//   'D' data: msg_id, then the format's bytes; every logged format has "uint64_t timestamp" (us).
//   'L' logged string: level, timestamp, text; 'C' tagged: level, tag (uint16), timestamp, text.
//   'S' sync (counted), 'O' dropout: duration (uint16, ms).
//   'P', 'I', 'M', 'Q' after the first 'A' are changes during the log.
// Appended data (incompat bit set): the log proper ends at the first non-zero appended offset,
// each appended part at the next one (or the end of the file). A message that would cross such a
// boundary was cut off by the writer: it is skipped and its bytes counted
// (Log::bytes_skipped_at_appended); reading resumes at the boundary.
//
// Contract. Every length is checked against the bytes that remain (in the file, and before an
// appended-data boundary) before anything is read or allocated; no message holds more than 65 535
// bytes, so the parser's memory is one message plus what it keeps. A truncated file (a message cut
// off by the end of the file), a corrupt definition (bad format text, unknown or cyclic nested
// type, a format over 65 535 bytes, no uint64_t timestamp), an unknown message type, data for an
// id that no 'A' subscribed, a payload of the wrong size: DataError naming the file, the byte
// offset of the message ("byte N") and what was expected. Never a crash, never a loop without
// progress (every message advances the offset by at least its 3-byte header).
//
// Streaming: the file is read in blocks (1 MiB), never whole. Every topic is counted (messages,
// first/last timestamp); values are kept only for the topics ReadOptions names, so reading the IMU
// topics of a 1-GB log holds only those. Values are kept as double per flattened scalar column
// (64-bit integers above 2^53 lose precision; timestamps are kept as uint64 separately).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace driftlab::ulog {

// The 7-byte file magic; true when `first_bytes` starts with it.
bool has_magic(std::string_view first_bytes);
inline constexpr std::size_t kMagicSize = 7;

enum class Type : std::uint8_t {
  Int8,
  UInt8,
  Int16,
  UInt16,
  Int32,
  UInt32,
  Int64,
  UInt64,
  Float,
  Double,
  Bool,
  Char,
  Nested
};

// A field of a format, as defined ("float[3] gyro_rad"), with its place in the message.
struct Field {
  std::string type_name;  // "float", "uint64_t", or a nested format's name
  Type type = Type::UInt8;
  std::size_t array_length = 0;  // 0: a scalar
  std::string name;
  std::size_t offset = 0;  // bytes from the start of the message (after msg_id)
  std::size_t size = 0;    // bytes, array included
  bool padding() const { return name.starts_with("_padding"); }
};

// One scalar of a message, arrays and nested formats flattened: "x", "gyro_rad[2]", "accel[1].x".
struct Column {
  std::string name;
  Type type = Type::Float;
  std::size_t offset = 0;
};

// A logged topic instance: one format name and multi_id ('A' messages may subscribe it under
// several msg_ids over the log; they all feed this one topic).
struct Topic {
  std::string name;
  int multi_id = 0;
  std::vector<Field> fields;     // the format's top-level fields, padding included
  std::vector<Column> columns;   // flattened scalars, padding left out
  std::size_t message_size = 0;  // bytes of one message by its format (trailing padding included)
  std::uint64_t count = 0;       // data messages
  std::uint64_t data_bytes = 0;  // their payload bytes as logged (msg_id excluded, trailing padding as written)
  std::uint64_t first_timestamp_us = 0, last_timestamp_us = 0;  // of the first / last message in the file
  bool kept = false;                                            // values stored (ReadOptions)
  std::vector<std::uint64_t> timestamp_us;                      // per message in file order, when kept
  std::vector<std::vector<double>> values;                      // per column, per message, when kept

  bool has_column(std::string_view column) const;
  // Values of a column; DataError naming the topic and the column when it is absent or not kept.
  const std::vector<double>& column(std::string_view column) const;
};

struct Parameter {
  std::string name;
  double value = 0.0;
};
struct ParameterChange {
  std::uint64_t timestamp_us = 0;  // of the last data message before the change
  std::string name;
  double value = 0.0;
};
struct DefaultParameter {
  std::string name;
  double value = 0.0;
  std::uint8_t default_types = 0;  // bit 0: system-wide default, bit 1: configuration default
};
struct Dropout {
  std::uint64_t timestamp_us = 0;  // of the last data message before it
  std::uint16_t duration_ms = 0;
};
struct LoggedString {
  std::uint8_t level = 0;            // syslog level, as the ASCII digit '0'..'7' PX4 writes
  std::optional<std::uint16_t> tag;  // 'C' messages
  std::uint64_t timestamp_us = 0;
  std::string text;
};

struct Log {
  std::string file;
  std::uint64_t file_size = 0;
  int version = 0;
  std::uint64_t start_timestamp_us = 0;  // header
  std::array<std::uint8_t, 8> compat_flags{}, incompat_flags{};
  std::array<std::uint64_t, 3> appended_offsets{};
  std::uint64_t bytes_skipped_at_appended = 0;  // cut-off messages before appended-data boundaries
  // 'I' values by key name (type stripped); numbers as text, char arrays as their text. A later
  // 'I' of the same key replaces the value.
  std::map<std::string, std::string> info;
  std::map<std::string, std::vector<std::string>> info_multiple;  // 'M', continued parts joined
  std::vector<Parameter> parameters;                              // definitions section, file order
  std::vector<ParameterChange> parameter_changes;                 // data section
  std::vector<DefaultParameter> default_parameters;
  std::vector<Topic> topics;  // in order of first subscription
  std::vector<Dropout> dropouts;
  std::vector<LoggedString> logged;
  std::uint64_t sync_messages = 0;

  const Topic* find(std::string_view name, int multi_id) const;
  std::vector<const Topic*> instances(std::string_view name) const;  // sorted by multi_id
};

struct ReadOptions {
  bool keep_all = false;                 // keep the values of every topic
  std::vector<std::string> keep_topics;  // else only of these topics (every multi_id)
};

// Reads a ULog file; DataError (see the contract above) for anything but a valid log.
Log read(const std::filesystem::path& path, const ReadOptions& options = {});
// The same on bytes in memory; `file` names them in messages.
Log parse(std::string_view bytes, const std::string& file, const ReadOptions& options = {});

}  // namespace driftlab::ulog
