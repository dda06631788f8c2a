#include "framework/ulog_imu.hpp"

#include <algorithm>
#include <cmath>

#include "framework/error.hpp"
#include "framework/imu_streams.hpp"

namespace driftlab::ulog {
namespace {

constexpr std::int32_t kRelativeTimestampInvalid = 0x7fffffff;  // PX4's RELATIVE_TIMESTAMP_INVALID
constexpr char kAxes[3] = {'x', 'y', 'z'};
using Stream = imu::SensorStream;

[[noreturn]] void fail(const Log& log, const std::string& field, const std::string& message) {
  throw DataError({log.file, 0, field}, message);
}

// "sensor_gyro[0], sensor_gyro[1], ..." of the IMU topics in the log.
std::string imu_topic_list(const Log& log) {
  std::string out;
  for (const auto& name : imu_topics())
    for (const auto* t : log.instances(name))
      out += (out.empty() ? "" : ", ") + t->name + "[" + std::to_string(t->multi_id) + "]";
  return out.empty() ? "none" : out;
}

// A field's values, DataError naming the file when the topic's format lacks it.
const std::vector<double>& field(const Log& log, const Topic& t, const std::string& name) {
  if (!t.has_column(name))
    fail(log, t.name + "." + name,
         "topic '" + t.name + "' multi_id " + std::to_string(t.multi_id) + " has no field '" + name + "'");
  return t.column(name);
}

std::string device_text(double id) { return std::to_string(static_cast<std::uint64_t>(id)); }

// sensor_gyro / sensor_accel, one stream per multi_id.
void sensor_streams(const Log& log, const std::string& topic, imu::Sensor sensor, std::vector<Stream>& out,
                    std::vector<std::string>* notes) {
  for (const auto* t : log.instances(topic)) {
    Stream s;
    s.sensor = sensor;
    s.instance = t->multi_id;
    s.label = topic + " multi_id " + std::to_string(t->multi_id);
    s.source = topic + "[" + std::to_string(t->multi_id) + "]";
    imu::SampleOrder raw;
    const std::vector<double>* sample_time =
        t->has_column("timestamp_sample") ? &t->column("timestamp_sample") : nullptr;
    for (std::size_t i = 0; i < t->timestamp_us.size(); ++i) {
      raw.time_us.push_back(imu::time_stamp_us(
          log.file, s.source, sample_time ? (*sample_time)[i] : static_cast<double>(t->timestamp_us[i])));
      raw.message.push_back(i);
    }
    imu::repair_order(raw, s.label, notes);
    s.time = raw.time_us;
    for (int a = 0; a < 3; ++a) {
      const std::string axis(1, kAxes[a]);
      s.axes[a] = imu::pick(log.file, s, field(log, *t, axis), raw, axis);
    }
    if (t->has_column("temperature"))
      s.temperature = imu::pick_temperature(log.file, s, t->column("temperature"), raw, notes);
    if (t->has_column("device_id") && !raw.message.empty()) {
      const auto& ids = t->column("device_id");
      s.device_id = device_text(ids[raw.message.front()]);
      for (const auto i : raw.message)
        if (ids[i] != ids[raw.message.front()]) {
          if (notes)
            notes->push_back(s.label + ": device_id changes within the log (" + s.device_id + " to " +
                             device_text(ids[i]) + "); the first is the record's");
          break;
        }
    }
    out.push_back(std::move(s));
  }
}

// sensor_combined multi_id 0: a gyro stream and an accelerometer stream.
void combined_streams(const Log& log, std::vector<Stream>& out, std::vector<std::string>* notes) {
  const Topic* t = log.find("sensor_combined", 0);
  if (!t) return;
  const std::string label = "sensor_combined multi_id 0";
  {
    Stream s{imu::Sensor::Gyro, 0, label + " gyro", "sensor_combined[0]", {}, {}, {}, {}};
    imu::SampleOrder raw;
    for (std::size_t i = 0; i < t->timestamp_us.size(); ++i) {
      raw.time_us.push_back(imu::time_stamp_us(log.file, s.source, static_cast<double>(t->timestamp_us[i])));
      raw.message.push_back(i);
    }
    imu::repair_order(raw, s.label, notes);
    s.time = raw.time_us;
    for (int a = 0; a < 3; ++a) {
      const std::string name = "gyro_rad[" + std::to_string(a) + "]";
      s.axes[a] = imu::pick(log.file, s, field(log, *t, name), raw, name);
    }
    out.push_back(std::move(s));
  }
  {
    Stream s{imu::Sensor::Accel, 0, label + " accelerometer", "sensor_combined[0]", {}, {}, {}, {}};
    imu::SampleOrder raw;
    const auto& relative = field(log, *t, "accelerometer_timestamp_relative");
    std::size_t invalid = 0;
    for (std::size_t i = 0; i < t->timestamp_us.size(); ++i) {
      if (relative[i] == static_cast<double>(kRelativeTimestampInvalid)) {
        ++invalid;
        continue;
      }
      raw.time_us.push_back(
          imu::time_stamp_us(log.file, s.source, static_cast<double>(t->timestamp_us[i]) + relative[i]));
      raw.message.push_back(i);
    }
    if (notes && invalid > 0)
      notes->push_back(s.label + ": " + std::to_string(invalid) +
                       " samples with an invalid relative time stamp left out");
    imu::repair_order(raw, s.label, notes);
    s.time = raw.time_us;
    for (int a = 0; a < 3; ++a) {
      const std::string name = "accelerometer_m_s2[" + std::to_string(a) + "]";
      s.axes[a] = imu::pick(log.file, s, field(log, *t, name), raw, name);
    }
    out.push_back(std::move(s));
  }
  if (notes) notes->push_back("sensor_combined carries no IMU temperature: the record has no temperature channel");
}

// vehicle_imu, one gyro and one accelerometer stream per multi_id: the mean rate over each
// integration period, delta / dt, at the period's midpoint timestamp_sample - dt / 2.
void integrated_streams(const Log& log, std::vector<Stream>& out, std::vector<std::string>* notes) {
  for (const auto* t : log.instances("vehicle_imu")) {
    const std::string id = std::to_string(t->multi_id);
    const auto& sample_time = t->has_column("timestamp_sample") ? t->column("timestamp_sample") : std::vector<double>{};
    for (const auto sensor : {imu::Sensor::Gyro, imu::Sensor::Accel}) {
      const bool gyro = sensor == imu::Sensor::Gyro;
      const std::string delta = gyro ? "delta_angle" : "delta_velocity";
      Stream s;
      s.sensor = sensor;
      s.instance = t->multi_id;
      s.label = "vehicle_imu multi_id " + id + (gyro ? " gyro" : " accelerometer");
      s.source = "vehicle_imu[" + id + "]";
      const auto& dt_us = field(log, *t, delta + "_dt");
      imu::SampleOrder raw;
      std::size_t empty = 0;
      for (std::size_t i = 0; i < t->timestamp_us.size(); ++i) {
        if (!(dt_us[i] > 0.0)) {
          ++empty;
          continue;
        }
        const double end = sample_time.empty() ? static_cast<double>(t->timestamp_us[i]) : sample_time[i];
        raw.time_us.push_back(imu::time_stamp_us(log.file, s.source, std::round(end - dt_us[i] / 2.0)));
        raw.message.push_back(i);
      }
      if (notes && empty > 0)
        notes->push_back(s.label + ": " + std::to_string(empty) + " samples with an empty integration period left out");
      imu::repair_order(raw, s.label, notes);
      s.time = raw.time_us;
      for (int a = 0; a < 3; ++a) {
        const std::string name = delta + "[" + std::to_string(a) + "]";
        const auto& d = field(log, *t, name);
        std::vector<double> rate(d.size());
        for (std::size_t i = 0; i < d.size(); ++i) rate[i] = d[i] / (dt_us[i] / imu::kMicrosecondsPerSecond);
        s.axes[a] = imu::pick(log.file, s, rate, raw, name);
      }
      const std::string device = gyro ? "gyro_device_id" : "accel_device_id";
      if (t->has_column(device) && !raw.message.empty())
        s.device_id = device_text(t->column(device)[raw.message.front()]);
      out.push_back(std::move(s));
    }
  }
  if (notes && !out.empty())
    notes->push_back("vehicle_imu carries no IMU temperature: the record has no temperature channel");
}

}  // namespace

const std::vector<std::string>& imu_topics() {
  static const std::vector<std::string> topics{"sensor_gyro", "sensor_accel", "vehicle_imu", "sensor_combined"};
  return topics;
}

TimeSeries imu_record(const Log& log, const LogSelection& selection, std::vector<std::string>* notes) {
  if (!selection.sensor.empty()) imu::parse_selection(selection.sensor, "--sensor");  // reported before the topics
  std::string topic = selection.topic;
  if (topic.empty()) {
    const bool has_sensor_topics = !log.instances("sensor_gyro").empty() || !log.instances("sensor_accel").empty();
    if (has_sensor_topics) {
      topic = "sensor";
    } else if (!log.instances("vehicle_imu").empty()) {
      topic = "vehicle_imu";
    } else if (log.find("sensor_combined", 0)) {
      topic = "sensor_combined";
    } else {
      fail(log, "--topic",
           "no IMU topic in the log (looked for sensor_gyro, sensor_accel, vehicle_imu, sensor_combined)");
    }
  } else if (std::find(imu_topics().begin(), imu_topics().end(), topic) == imu_topics().end()) {
    throw ConfigError(
        {"", 0, "--topic"},
        "'" + topic + "': a ULog's IMU is read from sensor_gyro, sensor_accel, vehicle_imu or sensor_combined");
  } else if (log.instances(topic).empty()) {
    fail(log, "--topic", "topic '" + topic + "' is not in the log (IMU topics it has: " + imu_topic_list(log) + ")");
  }

  std::vector<Stream> all;
  if (topic == "sensor" || topic == "sensor_gyro") sensor_streams(log, "sensor_gyro", imu::Sensor::Gyro, all, notes);
  if (topic == "sensor" || topic == "sensor_accel") sensor_streams(log, "sensor_accel", imu::Sensor::Accel, all, notes);
  if (topic == "vehicle_imu") integrated_streams(log, all, notes);
  if (topic == "sensor_combined") combined_streams(log, all, notes);

  return imu::assemble(std::move(all), {}, selection, imu::kMicrosecondsPerSecond, log.file, notes);
}

TimeSeries read_imu(const std::filesystem::path& path, const LogSelection& selection, std::vector<std::string>* notes) {
  ReadOptions options;
  options.keep_topics = imu_topics();
  return imu_record(read(path, options), selection, notes);
}

}  // namespace driftlab::ulog
