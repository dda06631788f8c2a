// The ROS 1 bag reader of rosbag::read, built as the module libdriftlab_ros1bag.so (loaded by
// rosbag_ros1_module.cpp when a ROS 1 bag is read) on Debian's librosbag-storage.
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <map>
#include <optional>

#include "framework/error.hpp"
#include "framework/rosbag_containers.hpp"

using namespace driftlab;
using namespace driftlab::rosbag;

extern "C" __attribute__((visibility("default"))) void driftlab_read_ros1(const std::filesystem::path& path,
                                                                          const Wanted& wanted, const Visitor& visit,
                                                                          Bag& out) {
  const std::string file = path.string();
  std::optional<std::uint64_t> message;  // being read; none: the index
  try {
    ::rosbag::Bag bag(file, ::rosbag::bagmode::Read);
    out.container = "ROS 1 bag v" + std::to_string(bag.getMajorVersion()) + "." + std::to_string(bag.getMinorVersion());
    std::error_code ec;
    out.bytes = std::filesystem::file_size(path, ec);
    out.files = {file};
    std::map<std::string, Topic> by_topic;
    ::rosbag::View all(bag);
    for (const auto* c : all.getConnections()) {
      Topic t{c->topic, c->datatype, "ros1", c->md5sum, 0, 0, 0};
      auto [it, fresh] = by_topic.try_emplace(c->topic, t);
      if (!fresh && (it->second.type != t.type || it->second.md5 != t.md5))
        throw DataError({file, 0, c->topic}, "topic '" + c->topic + "' has two types: " + it->second.type + " (md5 " +
                                                 it->second.md5 + ") and " + t.type + " (md5 " + t.md5 + ")");
    }
    for (auto& [name, t] : by_topic) {
      ::rosbag::View one(bag, ::rosbag::TopicQuery(name));
      t.count = one.size();
      if (t.count > 0) {
        t.first_ns = static_cast<std::int64_t>(one.getBeginTime().toNSec());
        t.last_ns = static_cast<std::int64_t>(one.getEndTime().toNSec());
      }
    }
    std::vector<std::string> present;
    for (const auto& [name, t] : by_topic)
      if (wanted(t)) present.push_back(name);
    if (!present.empty()) {
      ::rosbag::View view(bag, ::rosbag::TopicQuery(present));
      std::string buffer;
      message = 0;
      for (const ::rosbag::MessageInstance& m : view) {
        buffer.resize(m.size());
        ros::serialization::OStream stream(reinterpret_cast<std::uint8_t*>(buffer.data()),
                                           static_cast<std::uint32_t>(buffer.size()));
        m.write(stream);
        const std::uint64_t index = (*message)++;
        visit({&by_topic.at(m.getTopic()), static_cast<std::int64_t>(m.getTime().toNSec()), buffer,
               [index] { return "message " + std::to_string(index) + " in time order"; }});
      }
    }
    for (auto& [name, t] : by_topic) out.topics.push_back(std::move(t));
  } catch (const DataError&) {
    throw;
  } catch (const std::exception& e) {
    const std::string where = message ? "message " + std::to_string(*message) + " in time order" : "its index";
    throw DataError({file, 0, ""}, "reading " + where + ": " + e.what() + " (librosbag-storage)");
  }
}
