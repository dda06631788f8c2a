// Reading binary logs forward, in blocks: the byte source and the little-endian loads the PX4 ULog
// (framework/ulog.hpp) and ArduPilot DataFlash (framework/dataflash.hpp) parsers share.
//
// Contract. Input reads a file in blocks of 1 MiB (never the whole file) or walks bytes already in
// memory, forward only. A caller asks for at most `max_take` bytes at a time (one message of its
// format) and has checked that they remain (size() - offset()); Input itself only checks that the
// file did not shrink while being read (DataError naming the file and byte offset). Memory held:
// one block plus max_take bytes.
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace driftlab::binary {

// Little-endian load of N bytes, independent of the host's byte order.
template <std::size_t N>
std::uint64_t load(const unsigned char* p) {
  std::uint64_t v = 0;
  for (std::size_t i = N; i-- > 0;) v = (v << 8) | p[i];
  return v;
}

// IEEE-754 binary32 / binary64, little endian.
inline float load_float(const unsigned char* p) {
  const auto bits = static_cast<std::uint32_t>(load<4>(p));
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}
inline double load_double(const unsigned char* p) {
  const auto bits = load<8>(p);
  double d;
  std::memcpy(&d, &bits, sizeof d);
  return d;
}

// The file or the memory being parsed, read forward.
class Input {
 public:
  // Bytes in memory; `file` names them in errors.
  Input(std::string_view memory, std::string file);
  // A file: DataError when it is missing, not a regular file (check_data_input) or cannot be opened.
  Input(const std::filesystem::path& path, std::string file, std::size_t max_take);
  ~Input();
  Input(const Input&) = delete;
  Input& operator=(const Input&) = delete;

  std::uint64_t size() const { return size_; }
  std::uint64_t offset() const { return offset_; }

  // The next n bytes without moving on; n <= max_take and n <= size() - offset().
  const unsigned char* peek(std::size_t n);
  void advance(std::size_t n) {
    if (file_) begin_ += n;
    offset_ += n;
  }
  // peek(n), then advance(n).
  const unsigned char* take(std::size_t n) {
    const unsigned char* p = peek(n);
    advance(n);
    return p;
  }
  // Moves forward to `target` (offset() <= target <= size()).
  void seek(std::uint64_t target);

 private:
  void refill(std::size_t n);

  std::string_view memory_;
  std::string file_name_;
  std::FILE* file_ = nullptr;
  std::uint64_t size_ = 0, offset_ = 0;
  std::vector<unsigned char> block_;
  std::size_t begin_ = 0, end_ = 0;  // buffered bytes: file [offset_, offset_ + end_ - begin_)
};

}  // namespace driftlab::binary
