#include "framework/output_set.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "framework/error.hpp"
#include "framework/regular_file.hpp"

namespace driftlab {
namespace {

namespace fs = std::filesystem;

// The same file, whether or not it exists yet.
bool same_file(const fs::path& a, const fs::path& b) {
  std::error_code ec1, ec2;
  if (fs::exists(a, ec1) && fs::exists(b, ec2)) return fs::equivalent(a, b, ec1);
  return fs::weakly_canonical(a, ec1) == fs::weakly_canonical(b, ec2);
}

std::string errno_text() { return std::strerror(errno); }

// ConfigError when `path` exists and is not a regular file: a rename would replace it.
void refuse_non_regular(const fs::path& path, const Location& where) {
  const std::string kind = non_regular_kind(path);
  if (!kind.empty())
    throw ConfigError(where, "is " + kind + "; outputs are written only as regular files, choose another path");
}

}  // namespace

OutputSet::OutputSet(std::vector<fs::path> inputs) : inputs_(std::move(inputs)) {}

OutputSet::~OutputSet() {
  if (!committed_) discard();
}

void OutputSet::check_output(const fs::path& path, const Location& where) const {
  for (const auto& e : entries_)
    if (same_file(e.path, path))
      throw ConfigError(where, "the same file is also given as " + (e.option.empty() ? e.path.string() : e.option) +
                                   "; every output needs its own path");
  for (const auto& in : inputs_)
    if (!in.empty() && same_file(path, in))
      throw ConfigError(
          where, "would overwrite the input " + in.string() + "; inputs are never overwritten, choose another path");
  refuse_non_regular(path, where);
}

void OutputSet::plan(const fs::path& path, const std::string& option) {
  if (path.empty()) return;
  const Location where{path.string(), 0, option};
  check_output(path, where);
  for (const auto& r : retired_)
    if (same_file(r, path)) throw ConfigError(where, "is both written and retired by this command");
  if (path.filename().empty() || path.filename() == "." || path.filename() == "..")
    throw ConfigError(where, "expected a file path");
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw ConfigError(where, "output directory " + dir.string() + " does not exist");
  std::string temp = (dir / ("." + path.filename().string() + ".tmp-XXXXXX")).string();
  const int fd = ::mkstemp(temp.data());
  if (fd < 0) throw ConfigError(where, "cannot write to the output directory " + dir.string() + ": " + errno_text());
  ::close(fd);
  entries_.push_back({path, option, temp, false});
}

bool OutputSet::planned(const fs::path& path) const {
  for (const auto& e : entries_)
    if (e.path == path) return true;
  return false;
}

void OutputSet::make_directory(const fs::path& dir, const std::string& option) {
  const Location where{dir.string(), 0, option};
  std::vector<fs::path> missing;  // innermost first
  std::error_code ec;
  for (fs::path p = dir; !p.empty() && !fs::exists(fs::symlink_status(p, ec)); p = p.parent_path()) {
    missing.push_back(p);
    if (p == p.parent_path()) break;
  }
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir))
    throw ConfigError(where, "cannot create the directory" + (ec ? ": " + ec.message() : std::string()));
  created_dirs_.insert(created_dirs_.end(), missing.rbegin(), missing.rend());
}

OutputSet::Entry& OutputSet::entry(const fs::path& path) {
  for (auto& e : entries_)
    if (e.path == path) return e;
  throw std::logic_error("OutputSet: output " + path.string() + " was not planned");
}

void OutputSet::write_with(const fs::path& path,
                           const std::function<void(const std::function<void(std::string_view)>&)>& produce) {
  Entry& e = entry(path);
  const auto fail = [&](const std::string& what) {
    throw Error(Diagnostic{{path.string(), 0, e.option}, "cannot write output: " + what}.to_string());
  };
  const int fd = ::open(e.temp.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
  if (fd < 0) fail(errno_text());
  const auto append = [&](std::string_view content) {
    std::size_t written = 0;
    while (written < content.size()) {
      const auto n = ::write(fd, content.data() + written, content.size() - written);
      if (n < 0) {
        if (errno == EINTR) continue;
        fail(errno_text());  // the handler below closes the file
      }
      written += static_cast<std::size_t>(n);
    }
  };
  try {
    produce(append);
    if (::fsync(fd) != 0) fail(errno_text());
  } catch (...) {
    ::close(fd);
    throw;
  }
  if (::close(fd) != 0) fail(errno_text());
  e.written = true;
}

void OutputSet::write(const fs::path& path, std::string_view content) {
  write_with(path, [&](const auto& append) { append(content); });
}

void OutputSet::write_csv(const fs::path& path, const std::vector<CsvColumn>& columns) {
  write_with(path, [&](const auto& append) { stream_csv(columns, path.string(), append); });
}

void OutputSet::drop(const fs::path& path) {
  Entry& e = entry(path);
  std::remove(e.temp.c_str());
  entries_.erase(entries_.begin() + (&e - entries_.data()));
}

void OutputSet::retire(const fs::path& path, const std::string& option) {
  const Location where{path.string(), 0, option};
  check_output(path, where);
  retired_.push_back(path);
}

void OutputSet::remove_stale_temporaries(const fs::path& path) {
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  const std::string prefix = "." + path.filename().string() + ".tmp-";
  constexpr std::size_t kSuffix = 6;  // mkstemp's XXXXXX
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    const bool stale = name.rfind(prefix, 0) == 0 && (name.size() == prefix.size() + kSuffix ||
                                                      name == name.substr(0, prefix.size() + kSuffix) + ".old");
    if (stale && e.is_regular_file(ec) && !e.is_symlink(ec)) fs::remove(e.path(), ec);
  }
}

fs::path OutputSet::stage_path(const fs::path& path) {
  Entry& e = entry(path);
  e.written = true;
  return e.temp;
}

void OutputSet::commit() {
  for (const auto& e : entries_)
    if (!e.written) throw std::logic_error("OutputSet: output " + e.path.string() + " was planned but not written");
  for (const auto& e : entries_) refuse_non_regular(e.path, {e.path.string(), 0, e.option});  // made since plan()
  for (const auto& e : entries_) ::chmod(e.temp.c_str(), 0644);  // mkstemp made it 0600; staged files too
  // Keep a hard link to every file that will be replaced, so a failed rename can be undone.
  std::vector<std::string> backups(entries_.size());
  std::error_code ec;
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    if (!fs::exists(entries_[i].path, ec)) continue;
    std::string b = entries_[i].temp + ".old";
    if (::link(entries_[i].path.c_str(), b.c_str()) == 0) backups[i] = b;
  }
  std::size_t done = 0;
  std::string failure;
  for (; done < entries_.size(); ++done) {
    if (std::rename(entries_[done].temp.c_str(), entries_[done].path.c_str()) != 0) {
      failure = entries_[done].path.string() + ": cannot write output: " + errno_text();
      break;
    }
  }
  if (failure.empty()) {
    committed_ = true;
    for (const auto& b : backups)
      if (!b.empty()) std::remove(b.c_str());
    for (const auto& r : retired_)
      if (non_regular_kind(r).empty()) std::remove(r.c_str());
    return;
  }
  for (std::size_t i = 0; i < done; ++i) {  // undo: restore or remove what was renamed
    if (!backups[i].empty())
      std::rename(backups[i].c_str(), entries_[i].path.c_str());
    else
      std::remove(entries_[i].path.c_str());
  }
  for (std::size_t i = done; i < entries_.size(); ++i)
    if (!backups[i].empty()) std::remove(backups[i].c_str());
  discard();
  committed_ = true;  // nothing left to clean up
  throw Error(failure + " (no output of this command was written)");
}

void OutputSet::discard() noexcept {
  for (const auto& e : entries_) std::remove(e.temp.c_str());
  std::error_code ec;
  for (auto d = created_dirs_.rbegin(); d != created_dirs_.rend(); ++d) fs::remove(*d, ec);  // only when empty
}

}  // namespace driftlab
