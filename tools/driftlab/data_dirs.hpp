// Where the commands find the bundled data files named on the command line:
//   device files (`devices`, `simulate`, `discrepancy`, `nav`): --devices-dir, else
//     $DRIFTLAB_DEVICES_DIR, else an installed driftlab's share/driftlab/devices (cli.hpp
//     installed_data_dir), else the source tree's devices/ (compile definition DRIFTLAB_DEVICES_DIR);
//   pipelines (`run`, `compare`, `calibrate --paper-pipeline`): an installed driftlab's
//     share/driftlab/pipelines, else the source tree's models/pipelines/ (DRIFTLAB_PIPELINES_DIR).
#pragma once

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "devices/device_file.hpp"
#include "framework/error.hpp"
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

inline std::filesystem::path pipelines_dir() {
  if (const auto installed = installed_data_dir() / "pipelines"; std::filesystem::is_directory(installed))
    return installed;
  return DRIFTLAB_PIPELINES_DIR;
}

// A pipeline argument is a file path, or the name of a bundled pipeline ("li2023", with or without
// ".yaml"). Throws ConfigError at `option` naming the bundled pipelines when it is neither.
inline std::filesystem::path resolve_pipeline_file(const std::string& argument, const std::string& option) {
  const std::filesystem::path path(argument);
  if (std::filesystem::exists(path)) return path;
  const auto dir = pipelines_dir();
  if (!path.has_parent_path()) {
    const auto bundled = dir / (path.extension() == ".yaml" ? argument : argument + ".yaml");
    if (std::filesystem::is_regular_file(bundled)) return bundled;
  }
  std::vector<std::string> names;
  if (std::filesystem::is_directory(dir))
    for (const auto& entry : std::filesystem::directory_iterator(dir))
      if (entry.path().extension() == ".yaml") names.push_back(entry.path().stem().string());
  std::sort(names.begin(), names.end());
  std::string listed;
  for (const auto& n : names) listed += (listed.empty() ? "" : ", ") + n;
  throw ConfigError({argument, 0, option}, "no such file, and no bundled pipeline of that name (bundled, in " +
                                               dir.lexically_normal().string() + ": " +
                                               (listed.empty() ? "none" : listed) + ")");
}

}  // namespace driftlab::cli
