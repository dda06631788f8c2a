#include "framework/dataflash.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "framework/binary_input.hpp"
#include "framework/error.hpp"

namespace driftlab::dataflash {
namespace {

using binary::Input;
using binary::load;

constexpr unsigned char kHead1 = 0xA3, kHead2 = 0x95;
constexpr std::uint8_t kFmtType = 0x80;
constexpr std::size_t kHeaderSize = 3;
constexpr std::size_t kMaxLength = 255;  // FMT's Length is a uint8
constexpr std::size_t kFmtLength = 89;
constexpr const char* kFmtFormat = "BBnNZ";
constexpr const char* kFmtColumns = "Type,Length,Name,Format,Columns";

std::size_t format_size(char c) {
  switch (c) {
    case 'b':
    case 'B':
    case 'M':
      return 1;
    case 'h':
    case 'H':
    case 'c':
    case 'C':
    case 'g':
      return 2;
    case 'i':
    case 'I':
    case 'f':
    case 'e':
    case 'E':
    case 'L':
    case 'n':
      return 4;
    case 'd':
    case 'q':
    case 'Q':
      return 8;
    case 'N':
      return 16;
    case 'Z':
    case 'a':
      return 64;
    default:
      return 0;
  }
}

double half_float(std::uint16_t bits) {
  const double sign = (bits & 0x8000u) ? -1.0 : 1.0;
  const int exponent = (bits >> 10) & 0x1f;
  const int mantissa = bits & 0x3ff;
  if (exponent == 0) return sign * std::ldexp(mantissa, -24);
  if (exponent == 31) return mantissa ? std::nan("") : sign * HUGE_VAL;
  return sign * std::ldexp(mantissa + 1024, exponent - 25);
}

double decode(char c, const unsigned char* p) {
  switch (c) {
    case 'b':
      return static_cast<std::int8_t>(p[0]);
    case 'B':
    case 'M':
      return p[0];
    case 'h':
      return static_cast<std::int16_t>(load<2>(p));
    case 'H':
      return static_cast<double>(load<2>(p));
    case 'i':
      return static_cast<std::int32_t>(load<4>(p));
    case 'I':
      return static_cast<double>(load<4>(p));
    case 'q':
      return static_cast<double>(static_cast<std::int64_t>(load<8>(p)));
    case 'Q':
      return static_cast<double>(load<8>(p));
    case 'f':
      return binary::load_float(p);
    case 'd':
      return binary::load_double(p);
    case 'g':
      return half_float(static_cast<std::uint16_t>(load<2>(p)));
    // Divided rather than multiplied by 0.01 / 1e-7: the nearest double to the decimal value.
    case 'c':
      return static_cast<std::int16_t>(load<2>(p)) / 100.0;
    case 'C':
      return static_cast<double>(load<2>(p)) / 100.0;
    case 'e':
      return static_cast<std::int32_t>(load<4>(p)) / 100.0;
    case 'E':
      return static_cast<double>(load<4>(p)) / 100.0;
    case 'L':
      return static_cast<std::int32_t>(load<4>(p)) / 1e7;
    default:
      return 0.0;
  }
}

std::string text(const unsigned char* p, std::size_t n) {
  const auto* end = static_cast<const unsigned char*>(std::memchr(p, 0, n));
  return {reinterpret_cast<const char*>(p), end ? static_cast<std::size_t>(end - p) : n};
}

// Types whose messages the parser reads itself (besides counting and keeping them).
enum class Role { Data, Fmt, Fmtu, Unit, Mult, Parm };

Role role_of(const std::string& name) {
  if (name == "FMTU") return Role::Fmtu;
  if (name == "UNIT") return Role::Unit;
  if (name == "MULT") return Role::Mult;
  if (name == "PARM") return Role::Parm;
  return Role::Data;
}

std::vector<std::string> split_columns(const std::string& columns) {
  std::vector<std::string> out;
  if (columns.empty()) return out;
  std::size_t start = 0;
  while (true) {
    const auto comma = columns.find(',', start);
    out.push_back(columns.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) return out;
    start = comma + 1;
  }
}

class Parser {
 public:
  Parser(Input& in, Log& log, const ReadOptions& options) : in_(in), log_(log), options_(options) { index_.fill(-1); }

  void run() {
    const std::uint64_t size = in_.size();
    log_.file_size = size;
    const std::size_t head = static_cast<std::size_t>(std::min<std::uint64_t>(size, kHeaderSize));
    if (!has_magic({reinterpret_cast<const char*>(in_.peek(head)), head}))
      fail(0, "not an ArduPilot DataFlash log: expected 0xA3 0x95 0x80 (the FMT message) at the start, found " +
                  quoted_excerpt({reinterpret_cast<const char*>(in_.peek(head)), head}));
    define(0, kFmtType, "FMT", kFmtFormat, kFmtColumns, kFmtLength);
    bool skipping = false;
    while (in_.offset() < size) {
      const std::uint64_t at = in_.offset();
      const std::uint64_t remain = size - at;
      if (remain < kHeaderSize) {
        log_.truncated_bytes = remain;
        break;
      }
      const unsigned char* h = in_.peek(kHeaderSize);
      const bool header = h[0] == kHead1 && h[1] == kHead2;
      if (header && index_[h[2]] >= 0) {
        const auto index = static_cast<std::size_t>(index_[h[2]]);
        const std::size_t length = log_.types[index].length;
        if (length > remain) {
          log_.truncated_bytes = remain;
          break;
        }
        skipping = false;
        message(at, index, in_.take(length) + kHeaderSize);
        continue;
      }
      if (header) {
        auto& unknown = log_.unknown_types[h[2]];
        if (unknown.headers++ == 0) unknown.first_offset = at;
      }
      if (!skipping) {
        if (log_.skipped_runs++ == 0) log_.first_skip_offset = at;
        skipping = true;
      }
      ++log_.skipped_bytes;
      in_.advance(1);
    }
    if (log_.messages == 0)
      fail(0, "truncated: the file (" + std::to_string(size) + " bytes) ends before its first message is complete");
    apply_fmtu();
  }

 private:
  [[noreturn]] void fail(std::uint64_t at, const std::string& what) const {
    throw DataError({log_.file, 0, "byte " + std::to_string(at)}, what);
  }

  void define(std::uint64_t at, std::uint8_t type, const std::string& name, const std::string& format,
              const std::string& columns, std::size_t length) {
    MessageType t;
    t.type = type;
    t.name = name;
    t.format = format;
    t.length = length;
    t.defined_at = at;
    const auto names = split_columns(columns);
    std::size_t offset = 0;
    for (std::size_t i = 0; i < format.size(); ++i) {
      Column c;
      c.name = names[i];
      c.format = format[i];
      c.offset = offset;
      c.size = format_size(format[i]);
      offset += c.size;
      t.columns.push_back(std::move(c));
    }
    if (!t.columns.empty()) {
      const Column& first = t.columns.front();
      const bool integer = first.format == 'Q' || first.format == 'q' || first.format == 'I' || first.format == 'i';
      t.timed = integer && (first.name == "TimeUS" || first.name == "TimeMS");
    }
    t.kept = options_.keep_all ||
             std::find(options_.keep_types.begin(), options_.keep_types.end(), name) != options_.keep_types.end();
    if (t.kept) t.values.resize(t.columns.size());
    const Role role = type == kFmtType ? Role::Fmt : role_of(name);
    if (index_[type] >= 0) {
      const auto index = static_cast<std::size_t>(index_[type]);
      log_.types[index] = std::move(t);
      roles_[index] = role;
    } else {
      index_[type] = static_cast<std::int16_t>(log_.types.size());
      log_.types.push_back(std::move(t));
      roles_.push_back(role);
    }
  }

  void message(std::uint64_t at, std::size_t index, const unsigned char* p) {
    MessageType& t = log_.types[index];
    ++log_.messages;
    if (t.timed) {
      const Column& c = t.columns.front();
      std::uint64_t time = c.size == 8 ? load<8>(p) : load<4>(p);
      if (c.name == "TimeMS") time *= 1000;
      if (t.count == 0) t.first_time_us = time;
      t.last_time_us = time;
      if (t.kept) t.time_us.push_back(time);
    }
    ++t.count;
    if (t.kept)
      for (std::size_t i = 0; i < t.columns.size(); ++i)
        if (t.columns[i].numeric()) t.values[i].push_back(decode(t.columns[i].format, p + t.columns[i].offset));
    switch (roles_[index]) {
      case Role::Data:
        return;
      case Role::Fmt:
        return fmt(at, p);
      case Role::Fmtu:
        return fmtu(t, p);
      case Role::Unit:
        return unit(t, p);
      case Role::Mult:
        return mult(t, p);
      case Role::Parm:
        return parm(t, p);
    }
  }

  void fmt(std::uint64_t at, const unsigned char* p) {
    const std::uint8_t type = p[0];
    const std::size_t length = p[1];
    const std::string name = text(p + 2, 4), format = text(p + 6, 16), columns = text(p + 22, 64);
    const std::string what = "FMT of type " + std::to_string(type) + " ('" + quoted_excerpt(name, 4) + "')";
    if (name.empty() || std::any_of(name.begin(), name.end(), [](char c) { return c <= 0x20 || c >= 0x7f; }))
      fail(at, what + ": the name is empty or not printable");
    std::size_t size = kHeaderSize;
    for (const char c : format) {
      const std::size_t n = format_size(c);
      if (n == 0)
        fail(at, what + ": unknown format character " + quoted_excerpt(std::string(1, c)) + " in " +
                     quoted_excerpt(format) + " (known: a b B c C d e E f g h H i I L M n N q Q Z)");
      size += n;
    }
    if (length != size)
      fail(at, what + ": Length " + std::to_string(length) + " differs from the " + std::to_string(size) +
                   " bytes its format " + quoted_excerpt(format) + " needs (3-byte header included)");
    const auto names = split_columns(columns);
    if (names.size() != format.size())
      fail(at, what + ": " + std::to_string(names.size()) + " column names for the " + std::to_string(format.size()) +
                   " format characters of " + quoted_excerpt(format));
    if (type == kFmtType) {
      if (name != "FMT" || format != kFmtFormat || length != kFmtLength)
        fail(at, "FMT redefines itself as '" + name + "' " + quoted_excerpt(format) + ", " + std::to_string(length) +
                     " bytes (expected 'FMT' \"BBnNZ\", 89 bytes)");
      return;
    }
    if (index_[type] >= 0) {
      const MessageType& old = log_.types[static_cast<std::size_t>(index_[type])];
      std::string old_columns;
      for (const auto& c : old.columns) old_columns += (old_columns.empty() ? "" : ",") + c.name;
      if (old.name == name && old.format == format && old_columns == columns) return;
      if (old.count > 0)
        fail(at, what + " redefines type " + std::to_string(type) + " ('" + old.name + "' " +
                     quoted_excerpt(old.format) + ", defined at byte " + std::to_string(old.defined_at) + ") after " +
                     std::to_string(old.count) + " messages of it");
    }
    define(at, type, name, format, columns, length);
  }

  // A text or number column of a metadata message (FMTU, UNIT, MULT, PARM) by name.
  static const Column* find_column(const MessageType& t, std::string_view name) {
    const auto i = t.column_index(name);
    return i ? &t.columns[*i] : nullptr;
  }

  void fmtu(const MessageType& t, const unsigned char* p) {
    const Column* type = find_column(t, "FmtType");
    const Column* units = find_column(t, "UnitIds");
    const Column* mults = find_column(t, "MultIds");
    if (!type || !units || !mults || !type->numeric() || units->numeric() || mults->numeric()) return;
    const double id = decode(type->format, p + type->offset);
    if (!(id >= 0 && id <= 255)) return;
    fmtu_[static_cast<std::uint8_t>(id)] = {text(p + units->offset, units->size), text(p + mults->offset, mults->size)};
  }

  void unit(const MessageType& t, const unsigned char* p) {
    const Column* id = find_column(t, "Id");
    const Column* label = find_column(t, "Label");
    if (!id || !label || id->size != 1 || label->numeric()) return;
    log_.units[static_cast<char>(p[id->offset])] = text(p + label->offset, label->size);
  }

  void mult(const MessageType& t, const unsigned char* p) {
    const Column* id = find_column(t, "Id");
    const Column* factor = find_column(t, "Mult");
    if (!id || !factor || id->size != 1 || !factor->numeric()) return;
    // ArduPilot writes the factors from float constants (1e-6 arrives as 9.99999997e-07): rounded to
    // 7 significant digits, as pymavlink's DFReader does.
    char rounded[32];
    std::snprintf(rounded, sizeof rounded, "%.7g", decode(factor->format, p + factor->offset));
    log_.multipliers[static_cast<char>(p[id->offset])] = std::strtod(rounded, nullptr);
  }

  void parm(const MessageType& t, const unsigned char* p) {
    const Column* name = find_column(t, "Name");
    const Column* value = find_column(t, "Value");
    if (!name || !value || name->numeric() || !value->numeric()) return;
    Parameter parameter;
    parameter.time_us = t.timed ? t.last_time_us : 0;
    parameter.name = text(p + name->offset, name->size);
    parameter.value = decode(value->format, p + value->offset);
    log_.parameters.push_back(std::move(parameter));
  }

  // FMTU may come before or after UNIT and MULT: resolved once all are read.
  void apply_fmtu() {
    for (const auto& [type, ids] : fmtu_) {
      if (index_[type] < 0) continue;
      auto& columns = log_.types[static_cast<std::size_t>(index_[type])].columns;
      for (std::size_t i = 0; i < columns.size(); ++i) {
        if (i < ids.first.size()) {
          columns[i].unit_id = ids.first[i];
          if (const auto u = log_.units.find(ids.first[i]); u != log_.units.end()) columns[i].unit = u->second;
        }
        if (i < ids.second.size()) {
          columns[i].multiplier_id = ids.second[i];
          if (const auto m = log_.multipliers.find(ids.second[i]); m != log_.multipliers.end())
            columns[i].multiplier = m->second;
        }
      }
    }
  }

  Input& in_;
  Log& log_;
  const ReadOptions& options_;
  std::array<std::int16_t, 256> index_{};                             // type -> index into log_.types, -1: no FMT yet
  std::vector<Role> roles_;                                           // parallel to log_.types
  std::map<std::uint8_t, std::pair<std::string, std::string>> fmtu_;  // type -> (unit ids, multiplier ids)
};

Log parse_input(Input& in, const std::string& file, const ReadOptions& options) {
  Log log;
  log.file = file;
  Parser(in, log, options).run();
  return log;
}

}  // namespace

bool has_magic(std::string_view first_bytes) {
  return first_bytes.size() >= kMagicSize && static_cast<unsigned char>(first_bytes[0]) == kHead1 &&
         static_cast<unsigned char>(first_bytes[1]) == kHead2 && static_cast<unsigned char>(first_bytes[2]) == kFmtType;
}

bool Column::numeric() const { return format != 'n' && format != 'N' && format != 'Z' && format != 'a'; }

std::optional<std::size_t> MessageType::column_index(std::string_view column) const {
  for (std::size_t i = 0; i < columns.size(); ++i)
    if (columns[i].name == column) return i;
  return std::nullopt;
}

const std::vector<double>& MessageType::column(std::string_view column_name) const {
  const std::string field = name + "." + std::string(column_name);
  const auto i = column_index(column_name);
  if (!i)
    throw DataError({"", 0, field}, "message type '" + name + "' has no column '" + std::string(column_name) + "'");
  if (!kept) throw DataError({"", 0, field}, "the values of message type '" + name + "' were not kept (ReadOptions)");
  if (!columns[*i].numeric()) throw DataError({"", 0, field}, "column '" + field + "' holds text, not numbers");
  return values[*i];
}

const MessageType* Log::find(std::string_view name) const {
  for (const auto& t : types)
    if (t.name == name) return &t;
  return nullptr;
}

std::optional<double> Log::parameter(std::string_view name) const {
  for (const auto& p : parameters)
    if (p.name == name) return p.value;
  return std::nullopt;
}

Log read(const std::filesystem::path& path, const ReadOptions& options) {
  Input in(path, path.string(), kMaxLength);
  return parse_input(in, path.string(), options);
}

Log parse(std::string_view bytes, const std::string& file, const ReadOptions& options) {
  Input in(bytes, file);
  return parse_input(in, file, options);
}

}  // namespace driftlab::dataflash
