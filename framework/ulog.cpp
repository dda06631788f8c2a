#include "framework/ulog.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <system_error>
#include <unordered_map>

#include "framework/binary_input.hpp"
#include "framework/error.hpp"

namespace driftlab::ulog {
namespace {

using binary::Input;
using binary::load;

constexpr unsigned char kMagicBytes[kMagicSize] = {'U', 'L', 'o', 'g', 0x01, 0x12, 0x35};
constexpr std::size_t kHeaderSize = 16;
constexpr std::size_t kMessageHeaderSize = 3;
constexpr std::size_t kFlagBitsSize = 40;
constexpr std::size_t kMaxMessageBytes = 65535;  // msg_size is a uint16
constexpr int kMaxNesting = 32;
// Flattened columns kept over all topics: a real log has some 10^4; the bound keeps a hostile file
// (thousands of subscriptions of one 65 535-byte format) from asking for gigabytes of names.
constexpr std::size_t kMaxKeptColumns = std::size_t{1} << 20;

struct BaseType {
  std::string_view name;
  Type type;
  std::size_t size;
};
constexpr BaseType kBaseTypes[] = {
    {"int8_t", Type::Int8, 1},     {"uint8_t", Type::UInt8, 1},   {"int16_t", Type::Int16, 2},
    {"uint16_t", Type::UInt16, 2}, {"int32_t", Type::Int32, 4},   {"uint32_t", Type::UInt32, 4},
    {"int64_t", Type::Int64, 8},   {"uint64_t", Type::UInt64, 8}, {"float", Type::Float, 4},
    {"double", Type::Double, 8},   {"bool", Type::Bool, 1},       {"char", Type::Char, 1}};

const BaseType* base_type(std::string_view name) {
  for (const auto& b : kBaseTypes)
    if (b.name == name) return &b;
  return nullptr;
}

std::size_t base_size(Type type) {
  for (const auto& b : kBaseTypes)
    if (b.type == type) return b.size;
  return 0;
}

double decode(Type type, const unsigned char* p) {
  switch (type) {
    case Type::Int8:
      return static_cast<std::int8_t>(p[0]);
    case Type::UInt8:
    case Type::Char:
      return p[0];
    case Type::Bool:
      return p[0] != 0 ? 1.0 : 0.0;
    case Type::Int16:
      return static_cast<std::int16_t>(load<2>(p));
    case Type::UInt16:
      return static_cast<double>(load<2>(p));
    case Type::Int32:
      return static_cast<std::int32_t>(load<4>(p));
    case Type::UInt32:
      return static_cast<double>(load<4>(p));
    case Type::Int64:
      return static_cast<double>(static_cast<std::int64_t>(load<8>(p)));
    case Type::UInt64:
      return static_cast<double>(load<8>(p));
    case Type::Float:
      return binary::load_float(p);
    case Type::Double:
      return binary::load_double(p);
    case Type::Nested:
      break;
  }
  return 0.0;
}

// Shortest text of one value of a base type (float as float, so 0.1f prints "0.1").
std::string render(Type type, const unsigned char* p) {
  char buf[64];
  std::to_chars_result r{};
  if (type == Type::Float) {
    r = std::to_chars(buf, buf + sizeof buf, binary::load_float(p));
  } else if (type == Type::Double) {
    r = std::to_chars(buf, buf + sizeof buf, decode(type, p));
  } else if (type == Type::Int64) {
    r = std::to_chars(buf, buf + sizeof buf, static_cast<std::int64_t>(load<8>(p)));
  } else if (type == Type::UInt64) {
    r = std::to_chars(buf, buf + sizeof buf, load<8>(p));
  } else {
    r = std::to_chars(buf, buf + sizeof buf, static_cast<std::int64_t>(decode(type, p)));
  }
  return std::string(buf, r.ptr);
}

struct RawField {
  std::string type_name;
  std::optional<std::size_t> array_length;  // type[N]; N = 0 only in info keys (an empty char[0] value)
  std::string name;
};

struct Layout {
  std::vector<Field> fields;
  std::size_t size = 0;
};

// What the parser needs per topic besides the public Topic.
struct TopicState {
  std::size_t min_payload = 0;  // bytes without the trailing padding
  std::size_t timestamp_offset = 0;
};

std::string type_text(std::uint8_t type) {
  if (type >= 0x20 && type < 0x7f) return std::string("'") + static_cast<char>(type) + "'";
  char buf[8];
  std::snprintf(buf, sizeof buf, "0x%02x", type);
  return buf;
}

class Parser {
 public:
  Parser(Input& in, Log& log, const ReadOptions& options) : in_(in), log_(log), options_(options) {}

  void run() {
    const std::uint64_t size = in_.size();
    log_.file_size = size;
    if (size < kHeaderSize)
      fail(0, "expected the 16-byte ULog header, the file has " + std::to_string(size) + " bytes");
    const unsigned char* header = in_.take(kHeaderSize);
    if (!has_magic({reinterpret_cast<const char*>(header), kMagicSize}))
      fail(0, "not a ULog file: expected the magic 'ULog' 0x01 0x12 0x35, found " +
                  quoted_excerpt({reinterpret_cast<const char*>(header), kMagicSize}));
    log_.version = header[7];
    if (log_.version > 1)
      fail(7, "ULog version " + std::to_string(log_.version) + "; this reader knows versions 0 and 1");
    log_.start_timestamp_us = load<8>(header + 8);

    ends_ = {size};
    std::size_t part = 0;  // index into ends_: the log proper, then each appended part
    bool first = true;
    while (in_.offset() < size) {
      while (in_.offset() >= ends_[part]) ++part;
      const std::uint64_t at = in_.offset();
      const std::uint64_t end = ends_[part];
      const bool before_appended = part + 1 < ends_.size();
      const std::uint64_t remain = end - at;
      if (remain < kMessageHeaderSize) {
        if (!before_appended)
          fail(at, "truncated: expected a 3-byte message header, " + std::to_string(remain) + " bytes remain");
        skip_to(at, end);
        continue;
      }
      const unsigned char* h = in_.take(kMessageHeaderSize);
      const auto msg_size = static_cast<std::size_t>(load<2>(h));
      const std::uint8_t type = h[2];
      if (msg_size > remain - kMessageHeaderSize) {
        if (!before_appended)
          fail(at, "truncated: message " + type_text(type) + " declares " + std::to_string(msg_size) + " bytes, " +
                       std::to_string(remain - kMessageHeaderSize) + " remain in the file");
        skip_to(at, end);
        continue;
      }
      const unsigned char* p = in_.take(msg_size);
      if (type == 'B') {
        if (!first) fail(at, "a flag-bits message 'B' is allowed only as the first message (byte 16)");
        flag_bits(at, p, msg_size);
      } else {
        message(at, type, p, msg_size);
      }
      first = false;
    }
  }

 private:
  [[noreturn]] void fail(std::uint64_t at, const std::string& what) const {
    throw DataError({log_.file, 0, "byte " + std::to_string(at)}, what);
  }

  void need(std::uint64_t at, std::size_t n, std::size_t wanted, const char* what) const {
    if (n < wanted)
      fail(at, std::string(what) + ": expected at least " + std::to_string(wanted) + " bytes, the message has " +
                   std::to_string(n));
  }

  // Skips the cut-off message at `at` up to the appended-data boundary `end`.
  void skip_to(std::uint64_t at, std::uint64_t end) {
    log_.bytes_skipped_at_appended += end - at;
    in_.seek(end);
  }

  void flag_bits(std::uint64_t at, const unsigned char* p, std::size_t n) {
    need(at, n, kFlagBitsSize, "flag bits 'B'");
    std::copy(p, p + 8, log_.compat_flags.begin());
    std::copy(p + 8, p + 16, log_.incompat_flags.begin());
    for (int i = 0; i < 3; ++i) log_.appended_offsets[i] = load<8>(p + 16 + 8 * i);
    if ((log_.incompat_flags[0] & ~1u) != 0 ||
        std::any_of(log_.incompat_flags.begin() + 1, log_.incompat_flags.end(), [](auto b) { return b != 0; }))
      fail(at, "unknown incompatible flag bits: the log uses a ULog feature this reader does not know");
    if ((log_.incompat_flags[0] & 1u) == 0) return;
    std::vector<std::uint64_t> ends;
    for (const auto offset : log_.appended_offsets) {
      if (offset == 0) continue;
      const std::uint64_t previous = ends.empty() ? in_.offset() : ends.back();
      if (offset < previous || offset > in_.size())
        fail(at, "appended-data offset " + std::to_string(offset) + " is not between " + std::to_string(previous) +
                     " and the file size " + std::to_string(in_.size()));
      ends.push_back(offset);
    }
    ends.push_back(in_.size());
    ends_ = std::move(ends);
  }

  void message(std::uint64_t at, std::uint8_t type, const unsigned char* p, std::size_t n) {
    switch (type) {
      case 'F':
        return format(at, p, n);
      case 'I':
        return info(at, p, n);
      case 'M':
        return info_multiple(at, p, n);
      case 'P':
        return parameter(at, p, n);
      case 'Q':
        return default_parameter(at, p, n);
      case 'A':
        in_data_ = true;
        return add(at, p, n);
      case 'R':
        in_data_ = true;
        return remove(at, p, n);
      case 'D':
        return data(at, p, n);
      case 'L':
        in_data_ = true;
        need(at, n, 9, "logged string 'L'");
        log_.logged.push_back({p[0], std::nullopt, load<8>(p + 1), text(p + 9, n - 9)});
        return;
      case 'C':
        in_data_ = true;
        need(at, n, 11, "tagged logged string 'C'");
        log_.logged.push_back({p[0], static_cast<std::uint16_t>(load<2>(p + 1)), load<8>(p + 3), text(p + 11, n - 11)});
        return;
      case 'S':
        in_data_ = true;
        ++log_.sync_messages;
        return;
      case 'O':
        in_data_ = true;
        need(at, n, 2, "dropout 'O'");
        log_.dropouts.push_back({last_timestamp_, static_cast<std::uint16_t>(load<2>(p))});
        return;
      default:
        fail(at, "unknown message type " + type_text(type) + " (a ULog has B F I M P Q A R D L C S O)");
    }
  }

  static std::string text(const unsigned char* p, std::size_t n) { return {reinterpret_cast<const char*>(p), n}; }

  // "float[3]" -> ("float", 3); "float" -> ("float", none). N = 0 only when `allow_empty`.
  RawField parse_type(std::uint64_t at, std::string_view type, std::string_view context, bool allow_empty) const {
    RawField f;
    if (const auto bracket = type.find('['); bracket != std::string_view::npos) {
      const auto digits = type.substr(bracket + 1, type.size() - bracket - 2);
      std::size_t length = 0;
      const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), length);
      if (type.back() != ']' || digits.empty() || r.ec != std::errc() || r.ptr != digits.data() + digits.size() ||
          (length == 0 && !allow_empty) || length > kMaxMessageBytes)
        fail(at, std::string(context) + ": bad array type " + quoted_excerpt(type) + " (expected type[N], N in " +
                     (allow_empty ? "0" : "1") + "..65535)");
      f.array_length = length;
      type = type.substr(0, bracket);
    }
    if (type.empty()) fail(at, std::string(context) + ": empty type name");
    f.type_name = type;
    return f;
  }

  void format(std::uint64_t at, const unsigned char* p, std::size_t n) {
    const std::string_view definition(reinterpret_cast<const char*>(p), n);
    const auto colon = definition.find(':');
    if (colon == 0 || colon == std::string_view::npos)
      fail(at, "format 'F': expected 'name:type field;...', got " + quoted_excerpt(definition));
    const std::string name(definition.substr(0, colon));
    std::vector<RawField> fields;
    std::string_view rest = definition.substr(colon + 1);
    while (!rest.empty()) {
      const auto semicolon = rest.find(';');
      const auto item = rest.substr(0, semicolon);
      rest = semicolon == std::string_view::npos ? std::string_view() : rest.substr(semicolon + 1);
      if (item.empty()) continue;
      const auto space = item.find(' ');
      if (space == 0 || space == std::string_view::npos || space + 1 == item.size() ||
          item.find(' ', space + 1) != std::string_view::npos)
        fail(at, "format '" + name + "': expected 'type name', got " + quoted_excerpt(item));
      RawField f = parse_type(at, item.substr(0, space), "format '" + name + "'", false);
      f.name = item.substr(space + 1);
      fields.push_back(std::move(f));
    }
    if (fields.empty()) fail(at, "format '" + name + "' has no fields");
    formats_[name] = std::move(fields);
    layouts_.clear();  // a redefinition may change nested sizes; topics already added keep theirs
    flat_.clear();
  }

  const Layout& layout(std::uint64_t at, const std::string& name, int depth) {
    if (const auto it = layouts_.find(name); it != layouts_.end()) return it->second;
    if (depth > kMaxNesting)
      fail(at, "format '" + name + "': nested more than " + std::to_string(kMaxNesting) + " levels deep");
    const auto def = formats_.find(name);
    if (def == formats_.end()) fail(at, "no format 'F' defines '" + name + "'");
    if (std::find(resolving_.begin(), resolving_.end(), name) != resolving_.end())
      fail(at, "format '" + name + "' contains itself (a cycle of nested formats)");
    resolving_.push_back(name);
    Layout out;
    for (const auto& raw : def->second) {
      Field f;
      f.type_name = raw.type_name;
      f.array_length = raw.array_length.value_or(0);
      f.name = raw.name;
      f.offset = out.size;
      std::size_t element = 0;
      if (const auto* b = base_type(raw.type_name)) {
        f.type = b->type;
        element = b->size;
      } else {
        f.type = Type::Nested;
        element = layout(at, raw.type_name, depth + 1).size;
      }
      f.size = element * std::max<std::size_t>(1, f.array_length);
      if (f.size > kMaxMessageBytes || out.size + f.size > kMaxMessageBytes)
        fail(at, "format '" + name + "' is larger than 65535 bytes, more than a message can hold");
      out.size += f.size;
      out.fields.push_back(std::move(f));
    }
    resolving_.pop_back();
    return layouts_[name] = std::move(out);
  }

  // The flattened columns of a format, computed once per format (multi-instances share them).
  const std::vector<Column>& columns(std::uint64_t at, const std::string& name) {
    if (const auto it = flat_.find(name); it != flat_.end()) return it->second;
    std::vector<Column> out;
    flatten(at, layout(at, name, 0).fields, 0, "", out);
    return flat_[name] = std::move(out);
  }

  void flatten(std::uint64_t at, const std::vector<Field>& fields, std::size_t base, const std::string& prefix,
               std::vector<Column>& out) {
    for (const auto& f : fields) {
      if (f.padding()) continue;
      const std::size_t count = std::max<std::size_t>(1, f.array_length);
      const std::size_t element = f.size / count;
      for (std::size_t i = 0; i < count; ++i) {
        const std::string name = prefix + f.name + (f.array_length ? "[" + std::to_string(i) + "]" : "");
        const std::size_t offset = base + f.offset + i * element;
        if (f.type == Type::Nested) {
          flatten(at, layout(at, f.type_name, 0).fields, offset, name + ".", out);
        } else {
          out.push_back({name, f.type, offset});
        }
      }
    }
  }

  bool keeps(const std::string& name) const {
    return options_.keep_all ||
           std::find(options_.keep_topics.begin(), options_.keep_topics.end(), name) != options_.keep_topics.end();
  }

  void add(std::uint64_t at, const unsigned char* p, std::size_t n) {
    need(at, n, 4, "add logged message 'A'");
    const int multi_id = p[0];
    const auto msg_id = static_cast<std::uint16_t>(load<2>(p + 1));
    const std::string name = text(p + 3, n - 3);
    if (subscribed_[msg_id] >= 0)
      fail(at, "msg_id " + std::to_string(msg_id) + " added twice (no 'R' removed it in between)");
    const Layout& l = layout(at, name, 0);
    auto key = std::make_pair(name, multi_id);
    auto it = topic_index_.find(key);
    if (it == topic_index_.end()) {
      Topic t;
      t.name = name;
      t.multi_id = multi_id;
      t.fields = l.fields;
      t.message_size = l.size;
      TopicState s;
      const auto ts =
          std::find_if(l.fields.begin(), l.fields.end(), [](const Field& f) { return f.name == "timestamp"; });
      if (ts == l.fields.end() || ts->type != Type::UInt64 || ts->array_length != 0)
        fail(at, "format '" + name + "' has no 'uint64_t timestamp' field (every logged format needs one)");
      s.timestamp_offset = ts->offset;
      for (const auto& f : l.fields)
        if (!f.padding()) s.min_payload = std::max(s.min_payload, f.offset + f.size);
      t.kept = keeps(name);
      if (t.kept) {
        const auto& flat = columns(at, name);
        kept_columns_ += flat.size();
        if (kept_columns_ > kMaxKeptColumns)
          fail(at, "more than " + std::to_string(kMaxKeptColumns) + " value columns in the kept topics");
        t.columns = flat;
        t.values.resize(t.columns.size());
      }
      it = topic_index_.emplace(std::move(key), log_.topics.size()).first;
      log_.topics.push_back(std::move(t));
      states_.push_back(s);
    } else if (log_.topics[it->second].message_size != l.size) {
      fail(at, "topic '" + name + "' multi_id " + std::to_string(multi_id) + " added again with a format of " +
                   std::to_string(l.size) + " bytes (it had " + std::to_string(log_.topics[it->second].message_size) +
                   ")");
    }
    subscribed_[msg_id] = static_cast<std::int32_t>(it->second);
  }

  void remove(std::uint64_t at, const unsigned char* p, std::size_t n) {
    need(at, n, 2, "remove logged message 'R'");
    const auto msg_id = static_cast<std::uint16_t>(load<2>(p));
    if (subscribed_[msg_id] < 0) fail(at, "remove 'R' of msg_id " + std::to_string(msg_id) + ", which is not added");
    subscribed_[msg_id] = -1;
  }

  void data(std::uint64_t at, const unsigned char* p, std::size_t n) {
    need(at, n, 2, "data 'D'");
    const auto msg_id = static_cast<std::uint16_t>(load<2>(p));
    const std::int32_t index = subscribed_[msg_id];
    if (index < 0) fail(at, "data 'D' for msg_id " + std::to_string(msg_id) + ", which no 'A' message added");
    Topic& t = log_.topics[static_cast<std::size_t>(index)];
    const TopicState& s = states_[static_cast<std::size_t>(index)];
    const std::size_t payload = n - 2;
    if (payload < s.min_payload || payload > t.message_size)
      fail(at, "data 'D' of '" + t.name + "' multi_id " + std::to_string(t.multi_id) + " has " +
                   std::to_string(payload) + " bytes; its format needs " +
                   (s.min_payload == t.message_size
                        ? std::to_string(t.message_size)
                        : std::to_string(s.min_payload) + " to " + std::to_string(t.message_size)));
    const unsigned char* d = p + 2;
    const std::uint64_t timestamp = load<8>(d + s.timestamp_offset);
    if (t.count == 0) t.first_timestamp_us = timestamp;
    t.last_timestamp_us = timestamp;
    ++t.count;
    t.data_bytes += payload;
    last_timestamp_ = timestamp;
    if (!t.kept) return;
    t.timestamp_us.push_back(timestamp);
    for (std::size_t c = 0; c < t.columns.size(); ++c)
      t.values[c].push_back(decode(t.columns[c].type, d + t.columns[c].offset));
  }

  struct Key {
    RawField type;
    Type base = Type::UInt8;
  };
  // An info / parameter key "type name" and its value's size check.
  Key key(std::uint64_t at, std::string_view text, std::size_t value_size, const char* what) const {
    const auto space = text.find(' ');
    if (space == 0 || space == std::string_view::npos || space + 1 == text.size())
      fail(at, std::string(what) + ": expected a key 'type name', got " + quoted_excerpt(text));
    Key k;
    k.type = parse_type(at, text.substr(0, space), what, true);
    k.type.name = text.substr(space + 1);
    const auto* b = base_type(k.type.type_name);
    if (!b)
      fail(at, std::string(what) + " '" + k.type.name + "': type " + quoted_excerpt(k.type.type_name) +
                   " is not a base type");
    k.base = b->type;
    const std::size_t expected = b->size * k.type.array_length.value_or(1);
    if (value_size != expected)
      fail(at, std::string(what) + " '" + k.type.name + "': the value has " + std::to_string(value_size) +
                   " bytes, type " + quoted_excerpt(text.substr(0, space)) + " needs " + std::to_string(expected));
    return k;
  }

  // key_len, key, value from `p` (n bytes); the value as text.
  std::pair<Key, std::string> key_value(std::uint64_t at, const unsigned char* p, std::size_t n,
                                        const char* what) const {
    need(at, n, 1, what);
    const std::size_t key_len = p[0];
    if (key_len > n - 1)
      fail(at,
           std::string(what) + ": key of " + std::to_string(key_len) + " bytes, " + std::to_string(n - 1) + " remain");
    const std::string_view key_text(reinterpret_cast<const char*>(p + 1), key_len);
    const unsigned char* value = p + 1 + key_len;
    const std::size_t value_size = n - 1 - key_len;
    Key k = key(at, key_text, value_size, what);
    if (k.base == Type::Char) return {std::move(k), text(value, value_size)};
    std::string out;
    const std::size_t element = base_size(k.base);
    for (std::size_t i = 0; i < value_size; i += element) out += (i ? "," : "") + render(k.base, value + i);
    return {std::move(k), out};
  }

  double number(std::uint64_t at, const Key& k, const unsigned char* p, std::size_t n, const char* what) const {
    if (k.base == Type::Char || k.type.array_length)
      fail(at, std::string(what) + " '" + k.type.name + "': expected a number, the type is " + k.type.type_name +
                   (k.type.array_length ? "[" + std::to_string(*k.type.array_length) + "]" : ""));
    return decode(k.base, p + n - base_size(k.base));
  }

  void info(std::uint64_t at, const unsigned char* p, std::size_t n) {
    auto [k, value] = key_value(at, p, n, "info 'I'");
    log_.info[k.type.name] = std::move(value);
  }

  void info_multiple(std::uint64_t at, const unsigned char* p, std::size_t n) {
    need(at, n, 1, "info multiple 'M'");
    const bool continued = p[0] != 0;
    auto [k, value] = key_value(at, p + 1, n - 1, "info multiple 'M'");
    auto& values = log_.info_multiple[k.type.name];
    if (continued && !values.empty())
      values.back() += value;
    else
      values.push_back(std::move(value));
  }

  void parameter(std::uint64_t at, const unsigned char* p, std::size_t n) {
    const auto [k, text_value] = key_value(at, p, n, "parameter 'P'");
    const double value = number(at, k, p, n, "parameter 'P'");
    if (in_data_)
      log_.parameter_changes.push_back({last_timestamp_, k.type.name, value});
    else
      log_.parameters.push_back({k.type.name, value});
  }

  void default_parameter(std::uint64_t at, const unsigned char* p, std::size_t n) {
    need(at, n, 1, "default parameter 'Q'");
    const auto [k, text_value] = key_value(at, p + 1, n - 1, "default parameter 'Q'");
    log_.default_parameters.push_back({k.type.name, number(at, k, p + 1, n - 1, "default parameter 'Q'"), p[0]});
  }

  Input& in_;
  Log& log_;
  const ReadOptions& options_;
  std::vector<std::uint64_t> ends_;  // end of the log proper, of each appended part
  std::unordered_map<std::string, std::vector<RawField>> formats_;
  std::unordered_map<std::string, Layout> layouts_;
  std::vector<std::string> resolving_;  // formats whose layout is being computed (cycle check)
  std::unordered_map<std::string, std::vector<Column>> flat_;
  std::vector<std::int32_t> subscribed_ = std::vector<std::int32_t>(65536, -1);  // msg_id -> topic index
  std::map<std::pair<std::string, int>, std::size_t> topic_index_;
  std::vector<TopicState> states_;  // parallel to log_.topics
  std::size_t kept_columns_ = 0;
  bool in_data_ = false;
  std::uint64_t last_timestamp_ = 0;
};

Log parse_input(Input& in, const std::string& file, const ReadOptions& options) {
  Log log;
  log.file = file;
  Parser(in, log, options).run();
  return log;
}

}  // namespace

bool has_magic(std::string_view first_bytes) {
  return first_bytes.size() >= kMagicSize && std::memcmp(first_bytes.data(), kMagicBytes, kMagicSize) == 0;
}

bool Topic::has_column(std::string_view column_name) const {
  return std::any_of(columns.begin(), columns.end(), [&](const Column& c) { return c.name == column_name; });
}

const std::vector<double>& Topic::column(std::string_view column_name) const {
  for (std::size_t i = 0; i < columns.size(); ++i)
    if (columns[i].name == column_name) return values[i];
  const std::string field(column_name);
  throw DataError({"", 0, name + "." + field}, kept ? "topic '" + name + "' has no field '" + field + "'"
                                                    : "the values of topic '" + name + "' were not kept (ReadOptions)");
}

const Topic* Log::find(std::string_view name, int multi_id) const {
  for (const auto& t : topics)
    if (t.name == name && t.multi_id == multi_id) return &t;
  return nullptr;
}

std::vector<const Topic*> Log::instances(std::string_view name) const {
  std::vector<const Topic*> out;
  for (const auto& t : topics)
    if (t.name == name) out.push_back(&t);
  std::sort(out.begin(), out.end(), [](const Topic* a, const Topic* b) { return a->multi_id < b->multi_id; });
  return out;
}

Log read(const std::filesystem::path& path, const ReadOptions& options) {
  Input in(path, path.string(), kMaxMessageBytes + kMessageHeaderSize);
  return parse_input(in, path.string(), options);
}

Log parse(std::string_view bytes, const std::string& file, const ReadOptions& options) {
  Input in(bytes, file);
  return parse_input(in, file, options);
}

}  // namespace driftlab::ulog
