#include "framework/mcap.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>

#include <zlib.h>

#include "framework/decompress.hpp"
#include "framework/error.hpp"

namespace driftlab::mcap {
namespace {

constexpr unsigned char kMagic[kMagicSize] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
constexpr std::size_t kOpeningSize = 9;         // opcode + uint64 length
constexpr std::size_t kFooterSize = 8 + 8 + 4;  // summary_start, summary_offset_start, summary_crc
constexpr std::size_t kBlockSize = std::size_t{1} << 20;

enum Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kStatistics = 0x0B,
  kDataEnd = 0x0F,
};

std::uint32_t crc32(std::string_view bytes) {
  uLong crc = ::crc32(0L, Z_NULL, 0);
  for (std::size_t at = 0; at < bytes.size();) {  // zlib takes uInt lengths
    const auto n = static_cast<uInt>(std::min<std::size_t>(bytes.size() - at, std::size_t{1} << 30));
    crc = ::crc32(crc, reinterpret_cast<const Bytef*>(bytes.data() + at), n);
    at += n;
  }
  return static_cast<std::uint32_t>(crc);
}

std::string hex(unsigned value) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%02x", value);
  return buf;
}

// Little-endian fields of one record's content, each read checked against what remains.
class Fields {
 public:
  Fields(std::string_view data, const std::string& file, Place place, const char* what = "")
      : data_(data), file_(file), place_(place), what_(what) {}

  std::uint8_t u8() { return static_cast<std::uint8_t>(load(1, "uint8")); }
  std::uint16_t u16() { return static_cast<std::uint16_t>(load(2, "uint16")); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(load(4, "uint32")); }
  std::uint64_t u64() { return load(8, "uint64"); }
  std::string_view bytes(std::uint64_t length, const char* what) {
    if (length > data_.size() - pos_)
      fail(std::string(what) + " of " + std::to_string(length) + " bytes, but " + std::to_string(data_.size() - pos_) +
           " remain in the record");
    const auto out = data_.substr(pos_, static_cast<std::size_t>(length));
    pos_ += static_cast<std::size_t>(length);
    return out;
  }
  std::string string(const char* what) { return std::string(bytes(u32(), what)); }
  std::string_view rest() { return bytes(data_.size() - pos_, "data"); }
  std::size_t remaining() const { return data_.size() - pos_; }

  [[noreturn]] void fail(const std::string& message) const {
    throw DataError({file_, 0, ""}, place_.text() + (*what_ ? std::string(" (") + what_ + ")" : "") + ": " + message);
  }
  const Place& place() const { return place_; }

 private:
  std::uint64_t load(std::size_t size, const char* what) {
    if (data_.size() - pos_ < size)
      fail(std::string("a ") + what + " field needs " + std::to_string(size) + " bytes, " +
           std::to_string(data_.size() - pos_) + " remain in the record");
    std::uint64_t v = 0;
    for (std::size_t i = size; i-- > 0;) v = (v << 8) | static_cast<unsigned char>(data_[pos_ + i]);
    pos_ += size;
    return v;
  }

  std::string_view data_;
  const std::string& file_;
  Place place_;
  const char* what_;
  std::size_t pos_ = 0;
};

// The file or the memory being parsed: views of byte ranges, read in blocks.
class Input {
 public:
  Input(std::string_view memory, std::string file)
      : memory_(memory), file_name_(std::move(file)), size_(memory.size()) {}
  Input(const std::filesystem::path& path, std::string file) : file_name_(std::move(file)) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
      throw DataError({file_name_, 0, ""}, "not a readable file (missing, or a directory)");
    size_ = std::filesystem::file_size(path, ec);
    if (ec) throw DataError({file_name_, 0, ""}, "cannot read the file size: " + ec.message());
    file_.reset(std::fopen(path.c_str(), "rb"));
    if (!file_) throw DataError({file_name_, 0, ""}, "cannot open the file");
  }

  std::uint64_t size() const { return size_; }
  const std::string& name() const { return file_name_; }

  // Bytes [offset, offset + n), which the caller has checked lie in the file.
  std::string_view view(std::uint64_t offset, std::size_t n) {
    if (!file_) return memory_.substr(static_cast<std::size_t>(offset), n);
    if (offset < block_start_ || offset + n > block_start_ + block_.size()) {
      const auto want = static_cast<std::size_t>(std::min<std::uint64_t>(std::max(n, kBlockSize), size_ - offset));
      block_.resize(want);
      if (std::fseek(file_.get(), static_cast<long>(offset), SEEK_SET) != 0 ||
          std::fread(block_.data(), 1, want, file_.get()) != want)
        throw DataError({file_name_, 0, ""}, "byte " + std::to_string(offset) + ": read error");
      block_start_ = offset;
    }
    return std::string_view(block_).substr(static_cast<std::size_t>(offset - block_start_), n);
  }

 private:
  struct Close {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  std::string_view memory_;
  std::string file_name_;
  std::uint64_t size_ = 0;
  std::unique_ptr<std::FILE, Close> file_;
  std::string block_;
  std::uint64_t block_start_ = 0;
};

class Parser {
 public:
  Parser(Input& in, const Wanted& wanted, const Visitor& visit) : in_(in), wanted_channel_(wanted), visit_(visit) {
    file_.file = in.name();
    file_.file_size = in.size();
  }

  File run() {
    if (in_.size() < kMagicSize || !has_magic(in_.view(0, kMagicSize)))
      throw DataError({file_.file, 0, ""}, "not an MCAP file (it does not start with 0x89 'MCAP0' '\\r\\n')");
    std::uint64_t pos = kMagicSize;
    bool footer = false;
    while (!footer) {
      const Place place{Place::kNoChunk, pos};
      if (in_.size() - pos < kOpeningSize)
        throw DataError({file_.file, 0, ""},
                        place.text() + ": the file ends " +
                            (pos == in_.size() ? std::string("without a footer") : "inside a record's opening") +
                            " (truncated: the writer did not finish it)");
      Fields opening(in_.view(pos, kOpeningSize), file_.file, place);
      const std::uint8_t opcode = opening.u8();
      const std::uint64_t length = opening.u64();
      if (length > in_.size() - pos - kOpeningSize)
        opening.fail("a record of " + std::to_string(length) + " bytes, but " +
                     std::to_string(in_.size() - pos - kOpeningSize) + " remain in the file (truncated?)");
      if (pos == kMagicSize && opcode != kHeader) opening.fail("the first record is not a Header (opcode 0x01)");
      const std::uint64_t content = pos + kOpeningSize;
      const auto view = [&] { return in_.view(content, static_cast<std::size_t>(length)); };
      switch (opcode) {
        case kHeader: {
          Fields f(view(), file_.file, place, "Header");
          file_.profile = f.string("profile");
          file_.library = f.string("library");
          break;
        }
        case kSchema:
        case kChannel:
        case kMessage:
        case kStatistics: {
          Fields f(view(), file_.file, place);
          record(opcode, f);
          break;
        }
        case kChunk:
          chunk(view(), place);
          break;
        case kFooter: {
          Fields f(view(), file_.file, place, "Footer");
          if (length != kFooterSize)
            f.fail("a Footer of " + std::to_string(length) + " bytes, not " + std::to_string(kFooterSize));
          file_.has_summary = f.u64() != 0;
          if (in_.size() - content - length != kMagicSize || !has_magic(in_.view(content + length, kMagicSize)))
            f.fail("the Footer is not followed by the closing magic and the end of the file");
          footer = true;
          break;
        }
        default:
          break;  // indexes, attachments, metadata, summary offsets, data end, reserved
      }
      pos = content + length;
    }
    check_statistics();
    return std::move(file_);
  }

 private:
  void record(std::uint8_t opcode, Fields& f) {
    switch (opcode) {
      case kSchema:
        schema(f);
        break;
      case kChannel:
        channel(f);
        break;
      case kMessage:
        message(f);
        break;
      case kStatistics:
        statistics(f);
        break;
      default:
        f.fail("opcode " + hex(opcode) + " inside a chunk (only Schema, Channel and Message belong there)");
    }
  }

  void schema(Fields& f) {
    Schema s;
    s.id = f.u16();
    s.name = f.string("schema name");
    s.encoding = f.string("schema encoding");
    f.bytes(f.u32(), "schema data");
    if (s.id == 0) f.fail("schema id 0 is reserved (\"no schema\")");
    if (const Schema* known = file_.find_schema(s.id)) {
      if (known->name != s.name || known->encoding != s.encoding)
        f.fail("schema id " + std::to_string(s.id) + " redefined ('" + known->name + "', now " +
               quoted_excerpt(s.name) + ")");
      return;
    }
    file_.schemas.push_back(std::move(s));
  }

  void channel(Fields& f) {
    Channel c;
    c.id = f.u16();
    c.schema_id = f.u16();
    c.topic = f.string("topic");
    c.message_encoding = f.string("message encoding");
    Fields map(f.bytes(f.u32(), "metadata"), file_.file, f.place(), "channel metadata");
    while (map.remaining() > 0) {
      std::string key = map.string("metadata key");
      c.metadata[std::move(key)] = map.string("metadata value");
    }
    const Schema* schema = c.schema_id ? file_.find_schema(c.schema_id) : nullptr;
    if (c.schema_id && !schema)
      f.fail("channel " + std::to_string(c.id) + " names schema " + std::to_string(c.schema_id) +
             ", not defined before it");
    if (const int known = channel_index(c.id); known >= 0) {
      const Channel& k = file_.channels[static_cast<std::size_t>(known)];
      if (k.topic != c.topic || k.schema_id != c.schema_id || k.message_encoding != c.message_encoding)
        f.fail("channel id " + std::to_string(c.id) + " redefined ('" + k.topic + "', now " + quoted_excerpt(c.topic) +
               ")");
      return;
    }
    if (channel_index_.size() <= c.id) channel_index_.resize(std::size_t{c.id} + 1, -1);
    channel_index_[c.id] = static_cast<int>(file_.channels.size());
    wanted_.push_back(wanted_channel_ && wanted_channel_(c, schema));
    file_.channels.push_back(std::move(c));
  }

  void message(Fields& f) {
    Message m;
    const std::uint16_t id = f.u16();
    m.sequence = f.u32();
    m.log_time = f.u64();
    m.publish_time = f.u64();
    m.data = f.rest();
    const int index = channel_index(id);
    if (index < 0) f.fail("a message of channel " + std::to_string(id) + ", which no Channel record defined before it");
    Channel& c = file_.channels[static_cast<std::size_t>(index)];
    if (c.count == 0) {
      c.first_log_time = c.min_log_time = c.max_log_time = m.log_time;
    } else {
      c.min_log_time = std::min(c.min_log_time, m.log_time);
      c.max_log_time = std::max(c.max_log_time, m.log_time);
    }
    c.last_log_time = m.log_time;
    ++c.count;
    ++file_.messages;
    if (wanted_[static_cast<std::size_t>(index)] && visit_) {
      m.channel = &c;
      m.place = f.place();
      visit_(m);
    }
  }

  void statistics(Fields& f) {
    file_.has_statistics = true;
    statistics_messages_ = f.u64();
    f.u16();                              // schema_count
    for (int i = 0; i < 4; ++i) f.u32();  // channel, attachment, metadata, chunk counts
    f.u64();                              // message_start_time
    f.u64();                              // message_end_time
    Fields map(f.bytes(f.u32(), "channel message counts"), file_.file, f.place(), "Statistics");
    while (map.remaining() > 0) {
      const std::uint16_t id = map.u16();
      statistics_counts_.emplace_back(id, map.u64());
    }
  }

  void check_statistics() const {
    if (!file_.has_statistics) return;
    const auto fail = [&](const std::string& message) {
      throw DataError({file_.file, 0, ""},
                      "the summary's Statistics " + message + " (the summary or the data is corrupt)");
    };
    if (statistics_messages_ != file_.messages)
      fail("count " + std::to_string(statistics_messages_) + " messages; the data section holds " +
           std::to_string(file_.messages));
    for (const auto& [id, count] : statistics_counts_) {
      const int index = channel_index(id);
      const std::uint64_t have = index < 0 ? 0 : file_.channels[static_cast<std::size_t>(index)].count;
      if (have != count)
        fail("count " + std::to_string(count) + " messages on channel " + std::to_string(id) +
             "; the data section holds " + std::to_string(have));
    }
  }

  void chunk(std::string_view content, const Place& place) {
    Fields f(content, file_.file, place, "Chunk");
    f.u64();  // message_start_time
    f.u64();  // message_end_time
    const std::uint64_t uncompressed_size = f.u64();
    const std::uint32_t crc = f.u32();
    const std::string compression = f.string("compression");
    const std::string_view compressed = f.bytes(f.u64(), "chunk records");
    const std::string records =
        decompress(compression, compressed, uncompressed_size, {file_.file, 0, ""}, place.text() + " (Chunk)");
    if (crc != 0 && crc32(records) != crc) f.fail("the CRC-32 of its records differs from the one it states (corrupt)");
    ++file_.chunks;
    ++file_.chunk_compression[compression];
    file_.compressed_bytes += compressed.size();
    file_.uncompressed_bytes += records.size();
    const std::string_view all(records);
    std::size_t pos = 0;
    while (pos < all.size()) {
      const Place inner{place.record, pos};
      Fields opening(all.substr(pos, std::min(kOpeningSize, all.size() - pos)), file_.file, inner);
      const std::uint8_t opcode = opening.u8();
      const std::uint64_t length = opening.u64();
      if (length > all.size() - pos - kOpeningSize)
        opening.fail("a record of " + std::to_string(length) + " bytes, but " +
                     std::to_string(all.size() - pos - kOpeningSize) + " remain in the chunk");
      if (opcode == kStatistics) opening.fail("a Statistics record inside a chunk");
      Fields fields(all.substr(pos + kOpeningSize, static_cast<std::size_t>(length)), file_.file, inner);
      record(opcode, fields);
      pos += kOpeningSize + static_cast<std::size_t>(length);
    }
  }

  // Index into file_.channels of a channel id, -1 when not defined.
  int channel_index(std::uint16_t id) const { return id < channel_index_.size() ? channel_index_[id] : -1; }

  Input& in_;
  const Wanted& wanted_channel_;
  const Visitor& visit_;
  File file_;
  std::vector<int> channel_index_;  // by channel id, grown to the largest id defined
  std::vector<bool> wanted_;        // by index into file_.channels
  std::uint64_t statistics_messages_ = 0;
  std::vector<std::pair<std::uint16_t, std::uint64_t>> statistics_counts_;
};

}  // namespace

std::string Place::text() const {
  if (chunk == kNoChunk) return "byte " + std::to_string(record);
  return "chunk at byte " + std::to_string(chunk) + ", record at byte " + std::to_string(record) + " of its records";
}

bool has_magic(std::string_view first_bytes) {
  return first_bytes.size() >= kMagicSize && std::memcmp(first_bytes.data(), kMagic, kMagicSize) == 0;
}

const Schema* File::find_schema(std::uint16_t id) const {
  for (const auto& s : schemas)
    if (s.id == id) return &s;
  return nullptr;
}

File read(const std::filesystem::path& path, const Wanted& wanted, const Visitor& visit) {
  Input in(path, path.string());
  return Parser(in, wanted, visit).run();
}

File parse(std::string_view bytes, const std::string& file, const Wanted& wanted, const Visitor& visit) {
  Input in(bytes, file);
  return Parser(in, wanted, visit).run();
}

}  // namespace driftlab::mcap
