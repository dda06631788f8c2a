// Output files are written to a temporary file in the target directory and renamed into place,
// so a reader never sees a half-written file and a failed run never destroys an earlier output.
#pragma once

#include <filesystem>
#include <string_view>

namespace driftlab {

// Writes `content` to `path` atomically: an OutputSet of one file (output_set.hpp). A missing or
// unwritable directory, or a path that exists and is not a regular file, is a ConfigError, a failed
// write an Error; the temporary file is removed.
void write_file_atomically(const std::filesystem::path& path, std::string_view content);

}  // namespace driftlab
