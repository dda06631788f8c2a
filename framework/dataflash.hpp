// ArduPilot DataFlash (.bin) reader: the pure parser (no IMU knowledge; framework/dataflash_imu.hpp
// maps messages to the IMU record). Written from ArduPilot's log format documentation (the format
// types of libraries/AP_Logger/README.md, the FMT/FMTU/UNIT/MULT/PARM definitions of
// AP_Logger/LogStructure.h, https://ardupilot.org/dev/docs/code-overview-adding-a-new-log-message.html)
// and checked against pymavlink's DFReader on real logs (tests/data/logs); no ArduPilot or pymavlink
// code.
//
// The format, as read here. Little endian throughout.
//   Every message: 0xA3 0x95, a type byte, then its payload. The length of a message (header
//   included) is what the FMT message of its type says; a type without an FMT cannot be read.
//   FMT (type 128, 89 bytes, the first message of every log): Type (uint8), Length (uint8, header
//   included), Name (char[4]), Format (char[16]), Columns (char[64], comma-separated). One format
//   character per column:
//     b int8   B uint8   h int16   H uint16   i int32   I uint32   q int64   Q uint64
//     f float  d double  M uint8 (flight mode)  g float16 (IEEE half; pymavlink reads it too)
//     c int16 x 0.01   C uint16 x 0.01   e int32 x 0.01   E uint32 x 0.01   L int32 x 1e-7 (lat/lon)
//     n char[4]   N char[16]   Z char[64]   a int16[32]
//   c C e E L are stored scaled (the value x 0.01, x 1e-7), as pymavlink's DFReader gives them.
//   FMTU: FmtType, UnitIds (char[16]: one unit character per column; '#' marks the instance
//   column, '-' none), MultIds (one multiplier character per column). UNIT: Id (char), Label
//   (char[64], e.g. "rad/s"). MULT: Id (char), Mult (double; rounded to 7 significant digits, as
//   ArduPilot writes float constants such as 1e-6 into it). Units and multipliers are metadata:
//   a column's values are never multiplied by its MULT (ArduPilot logs IMU values in SI already).
//   PARM: TimeUS, Name (char[16]), Value (float)[, Default (float)]: the parameters at boot, then
//   every change.
//   Time: a type whose first column is TimeUS (us) or TimeMS (ms, old logs) is timed; its time
//   stamps are kept in us.
//
// Contract: streamed (the file is read in 1-MiB blocks, never whole; values are kept only for the
// types ReadOptions names, every type is counted), robust like ArduPilot's own readers:
//   - garbage between messages (bytes that do not start 0xA3 0x95 <type with an FMT>; logs have
//     it after a reboot or a lost page): skipped byte by byte until the next such header; the bytes
//     and the places are counted (Log::skipped_bytes / skipped_runs / first_skip_offset). A header
//     whose type no FMT defines is skipped the same way and counted per type (Log::unknown_types).
//   - a last message cut off by the end of the file (the usual end of a log whose power went off):
//     left out, its bytes counted (Log::truncated_bytes).
// DataError naming the file and the byte offset ("byte N") for: a file that does not start with
// the FMT message of FMT (0xA3 0x95 0x80), a file without one complete message, a corrupt FMT (an
// empty or unprintable name, an unknown format character, a Length that is not 3 + the sizes of its
// format, a column count that differs from the format's, FMT itself redefined, a type redefined
// differently after messages of it were read). No length is trusted before it is checked against
// the bytes that remain; a message holds at most 255 bytes, so the parser's memory is one block plus
// what it keeps. Never a crash, never a loop without progress.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace driftlab::dataflash {

// The first 3 bytes of every DataFlash log (the header of the FMT message that defines FMT).
inline constexpr std::size_t kMagicSize = 3;
bool has_magic(std::string_view first_bytes);

// One column of a message type, as its FMT (and FMTU, UNIT, MULT) define it.
struct Column {
  std::string name;
  char format = 'f';                 // the format character (table above)
  std::size_t offset = 0;            // bytes from the start of the payload (after the 3-byte header)
  std::size_t size = 0;              // bytes
  char unit_id = 0;                  // FMTU unit character (0: no FMTU); '#': the instance column
  std::string unit;                  // its UNIT label ("rad/s", "degC"); "" when unknown
  char multiplier_id = 0;            // FMTU multiplier character (0: no FMTU)
  std::optional<double> multiplier;  // its MULT value, when the log defines it
  bool numeric() const;              // false for text (n N Z) and int16 arrays (a)
};

// A message type: its definition, counts, and (when kept) its values.
struct MessageType {
  std::uint8_t type = 0;
  std::string name;
  std::string format;
  std::vector<Column> columns;
  std::size_t length = 0;                             // bytes of one message, the 3-byte header included
  std::uint64_t defined_at = 0;                       // byte offset of its FMT
  bool timed = false;                                 // first column TimeUS or TimeMS
  std::uint64_t count = 0;                            // messages
  std::uint64_t first_time_us = 0, last_time_us = 0;  // of the first / last message in the file (timed types)
  bool kept = false;                                  // values stored (ReadOptions)
  std::vector<std::uint64_t> time_us;                 // per message in file order, when kept and timed
  std::vector<std::vector<double>> values;            // per column, per message, when kept (empty for text columns)

  std::optional<std::size_t> column_index(std::string_view column) const;
  bool has_column(std::string_view column) const { return column_index(column).has_value(); }
  // Values of a numeric column; DataError naming the type and column when absent, text or not kept.
  const std::vector<double>& column(std::string_view column) const;
};

struct Parameter {
  std::uint64_t time_us = 0;  // PARM's TimeUS (0 in the boot dump of some logs)
  std::string name;
  double value = 0.0;
};

struct UnknownType {
  std::uint64_t headers = 0;       // headers of this type met (each skipped as garbage)
  std::uint64_t first_offset = 0;  // byte of the first
};

struct Log {
  std::string file;
  std::uint64_t file_size = 0;
  std::vector<MessageType> types;       // in order of their FMT
  std::vector<Parameter> parameters;    // PARM messages in file order
  std::map<char, std::string> units;    // UNIT: id -> label
  std::map<char, double> multipliers;   // MULT: id -> factor
  std::uint64_t messages = 0;           // complete messages read, FMT included
  std::uint64_t skipped_bytes = 0;      // garbage between messages, unknown-type headers included
  std::uint64_t skipped_runs = 0;       // places where garbage began
  std::uint64_t first_skip_offset = 0;  // byte where the first run began (when skipped_runs > 0)
  std::map<std::uint8_t, UnknownType> unknown_types;
  std::uint64_t truncated_bytes = 0;  // an incomplete last message (0: the file ends cleanly)

  const MessageType* find(std::string_view name) const;
  // The first logged value of a parameter (the value at boot), if the log has it.
  std::optional<double> parameter(std::string_view name) const;
};

struct ReadOptions {
  bool keep_all = false;                // keep the values of every type
  std::vector<std::string> keep_types;  // else only of these types (by name)
};

// Reads a DataFlash log; DataError (see the contract above) for anything but a readable log.
Log read(const std::filesystem::path& path, const ReadOptions& options = {});
// The same on bytes in memory; `file` names them in messages.
Log parse(std::string_view bytes, const std::string& file, const ReadOptions& options = {});

}  // namespace driftlab::dataflash
