// ROS 1 bags are read by the module libdriftlab_ros1bag.so (framework/rosbag_ros1.cpp, linked to
// librosbag-storage), loaded from the framework library's directory the first time a ROS 1 bag is
// read: librosbag-storage brings libroslib, librospack and libpython, which every other command
// should not load at start (DESIGN.md section 8, optional heavy parts load only when used).
#include <dlfcn.h>

#include <mutex>

#include "framework/error.hpp"
#include "framework/rosbag_containers.hpp"

namespace driftlab::rosbag::detail {
namespace {

using ReadRos1 = void (*)(const std::filesystem::path&, const Wanted&, const Visitor&, Bag&);

std::filesystem::path module_path() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<const void*>(&read_ros1), &info) == 0 || !info.dli_fname) return "libdriftlab_ros1bag.so";
  return std::filesystem::path(info.dli_fname).parent_path() / "libdriftlab_ros1bag.so";
}

}  // namespace

void read_ros1(const std::filesystem::path& path, const Wanted& wanted, const Visitor& visit, Bag& bag) {
  static std::once_flag once;
  static ReadRos1 reader = nullptr;
  static std::string problem;
  std::call_once(once, [] {
    const auto module = module_path();
    if (!DRIFTLAB_HAVE_ROSBAG1) {
      problem = "this driftlab was built without librosbag-storage (Debian: librosbag-storage-dev)";
    } else if (void* handle = dlopen(module.c_str(), RTLD_NOW | RTLD_LOCAL)) {
      reader = reinterpret_cast<ReadRos1>(dlsym(handle, "driftlab_read_ros1"));
      if (!reader) problem = module.string() + " lacks driftlab_read_ros1";
    } else {
      const char* error = dlerror();
      problem = "cannot load " + module.string() + " (" + (error ? error : "unknown error") +
                "; it needs librosbag-storage, Debian: librosbag-storage4d)";
    }
  });
  if (!reader) throw DataError({path.string(), 0, ""}, "a ROS 1 bag, and " + problem);
  reader(path, wanted, visit, bag);
}

}  // namespace driftlab::rosbag::detail
