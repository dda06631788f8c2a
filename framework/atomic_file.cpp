#include "framework/atomic_file.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "framework/error.hpp"

namespace driftlab {

void write_file_atomically(const std::filesystem::path& path, std::string_view content) {
  const auto fail = [&](const std::string& what) {
    throw DataError({path.string(), 0, ""}, "cannot write output: " + what);
  };
  const auto dir = path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) fail("directory " + dir.string() + " does not exist");
  std::string tmpl = (dir / ("." + path.filename().string() + ".tmp-XXXXXX")).string();
  const int fd = mkstemp(tmpl.data());
  if (fd < 0) fail(std::strerror(errno));
  std::size_t written = 0;
  while (written < content.size()) {
    const auto n = ::write(fd, content.data() + written, content.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string err = std::strerror(errno);
      ::close(fd);
      std::remove(tmpl.c_str());
      fail(err);
    }
    written += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const std::string err = std::strerror(errno);
    std::remove(tmpl.c_str());
    fail(err);
  }
  ::chmod(tmpl.c_str(), 0644);
  if (std::rename(tmpl.c_str(), path.c_str()) != 0) {
    const std::string err = std::strerror(errno);
    std::remove(tmpl.c_str());
    fail(err);
  }
}

void ensure_not_an_input(const std::filesystem::path& output, const std::vector<std::filesystem::path>& inputs) {
  std::error_code ec;
  for (const auto& in : inputs) {
    const bool same = std::filesystem::exists(output, ec) && std::filesystem::exists(in, ec)
                          ? std::filesystem::equivalent(output, in, ec)
                          : std::filesystem::weakly_canonical(output, ec) == std::filesystem::weakly_canonical(in, ec);
    if (same)
      throw ConfigError({output.string(), 0, ""}, "output would overwrite the input " + in.string() +
                                                      "; inputs are never overwritten, choose another path");
  }
}

}  // namespace driftlab
