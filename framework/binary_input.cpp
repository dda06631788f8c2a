#include "framework/binary_input.hpp"

#include <algorithm>
#include <system_error>

#include "framework/error.hpp"
#include "framework/regular_file.hpp"

namespace driftlab::binary {
namespace {

constexpr std::size_t kBlockSize = std::size_t{1} << 20;

}  // namespace

Input::Input(std::string_view memory, std::string file)
    : memory_(memory), file_name_(std::move(file)), size_(memory.size()) {}

Input::Input(const std::filesystem::path& path, std::string file, std::size_t max_take) : file_name_(std::move(file)) {
  size_ = check_data_input(path);
  file_ = std::fopen(path.c_str(), "rb");
  if (!file_) throw DataError({file_name_, 0, ""}, "cannot open the file");
  block_.resize(kBlockSize + max_take);
}

Input::~Input() {
  if (file_) std::fclose(file_);
}

const unsigned char* Input::peek(std::size_t n) {
  if (!file_) return reinterpret_cast<const unsigned char*>(memory_.data()) + offset_;
  if (end_ - begin_ < n) refill(n);
  return block_.data() + begin_;
}

void Input::seek(std::uint64_t target) {
  if (file_) {
    if (target - offset_ <= end_ - begin_) {
      begin_ += static_cast<std::size_t>(target - offset_);
    } else {
      if (::fseeko(file_, static_cast<off_t>(target), SEEK_SET) != 0)
        throw DataError({file_name_, 0, "byte " + std::to_string(target)}, "cannot seek to this offset");
      begin_ = end_ = 0;
    }
  }
  offset_ = target;
}

void Input::refill(std::size_t n) {
  const std::size_t have = end_ - begin_;
  std::memmove(block_.data(), block_.data() + begin_, have);
  begin_ = 0;
  end_ = have;
  const std::uint64_t left_in_file = size_ - (offset_ + have);
  const auto want = static_cast<std::size_t>(std::min<std::uint64_t>(block_.size() - have, left_in_file));
  const std::size_t got = std::fread(block_.data() + have, 1, want, file_);
  end_ += got;
  if (end_ < n)
    throw DataError({file_name_, 0, "byte " + std::to_string(offset_ + end_)},
                    "the file ended before its size said (was it changed while being read?)");
}

}  // namespace driftlab::binary
