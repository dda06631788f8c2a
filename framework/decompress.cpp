#include "framework/decompress.hpp"

#include <memory>

#if DRIFTLAB_HAVE_ZSTD
#include <zstd.h>
#endif
#if DRIFTLAB_HAVE_LZ4
#include <lz4frame.h>
#endif

namespace driftlab {
namespace {

constexpr std::size_t kStep = std::size_t{1} << 20;  // output grown by at most this much at a time

[[noreturn]] void fail(const Location& where, const std::string& what, const std::string& message) {
  throw DataError(where, what + ": " + message);
}

// Room for the next piece of output: up to kStep more, never beyond expected + 1 (to see an overrun).
std::size_t grow(std::string& out, std::size_t used, std::optional<std::uint64_t> expected) {
  std::size_t size = used + kStep;
  if (expected && *expected + 1 < size) size = static_cast<std::size_t>(*expected + 1);
  if (out.size() < size) out.resize(size);
  return out.size() - used;
}

void check_size(std::size_t used, std::optional<std::uint64_t> expected, const Location& where,
                const std::string& what) {
  if (expected && used != *expected)
    fail(where, what,
         "decompressed to " + std::string(used > *expected ? "more than " : "") + std::to_string(used) +
             " bytes, not the " + std::to_string(*expected) + " its record states");
}

#if DRIFTLAB_HAVE_ZSTD
std::string zstd(std::string_view input, std::optional<std::uint64_t> expected, const Location& where,
                 const std::string& what) {
  // One decompression context per thread, reset for each input: a bag holds thousands of chunks.
  thread_local std::unique_ptr<ZSTD_DStream, decltype(&ZSTD_freeDStream)> stream(ZSTD_createDStream(),
                                                                                 ZSTD_freeDStream);
  if (!stream) fail(where, what, "out of memory for a zstd stream");
  ZSTD_DCtx_reset(stream.get(), ZSTD_reset_session_only);
  ZSTD_inBuffer in{input.data(), input.size(), 0};
  std::string out;
  std::size_t used = 0;
  std::size_t last = 1;
  while (in.pos < in.size || last != 0) {
    const std::size_t room = grow(out, used, expected);
    ZSTD_outBuffer piece{out.data() + used, room, 0};
    last = ZSTD_decompressStream(stream.get(), &piece, &in);
    if (ZSTD_isError(last)) fail(where, what, std::string("corrupt zstd data: ") + ZSTD_getErrorName(last));
    used += piece.pos;
    if (expected && used > *expected) check_size(used, expected, where, what);
    if (piece.pos == 0 && in.pos == in.size && last != 0) fail(where, what, "zstd data ends inside a frame");
  }
  out.resize(used);
  check_size(used, expected, where, what);
  return out;
}
#endif

#if DRIFTLAB_HAVE_LZ4
std::string lz4(std::string_view input, std::optional<std::uint64_t> expected, const Location& where,
                const std::string& what) {
  thread_local std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> context(
      nullptr, LZ4F_freeDecompressionContext);
  if (!context) {
    LZ4F_dctx* raw = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION)))
      fail(where, what, "out of memory for an lz4 context");
    context.reset(raw);
  }
  LZ4F_resetDecompressionContext(context.get());
  std::string out;
  std::size_t used = 0, consumed = 0, hint = 1;
  while (hint != 0) {
    std::size_t room = grow(out, used, expected);
    std::size_t in_size = input.size() - consumed;
    hint = LZ4F_decompress(context.get(), out.data() + used, &room, input.data() + consumed, &in_size, nullptr);
    if (LZ4F_isError(hint)) fail(where, what, std::string("corrupt lz4 data: ") + LZ4F_getErrorName(hint));
    used += room;
    consumed += in_size;
    if (expected && used > *expected) check_size(used, expected, where, what);
    if (hint != 0 && room == 0 && in_size == 0) fail(where, what, "lz4 data ends inside a frame");
  }
  if (consumed != input.size())
    fail(where, what, std::to_string(input.size() - consumed) + " bytes after the lz4 frame");
  out.resize(used);
  check_size(used, expected, where, what);
  return out;
}
#endif

}  // namespace

std::string decompress(std::string_view codec, std::string_view input, std::optional<std::uint64_t> expected_size,
                       const Location& where, const std::string& what) {
  if (codec.empty()) {
    check_size(input.size(), expected_size, where, what);
    return std::string(input);
  }
  if (codec == "zstd") {
#if DRIFTLAB_HAVE_ZSTD
    return zstd(input, expected_size, where, what);
#else
    fail(where, what, "zstd-compressed, and this driftlab was built without libzstd (Debian: libzstd-dev)");
#endif
  }
  if (codec == "lz4") {
#if DRIFTLAB_HAVE_LZ4
    return lz4(input, expected_size, where, what);
#else
    fail(where, what, "lz4-compressed, and this driftlab was built without liblz4 (Debian: liblz4-dev)");
#endif
  }
  fail(where, what, "compression " + quoted_excerpt(codec, 40) + " is not one driftlab reads (zstd, lz4 or none)");
}

}  // namespace driftlab
