#include "framework/ros_imu.hpp"

#include <algorithm>
#include <cctype>
#include <map>
#include <optional>

#include "framework/error.hpp"
#include "framework/ros_messages.hpp"

namespace driftlab::ros {
namespace {

constexpr std::int64_t kNanosecondsPerSecond = 1000000000;

std::string namespace_of(const std::string& topic) {
  const auto slash = topic.find_last_of('/');
  return slash == std::string::npos ? "" : topic.substr(0, slash);
}

std::string last_part(const std::string& topic) {
  const auto slash = topic.find_last_of('/');
  return slash == std::string::npos ? topic : topic.substr(slash + 1);
}

bool is_imu(const rosbag::Topic& t) { return message_type(t.type) == MessageType::Imu; }

bool is_temperature(const rosbag::Topic& t, bool named) {
  const auto type = message_type(t.type);
  if (type == MessageType::Temperature) return true;
  if (type != MessageType::Float32 && type != MessageType::Float64) return false;
  if (named) return true;
  std::string name = last_part(t.name);
  std::transform(name.begin(), name.end(), name.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return name.find("temp") != std::string::npos;
}

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    const auto comma = text.find(',', start);
    const auto end = comma == std::string::npos ? text.size() : comma;
    if (end > start) out.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  return out;
}

std::string topic_list(const rosbag::Bag& bag) {
  std::string out;
  for (const auto& t : bag.topics) out += (out.empty() ? "" : ", ") + t.name + " (" + t.type + ")";
  return out.empty() ? "none" : out;
}

std::string imu_topic_list(const rosbag::Bag& bag) {
  std::string out;
  for (const auto& t : bag.topics)
    if (is_imu(t)) out += (out.empty() ? "" : ", ") + t.name;
  return out.empty() ? "none" : out;
}

// md5 and encoding of a topic the decoders will read; DataError when they cannot.
Encoding encoding_of(const std::string& file, const rosbag::Topic& t) {
  if (t.encoding != "ros1" && t.encoding != "cdr")
    throw DataError({file, 0, t.name}, "topic '" + t.name + "' is encoded as " + quoted_excerpt(t.encoding, 40) +
                                           "; driftlab decodes ros1 and cdr messages");
  const auto type = message_type(t.type);
  if (t.encoding == "ros1" && !t.md5.empty() && type && t.md5 != ros1_md5(*type))
    throw DataError({file, 0, t.name}, "topic '" + t.name + "': " + t.type + " with md5sum " + t.md5 +
                                           " is another version of the message than the one driftlab reads (md5sum " +
                                           std::string(ros1_md5(*type)) + ")");
  return t.encoding == "ros1" ? Encoding::Ros1 : Encoding::Cdr;
}

// Raw samples of one topic in message order.
struct Raw {
  const rosbag::Topic* topic = nullptr;
  std::optional<DataError> error;
  Location where;  // of its messages' errors: the file and the topic
  Encoding encoding = Encoding::Cdr;
  int instance = 0;
  std::vector<std::int64_t> stamp, time;  // header stamp, message time
  std::vector<std::array<double, 3>> gyro, accel;
  std::vector<double> gyro_cov0, accel_cov0, values;
};

std::vector<std::int64_t> stamps(Raw& r, std::vector<std::string>* notes) {
  const bool empty_headers =
      !r.stamp.empty() && std::all_of(r.stamp.begin(), r.stamp.end(), [](std::int64_t s) { return s == 0; });
  if (!empty_headers) return r.stamp;
  if (notes) notes->push_back(r.topic->name + ": every header stamp is 0; the bag's message times are used instead");
  return r.time;
}

void check_value(const std::string& file, const Raw& r, const std::string& part, int axis, double v,
                 std::int64_t stamp) {
  if (imu::usable_value(v)) return;
  throw DataError({file, 0, r.topic->name + "." + part + "." + "xyz"[axis]},
                  imu::unusable_value(v) + " at stamp " + std::to_string(stamp) + " ns");
}

void add_sensor(const std::string& file, const Raw& r, imu::Sensor sensor, const std::vector<std::int64_t>& time,
                const std::vector<std::size_t>& order, std::vector<imu::SensorStream>& out,
                std::vector<std::string>* notes) {
  const bool gyro = sensor == imu::Sensor::Gyro;
  const auto& values = gyro ? r.gyro : r.accel;
  const auto& cov0 = gyro ? r.gyro_cov0 : r.accel_cov0;
  const std::string part = gyro ? "angular_velocity" : "linear_acceleration";
  if (!cov0.empty() && std::all_of(cov0.begin(), cov0.end(), [](double c) { return c == -1.0; })) {
    if (notes)
      notes->push_back(r.topic->name + ": " + part + "_covariance[0] is -1 in every message (not provided); no " +
                       imu::to_string(sensor) + " from it");
    return;
  }
  imu::SensorStream s;
  s.sensor = sensor;
  s.instance = r.instance;
  s.label = r.topic->name + " " + part;
  s.source = r.topic->name;
  for (const auto i : order) {
    s.time.push_back(time[i]);
    for (int a = 0; a < 3; ++a) {
      check_value(file, r, part, a, values[i][static_cast<std::size_t>(a)], time[i]);
      s.axes[static_cast<std::size_t>(a)].push_back(values[i][static_cast<std::size_t>(a)]);
    }
  }
  out.push_back(std::move(s));
}

}  // namespace

ImuLayout imu_layout(const rosbag::Bag& bag, const std::string& topic_option) {
  ImuLayout layout;
  std::vector<const rosbag::Topic*> imus, temperatures;
  if (topic_option.empty()) {
    for (const auto& t : bag.topics) {  // sorted by name
      if (is_imu(t))
        imus.push_back(&t);
      else if (is_temperature(t, false))
        temperatures.push_back(&t);
    }
  } else {
    for (const auto& name : split(topic_option)) {
      const rosbag::Topic* t = bag.find(name);
      if (!t)
        throw DataError({bag.file, 0, "--topic"},
                        "topic '" + name + "' is not in the bag (IMU topics it has: " + imu_topic_list(bag) + ")");
      if (is_imu(*t))
        imus.push_back(t);
      else if (is_temperature(*t, true))
        temperatures.push_back(t);
      else
        throw DataError({bag.file, 0, "--topic"}, "topic '" + name + "' is " + t->type +
                                                      ", neither an IMU (sensor_msgs/Imu) nor a temperature topic");
    }
    if (imus.empty())
      throw DataError({bag.file, 0, "--topic"},
                      "--topic names no sensor_msgs/Imu topic (IMU topics: " + imu_topic_list(bag) + ")");
  }
  for (std::size_t i = 0; i < imus.size(); ++i) layout.instances.push_back({static_cast<int>(i), imus[i]->name, ""});
  for (const auto* t : temperatures) {
    std::vector<ImuInstance*> matches;
    for (auto& instance : layout.instances)
      if (namespace_of(instance.imu_topic) == namespace_of(t->name)) matches.push_back(&instance);
    if (matches.empty() && !topic_option.empty() && layout.instances.size() == 1)
      matches.push_back(&layout.instances.front());
    if (matches.size() == 1 && matches.front()->temperature_topic.empty())
      matches.front()->temperature_topic = t->name;
    else
      layout.unpaired_temperatures.push_back(t->name);
  }
  return layout;
}

ImuStreams read_streams(const std::filesystem::path& path, const std::string& topic_option,
                        std::vector<std::string>* notes) {
  // One pass: every topic that may become an instance or its temperature is decoded as it comes; a
  // topic's decoding error is kept and thrown only if the layout then selects the topic.
  const std::vector<std::string> listed = split(topic_option);
  std::map<std::string, Raw> raw;
  ImuStreams out;
  const std::string file = path.string();
  out.bag = rosbag::read(
      path,
      [&](const rosbag::Topic& t) {
        if (!message_type(t.type)) return false;
        return listed.empty() || std::find(listed.begin(), listed.end(), t.name) != listed.end();
      },
      [&](const rosbag::Message& m) {
        Raw& r = raw[m.topic->name];
        if (r.error) return;
        try {
          if (!r.topic) {
            r.topic = m.topic;
            r.encoding = encoding_of(file, *m.topic);
            r.where = {file, 0, m.topic->name};
          }
          const auto type = *message_type(m.topic->type);
          if (type == MessageType::Imu) {
            const Imu imu = decode_imu(m.data, r.encoding, r.where, m.where);
            r.stamp.push_back(imu.stamp_ns);
            r.gyro.push_back(imu.angular_velocity);
            r.accel.push_back(imu.linear_acceleration);
            r.gyro_cov0.push_back(imu.angular_velocity_covariance0);
            r.accel_cov0.push_back(imu.linear_acceleration_covariance0);
          } else {
            const Temperature temperature = decode_temperature(m.data, type, r.encoding, r.where, m.where);
            r.stamp.push_back(temperature.stamp_ns.value_or(m.time_ns));
            r.values.push_back(temperature.degc);
          }
          r.time.push_back(m.time_ns);
        } catch (const DataError& e) {
          r.error = e;
        }
      });
  out.layout = imu_layout(out.bag, topic_option);
  for (const auto& name : out.layout.unpaired_temperatures)
    if (notes)
      notes->push_back(
          name + ": a temperature topic that pairs with no IMU topic by namespace; name both with --topic to use it");

  for (const auto& instance : out.layout.instances) {
    for (const auto& name : {instance.imu_topic, instance.temperature_topic}) {
      if (name.empty()) continue;
      Raw& r = raw[name];
      if (r.error) throw *r.error;
      const rosbag::Topic* topic = out.bag.find(name);
      encoding_of(file, *topic);  // a topic without messages is checked too
      r.topic = topic;
      r.instance = instance.instance;
      const std::vector<std::int64_t> time = stamps(r, notes);
      const auto order = imu::repaired_order(time, name, notes);
      if (name == instance.imu_topic) {
        add_sensor(file, r, imu::Sensor::Gyro, time, order, out.sensors, notes);
        add_sensor(file, r, imu::Sensor::Accel, time, order, out.sensors, notes);
        continue;
      }
      imu::TemperatureStream t{r.instance, name, name, {}, {}};
      for (const auto i : order) {
        t.time.push_back(time[i]);
        t.values.push_back(r.values[i]);
      }
      imu::check_temperature(t.values, file, name, name, notes);
      if (!t.values.empty()) out.temperatures.push_back(std::move(t));
    }
  }
  return out;
}

TimeSeries read_imu(const std::filesystem::path& path, const LogSelection& selection, std::vector<std::string>* notes) {
  if (!selection.sensor.empty()) imu::parse_selection(selection.sensor, "--sensor");  // reported before the bag is read
  ImuStreams s = read_streams(path, selection.topic, notes);
  if (s.layout.instances.empty())
    throw DataError({s.bag.file, 0, "--topic"}, "no sensor_msgs/Imu topic in the bag (its " +
                                                    std::to_string(s.bag.topics.size()) +
                                                    " topics: " + topic_list(s.bag) + ")");
  return imu::assemble(std::move(s.sensors), std::move(s.temperatures), selection, kNanosecondsPerSecond, s.bag.file,
                       notes);
}

}  // namespace driftlab::ros
