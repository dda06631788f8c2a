// The per-container readers behind rosbag::read (framework/rosbag.hpp), each in its own source so
// that a container whose library is missing compiles to a reader that says so. Each fills `bag`
// (container, bytes, files, topics in any order) and visits the messages of the wanted topics.
#pragma once

#include <filesystem>

#include "framework/rosbag.hpp"

namespace driftlab::rosbag::detail {

void read_ros1(const std::filesystem::path& path, const Wanted& wanted, const Visitor& visit, Bag& bag);
void read_sqlite3(const std::filesystem::path& path, const Wanted& wanted, const Visitor& visit, Bag& bag);

}  // namespace driftlab::rosbag::detail
