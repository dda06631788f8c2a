#include "framework/ulog_imu.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

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
// imu_topics() as text: "a, b, ... <last_separator> z".
std::string imu_topic_names(const std::string& last_separator) {
  const auto& topics = imu_topics();
  std::string out;
  for (std::size_t i = 0; i < topics.size(); ++i)
    out += (i == 0 ? "" : i + 1 == topics.size() ? last_separator : ", ") + topics[i];
  return out;
}

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

// One sample per message of `t` at timestamp_sample (else timestamp), repaired (notes naming s.label).
imu::SampleOrder message_order(const Log& log, const Topic& t, const Stream& s, std::vector<std::string>* notes) {
  imu::SampleOrder raw;
  const std::vector<double>* sample_time = t.has_column("timestamp_sample") ? &t.column("timestamp_sample") : nullptr;
  for (std::size_t i = 0; i < t.timestamp_us.size(); ++i) {
    raw.time_us.push_back(imu::time_stamp_us(log.file, s.source,
                                             sample_time ? (*sample_time)[i] : static_cast<double>(t.timestamp_us[i])));
    raw.message.push_back(i);
  }
  imu::repair_order(raw, s.label, notes);
  return raw;
}

// The device id of the stream whose samples come from `messages` of `t` (record order): the first
// one's; a note when it changes. Empty when the topic has no device_id.
std::string stream_device_id(const Topic& t, const std::vector<std::size_t>& messages, const std::string& label,
                             std::vector<std::string>* notes) {
  if (!t.has_column("device_id") || messages.empty()) return {};
  const auto& ids = t.column("device_id");
  const std::string first = device_text(ids[messages.front()]);
  for (const auto i : messages)
    if (ids[i] != ids[messages.front()]) {
      if (notes)
        notes->push_back(label + ": device_id changes within the log (" + first + " to " + device_text(ids[i]) +
                         "); the first is the record's");
      break;
    }
  return first;
}

Stream topic_stream(const Topic& t, imu::Sensor sensor) {
  Stream s;
  s.sensor = sensor;
  s.instance = t.multi_id;
  s.label = t.name + " multi_id " + std::to_string(t.multi_id);
  s.source = t.name + "[" + std::to_string(t.multi_id) + "]";
  return s;
}

// sensor_gyro / sensor_accel, one stream per multi_id.
void sensor_streams(const Log& log, const std::string& topic, imu::Sensor sensor, std::vector<Stream>& out,
                    std::vector<std::string>* notes) {
  for (const auto* t : log.instances(topic)) {
    Stream s = topic_stream(*t, sensor);
    const imu::SampleOrder raw = message_order(log, *t, s, notes);
    s.time = raw.time_us;
    for (int a = 0; a < 3; ++a) {
      const std::string axis(1, kAxes[a]);
      s.axes[a] = imu::pick(log.file, s, field(log, *t, axis), raw, axis);
    }
    if (t->has_column("temperature"))
      s.temperature = imu::pick_temperature(log.file, s, t->column("temperature"), raw, notes);
    s.device_id = stream_device_id(*t, raw.message, s.label, notes);
    out.push_back(std::move(s));
  }
}

// The length of an array field of `t` (FIFO x, y, z); DataError when the format has no such array.
std::size_t array_length(const Log& log, const Topic& t, const std::string& name) {
  for (const auto& f : t.fields)
    if (f.name == name && f.array_length > 0) return f.array_length;
  fail(log, t.name + "." + name,
       "topic '" + t.name + "' multi_id " + std::to_string(t.multi_id) + " has no array field '" + name + "'");
}

// sensor_gyro_fifo / sensor_accel_fifo, one stream per multi_id: sample i of a message with N samples
// at timestamp_sample - (N - 1 - i) dt, rounded to 1 us, its value count * scale.
void fifo_streams(const Log& log, const std::string& topic, imu::Sensor sensor, std::vector<Stream>& out,
                  std::vector<std::string>* notes) {
  for (const auto* t : log.instances(topic)) {
    Stream s = topic_stream(*t, sensor);
    const auto& dt_us = field(log, *t, "dt");
    const auto& scale = field(log, *t, "scale");
    const auto& samples = field(log, *t, "samples");
    const std::vector<double>* sample_time =
        t->has_column("timestamp_sample") ? &t->column("timestamp_sample") : nullptr;
    std::array<std::vector<const std::vector<double>*>, 3> counts;
    for (int a = 0; a < 3; ++a) {
      const std::string axis(1, kAxes[a]);
      const std::size_t length = array_length(log, *t, axis);
      for (std::size_t k = 0; k < length; ++k)
        counts[a].push_back(&field(log, *t, axis + "[" + std::to_string(k) + "]"));
    }
    const std::size_t capacity = std::min({counts[0].size(), counts[1].size(), counts[2].size()});
    const std::vector<double>* rotation = t->has_column("rotation") ? &t->column("rotation") : nullptr;
    imu::SampleOrder raw;
    std::vector<std::size_t> message_of;  // per expanded sample
    std::array<std::vector<double>, 3> values;
    for (std::size_t m = 0; m < t->timestamp_us.size(); ++m) {
      const auto at = [&] { return s.label + " message " + std::to_string(m); };
      if (rotation && (*rotation)[m] != 0.0)
        fail(log, s.source + ".rotation",
             at() + ": rotation " + message_number((*rotation)[m]) +
                 ": the samples are in the sensor's own frame (PX4 rotates them by this enum); only rotation 0 "
                 "(none) is read");
      if (!(samples[m] >= 0.0 && samples[m] <= static_cast<double>(capacity) && samples[m] == std::floor(samples[m])))
        fail(log, s.source + ".samples",
             at() + ": samples " + message_number(samples[m]) + "; expected a whole number up to " +
                 std::to_string(capacity) + ", the format's array length");
      const auto n = static_cast<std::size_t>(samples[m]);
      if (n == 0) continue;
      if (!(std::isfinite(dt_us[m]) && dt_us[m] > 0.0))
        fail(log, s.source + ".dt", at() + ": dt " + message_number(dt_us[m]) + " us; expected a finite interval > 0");
      if (!(std::isfinite(scale[m]) && scale[m] > 0.0))
        fail(log, s.source + ".scale", at() + ": scale " + message_number(scale[m]) + "; expected a finite value > 0");
      const double last = sample_time ? (*sample_time)[m] : static_cast<double>(t->timestamp_us[m]);
      for (std::size_t i = 0; i < n; ++i) {
        const std::int64_t us =
            imu::time_stamp_us(log.file, s.source, std::round(last - static_cast<double>(n - 1 - i) * dt_us[m]));
        if (i > 0 && us <= raw.time_us.back())
          fail(log, s.source + ".dt",
               at() + ": sample " + std::to_string(i) + " at " + std::to_string(us) + " us is not after sample " +
                   std::to_string(i - 1) + " (dt " + message_number(dt_us[m]) + " us, times rounded to 1 us)");
        raw.time_us.push_back(us);
        raw.message.push_back(message_of.size());
        message_of.push_back(m);
        for (int a = 0; a < 3; ++a) values[a].push_back((*counts[a][i])[m] * scale[m]);
      }
    }
    imu::repair_order(raw, s.label, notes);
    s.time = raw.time_us;
    for (int a = 0; a < 3; ++a) s.axes[a] = imu::pick(log.file, s, values[a], raw, std::string(1, kAxes[a]));
    std::vector<std::size_t> messages;
    for (const auto i : raw.message) messages.push_back(message_of[i]);
    s.device_id = stream_device_id(*t, messages, s.label, notes);
    out.push_back(std::move(s));
  }
}

// The temperature of a FIFO stream's device: `topic`'s (sensor_gyro / sensor_accel) instance of the
// same device id, as a temperature stream of the FIFO's instance.
std::optional<imu::TemperatureStream> device_temperature(const Log& log, const std::string& topic, const Stream& fifo,
                                                         std::vector<std::string>* notes) {
  if (fifo.device_id.empty()) return std::nullopt;
  for (const auto* t : log.instances(topic)) {
    if (!t->has_column("temperature")) continue;
    Stream s = topic_stream(*t, fifo.sensor);
    std::vector<std::string> repairs;  // kept only for the topic that is the FIFO's device
    const imu::SampleOrder raw = message_order(log, *t, s, &repairs);
    if (stream_device_id(*t, raw.message, s.label, nullptr) != fifo.device_id) continue;
    if (notes) notes->insert(notes->end(), repairs.begin(), repairs.end());
    auto values = imu::pick_temperature(log.file, s, t->column("temperature"), raw, notes);
    if (values.empty()) return std::nullopt;
    return imu::TemperatureStream{fifo.instance, s.label + " temperature", s.source, raw.time_us, std::move(values)};
  }
  return std::nullopt;
}

// Per instance of the FIFO streams (gyros first), the temperature of its gyro's device from
// sensor_gyro, else of its accelerometer's from sensor_accel; a note for an instance with none.
std::vector<imu::TemperatureStream> fifo_temperatures(const Log& log, const std::vector<Stream>& fifo,
                                                      std::vector<std::string>* notes) {
  std::vector<imu::TemperatureStream> out;
  const auto has = [&](int instance) {
    return std::any_of(out.begin(), out.end(), [&](const auto& t) { return t.instance == instance; });
  };
  for (const auto& s : fifo)
    if (!has(s.instance))
      if (auto t = device_temperature(log, s.sensor == imu::Sensor::Gyro ? "sensor_gyro" : "sensor_accel", s, notes))
        out.push_back(std::move(*t));
  std::vector<int> noted;
  for (const auto& s : fifo)
    if (!has(s.instance) && std::find(noted.begin(), noted.end(), s.instance) == noted.end()) {
      noted.push_back(s.instance);
      if (notes)
        notes->push_back(s.label +
                         ": the FIFO topics carry no temperature and no sensor_gyro / sensor_accel of its device id (" +
                         (s.device_id.empty() ? std::string("none") : s.device_id) +
                         ") has one: no temperature channel for instance " + std::to_string(s.instance));
    }
  return out;
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
  static const std::vector<std::string> topics{"sensor_gyro",       "sensor_accel", "sensor_gyro_fifo",
                                               "sensor_accel_fifo", "vehicle_imu",  "sensor_combined"};
  return topics;
}

TimeSeries imu_record(const Log& log, const LogSelection& selection, std::vector<std::string>* notes) {
  if (!selection.sensor.empty()) imu::parse_selection(selection.sensor, "--sensor");  // reported before the topics
  std::string topic = selection.topic;
  if (topic.empty()) {
    const auto has = [&](const char* name) { return !log.instances(name).empty(); };
    if (has("sensor_gyro") || has("sensor_accel")) {
      topic = "sensor";
    } else if (has("sensor_gyro_fifo") || has("sensor_accel_fifo")) {
      topic = "fifo";
    } else if (has("vehicle_imu")) {
      topic = "vehicle_imu";
    } else if (log.find("sensor_combined", 0)) {
      topic = "sensor_combined";
    } else {
      fail(log, "--topic", "no IMU topic in the log (looked for " + imu_topic_names(", ") + ")");
    }
  } else if (std::find(imu_topics().begin(), imu_topics().end(), topic) == imu_topics().end()) {
    throw ConfigError({"", 0, "--topic"}, "'" + topic + "': a ULog's IMU is read from " + imu_topic_names(" or "));
  } else if (log.instances(topic).empty()) {
    fail(log, "--topic", "topic '" + topic + "' is not in the log (IMU topics it has: " + imu_topic_list(log) + ")");
  }

  std::vector<Stream> all;
  std::vector<imu::TemperatureStream> temperatures;
  if (topic == "sensor" || topic == "sensor_gyro") sensor_streams(log, "sensor_gyro", imu::Sensor::Gyro, all, notes);
  if (topic == "sensor" || topic == "sensor_accel") sensor_streams(log, "sensor_accel", imu::Sensor::Accel, all, notes);
  if (topic == "fifo" || topic == "sensor_gyro_fifo")
    fifo_streams(log, "sensor_gyro_fifo", imu::Sensor::Gyro, all, notes);
  if (topic == "fifo" || topic == "sensor_accel_fifo")
    fifo_streams(log, "sensor_accel_fifo", imu::Sensor::Accel, all, notes);
  if (topic == "fifo" || topic == "sensor_gyro_fifo" || topic == "sensor_accel_fifo")
    temperatures = fifo_temperatures(log, all, notes);
  if (topic == "vehicle_imu") integrated_streams(log, all, notes);
  if (topic == "sensor_combined") combined_streams(log, all, notes);

  return imu::assemble(std::move(all), std::move(temperatures), selection, imu::kMicrosecondsPerSecond, log.file,
                       notes);
}

TimeSeries read_imu(const std::filesystem::path& path, const LogSelection& selection, std::vector<std::string>* notes) {
  ReadOptions options;
  options.keep_topics = imu_topics();
  return imu_record(read(path, options), selection, notes);
}

}  // namespace driftlab::ulog
