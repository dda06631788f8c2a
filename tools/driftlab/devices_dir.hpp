// Where `driftlab devices` and `driftlab simulate` find device files: --devices-dir, else
// $DRIFTLAB_DEVICES_DIR, else the source tree's devices/ (compile definition DRIFTLAB_DEVICES_DIR).
#pragma once

#include <cstdlib>
#include <filesystem>
#include <string>

namespace driftlab::cli {

inline std::filesystem::path resolve_devices_dir(const std::string& option) {
  if (!option.empty()) return option;
  if (const char* env = std::getenv("DRIFTLAB_DEVICES_DIR"); env && *env) return env;
  return DRIFTLAB_DEVICES_DIR;
}

// A device argument is a file path, or the name of a file in the devices directory ("fmvmg").
inline std::filesystem::path resolve_device_file(const std::string& argument, const std::string& devices_dir_option) {
  const std::filesystem::path path(argument);
  if (std::filesystem::exists(path)) return path;
  const std::string file_name = path.filename().string();
  const auto in_dir = resolve_devices_dir(devices_dir_option) /
                      (path.extension() == ".yaml" ? file_name : file_name + ".yaml");
  return std::filesystem::exists(in_dir) ? in_dir : path;
}

}  // namespace driftlab::cli
