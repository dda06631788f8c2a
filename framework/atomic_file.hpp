// Output files are written to a temporary file in the target directory and renamed into place,
// so a reader never sees a half-written file and a failed run never destroys an earlier output.
#pragma once

#include <filesystem>
#include <string_view>
#include <vector>

namespace driftlab {

// Writes `content` to `path` atomically: an OutputSet of one file (output_set.hpp). A missing or
// unwritable directory is a ConfigError, a failed write an Error; the temporary file is removed.
void write_file_atomically(const std::filesystem::path& path, std::string_view content);

// Throws ConfigError when `output` is (or resolves to the same file as) one of `inputs`.
void ensure_not_an_input(const std::filesystem::path& output, const std::vector<std::filesystem::path>& inputs);

}  // namespace driftlab
