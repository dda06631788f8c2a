#include "framework/rosbag.hpp"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <map>

#include "framework/decompress.hpp"
#include "framework/error.hpp"
#include "framework/mcap.hpp"
#include "framework/rosbag_containers.hpp"
#include "framework/yaml_io.hpp"

namespace driftlab::rosbag {
namespace {

constexpr std::string_view kRos1Magic = "#ROSBAG V";
constexpr std::string_view kSqliteMagic{"SQLite format 3\0", 16};
constexpr const char* kMetadataFile = "metadata.yaml";

std::string describe_compression(const std::map<std::string, std::uint64_t>& chunks) {
  std::string out;
  for (const auto& [codec, n] : chunks)
    out += (out.empty() ? "" : " and ") + (codec.empty() ? std::string("uncompressed") : codec);
  return out.empty() ? "no chunks" : out + " chunks";
}

void read_mcap(const std::filesystem::path& path, const Wanted& wanted, const Visitor& visit, Bag& bag) {
  const std::string file = path.string();
  std::map<std::uint16_t, Topic> by_channel;  // stable addresses for the visits
  const mcap::File f = mcap::read(
      path,
      [&](const mcap::Channel& c, const mcap::Schema* schema) {
        Topic& t = by_channel[c.id];
        t.name = c.topic;
        t.type = schema ? schema->name : "";
        t.encoding = c.message_encoding;
        return wanted(t);
      },
      [&](const mcap::Message& m) {
        visit({&by_channel.at(m.channel->id), static_cast<std::int64_t>(m.log_time), m.data,
               [&m] { return m.place.text(); }});
      });
  bag.container = "MCAP (profile " + (f.profile.empty() ? std::string("none") : f.profile) + ", " +
                  describe_compression(f.chunk_compression) + (f.has_summary ? ", summary" : ", no summary") + ")";
  bag.bytes = f.file_size;
  bag.files = {file};
  for (const auto& c : f.channels) {
    Topic t = by_channel.at(c.id);
    t.count = c.count;
    t.first_ns = static_cast<std::int64_t>(c.min_log_time);
    t.last_ns = static_cast<std::int64_t>(c.max_log_time);
    bag.topics.push_back(std::move(t));
  }
}

// One topic per name: channels / connections of one name merged (counts added, spans joined).
void merge_topics(Bag& bag) {
  std::map<std::string, Topic> merged;
  for (auto& t : bag.topics) {
    auto [it, fresh] = merged.try_emplace(t.name, t);
    if (fresh) continue;
    Topic& m = it->second;
    if (m.type != t.type || m.encoding != t.encoding || m.md5 != t.md5)
      throw DataError({bag.file, 0, t.name}, "topic '" + t.name + "' has two types: " + m.type + " (" + m.encoding +
                                                 ") and " + t.type + " (" + t.encoding + ")");
    if (t.count == 0) continue;
    if (m.count == 0) {
      m.first_ns = t.first_ns;
      m.last_ns = t.last_ns;
    } else {
      m.first_ns = std::min(m.first_ns, t.first_ns);
      m.last_ns = std::max(m.last_ns, t.last_ns);
    }
    m.count += t.count;
  }
  bag.topics.clear();
  for (auto& [name, t] : merged) bag.topics.push_back(std::move(t));
}

void read_file(const std::filesystem::path& path, Format format, const Wanted& wanted, const Visitor& visit, Bag& bag) {
  switch (format) {
    case Format::Ros1:
      detail::read_ros1(path, wanted, visit, bag);
      break;
    case Format::Sqlite3:
      detail::read_sqlite3(path, wanted, visit, bag);
      break;
    case Format::Mcap:
      read_mcap(path, wanted, visit, bag);
      break;
    case Format::Directory:
      break;
  }
}

std::string text(const YAML::Node& node) { return scalar_text(node).value_or(""); }

void read_directory(const std::filesystem::path& dir, const Wanted& wanted, const Visitor& visit, Bag& bag) {
  const auto metadata_path = dir / kMetadataFile;
  const std::string metadata_file = metadata_path.string();
  std::ifstream in(metadata_path, std::ios::binary);
  const std::string yaml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  YAML::Node root;
  try {
    root = load_yaml_checked(yaml, metadata_file);
  } catch (const ConfigError& e) {
    throw DataError({metadata_file, 0, ""}, e.what());
  }
  const YAML::Node info = root.IsMap() ? root["rosbag2_bagfile_information"] : YAML::Node();
  if (!info.IsMap())
    throw DataError({metadata_file, 0, ""}, "not a rosbag2 metadata.yaml (no rosbag2_bagfile_information map)");
  const std::string storage = text(info["storage_identifier"]);
  if (storage != "sqlite3" && storage != "mcap")
    throw DataError({metadata_file, 0, "storage_identifier"},
                    "storage " + quoted_excerpt(storage) + ": driftlab reads the sqlite3 and mcap storages");
  const std::string mode = text(info["compression_mode"]);
  const std::string codec = text(info["compression_format"]);
  if (mode == "FILE" || mode == "file")
    throw DataError({metadata_file, 0, "compression_mode"}, "the bag's files are compressed whole (" + codec +
                                                                "); decompress them first (zstd -d FILE), "
                                                                "then read the files themselves");
  const bool per_message = !mode.empty() && mode != "NONE" && mode != "none" && !codec.empty();
  const YAML::Node paths = info["relative_file_paths"];
  if (!paths.IsSequence() || paths.size() == 0)
    throw DataError({metadata_file, 0, "relative_file_paths"}, "lists no files");

  const Visitor unpacked = [&](const Message& m) {
    const std::string data = decompress(codec, m.data, std::nullopt, {bag.file, 0, m.topic->name}, m.where());
    visit({m.topic, m.time_ns, data, m.where});
  };
  for (const auto& p : paths) {
    std::filesystem::path file = dir / text(p);
    // rosbag2 before Foxy wrote paths relative to the directory's parent ("bag/bag_0.db3").
    if (!std::filesystem::exists(file) && std::filesystem::exists(dir.parent_path() / text(p)))
      file = dir.parent_path() / text(p);
    const auto format = sniff(file);
    if (!format || *format == Format::Directory || *format == Format::Ros1)
      throw DataError({metadata_file, 0, "relative_file_paths"},
                      quoted_excerpt(text(p)) + " is " +
                          (std::filesystem::exists(file) ? "not a " + storage + " file" : "missing") + " (" +
                          file.string() + ")");
    Bag part;
    part.file = file.string();
    const std::string name = file.filename().string();
    const Visitor each = [&](const Message& m) {
      const Message named{m.topic, m.time_ns, m.data, [&m, &name] { return name + ": " + m.where(); }};
      per_message ? unpacked(named) : visit(named);
    };
    read_file(file, *format, wanted, each, part);
    bag.bytes += part.bytes;
    bag.files.push_back(part.file);
    for (auto& t : part.topics) bag.topics.push_back(std::move(t));
    if (bag.container.empty()) bag.container = "rosbag2 directory, " + storage + " storage";
  }
  if (per_message) bag.container += ", messages " + codec + "-compressed";
  bag.container += " (" + std::to_string(bag.files.size()) + (bag.files.size() == 1 ? " file)" : " files)");
}

}  // namespace

std::optional<Format> sniff(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    return std::filesystem::is_regular_file(path / kMetadataFile, ec) ? std::optional(Format::Directory) : std::nullopt;
  std::ifstream in(path, std::ios::binary);
  char first[16] = {};
  in.read(first, sizeof first);
  const std::string_view bytes(first, static_cast<std::size_t>(in.gcount()));
  if (bytes.starts_with(kRos1Magic)) return Format::Ros1;
  if (bytes.starts_with(kSqliteMagic)) return Format::Sqlite3;
  if (mcap::has_magic(bytes)) return Format::Mcap;
  return std::nullopt;
}

const Topic* Bag::find(std::string_view name) const {
  for (const auto& t : topics)
    if (t.name == name) return &t;
  return nullptr;
}

Bag read(const std::filesystem::path& path, const Wanted& wanted, const Visitor& visit) {
  Bag bag;
  bag.file = path.string();
  const auto format = sniff(path);
  if (!format) {
    std::error_code ec;
    throw DataError({bag.file, 0, ""},
                    std::filesystem::exists(path, ec)
                        ? "not a ROS bag (ROS 1 bag, rosbag2 sqlite3 or MCAP file, or a directory with metadata.yaml)"
                        : "no such file");
  }
  bag.format = *format;
  const Wanted& w = visit && wanted ? wanted : Wanted([](const Topic&) { return false; });
  if (*format == Format::Directory)
    read_directory(path, w, visit, bag);
  else
    read_file(path, *format, w, visit, bag);
  merge_topics(bag);
  return bag;
}

}  // namespace driftlab::rosbag
