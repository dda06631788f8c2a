#include "framework/ros_messages.hpp"

#include <bit>
#include <cstring>

namespace driftlab::ros {
namespace {

constexpr std::int64_t kNanosecondsPerSecond = 1000000000;
constexpr std::size_t kEncapsulationSize = 4;
constexpr std::size_t kCdrTrailingAlignment = 3;
constexpr std::size_t kCovarianceSize = 9;

// A bounds-checked cursor over one serialized message.
class Cursor {
 public:
  Cursor(std::string_view bytes, Encoding encoding, const Location& where, const Describe& what)
      : bytes_(bytes), where_(where), what_(what) {
    if (encoding == Encoding::Ros1) return;
    if (bytes.size() < kEncapsulationSize) fail(0, "shorter than the 4-byte CDR encapsulation header");
    const auto kind = static_cast<unsigned char>(bytes[1]);
    if (bytes[0] != 0 || (kind != 0x00 && kind != 0x01 && kind != 0x06 && kind != 0x07))
      fail(0, "CDR encapsulation 0x" + hex(bytes[0]) + hex(bytes[1]) +
                  " is not read (plain CDR only: 0x0000/0x0001 XCDR1, 0x0006/0x0007 XCDR2)");
    big_endian_ = (kind & 1) == 0;
    max_align_ = kind >= 0x06 ? 4 : 8;
    body_ = kEncapsulationSize;
    pos_ = body_;
    trailing_ = kCdrTrailingAlignment;
  }

  std::uint32_t u32() { return static_cast<std::uint32_t>(load(4)); }
  std::int32_t i32() { return static_cast<std::int32_t>(u32()); }
  double f64() { return std::bit_cast<double>(load(8)); }
  float f32() { return std::bit_cast<float>(static_cast<std::uint32_t>(load(4))); }
  void skip_f64(std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) load(8);
  }
  void skip_string() {
    const std::uint32_t length = u32();
    if (length > bytes_.size() - pos_)
      fail(pos_ - 4, "string of " + std::to_string(length) + " bytes, but " + std::to_string(bytes_.size() - pos_) +
                         " remain in the message");
    pos_ += length;
  }
  std::int64_t stamp_ns(bool signed_seconds) {
    const std::size_t at = pos_;
    const std::int64_t sec = signed_seconds ? i32() : static_cast<std::int64_t>(u32());
    const std::uint32_t nsec = u32();
    if (nsec >= kNanosecondsPerSecond)
      fail(at, "header stamp nanoseconds " + std::to_string(nsec) + " are not below 10^9");
    return sec * kNanosecondsPerSecond + nsec;
  }
  void finish() const {
    if (bytes_.size() - pos_ > trailing_)
      fail(pos_, std::to_string(bytes_.size() - pos_) + " bytes after the end of the message's fields (" +
                     std::to_string(bytes_.size()) + " bytes in all): not this message type");
  }

 private:
  static std::string hex(char c) {
    static constexpr char kHex[] = "0123456789abcdef";
    const auto u = static_cast<unsigned char>(c);
    return {kHex[u >> 4], kHex[u & 15]};
  }

  std::uint64_t load(std::size_t size) {
    const std::size_t align = std::min(size, max_align_);
    if (align > 1) pos_ = body_ + (pos_ - body_ + align - 1) / align * align;
    if (pos_ > bytes_.size() || bytes_.size() - pos_ < size)
      fail(pos_, "message ends after " + std::to_string(bytes_.size()) + " bytes; its type needs more");
    std::uint64_t v = 0;
    const auto* p = reinterpret_cast<const unsigned char*>(bytes_.data() + pos_);
    for (std::size_t i = 0; i < size; ++i)
      v |= static_cast<std::uint64_t>(p[big_endian_ ? size - 1 - i : i]) << (8 * i);
    pos_ += size;
    return v;
  }

  [[noreturn]] void fail(std::size_t at, const std::string& message) const {
    throw DataError(where_, what_() + ": byte " + std::to_string(at) + " of the message: " + message);
  }

  std::string_view bytes_;
  const Location& where_;
  const Describe& what_;
  bool big_endian_ = false;
  std::size_t max_align_ = 1;  // ROS 1: packed
  std::size_t body_ = 0;
  std::size_t pos_ = 0;
  std::size_t trailing_ = 0;
};

// Header: the stamp (ROS 1 also has seq first; its seconds are unsigned, ROS 2's signed).
std::int64_t header(Cursor& in, Encoding encoding) {
  if (encoding == Encoding::Ros1) in.u32();  // seq
  const std::int64_t stamp = in.stamp_ns(encoding == Encoding::Cdr);
  in.skip_string();  // frame_id
  return stamp;
}

std::array<double, 3> vector3(Cursor& in) {
  std::array<double, 3> v{};
  for (auto& x : v) x = in.f64();
  return v;
}

}  // namespace

std::optional<MessageType> message_type(std::string_view type_name) {
  if (type_name == "sensor_msgs/Imu" || type_name == "sensor_msgs/msg/Imu") return MessageType::Imu;
  if (type_name == "sensor_msgs/Temperature" || type_name == "sensor_msgs/msg/Temperature")
    return MessageType::Temperature;
  if (type_name == "std_msgs/Float32" || type_name == "std_msgs/msg/Float32") return MessageType::Float32;
  if (type_name == "std_msgs/Float64" || type_name == "std_msgs/msg/Float64") return MessageType::Float64;
  return std::nullopt;
}

std::string_view ros1_md5(MessageType type) {
  switch (type) {
    case MessageType::Imu:
      return "6a62c6daae103f4ff57a132d6f95cec2";
    case MessageType::Temperature:
      return "ff71b307acdbe7c871a5a6d7ed359100";
    case MessageType::Float32:
      return "73fcbf46b49191e672908e50842a83d4";
    case MessageType::Float64:
      return "fdb28210bfa9d7c91146260178d9a584";
  }
  return {};
}

Imu decode_imu(std::string_view bytes, Encoding encoding, const Location& where, const Describe& what) {
  Cursor in(bytes, encoding, where, what);
  Imu m;
  m.stamp_ns = header(in, encoding);
  in.skip_f64(4 + kCovarianceSize);  // orientation, its covariance
  m.angular_velocity = vector3(in);
  m.angular_velocity_covariance0 = in.f64();
  in.skip_f64(kCovarianceSize - 1);
  m.linear_acceleration = vector3(in);
  m.linear_acceleration_covariance0 = in.f64();
  in.skip_f64(kCovarianceSize - 1);
  in.finish();
  return m;
}

Temperature decode_temperature(std::string_view bytes, MessageType type, Encoding encoding, const Location& where,
                               const Describe& what) {
  Cursor in(bytes, encoding, where, what);
  Temperature m;
  switch (type) {
    case MessageType::Temperature:
      m.stamp_ns = header(in, encoding);
      m.degc = in.f64();
      in.f64();  // variance
      break;
    case MessageType::Float32:
      m.degc = in.f32();
      break;
    case MessageType::Float64:
      m.degc = in.f64();
      break;
    case MessageType::Imu:
      throw DataError(where, what() + ": an Imu message is not a temperature");
  }
  in.finish();
  return m;
}

}  // namespace driftlab::ros
