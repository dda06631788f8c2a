// Built when libsqlite3 was not found (CMake says so): rosbag2 sqlite3 bags are refused by name.
#include "framework/error.hpp"
#include "framework/rosbag_containers.hpp"

namespace driftlab::rosbag::detail {

void read_sqlite3(const std::filesystem::path& path, const Wanted&, const Visitor&, Bag&) {
  throw DataError({path.string(), 0, ""},
                  "a ROS 2 sqlite3 bag, and this driftlab was built without libsqlite3 (Debian: libsqlite3-dev)");
}

}  // namespace driftlab::rosbag::detail
