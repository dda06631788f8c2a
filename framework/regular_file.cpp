#include "framework/regular_file.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "framework/error.hpp"

namespace driftlab {
namespace {

namespace fs = std::filesystem;

// "" when `path` is a regular file, else why it cannot be read as one.
std::string input_problem(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return "does not exist";
  const std::string kind = non_regular_kind(path);
  return kind.empty() ? "" : "is " + kind + "; expected a regular file";
}

}  // namespace

std::string non_regular_kind(const fs::path& path) {
  std::error_code ec;
  switch (fs::status(path, ec).type()) {
    case fs::file_type::none:  // the status could not be read: opening will say why
    case fs::file_type::not_found:
    case fs::file_type::regular:
      return "";
    case fs::file_type::directory:
      return "a directory";
    case fs::file_type::fifo:
      return "a FIFO (named pipe)";
    case fs::file_type::socket:
      return "a socket";
    case fs::file_type::character:
      return "a character device";
    case fs::file_type::block:
      return "a block device";
    default:
      return "not a regular file";
  }
}

std::uintmax_t check_data_input(const fs::path& path) {
  if (const auto problem = input_problem(path); !problem.empty()) throw DataError({path.string(), 0, ""}, problem);
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  if (ec) throw DataError({path.string(), 0, ""}, "cannot read the file size: " + ec.message());
  return size;
}

bool is_stdin(const fs::path& path) { return path == "-"; }

std::string input_name(const fs::path& path) { return is_stdin(path) ? "<stdin>" : path.string(); }

std::string read_stdin_text(const std::string& what, std::uintmax_t max_bytes) {
  static std::string reader;  // who read it: standard input has one content per process
  const Location where{"<stdin>", 0, ""};
  if (!reader.empty())
    throw ConfigError(where, "standard input is already read as the " + reader + "; only one input can be -, not the " +
                                 what + " too");
  reader = what;
  std::string text;
  char buffer[1 << 16];
  while (true) {
    const std::size_t n = std::fread(buffer, 1, sizeof buffer, stdin);
    text.append(buffer, n);
    if (text.size() > max_bytes)
      throw ConfigError(where, "the " + what + " on standard input has more than " + std::to_string(max_bytes) +
                                   " bytes; expected at most that (reading stopped there)");
    if (n < sizeof buffer) break;
  }
  if (std::ferror(stdin))
    throw ConfigError(where, "cannot read the " + what + " from standard input: " + std::strerror(errno));
  return text;
}

std::string read_config_text(const fs::path& path, const std::string& what) {
  if (is_stdin(path)) return read_stdin_text(what, kMaxTextInputBytes);
  const Location where{path.string(), 0, ""};
  if (const auto problem = input_problem(path); !problem.empty())
    throw ConfigError(where, "cannot read the " + what + ": it " + problem);
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  if (ec) throw ConfigError(where, "cannot read the " + what + ": " + ec.message());
  if (size > kMaxTextInputBytes)
    throw ConfigError(where, "the " + what + " has " + std::to_string(size) + " bytes; expected at most " +
                                 std::to_string(kMaxTextInputBytes >> 20) + " MiB");
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw ConfigError(where, "cannot open the " + what + ": " + std::strerror(errno));
  // Read at most one byte past the stated size: a file that grows meanwhile is still bounded.
  std::string text(static_cast<std::size_t>(size) + 1, '\0');
  const std::size_t n = std::fread(text.data(), 1, text.size(), f.get());
  if (std::ferror(f.get())) throw ConfigError(where, "cannot read the " + what + ": " + std::strerror(errno));
  if (n > size) throw ConfigError(where, "the " + what + " grew while it was read");
  text.resize(n);
  return text;
}

}  // namespace driftlab
