#include "tools/driftlab/bag_info.hpp"

#include <algorithm>
#include <cstdio>

#include "framework/ros_imu.hpp"

namespace driftlab::cli {
namespace {

constexpr double kSecondsPerNanosecond = 1e-9;

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

double seconds(std::int64_t ns) { return static_cast<double>(ns) * kSecondsPerNanosecond; }

double rate_hz(std::size_t count, std::int64_t first_ns, std::int64_t last_ns) {
  if (count < 2 || last_ns <= first_ns) return 0.0;
  return static_cast<double>(count - 1) / seconds(last_ns - first_ns);
}

std::string span(const std::vector<std::int64_t>& time_ns) {
  if (time_ns.empty()) return "no messages";
  return std::to_string(time_ns.size()) + " samples at " +
         fixed(rate_hz(time_ns.size(), time_ns.front(), time_ns.back()), 1) + " Hz, " +
         fixed(seconds(time_ns.front()), 3) + " to " + fixed(seconds(time_ns.back()), 3) + " s";
}

}  // namespace

void print_bag_info(const std::string& path, std::ostream& out) {
  std::vector<std::string> notes;
  const ros::ImuStreams s = ros::read_streams(path, "", &notes);
  const rosbag::Bag& bag = s.bag;
  out << path << ": " << bag.container << ", " << bag.bytes << " bytes\n";
  std::int64_t first = 0, last = 0;
  std::uint64_t messages = 0;
  for (const auto& t : bag.topics) {
    if (t.count == 0) continue;
    first = messages == 0 ? t.first_ns : std::min(first, t.first_ns);
    last = messages == 0 ? t.last_ns : std::max(last, t.last_ns);
    messages += t.count;
  }
  out << "messages: " << messages;
  if (messages > 0)
    out << ", " << fixed(seconds(first), 3) << " to " << fixed(seconds(last), 3) << " s ("
        << fixed(seconds(last - first), 3) << " s; the bag's message times, s since the epoch of the recording clock)";
  out << "\ntopics: " << bag.topics.size() << "\n";
  char row[512];
  std::snprintf(row, sizeof row, "  %-36s %-36s %-8s %9s %9s %16s %16s\n", "name", "type", "encoding", "messages",
                "rate Hz", "from s", "to s");
  out << row;
  for (const auto& t : bag.topics) {
    if (t.count == 0)
      std::snprintf(row, sizeof row, "  %-36s %-36s %-8s %9d\n", t.name.c_str(), t.type.c_str(), t.encoding.c_str(), 0);
    else
      std::snprintf(row, sizeof row, "  %-36s %-36s %-8s %9llu %9.1f %16.3f %16.3f\n", t.name.c_str(), t.type.c_str(),
                    t.encoding.c_str(), static_cast<unsigned long long>(t.count),
                    rate_hz(t.count, t.first_ns, t.last_ns), seconds(t.first_ns), seconds(t.last_ns));
    out << row;
  }
  if (s.layout.instances.empty()) {
    out << "IMU: no sensor_msgs/Imu topic\n";
  } else {
    out << "IMU instances (one per sensor_msgs/Imu topic, by name; header stamps in s; temperature in degC):\n";
    for (const auto& instance : s.layout.instances) {
      out << "  instance " << instance.instance << ": " << instance.imu_topic << "\n";
      for (const auto& sensor : s.sensors)
        if (sensor.instance == instance.instance)
          out << "    " << (sensor.sensor == imu::Sensor::Gyro ? "gyro:  " : "accel: ") << span(sensor.time) << "\n";
      const auto t = std::find_if(s.temperatures.begin(), s.temperatures.end(),
                                  [&](const imu::TemperatureStream& x) { return x.instance == instance.instance; });
      if (t == s.temperatures.end()) {
        out << "    temperature: "
            << (instance.temperature_topic.empty() ? "no topic pairs with it"
                                                   : instance.temperature_topic + ", none usable")
            << "\n";
      } else {
        const auto [lo, hi] = std::minmax_element(t->values.begin(), t->values.end());
        out << "    temperature: " << instance.temperature_topic << ", " << span(t->time) << ", " << fixed(*lo, 2)
            << " to " << fixed(*hi, 2) << " degC\n";
      }
    }
  }
  for (const auto& name : s.layout.unpaired_temperatures) out << "unpaired temperature topic: " << name << "\n";
  for (const auto& n : notes) out << "note: " << n << "\n";
}

}  // namespace driftlab::cli
