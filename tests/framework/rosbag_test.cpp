// The ROS bag readers: MCAP parser (framework/mcap.hpp), message decoders (ros_messages.hpp), the
// containers (rosbag.hpp: ROS 1 through librosbag-storage, rosbag2 sqlite3, MCAP, rosbag2
// directories) and the bag -> IMU record adapter (ros_imu.hpp).
// Truth, never a writer of driftlab's own (tests/data/logs/*/README.md):
//   ros1-robot-localization/test2.bag  a real Jackal recording; python3-rosbag's counts and values
//   ros2-rosbag2/                      rosbag2's own bags; sqlite3 CLI and @mcap/core counts
//   ros2-robot-localization/           that IMU in MCAP / db3 written by @mcap/core and @foxglove's
//                                      CDR serializers; @mcap/core + MessageReader values
//   write_ros1_bags.py                 ROS 1 bags written at test time by python3-rosbag, known values
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/mcap.hpp"
#include "framework/record_reader.hpp"
#include "framework/ros_imu.hpp"
#include "framework/ros_messages.hpp"
#include "framework/rosbag.hpp"

namespace driftlab {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::Contains;
using ::testing::HasSubstr;

// Stamps become s since the epoch: 1.7e9 s holds 2.4e-7 s steps of double; the fixtures' stamps
// are near 1e2 s and 1.6e9 s.
constexpr double kStampTolerance = 1e-6;
// A value interpolated linearly between two stamps, against the exact line through the fixture's
// samples: double rounding of the stamps (~1e-14 s near 1e2 s) and of the weights gives errors near
// 1e-13 on these magnitudes (1 to 40); a sample taken from the wrong neighbour is off by 1e-3 or more.
constexpr double kInterpolationTolerance = 1e-9;

fs::path logs() { return fs::path(DRIFTLAB_TEST_DATA) / "logs"; }
fs::path ros1_fixture() { return logs() / "ros1-robot-localization" / "test2.bag"; }
fs::path ros2_dir() { return logs() / "ros2-robot-localization"; }
fs::path rosbag2_dir() { return logs() / "ros2-rosbag2"; }

nlohmann::json load_json(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_bytes(const fs::path& p, const std::string& bytes) { std::ofstream(p, std::ios::binary) << bytes; }

fs::path scratch(const std::string& name) {
  const auto dir = fs::temp_directory_path() / ("driftlab_rosbag_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string data_error(const std::function<void()>& f) {
  try {
    f();
  } catch (const DataError& e) {
    return e.what();
  }
  return "no DataError";
}

// ---- MCAP container ----------------------------------------------------------------------------

TEST(Mcap, RosbagTalkerChannelsCountsAndTimesAreThoseOfMcapCore) {
  const auto reference = load_json(rosbag2_dir() / "reference_mcap.json");
  for (const char* name : {"talker", "cdr_test"}) {
    SCOPED_TRACE(name);
    const std::string file = std::string(name) + (std::string(name) == "talker" ? ".mcap" : "_0.mcap");
    const auto f = mcap::read(rosbag2_dir() / (std::string(name) + "-mcap") / file);
    EXPECT_EQ(f.profile, "ros2");
    EXPECT_TRUE(f.has_summary);
    EXPECT_TRUE(f.has_statistics);
    std::size_t with_messages = 0;
    for (const auto& c : f.channels) {
      if (c.count == 0) continue;
      ++with_messages;
      const auto& r = reference.at(file).at("topics").at(c.topic);
      EXPECT_EQ(c.count, r.at("count").get<std::uint64_t>()) << c.topic;
      EXPECT_EQ(std::to_string(c.first_log_time), r.at("first").at("log_time").get<std::string>()) << c.topic;
      EXPECT_EQ(std::to_string(c.last_log_time), r.at("last").at("log_time").get<std::string>()) << c.topic;
      EXPECT_EQ(f.find_schema(c.schema_id)->name, r.at("type").get<std::string>());
    }
    EXPECT_EQ(with_messages, reference.at(file).at("topics").size());
  }
}

TEST(Mcap, EveryFixtureVariantGivesTheIndependentReadersValues) {
  const auto reference = load_json(ros2_dir() / "reference_mcap.json");
  for (const auto& [file, expected] : reference.items()) {
    SCOPED_TRACE(file);
    const auto& imu = expected.at("topics").at("/imu/data");
    LogSelection selection;
    selection.topic = "/imu/data";
    std::vector<std::string> notes;
    const TimeSeries record = ros::read_imu(ros2_dir() / file, selection, &notes);
    ASSERT_EQ(static_cast<std::uint64_t>(record.size()), imu.at("count").get<std::uint64_t>());
    for (const auto* end : {"first", "last"}) {
      const auto& m = imu.at(end);
      const Eigen::Index i = std::string(end) == "first" ? 0 : record.size() - 1;
      EXPECT_NEAR(record.time()[i], std::stod(m.at("stamp_ns").get<std::string>()) * 1e-9, kStampTolerance);
      for (int a = 0; a < 3; ++a) {
        const std::string axis(1, "xyz"[a]);
        EXPECT_EQ(record.channel("gyro_" + axis).values[i], m.at("angular_velocity")[a].get<double>()) << end << axis;
        EXPECT_EQ(record.channel("accel_" + axis).values[i], m.at("linear_acceleration")[a].get<double>())
            << end << axis;
      }
    }
    EXPECT_FALSE(record.has("temperature")) << "--topic names the Imu topic only";
  }
}

TEST(Mcap, TheSummaryIsReadWhenPresentAndTheStreamSufficesWithout) {
  const auto with = mcap::read(ros2_dir() / "imu_zstd.mcap");
  EXPECT_TRUE(with.has_summary && with.has_statistics);
  EXPECT_EQ(with.chunk_compression.at("zstd"), with.chunks);
  EXPECT_GT(with.uncompressed_bytes, 2 * with.compressed_bytes);
  const auto without = mcap::read(ros2_dir() / "imu_no_summary_no_chunks.mcap");
  EXPECT_FALSE(without.has_summary || without.has_statistics);
  EXPECT_EQ(without.chunks, 0u);
  EXPECT_EQ(without.messages, 500u);
  const auto lz4 = mcap::read(ros2_dir() / "imu_lz4.mcap");
  EXPECT_EQ(lz4.chunk_compression.at("lz4"), lz4.chunks);
  const auto plain = mcap::read(ros2_dir() / "imu_uncompressed_chunks.mcap");
  EXPECT_GT(plain.chunks, 1u);
  EXPECT_EQ(plain.chunk_compression.at(""), plain.chunks);
  EXPECT_EQ(plain.compressed_bytes, plain.uncompressed_bytes);
}

TEST(Mcap, ATemperatureTopicPairsByNamespaceAndIsInterpolatedOntoTheGyro) {
  const auto reference =
      load_json(ros2_dir() / "reference_mcap.json").at("imu_zstd.mcap").at("topics").at("/imu/temperature");
  std::vector<std::string> notes;
  const TimeSeries record = ros::read_imu(ros2_dir() / "imu_zstd.mcap", {}, &notes);
  ASSERT_TRUE(record.has("temperature"));
  EXPECT_EQ(record.channel("temperature").unit, "degC");
  EXPECT_EQ(record.channel("temperature").source, "/imu/temperature");
  // Temperatures at every 10th gyro stamp, from the first to the last (20 + 0.05 x 306 degC): the
  // gyro keeps all its samples, the temperature is linear in between.
  EXPECT_EQ(record.size(), 3061);
  EXPECT_DOUBLE_EQ(record.channel("temperature").values[0], reference.at("first").at("temperature").get<double>());
  EXPECT_DOUBLE_EQ(record.channel("temperature").values[record.size() - 1],
                   reference.at("last").at("temperature").get<double>());
  EXPECT_NEAR(record.channel("temperature").values[5], 20.025, kInterpolationTolerance);
  EXPECT_THAT(notes, Contains("time base: /imu/data angular_velocity; 2 other streams linearly interpolated onto it"));
}

TEST(McapBadInput, TruncatedAnywhereIsADataErrorNamingFileAndByte) {
  const std::string bytes = read_bytes(ros2_dir() / "imu_lz4.mcap");
  for (std::size_t cut = 0; cut < bytes.size(); cut += cut < 256 ? 1 : 997) {
    const std::string message = data_error([&] { mcap::parse(std::string_view(bytes).substr(0, cut), "cut.mcap"); });
    ASSERT_THAT(message, HasSubstr("cut.mcap: ")) << cut;
    if (cut >= mcap::kMagicSize) {
      EXPECT_THAT(message, HasSubstr("byte ")) << cut;
    }
  }
}

TEST(McapBadInput, CorruptChunksBadMagicAndUnknownCompressionAreDataErrors) {
  std::string bytes = read_bytes(ros2_dir() / "imu_uncompressed_chunks.mcap");
  EXPECT_THAT(data_error([&] { mcap::parse("PK\x03\x04 not an mcap", "zip.mcap"); }), HasSubstr("not an MCAP file"));
  const auto imu = bytes.find("base_link");
  ASSERT_NE(imu, std::string::npos);
  std::string flipped = bytes;
  flipped[imu] ^= 0x20;  // a frame_id byte inside the first chunk's records: its CRC no longer holds
  EXPECT_THAT(data_error([&] { mcap::parse(flipped, "crc.mcap"); }), AllOf(HasSubstr("Chunk"), HasSubstr("CRC-32")));

  std::string zstd = read_bytes(ros2_dir() / "imu_zstd.mcap");
  const auto codec = zstd.find("zstd");
  ASSERT_NE(codec, std::string::npos);
  zstd.replace(codec, 4, "zzzz");
  EXPECT_THAT(data_error([&] { mcap::parse(zstd, "codec.mcap"); }),
              HasSubstr("compression 'zzzz' is not one driftlab reads"));

  std::string compressed = read_bytes(ros2_dir() / "imu_zstd.mcap");
  compressed[compressed.find("zstd") + 40] ^= 0x55;  // inside the first chunk's zstd frame
  EXPECT_THAT(data_error([&] { mcap::parse(compressed, "frame.mcap"); }), HasSubstr("frame.mcap: byte "));

  std::string no_footer = bytes.substr(0, bytes.size() - 8) + "XXXXXXXX";
  EXPECT_THAT(data_error([&] { mcap::parse(no_footer, "end.mcap"); }), HasSubstr("closing magic"));
}

TEST(McapBadInput, StatisticsThatDisagreeWithTheDataAreADataError) {
  std::string bytes = read_bytes(ros2_dir() / "imu_lz4.mcap");
  // The Statistics record (opcode 0x0B) of the summary: its message_count (the first field) + 1.
  const std::string opening("\x0b", 1);
  const std::size_t at = bytes.rfind(opening + std::string("\x38\x00\x00\x00\x00\x00\x00\x00\xf4\x01", 10));
  ASSERT_NE(at, std::string::npos) << "Statistics record of 56 bytes counting 500 messages";
  bytes[at + 9] = static_cast<char>(bytes[at + 9] + 1);
  EXPECT_THAT(data_error([&] { mcap::parse(bytes, "stats.mcap"); }),
              AllOf(HasSubstr("Statistics count 501 messages; the data section holds 500"), HasSubstr("corrupt")));
}

// ---- message decoders --------------------------------------------------------------------------

TEST(RosMessages, EncapsulationsOtherThanPlainCdrAndShortMessagesAreDataErrors) {
  const Location where{"x.mcap", 0, "/imu"};
  const ros::Describe m = [] { return std::string("m"); };
  EXPECT_THAT(
      data_error([&] {
        ros::decode_imu(std::string("\x00\x02\x00\x00", 4), ros::Encoding::Cdr, where,
                        [] { return std::string("/imu row 3"); });
      }),
      AllOf(HasSubstr("x.mcap: /imu: /imu row 3: byte 0 of the message: CDR encapsulation 0x0002 is not read")));
  EXPECT_THAT(data_error([&] {
                ros::decode_imu(std::string("\x00\x01\x00\x00\x01\x00\x00\x00", 8), ros::Encoding::Cdr, where, m);
              }),
              HasSubstr("byte 8 of the message: message ends after 8 bytes"));
  EXPECT_THAT(data_error([&] {
                ros::decode_temperature(std::string(9, '\0'), ros::MessageType::Float64, ros::Encoding::Ros1, where, m);
              }),
              HasSubstr("1 bytes after the end of the message's fields"));
  std::string huge_string("\x00\x01\x00\x00\x01\x00\x00\x00\x02\x00\x00\x00\xff\xff\xff\x7f", 16);
  EXPECT_THAT(data_error([&] { ros::decode_imu(huge_string, ros::Encoding::Cdr, where, m); }),
              HasSubstr("string of 2147483647 bytes, but 0 remain"));
  EXPECT_EQ(ros::decode_temperature(std::string("\x00\x00\x80\x3f", 4), ros::MessageType::Float32, ros::Encoding::Ros1,
                                    where, m)
                .degc,
            1.0);
}

// ---- rosbag2 sqlite3 and directories -----------------------------------------------------------

TEST(Rosbag2, Sqlite3TopicsCountsAndTimesAreThoseOfTheSqlite3Cli) {
  const auto reference = load_json(rosbag2_dir() / "reference_db3.json");
  for (const auto& [dir, file] :
       {std::pair{"talker-sqlite3", "talker.db3"}, std::pair{"cdr_test-sqlite3", "cdr_test_0.db3"}}) {
    SCOPED_TRACE(file);
    for (const auto& path : {rosbag2_dir() / dir / file, rosbag2_dir() / dir}) {
      const auto bag = rosbag::read(path);
      const auto& topics = reference.at(file);
      ASSERT_EQ(bag.topics.size(), topics.size());
      for (const auto& t : topics) {
        const auto* topic = bag.find(t.at("name").get<std::string>());
        ASSERT_NE(topic, nullptr);
        EXPECT_EQ(topic->type, t.at("type").get<std::string>());
        EXPECT_EQ(topic->encoding, "cdr");
        EXPECT_EQ(topic->count, t.at("count").get<std::uint64_t>());
        if (topic->count == 0) continue;
        EXPECT_EQ(topic->first_ns, t.at("first_ns").get<std::int64_t>());
        EXPECT_EQ(topic->last_ns, t.at("last_ns").get<std::int64_t>());
      }
    }
  }
  EXPECT_EQ(rosbag::read(rosbag2_dir() / "talker-sqlite3").format, rosbag::Format::Directory);
  // talker.db3 is in WAL mode: reading it leaves no -shm or -wal file next to it.
  EXPECT_FALSE(fs::exists(rosbag2_dir() / "talker-sqlite3" / "talker.db3-shm"));
  EXPECT_FALSE(fs::exists(rosbag2_dir() / "talker-sqlite3" / "talker.db3-wal"));
}

TEST(Rosbag2, TheMcapAndSqlite3BagsOfOneRecordingAgree) {
  const auto db3 = rosbag::read(rosbag2_dir() / "talker-sqlite3");
  const auto mcap = rosbag::read(rosbag2_dir() / "talker-mcap");
  ASSERT_EQ(db3.topics.size(), mcap.topics.size());
  for (std::size_t i = 0; i < db3.topics.size(); ++i) {
    EXPECT_EQ(db3.topics[i].name, mcap.topics[i].name);
    EXPECT_EQ(db3.topics[i].type, mcap.topics[i].type);
    EXPECT_EQ(db3.topics[i].count, mcap.topics[i].count);
    EXPECT_EQ(db3.topics[i].first_ns, mcap.topics[i].first_ns);
  }
}

TEST(Rosbag2, ADb3DirectoryGivesTheImuAndTemperatureOfItsMessages) {
  const auto counts = load_json(ros2_dir() / "reference_db3.json");
  const auto values = load_json(ros2_dir() / "reference_mcap.json").at("imu_zstd.mcap").at("topics");
  const auto bag = rosbag::read(ros2_dir() / "imu_db3");
  for (const auto& t : counts)
    EXPECT_EQ(bag.find(t.at("name").get<std::string>())->count, t.at("count").get<std::uint64_t>());
  std::vector<std::string> notes;
  const TimeSeries record = read_record(ros2_dir() / "imu_db3", {.required_roles = {}}, {}, &notes);
  EXPECT_EQ(record.channel("gyro_z").values[0],
            values.at("/imu/data").at("first").at("angular_velocity")[2].get<double>());
  EXPECT_EQ(record.channel("temperature").values[0], 20.0);
  EXPECT_NEAR(record.time()[0], 47.58, kStampTolerance);
}

TEST(Rosbag2, MessagesCompressedOneByOneAreDecompressed) {
  const auto bag = rosbag::read(ros2_dir() / "imu_db3_zstd_messages");
  EXPECT_EQ(bag.container, "rosbag2 directory, sqlite3 storage, messages zstd-compressed (1 file)");
  const TimeSeries compressed = ros::read_imu(ros2_dir() / "imu_db3_zstd_messages", {});
  LogSelection imu_only;
  imu_only.topic = "/imu/data";
  const TimeSeries plain = ros::read_imu(ros2_dir() / "imu_lz4.mcap", imu_only);
  ASSERT_EQ(compressed.size(), 100);
  EXPECT_EQ(compressed.time(), plain.time().head(100));
  EXPECT_EQ(compressed.channel("gyro_y").values, plain.channel("gyro_y").values.head(100));
  EXPECT_EQ(compressed.channel("accel_x").values, plain.channel("accel_x").values.head(100));
}

TEST(Rosbag2, ADirectoryOfSeveralFilesIsOneBag) {
  const auto dir = scratch("split");
  fs::copy_file(ros2_dir() / "imu_lz4.mcap", dir / "split_0.mcap");
  fs::copy_file(ros2_dir() / "imu_zstd.mcap", dir / "split_1.mcap");
  write_bytes(dir / "metadata.yaml",
              "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n"
              "  relative_file_paths: [split_0.mcap, split_1.mcap]\n");
  const auto bag = rosbag::read(dir);
  EXPECT_EQ(bag.files.size(), 2u);
  EXPECT_EQ(bag.find("/imu/data")->count, 500u + 3061u);
  EXPECT_EQ(bag.find("/imu/temperature")->count, 307u);
  std::vector<std::string> notes;
  const TimeSeries r = ros::read_imu(dir, {}, &notes);
  EXPECT_EQ(r.size(), 3061);  // the first 500 stamps twice: the first of each kept
  EXPECT_THAT(notes,
              Contains("/imu/data: 1 samples earlier than the one before; sorted by time"));  // at the file boundary
  EXPECT_THAT(notes, Contains("/imu/data: 500 repeated time stamps; the first sample of each kept"));
}

TEST(Rosbag2BadInput, TruncatedDb3AndBadMetadataAreDataErrors) {
  const auto dir = scratch("db3");
  const std::string db3 = read_bytes(ros2_dir() / "imu_db3" / "imu_db3_0.db3");
  write_bytes(dir / "cut.db3", db3.substr(0, db3.size() / 2));
  EXPECT_THAT(data_error([&] { ros::read_imu(dir / "cut.db3", {}); }),
              AllOf(HasSubstr("cut.db3"), HasSubstr("sqlite3:")));
  write_bytes(dir / "header.db3", db3.substr(0, 100));
  EXPECT_THAT(data_error([&] { rosbag::read(dir / "header.db3"); }), HasSubstr("header.db3"));

  fs::create_directories(dir / "file_mode");
  write_bytes(dir / "file_mode" / "metadata.yaml",
              "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n  compression_format: zstd\n"
              "  compression_mode: FILE\n  relative_file_paths: [b_0.db3.zstd]\n");
  EXPECT_THAT(data_error([&] { rosbag::read(dir / "file_mode"); }),
              AllOf(HasSubstr("compressed whole"), HasSubstr("zstd -d")));
  fs::create_directories(dir / "missing");
  write_bytes(dir / "missing" / "metadata.yaml",
              "rosbag2_bagfile_information:\n  storage_identifier: mcap\n  relative_file_paths: [gone_0.mcap]\n");
  EXPECT_THAT(data_error([&] { rosbag::read(dir / "missing"); }), AllOf(HasSubstr("'gone_0.mcap' is missing")));
  fs::create_directories(dir / "other");
  write_bytes(dir / "other" / "metadata.yaml", "just: text\n");
  EXPECT_THAT(data_error([&] { rosbag::read(dir / "other"); }), HasSubstr("not a rosbag2 metadata.yaml"));
  write_bytes(dir / "other" / "metadata.yaml", "rosbag2_bagfile_information: {storage_identifier: [1, 2\n");
  EXPECT_THAT(data_error([&] { rosbag::read(dir / "other"); }), HasSubstr("metadata.yaml"));
}

TEST(Rosbag2BadInput, ABagWithoutImuATopicNotThereAndAnUnreadTypeAreNamed) {
  EXPECT_THAT(data_error([&] { ros::read_imu(rosbag2_dir() / "talker-mcap", {}); }),
              AllOf(HasSubstr("no sensor_msgs/Imu topic in the bag"), HasSubstr("/topic (std_msgs/msg/String)")));
  LogSelection missing;
  missing.topic = "/imu/dat";
  EXPECT_THAT(data_error([&] { ros::read_imu(ros2_dir() / "imu_lz4.mcap", missing); }),
              AllOf(HasSubstr("'/imu/dat' is not in the bag"), HasSubstr("IMU topics it has: /imu/data")));
  LogSelection string_topic;
  string_topic.topic = "/topic";
  EXPECT_THAT(data_error([&] { ros::read_imu(rosbag2_dir() / "talker-sqlite3", string_topic); }),
              HasSubstr("std_msgs/msg/String, neither an IMU"));
  LogSelection instance;
  instance.instance = 1;
  EXPECT_THAT(data_error([&] { ros::read_imu(ros2_dir() / "imu_lz4.mcap", instance); }),
              HasSubstr("matches no stream"));
}

// ---- ROS 1 -------------------------------------------------------------------------------------

TEST(Ros1, RobotLocalizationBagCountsAndValuesAreThoseOfPython3Rosbag) {
  const auto bag = rosbag::read(ros1_fixture());
  EXPECT_EQ(bag.container, "ROS 1 bag v2.0");
  ASSERT_EQ(bag.topics.size(), 2u);
  EXPECT_EQ(bag.topics[0].name, "/imu/data");
  EXPECT_EQ(bag.topics[0].md5, "6a62c6daae103f4ff57a132d6f95cec2");
  EXPECT_EQ(bag.topics[0].count, 3061u);
  EXPECT_EQ(bag.topics[0].first_ns, 47580000000);
  EXPECT_EQ(bag.topics[0].last_ns, 108781000000);
  EXPECT_EQ(bag.topics[1].type, "nav_msgs/Odometry");
  EXPECT_EQ(bag.topics[1].count, 3060u);
  EXPECT_EQ(bag.topics[1].first_ns, 47585000000);
  EXPECT_EQ(bag.topics[1].last_ns, 108770000000);

  const TimeSeries r = ros::read_imu(ros1_fixture(), {});
  ASSERT_EQ(r.size(), 3061);
  EXPECT_EQ(r.time()[0], 47.58);
  EXPECT_EQ(r.time()[3060], 108.78);
  EXPECT_EQ(r.channel("gyro_x").values[0], 0.006656444803353631);
  EXPECT_EQ(r.channel("gyro_y").values[0], -0.00236638747633773);
  EXPECT_EQ(r.channel("gyro_z").values[0], 0.04275138193045083);
  EXPECT_EQ(r.channel("accel_x").values[0], -0.5942556862503618);
  EXPECT_EQ(r.channel("accel_z").values[0], 9.703827518410009);
  EXPECT_EQ(r.channel("gyro_x").values[3060], 0.004066151195657548);
  EXPECT_EQ(r.channel("gyro_y").values[3060], -0.005366438265441694);
  EXPECT_EQ(r.channel("gyro_z").values[3060], 0.03825877566845808);
  EXPECT_EQ(r.channel("accel_y").values[3060], -0.5259286964903248);
  EXPECT_EQ(r.channel("accel_z").values[3060], 9.806229082013386);
}

TEST(Ros1, TheRos2CopiesOfTheRecordingGiveTheSameRecord) {
  const TimeSeries ros1 = ros::read_imu(ros1_fixture(), {});
  LogSelection imu_only;
  imu_only.topic = "/imu/data";
  const TimeSeries ros2 = ros::read_imu(ros2_dir() / "imu_zstd.mcap", imu_only);
  ASSERT_EQ(ros1.size(), ros2.size());
  EXPECT_EQ(ros1.time(), ros2.time());
  for (const auto* role : {"gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z"})
    EXPECT_EQ(ros1.channel(role).values, ros2.channel(role).values) << role;
}

TEST(Ros1BadInput, TruncatedAndCorruptBagsAreDataErrorsNeverCrashes) {
  const auto dir = scratch("ros1_cut");
  const std::string bytes = read_bytes(ros1_fixture());
  for (const std::size_t cut :
       {std::size_t{5}, std::size_t{13}, std::size_t{4200}, bytes.size() / 2, bytes.size() - 100, bytes.size() - 1}) {
    SCOPED_TRACE(cut);
    write_bytes(dir / "cut.bag", bytes.substr(0, cut));
    EXPECT_THAT(data_error([&] { ros::read_imu(dir / "cut.bag", {}); }), HasSubstr("cut.bag"));
  }
  std::string corrupt = bytes;
  for (std::size_t i = 5000; i < corrupt.size(); i += 7919) corrupt[i] = static_cast<char>(corrupt[i] ^ 0xA5);
  write_bytes(dir / "corrupt.bag", corrupt);
  EXPECT_THAT(data_error([&] { ros::read_imu(dir / "corrupt.bag", {}); }), HasSubstr("corrupt.bag"));
}

// Bags written by python3-rosbag at test time (tests/framework/write_ros1_bags.py), once.
class Ros1Written : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = scratch("written");
    const std::string command = "/usr/bin/python3 " + std::string(DRIFTLAB_SOURCE_DIR) +
                                "/tests/framework/write_ros1_bags.py cases " + dir_.string() + " 2>/dev/null";
    const int status = std::system(command.c_str());
    status_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  void SetUp() override {
    if (status_ == 77) GTEST_SKIP() << "python3-rosbag or python3-sensor-msgs is not installed";
    ASSERT_EQ(status_, 0) << "write_ros1_bags.py failed";
  }
  static fs::path bag(const std::string& name) { return dir_ / name; }
  static inline fs::path dir_;
  static inline int status_ = -1;
};

TEST_F(Ros1Written, OutOfOrderAndRepeatedStampsAreSortedAndDroppedWithCounts) {
  std::vector<std::string> notes;
  const TimeSeries r = ros::read_imu(bag("disorder.bag"), {}, &notes);
  EXPECT_THAT(notes, Contains("/imu/data: 1 samples earlier than the one before; sorted by time"));
  EXPECT_THAT(notes, Contains("/imu/data: 1 repeated time stamps; the first sample of each kept"));
  ASSERT_EQ(r.size(), 49);
  for (Eigen::Index i = 1; i < r.size(); ++i) EXPECT_GT(r.time()[i], r.time()[i - 1]);
  EXPECT_DOUBLE_EQ(r.channel("gyro_z").values[10], 0.010);  // back in stamp order
  EXPECT_DOUBLE_EQ(r.channel("gyro_z").values[19], 0.019);  // of stamp 19's two samples, the first
  EXPECT_DOUBLE_EQ(r.channel("gyro_z").values[20], 0.021);
}

TEST_F(Ros1Written, TwoImuTopicsAreTwoInstancesWithTheirTemperatureTopics) {
  std::vector<std::string> notes;
  const TimeSeries r = ros::read_imu(bag("two_imus.bag"), {}, &notes);
  EXPECT_THAT(notes, Contains(HasSubstr("/cabin/temperature: a temperature topic that pairs with no IMU topic")));
  for (const auto* role : {"gyro_z", "gyro1_z", "accel1_z", "temperature", "temperature1"})
    EXPECT_TRUE(r.has(role)) << role;
  EXPECT_EQ(r.channel("temperature").source, "/imu0/temperature");
  EXPECT_EQ(r.channel("temperature1").source, "/imu1/temp_c");  // std_msgs/Float64 named *temp*
  // Instance 1 starts 3 ms later: the first base sample (100.0 s) is dropped; at 100.1 s instance 1
  // lies 0.97 of the way from its sample 0 (100.003 s) to sample 1 (100.103 s).
  ASSERT_EQ(r.size(), 49);
  EXPECT_NEAR(r.time()[0], 100.1, kStampTolerance);
  EXPECT_DOUBLE_EQ(r.channel("gyro_z").values[0], 0.001);  // the time base's own sample
  EXPECT_NEAR(r.channel("gyro1_z").values[0], 1.00097, kInterpolationTolerance);
  EXPECT_NEAR(r.channel("temperature").values[0], 30.1, kInterpolationTolerance);
  EXPECT_NEAR(r.channel("temperature1").values[0], 40.096,
              kInterpolationTolerance);  // Float64 at receive time t + 4 ms

  LogSelection one;
  one.topic = "/imu1/data,/cabin/temperature";  // --topic pairs a temperature of another namespace
  const TimeSeries chosen = ros::read_imu(bag("two_imus.bag"), one);
  EXPECT_TRUE(chosen.has("gyro_z"));
  EXPECT_FALSE(chosen.has("gyro1_z"));
  EXPECT_EQ(chosen.channel("temperature").source, "/cabin/temperature");
  EXPECT_DOUBLE_EQ(chosen.channel("gyro_z").values[0], 1.0);  // the time base's own sample

  LogSelection second;
  second.instance = 1;
  second.sensor = "gyro";
  const TimeSeries gyro1 = ros::read_imu(bag("two_imus.bag"), second);
  EXPECT_EQ(gyro1.channels().size(), 4u);  // gyro1_x..z, temperature1
  // temperature1 (Float64 at receive time t + 4 ms) starts after gyro1 (t + 3 ms): one sample dropped.
  EXPECT_NEAR(gyro1.time()[0], 100.103, kStampTolerance);
}

TEST_F(Ros1Written, MessageConventionsAndOtherVersionsAreHonoured) {
  std::vector<std::string> notes;
  const TimeSeries accel_only = ros::read_imu(bag("gyro_not_provided.bag"), {}, &notes);
  EXPECT_FALSE(accel_only.has("gyro_z"));
  EXPECT_TRUE(accel_only.has("accel_z"));
  EXPECT_THAT(notes, Contains(HasSubstr("angular_velocity_covariance[0] is -1 in every message (not provided)")));

  notes.clear();
  const TimeSeries received = ros::read_imu(bag("empty_stamps.bag"), {}, &notes);
  EXPECT_THAT(notes, Contains(HasSubstr("every header stamp is 0; the bag's message times are used instead")));
  EXPECT_NEAR(received.time()[1], 100.1, kStampTolerance);

  EXPECT_THAT(data_error([&] { ros::read_imu(bag("wrong_md5.bag"), {}); }),
              AllOf(HasSubstr("md5sum 0123456789abcdef0123456789abcdef is another version of the message"),
                    HasSubstr("6a62c6daae103f4ff57a132d6f95cec2")));
  EXPECT_THAT(data_error([&] { ros::read_imu(bag("nan.bag"), {}); }),
              AllOf(HasSubstr("/imu/data.angular_velocity.x: non-finite value at stamp 100500000000 ns")));
}

TEST_F(Ros1Written, TheRecordReaderChoosesTheBagByContent) {
  fs::copy_file(bag("two_imus.bag"), dir_ / "named.csv", fs::copy_options::overwrite_existing);
  EXPECT_EQ(sniff_record_format(dir_ / "named.csv"), RecordFormat::RosBag);
  CsvReadOptions options;
  options.columns = {parse_column_mapping("rate=gyro1_z")};
  const TimeSeries r = read_record(dir_ / "named.csv", options);
  EXPECT_TRUE(r.has("rate"));
  EXPECT_EQ(r.channels().size(), 1u);
}

}  // namespace
}  // namespace driftlab
