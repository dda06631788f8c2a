// Where `driftlab devices` and `driftlab simulate` find device files: --devices-dir, else
// $DRIFTLAB_DEVICES_DIR, else an installed driftlab's share/driftlab/devices (cli.hpp
// installed_data_dir), else the source tree's devices/ (compile definition DRIFTLAB_DEVICES_DIR).
#pragma once

#include <cstdlib>
#include <filesystem>
#include <string>

#include "devices/device_file.hpp"
#include "tools/driftlab/cli.hpp"

namespace driftlab::cli {

inline std::filesystem::path resolve_devices_dir(const std::string& option) {
  if (!option.empty()) return option;
  if (const char* env = std::getenv("DRIFTLAB_DEVICES_DIR"); env && *env) return env;
  if (const auto installed = installed_data_dir() / "devices"; std::filesystem::is_directory(installed))
    return installed;
  return DRIFTLAB_DEVICES_DIR;
}

// A device argument is a file path, or the name of a file in the devices directory ("fmvmg").
inline std::filesystem::path resolve_device_file(const std::string& argument, const std::string& devices_dir_option) {
  return devices::find_device_file(argument, resolve_devices_dir(devices_dir_option));
}

}  // namespace driftlab::cli
