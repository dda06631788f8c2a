#include "framework/rawlog.hpp"

#include <dlfcn.h>
#include <zlib.h>

#include <mutex>

#include "framework/error.hpp"
#include "framework/regular_file.hpp"

namespace driftlab::rawlog {
namespace {

using ReadImu = void (*)(const std::filesystem::path&, const LogSelection&, std::vector<std::string>*, TimeSeries*);
using ReadInfo = void (*)(const std::filesystem::path&, Info*);

struct Module {
  ReadImu read_imu = nullptr;
  ReadInfo info = nullptr;
  std::string problem;
};

const Module& module(const std::filesystem::path& path) {
  static std::once_flag once;
  static Module m;
  std::call_once(once, [] {
    Dl_info self{};
    const std::filesystem::path file =
        dladdr(reinterpret_cast<const void*>(&sniff), &self) != 0 && self.dli_fname
            ? std::filesystem::path(self.dli_fname).parent_path() / "libdriftlab_rawlog.so"
            : std::filesystem::path("libdriftlab_rawlog.so");
    if (!DRIFTLAB_HAVE_MRPT) {
      m.problem = "this driftlab was built without MRPT (Debian: libmrpt-obs-dev), which reads rawlogs";
    } else if (void* handle = dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL)) {
      m.read_imu = reinterpret_cast<ReadImu>(dlsym(handle, "driftlab_rawlog_read_imu"));
      m.info = reinterpret_cast<ReadInfo>(dlsym(handle, "driftlab_rawlog_info"));
      if (!m.read_imu || !m.info) m.problem = file.string() + " lacks driftlab_rawlog_read_imu or driftlab_rawlog_info";
    } else {
      const char* error = dlerror();
      m.problem = "cannot load " + file.string() + " (" + (error ? error : "unknown error") +
                  "; it needs MRPT's shared libraries, Debian: libmrpt-obs2.5)";
    }
  });
  if (!m.problem.empty()) throw DataError({path.string(), 0, ""}, "an MRPT rawlog, and " + m.problem);
  return m;
}

bool is_name_char(unsigned char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == ':';
}

}  // namespace

bool sniff(const std::filesystem::path& path) {
  if (!non_regular_kind(path).empty()) return false;
  gzFile in = gzopen(path.c_str(), "rb");
  if (!in) return false;
  unsigned char head[128] = {};
  const int got = gzread(in, head, sizeof head);
  gzclose(in);
  if (got < 2) return false;
  int length = 0, offset = 0;
  if (head[0] > 0x80) {
    length = head[0] & 0x7F;
    offset = 1;
  } else if (got >= 4 && head[0] > 0 && head[1] == 0 && head[2] == 0 && head[3] == 0) {
    length = head[0];
    offset = 4;
  }
  if (length == 0 || got < offset + length) return false;
  const std::string name(reinterpret_cast<const char*>(head + offset), static_cast<std::size_t>(length));
  for (const char c : name)
    if (!is_name_char(static_cast<unsigned char>(c))) return false;
  const std::string bare = name.substr(name.rfind(':') == std::string::npos ? 0 : name.rfind(':') + 1);
  return bare.starts_with("CObservation") || bare == "CSensoryFrame" || bare == "CActionCollection";
}

TimeSeries read_imu(const std::filesystem::path& path, const LogSelection& selection, std::vector<std::string>* notes) {
  TimeSeries record;
  module(path).read_imu(path, selection, notes, &record);
  return record;
}

Info info(const std::filesystem::path& path) {
  Info out;
  module(path).info(path, &out);
  return out;
}

}  // namespace driftlab::rawlog
