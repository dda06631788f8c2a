// Inputs and outputs are regular files (issue 28): a FIFO with no writer would block a reader
// forever, /dev/zero would feed it without end, and a rename onto a device node replaces the node.
// The checks here run before anything is opened; symbolic links are followed (a link to a FIFO is a
// FIFO). Every reader of a file path and OutputSet (every writer) use them.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace driftlab {

// Size limit of the small text formats read whole into memory (pipeline, device file, profile,
// calibration model JSON, nav scenario): 64 MiB, far above any real one.
inline constexpr std::uintmax_t kMaxTextInputBytes = std::uintmax_t{64} << 20;

// What `path` is when it exists and is not a regular file: "a directory", "a FIFO (named pipe)",
// "a socket", "a character device", "a block device", "not a regular file"; empty when it is a
// regular file or does not exist.
std::string non_regular_kind(const std::filesystem::path& path);

// A data input (CSV, logs, rawlogs): its size in bytes when it is a regular file; DataError (exit 3)
// naming the file and what it is otherwise ("does not exist", "is a FIFO (named pipe); expected a
// regular file").
std::uintmax_t check_data_input(const std::filesystem::path& path);

// "-" names standard input, explicitly, where a reader accepts it (issue 28): read_config_text (model
// JSON, pipeline, device file, profile, nav scenario) and the CSV reader's read_text_file. Standard
// input is read once per process, bounded like a file; a second reader of "-" in the same command is
// a ConfigError ("standard input is already read as the ...").
bool is_stdin(const std::filesystem::path& path);
// How messages name an input: "<stdin>" for "-", the path otherwise.
std::string input_name(const std::filesystem::path& path);
// The whole of standard input for `what` ("pipeline file"), at most `max_bytes`; ConfigError naming
// <stdin> when it is longer (reading stops one byte past the cap), unreadable, or already read.
std::string read_stdin_text(const std::string& what, std::uintmax_t max_bytes);

// The whole text of a small configuration file; `what` names the format in messages ("pipeline
// file"). ConfigError (exit 2) naming the file when it is missing, not a regular file, larger than
// kMaxTextInputBytes or unreadable. "-" reads standard input, with the same cap.
std::string read_config_text(const std::filesystem::path& path, const std::string& what);

}  // namespace driftlab
