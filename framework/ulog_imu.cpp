#include "framework/ulog_imu.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <optional>

#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/imu.hpp"

namespace driftlab::ulog {
namespace {

constexpr double kMicrosecondsPerSecond = 1e6;  // divided by: 22311243 us -> 22.311243 s exactly rounded
constexpr std::int32_t kRelativeTimestampInvalid = 0x7fffffff;  // PX4's RELATIVE_TIMESTAMP_INVALID
constexpr int kMaxInstance = 99;                                  // imu role names: gyro1_x .. gyro99_x
constexpr char kAxes[3] = {'x', 'y', 'z'};

// One sensor of one instance, repaired: strictly increasing time stamps.
struct Stream {
  imu::Sensor sensor = imu::Sensor::Gyro;
  int instance = 0;
  std::string label;   // "sensor_gyro multi_id 1", for notes and errors
  std::string source;  // "sensor_gyro[1]", the channels' source
  std::vector<std::int64_t> time_us;
  std::array<std::vector<double>, 3> axes;
  std::vector<double> temperature;  // empty: none
  std::string device_id;            // empty: none
};

// Raw samples of a stream before repair: time and the message index they come from.
struct Raw {
  std::vector<std::int64_t> time_us;
  std::vector<std::size_t> message;
};

[[noreturn]] void fail(const Log& log, const std::string& field, const std::string& message) {
  throw DataError({log.file, 0, field}, message);
}

// "sensor_gyro[0], sensor_gyro[1], ..." of the IMU topics in the log.
std::string imu_topic_list(const Log& log) {
  std::string out;
  for (const auto& name : imu_topics())
    for (const auto* t : log.instances(name)) out += (out.empty() ? "" : ", ") + t->name + "[" + std::to_string(t->multi_id) + "]";
  return out.empty() ? "none" : out;
}

// A field's values, DataError naming the file when the topic's format lacks it.
const std::vector<double>& field(const Log& log, const Topic& t, const std::string& name) {
  if (!t.has_column(name))
    fail(log, t.name + "." + name, "topic '" + t.name + "' multi_id " + std::to_string(t.multi_id) + " has no field '" + name + "'");
  return t.column(name);
}

// A time stamp in us as int64: DataError beyond 2^53 us (285 years; the arithmetic stays exact).
std::int64_t time_stamp(const Log& log, const std::string& source, double us) {
  constexpr double kMaxTimeUs = 9007199254740992.0;
  if (!(us >= 0.0 && us <= kMaxTimeUs))
    fail(log, source, "time stamp " + std::to_string(us) + " us is outside 0 to 2^53 us");
  return static_cast<std::int64_t>(us);
}

// Sorts `raw` by time (stable) and drops repeated time stamps, keeping the first; notes the counts.
void repair_order(Raw& raw, const std::string& label, std::vector<std::string>* notes) {
  std::size_t out_of_order = 0;
  for (std::size_t i = 1; i < raw.time_us.size(); ++i) out_of_order += raw.time_us[i] < raw.time_us[i - 1];
  std::vector<std::size_t> order(raw.time_us.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  if (out_of_order > 0)
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return raw.time_us[a] < raw.time_us[b]; });
  Raw repaired;
  std::size_t duplicates = 0;
  for (const auto i : order) {
    if (!repaired.time_us.empty() && repaired.time_us.back() == raw.time_us[i]) {
      ++duplicates;
      continue;
    }
    repaired.time_us.push_back(raw.time_us[i]);
    repaired.message.push_back(raw.message[i]);
  }
  if (notes && out_of_order > 0)
    notes->push_back(label + ": " + std::to_string(out_of_order) + " samples earlier than the one before; sorted by time");
  if (notes && duplicates > 0)
    notes->push_back(label + ": " + std::to_string(duplicates) + " repeated time stamps; the first sample of each kept");
  raw = std::move(repaired);
}

std::vector<double> pick(const Log& log, const Stream& s, const std::vector<double>& values, const Raw& raw,
                         const std::string& field) {
  std::vector<double> out(raw.message.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i] = values[raw.message[i]];
    if (!std::isfinite(out[i]) || std::abs(out[i]) > kMaxMagnitude)
      fail(log, s.source + "." + field,
           (std::isfinite(out[i]) ? "value beyond 1e100" : "non-finite value") + std::string(" at time stamp ") +
               std::to_string(raw.time_us[i]) + " us (" + s.label + ")");
  }
  return out;
}

std::string device_text(double id) { return std::to_string(static_cast<std::uint64_t>(id)); }

// The temperature of a stream: all finite, or all NaN (left out with a note); else DataError.
std::vector<double> temperature(const Log& log, const Stream& s, const std::vector<double>& values, const Raw& raw,
                                std::vector<std::string>* notes) {
  std::vector<double> out(raw.message.size());
  std::size_t missing = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i] = values[raw.message[i]];
    missing += !std::isfinite(out[i]) || std::abs(out[i]) > kMaxMagnitude;
  }
  if (missing == out.size()) {
    if (notes) notes->push_back(s.label + ": temperature is NaN throughout; no temperature channel for it");
    return {};
  }
  if (missing > 0)
    fail(log, s.source + ".temperature",
         std::to_string(missing) + " of " + std::to_string(out.size()) + " temperatures are not finite (" + s.label + ")");
  return out;
}

// sensor_gyro / sensor_accel, one stream per multi_id.
void sensor_streams(const Log& log, const std::string& topic, imu::Sensor sensor, std::vector<Stream>& out,
                    std::vector<std::string>* notes) {
  for (const auto* t : log.instances(topic)) {
    Stream s;
    s.sensor = sensor;
    s.instance = t->multi_id;
    s.label = topic + " multi_id " + std::to_string(t->multi_id);
    s.source = topic + "[" + std::to_string(t->multi_id) + "]";
    Raw raw;
    const std::vector<double>* sample_time = t->has_column("timestamp_sample") ? &t->column("timestamp_sample") : nullptr;
    for (std::size_t i = 0; i < t->timestamp_us.size(); ++i) {
      raw.time_us.push_back(time_stamp(log, s.source, sample_time ? (*sample_time)[i] : static_cast<double>(t->timestamp_us[i])));
      raw.message.push_back(i);
    }
    repair_order(raw, s.label, notes);
    s.time_us = raw.time_us;
    for (int a = 0; a < 3; ++a) {
      const std::string axis(1, kAxes[a]);
      s.axes[a] = pick(log, s, field(log, *t, axis), raw, axis);
    }
    if (t->has_column("temperature")) s.temperature = temperature(log, s, t->column("temperature"), raw, notes);
    if (t->has_column("device_id") && !raw.message.empty()) {
      const auto& ids = t->column("device_id");
      s.device_id = device_text(ids[raw.message.front()]);
      for (const auto i : raw.message)
        if (ids[i] != ids[raw.message.front()]) {
          if (notes) notes->push_back(s.label + ": device_id changes within the log (" + s.device_id + " to " +
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
    Raw raw;
    for (std::size_t i = 0; i < t->timestamp_us.size(); ++i) {
      raw.time_us.push_back(time_stamp(log, s.source, static_cast<double>(t->timestamp_us[i])));
      raw.message.push_back(i);
    }
    repair_order(raw, s.label, notes);
    s.time_us = raw.time_us;
    for (int a = 0; a < 3; ++a) {
      const std::string name = "gyro_rad[" + std::to_string(a) + "]";
      s.axes[a] = pick(log, s, field(log, *t, name), raw, name);
    }
    out.push_back(std::move(s));
  }
  {
    Stream s{imu::Sensor::Accel, 0, label + " accelerometer", "sensor_combined[0]", {}, {}, {}, {}};
    Raw raw;
    const auto& relative = field(log, *t, "accelerometer_timestamp_relative");
    std::size_t invalid = 0;
    for (std::size_t i = 0; i < t->timestamp_us.size(); ++i) {
      if (relative[i] == static_cast<double>(kRelativeTimestampInvalid)) {
        ++invalid;
        continue;
      }
      raw.time_us.push_back(time_stamp(log, s.source, static_cast<double>(t->timestamp_us[i]) + relative[i]));
      raw.message.push_back(i);
    }
    if (notes && invalid > 0)
      notes->push_back(s.label + ": " + std::to_string(invalid) + " samples with an invalid relative time stamp left out");
    repair_order(raw, s.label, notes);
    s.time_us = raw.time_us;
    for (int a = 0; a < 3; ++a) {
      const std::string name = "accelerometer_m_s2[" + std::to_string(a) + "]";
      s.axes[a] = pick(log, s, field(log, *t, name), raw, name);
    }
    out.push_back(std::move(s));
  }
  if (notes) notes->push_back("sensor_combined carries no IMU temperature: the record has no temperature channel");
}

// Values of `s` at the times `base` (all within s's span), linear between its samples.
Eigen::VectorXd resample(const std::vector<std::int64_t>& time_us, const std::vector<double>& values,
                         const std::vector<std::int64_t>& base) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(base.size()));
  std::size_t j = 0;
  for (std::size_t i = 0; i < base.size(); ++i) {
    const std::int64_t t = base[i];
    while (j + 1 < time_us.size() && time_us[j + 1] <= t) ++j;
    double v = values[j];
    if (time_us[j] != t && j + 1 < time_us.size())
      v += (values[j + 1] - values[j]) * static_cast<double>(t - time_us[j]) / static_cast<double>(time_us[j + 1] - time_us[j]);
    out[static_cast<Eigen::Index>(i)] = v;
  }
  return out;
}

bool selects_any_axis(const imu::Selection& sel, imu::Sensor sensor, int instance) {
  return std::any_of(std::begin(kAxes), std::end(kAxes), [&](char axis) { return sel.selects({sensor, axis, instance}); });
}

}  // namespace

const std::vector<std::string>& imu_topics() {
  static const std::vector<std::string> topics{"sensor_gyro", "sensor_accel", "sensor_combined"};
  return topics;
}

TimeSeries imu_record(const Log& log, const LogSelection& selection, std::vector<std::string>* notes) {
  const imu::Selection sel = selection.sensor.empty() ? imu::Selection{} : imu::parse_selection(selection.sensor, "--sensor");
  std::string topic = selection.topic;
  if (topic.empty()) {
    const bool has_sensor_topics = !log.instances("sensor_gyro").empty() || !log.instances("sensor_accel").empty();
    if (has_sensor_topics) {
      topic = "sensor";
    } else if (log.find("sensor_combined", 0)) {
      topic = "sensor_combined";
    } else {
      fail(log, "--topic", "no IMU topic in the log (looked for sensor_gyro, sensor_accel, sensor_combined)");
    }
  } else if (std::find(imu_topics().begin(), imu_topics().end(), topic) == imu_topics().end()) {
    throw ConfigError({"", 0, "--topic"}, "'" + topic + "': a ULog's IMU is read from sensor_gyro, sensor_accel or sensor_combined");
  } else if (log.instances(topic).empty()) {
    fail(log, "--topic", "topic '" + topic + "' is not in the log (IMU topics it has: " + imu_topic_list(log) + ")");
  }

  std::vector<Stream> all;
  if (topic == "sensor" || topic == "sensor_gyro") sensor_streams(log, "sensor_gyro", imu::Sensor::Gyro, all, notes);
  if (topic == "sensor" || topic == "sensor_accel") sensor_streams(log, "sensor_accel", imu::Sensor::Accel, all, notes);
  if (topic == "sensor_combined") combined_streams(log, all, notes);

  std::vector<Stream> streams;
  for (auto& s : all) {
    if (selection.instance >= 0 && s.instance != selection.instance) continue;
    if (!selects_any_axis(sel, s.sensor, s.instance)) continue;
    if (s.instance > kMaxInstance)
      fail(log, s.source, "instance " + std::to_string(s.instance) + " is beyond the IMU role names (0 to 99)");
    if (s.time_us.size() < 2)
      fail(log, s.source, s.label + " has " + std::to_string(s.time_us.size()) + " samples; a record needs at least 2");
    streams.push_back(std::move(s));
  }
  if (streams.empty()) {
    std::string have;
    for (const auto& s : all) have += (have.empty() ? "" : ", ") + s.label;
    fail(log, selection.instance >= 0 ? "--instance" : "--sensor",
         "the selection (instance " + (selection.instance >= 0 ? std::to_string(selection.instance) : std::string("any")) +
             ", sensor '" + (selection.sensor.empty() ? std::string("all") : selection.sensor) +
             "') matches no stream of the log (it has: " + (have.empty() ? std::string("none") : have) + ")");
  }
  // Gyros first, then accelerometers; by instance within each.
  std::stable_sort(streams.begin(), streams.end(), [](const Stream& a, const Stream& b) {
    return std::pair(a.sensor != imu::Sensor::Gyro, a.instance) < std::pair(b.sensor != imu::Sensor::Gyro, b.instance);
  });

  std::int64_t from = streams.front().time_us.front(), to = streams.front().time_us.back();
  for (const auto& s : streams) {
    from = std::max(from, s.time_us.front());
    to = std::min(to, s.time_us.back());
  }
  const Stream& base = streams.front();
  std::vector<std::int64_t> base_time;
  for (const auto t : base.time_us)
    if (t >= from && t <= to) base_time.push_back(t);
  if (base_time.size() < 2)
    fail(log, base.source, "the selected streams overlap in time at fewer than 2 samples of the time base (" + base.label + ")");
  if (notes && streams.size() > 1) {
    notes->push_back("time base: " + base.label + "; " + std::to_string(streams.size() - 1) +
                     " other streams linearly interpolated onto it");
    if (base_time.size() < base.time_us.size())
      notes->push_back(std::to_string(base.time_us.size() - base_time.size()) + " samples of the time base outside the span " +
                       "every selected stream covers were dropped");
  }

  Eigen::VectorXd time(static_cast<Eigen::Index>(base_time.size()));
  for (std::size_t i = 0; i < base_time.size(); ++i)
    time[static_cast<Eigen::Index>(i)] = static_cast<double>(base_time[i]) / kMicrosecondsPerSecond;
  TimeSeries record(std::move(time));
  std::vector<bool> has_temperature(kMaxInstance + 1, false), has_device(kMaxInstance + 1, false);
  for (const auto& s : streams) {
    for (int a = 0; a < 3; ++a) {
      const imu::ChannelId id{s.sensor, kAxes[a], s.instance};
      if (!sel.selects(id)) continue;
      const std::string unit = imu::internal_unit(s.sensor);
      record.set_channel({id.role(), unit, s.source, resample(s.time_us, s.axes[a], base_time), unit});
    }
    const auto instance = static_cast<std::size_t>(s.instance);
    if (!s.temperature.empty() && !has_temperature[instance]) {
      has_temperature[instance] = true;
      record.set_channel({imu::temperature_role(s.instance), "degC", s.source, resample(s.time_us, s.temperature, base_time), "degC"});
    }
    if (!s.device_id.empty() && !has_device[instance]) {
      has_device[instance] = true;
      record.set_device_id(s.instance, s.device_id);
    }
  }
  return record;
}

TimeSeries read_imu(const std::filesystem::path& path, const LogSelection& selection, std::vector<std::string>* notes) {
  ReadOptions options;
  options.keep_topics = imu_topics();
  return imu_record(read(path, options), selection, notes);
}

}  // namespace driftlab::ulog
