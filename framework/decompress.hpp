// Decompression of the compressed blocks bags hold: MCAP chunks ("zstd", "lz4": the LZ4 frame
// format) and rosbag2 messages of a bag recorded with compression_mode MESSAGE (zstd). Through
// Debian's libzstd / liblz4 when driftlab was built with them (CMake reports it); without, asking
// for that codec is a DataError naming the package.
//
// Contract: the output grows only as the decompressor produces it (a hostile size field never
// allocates by itself) and must come to exactly `expected_size` bytes when that is given: more, less,
// a corrupt frame or an unknown codec is a DataError at `where` with `what` in its message.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "framework/error.hpp"

namespace driftlab {

// "" (none, the input returned as is), "zstd", "lz4".
std::string decompress(std::string_view codec, std::string_view input, std::optional<std::uint64_t> expected_size,
                       const Location& where, const std::string& what);

}  // namespace driftlab
