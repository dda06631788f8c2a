// `driftlab log info FILE`: what a log holds. PX4 ULog: system info, topics with message counts,
// rates and time spans, IMU instances with device ids and temperature spans, dropouts, parameters.
// ArduPilot DataFlash: message types with counts, rates and time spans, skipped garbage, unknown
// types and a cut-off end, IMU instances with device ids and temperature spans, the INS_TCAL*
// temperature-calibration parameters and whether the record has the firmware's correction removed,
// TCLR (calibration learning) messages. ROS bags: tools/driftlab/bag_info.hpp.
// `driftlab log export FILE --out x.csv`: its IMU record (framework/ulog_imu.hpp,
// framework/dataflash_imu.hpp, framework/ros_imu.hpp) as CSV, in column names the CSV reader
// recognises: t_s, gyro_x_rad_s, accel1_z_m_s2, temp_c, temp1_c, device_id.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <numeric>

#include "framework/dataflash.hpp"
#include "framework/dataflash_imu.hpp"
#include "framework/rawlog.hpp"
#include "framework/error.hpp"
#include "framework/imu.hpp"
#include "framework/output_set.hpp"
#include "framework/record_reader.hpp"
#include "framework/regular_file.hpp"
#include "framework/ulog.hpp"
#include "framework/ulog_imu.hpp"
#include "tools/driftlab/bag_info.hpp"
#include "tools/driftlab/cli.hpp"

namespace driftlab::cli {
namespace {

constexpr double kSecondsPerMicrosecond = 1e-6;
constexpr std::size_t kInfoValueChars = 60;  // longer info values are cut in the listing

RecordFormat require_log(const std::string& path) {
  const RecordFormat format = sniff_record_format(path);
  if (format == RecordFormat::RosBag) return format;  // a file, or a rosbag2 directory
  check_data_input(path);
  if (format == RecordFormat::Csv)
    throw DataError({path, 0, ""},
                    "not a log driftlab reads (a PX4 ULog, an ArduPilot DataFlash log, a ROS 1 bag, a "
                    "ROS 2 bag (.db3, .mcap, or its directory), an MRPT rawlog); CSV records are read by "
                    "the other commands directly");
  return format;
}

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

double rate_hz(const ulog::Topic& t) {
  if (t.count < 2 || t.last_timestamp_us <= t.first_timestamp_us) return 0.0;
  return static_cast<double>(t.count - 1) /
         (static_cast<double>(t.last_timestamp_us - t.first_timestamp_us) * kSecondsPerMicrosecond);
}

std::string seconds(std::uint64_t us) { return fixed(static_cast<double>(us) * kSecondsPerMicrosecond, 3); }

// "2424842 (0x25000a)"
std::string device_text(double id) {
  const auto value = static_cast<unsigned long long>(id);
  char hex[32];
  std::snprintf(hex, sizeof hex, "0x%llx", value);
  return std::to_string(value) + " (" + hex + ")";
}

std::string span(const std::vector<double>& values, int digits, const char* unit) {
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  return fixed(*lo, digits) + " to " + fixed(*hi, digits) + " " + unit;
}

// "device_id 2424842 (0x25000a), 6 messages at 1.0 Hz, 40.03 to 40.36 degC"; a FIFO topic's
// samples after its messages: "50 messages at 125.0 Hz, 400 samples".
std::string imu_line(const ulog::Topic& t) {
  std::string out;
  if (t.has_column("device_id") && !t.column("device_id").empty())
    out += "device_id " + device_text(t.column("device_id").front()) + ", ";
  out += std::to_string(t.count) + " messages at " + fixed(rate_hz(t), 1) + " Hz";
  if (t.name.ends_with("_fifo") && t.has_column("samples")) {
    const auto& samples = t.column("samples");
    out += ", " + fixed(std::accumulate(samples.begin(), samples.end(), 0.0), 0) + " samples";
  }
  if (t.has_column("temperature") && !t.column("temperature").empty())
    out += ", " + span(t.column("temperature"), 2, "degC");
  return out;
}

void ulog_info(const std::string& path) {
  ulog::ReadOptions options;
  options.keep_topics = ulog::imu_topics();
  const ulog::Log log = ulog::read(path, options);
  std::cout << path << ": PX4 ULog version " << log.version << ", " << log.file_size << " bytes\n";
  std::cout << "info:\n";
  for (const auto& [key, value] : log.info)
    std::cout << "  " << key << ": "
              << (value.size() > kInfoValueChars ? value.substr(0, kInfoValueChars) + "..." : value) << "\n";
  for (const auto& [key, parts] : log.info_multiple)
    std::cout << "  " << key << ": (multi-info, " << parts.size() << (parts.size() == 1 ? " part" : " parts") << ")\n";

  // The duration as pyulog's ulog_info gives it: header start to the last data time stamp; topics
  // with a single message are left out (often a latched state with an old or future time stamp).
  std::uint64_t last = 0;
  for (const auto& t : log.topics)
    if (t.count >= 2) last = std::max(last, t.last_timestamp_us);
  std::cout << "logging started at " << seconds(log.start_timestamp_us) << " s (time since boot)";
  if (last > log.start_timestamp_us)
    std::cout << "; last data at " << seconds(last) << " s, " << seconds(last - log.start_timestamp_us) << " s later";
  std::cout << "\n";
  std::uint64_t dropped_ms = 0, longest_ms = 0;
  for (const auto& d : log.dropouts) {
    dropped_ms += d.duration_ms;
    longest_ms = std::max<std::uint64_t>(longest_ms, d.duration_ms);
  }
  std::cout << "dropouts: " << log.dropouts.size();
  if (!log.dropouts.empty())
    std::cout << ", " << fixed(static_cast<double>(dropped_ms) * 1e-3, 3) << " s in all, longest " << longest_ms
              << " ms";
  std::cout << "\nparameters: " << log.parameters.size() << " (" << log.parameter_changes.size()
            << " changes during the log, " << log.default_parameters.size() << " defaults)\n";
  std::cout << "logged messages: " << log.logged.size() << "\n";
  if (log.incompat_flags[0] & 1u) {
    std::cout << "appended data at byte";
    for (const auto o : log.appended_offsets)
      if (o) std::cout << " " << o;
    std::cout << " (" << log.bytes_skipped_at_appended << " bytes of cut-off messages skipped)\n";
  }

  std::size_t with_data = 0;
  for (const auto& t : log.topics) with_data += t.count > 0;
  std::cout << "topics: " << log.topics.size() << " subscribed, " << with_data << " with data\n";
  char row[256];
  std::snprintf(row, sizeof row, "  %-36s %8s %10s %10s %12s %12s\n", "name", "multi_id", "messages", "rate Hz",
                "from s", "to s");
  std::cout << row;
  for (const auto& t : log.topics) {
    if (t.count == 0)
      std::snprintf(row, sizeof row, "  %-36s %8d %10d\n", t.name.c_str(), t.multi_id, 0);
    else
      std::snprintf(row, sizeof row, "  %-36s %8d %10llu %10.1f %12.3f %12.3f\n", t.name.c_str(), t.multi_id,
                    static_cast<unsigned long long>(t.count), rate_hz(t),
                    static_cast<double>(t.first_timestamp_us) * kSecondsPerMicrosecond,
                    static_cast<double>(t.last_timestamp_us) * kSecondsPerMicrosecond);
    std::cout << row;
  }

  const char* imu_topics[] = {"sensor_gyro", "sensor_accel", "sensor_gyro_fifo", "sensor_accel_fifo"};
  const char* imu_labels[] = {"gyro:  ", "accel: ", "gyro FIFO:  ", "accel FIFO: "};
  if (std::any_of(std::begin(imu_topics), std::end(imu_topics),
                  [&](const char* t) { return !log.instances(t).empty(); })) {
    std::cout << "IMU instances (sensor_gyro / sensor_accel and their FIFO topics, temperature in degC):\n";
    for (int instance = 0; instance <= imu::kMaxInstance; ++instance) {
      const ulog::Topic* topics[4];
      for (int k = 0; k < 4; ++k) topics[k] = log.find(imu_topics[k], instance);
      if (std::none_of(std::begin(topics), std::end(topics), [](const auto* t) { return t != nullptr; })) continue;
      std::cout << "  instance " << instance << ":\n";
      for (int k = 0; k < 4; ++k)
        if (topics[k]) std::cout << "    " << imu_labels[k] << imu_line(*topics[k]) << "\n";
    }
  } else if (const auto* c = log.find("sensor_combined", 0)) {
    std::cout << "IMU: sensor_combined only (gyro and accelerometer of instance 0, no temperature): " << c->count
              << " messages at " << fixed(rate_hz(*c), 1) << " Hz\n";
  } else {
    std::cout << "IMU: none of sensor_gyro, sensor_accel, sensor_gyro_fifo, sensor_accel_fifo, sensor_combined\n";
  }
}

double rate_hz(const dataflash::MessageType& t) {
  if (t.count < 2 || t.last_time_us <= t.first_time_us) return 0.0;
  return static_cast<double>(t.count - 1) /
         (static_cast<double>(t.last_time_us - t.first_time_us) * kSecondsPerMicrosecond);
}

// Rate of `count` samples between two time stamps (us), 0 when it cannot be told.
double rate_hz(std::size_t count, double first_us, double last_us) {
  if (count < 2 || last_us <= first_us) return 0.0;
  return static_cast<double>(count - 1) / ((last_us - first_us) * kSecondsPerMicrosecond);
}

// The IMU messages of one instance (ArduPilot's I, or IMU/IMU2/IMU3 of older logs).
void dataflash_imu_lines(const dataflash::Log& log) {
  const auto* imu = log.find("IMU");
  const bool by_column = imu && imu->has_column("I");
  const char* old_names[] = {"IMU", "IMU2", "IMU3"};
  bool any = false;
  for (int instance = 0; instance <= imu::kMaxInstance; ++instance) {
    const dataflash::MessageType* t = by_column ? imu : (instance < 3 ? log.find(old_names[instance]) : nullptr);
    if (!t || t->count == 0) continue;
    std::vector<std::size_t> rows;
    for (std::size_t i = 0; i < t->count; ++i)
      if (!by_column || t->column("I")[i] == instance) rows.push_back(i);
    if (rows.empty()) continue;
    if (!any) std::cout << "IMU instances (" << (by_column ? "IMU messages by I" : "IMU, IMU2, IMU3") << "):\n";
    any = true;
    std::cout << "  instance " << instance << ": " << rows.size() << " messages at "
              << fixed(rate_hz(rows.size(), static_cast<double>(t->time_us[rows.front()]),
                               static_cast<double>(t->time_us[rows.back()])),
                       1)
              << " Hz";
    if (t->has_column("T")) {
      std::vector<double> temp;
      for (const auto i : rows) temp.push_back(t->column("T")[i]);
      std::cout << ", " << span(temp, 2, "degC");
    }
    std::cout << "\n";
    for (const auto sensor : {imu::Sensor::Gyro, imu::Sensor::Accel})
      if (const auto id = dataflash::device_id(log, sensor, instance))
        std::cout << "    " << (sensor == imu::Sensor::Gyro ? "gyro " : "accel") << " device id " << device_text(*id)
                  << " (" << dataflash::device_id_parameter(sensor, instance) << ")\n";
  }
  if (!any) std::cout << "IMU: no IMU messages\n";
}

// AHRS_ORIENTATION: the frame the IMU values are logged in and what the record makes of it.
void dataflash_orientation_line(const dataflash::Log& log) {
  const auto value = log.parameter("AHRS_ORIENTATION");
  std::cout << "board orientation: ";
  if (!value || *value == 0.0) {
    std::cout << "AHRS_ORIENTATION " << (value ? "0" : "not logged (default 0)") << ": body frame = sensor frame\n";
    return;
  }
  std::cout << "AHRS_ORIENTATION " << *value;
  if (const auto rotation = dataflash::board_rotation(*value))
    std::cout << " (" << rotation->name << "): IMU values are logged in the body frame; the record rotates them back "
              << "into the sensor frame\n";
  else
    std::cout << ": not one of ArduPilot's fixed rotations 0..43; the IMU record is refused\n";
}

void dataflash_tcal_lines(const dataflash::Log& log) {
  std::vector<const dataflash::Parameter*> tcal;
  std::vector<std::string> seen;
  for (const auto& p : log.parameters) {
    const bool calibration =
        p.name.starts_with("INS_TCAL") ||
        ((p.name.starts_with("INS_GYR") || p.name.starts_with("INS_ACC")) && p.name.ends_with("_CALTEMP"));
    if (!calibration || std::find(seen.begin(), seen.end(), p.name) != seen.end()) continue;
    seen.push_back(p.name);
    tcal.push_back(&p);
  }
  if (tcal.empty()) {
    std::cout << "temperature calibration: no INS_TCAL* parameters in the log\n";
    return;
  }
  std::cout << "temperature calibration (INS_TCALn, n = instance + 1; values at boot):\n";
  for (int instance = 0; instance < 3; ++instance) {
    const auto enable = log.parameter("INS_TCAL" + std::to_string(instance + 1) + "_ENABLE");
    if (!enable) continue;
    std::cout << "  instance " << instance << ": INS_TCAL" << instance + 1 << "_ENABLE " << *enable;
    if (*enable == 1.0)
      std::cout
          << " (the firmware corrected the logged values; the record has the correction removed, see the notes of "
             "log export)";
    else if (*enable == 2.0)
      std::cout << " (learning: TCLR messages hold the samples)";
    else
      std::cout << " (off: the logged values are raw)";
    std::cout << "\n";
  }
  for (const auto* p : tcal) std::cout << "  " << p->name << " = " << p->value << "\n";
}

void dataflash_tclr_lines(const dataflash::Log& log) {
  const auto* t = log.find("TCLR");
  if (!t || t->count == 0) {
    std::cout << "TCLR (temperature-calibration learning): none\n";
    return;
  }
  std::cout << "TCLR (temperature-calibration learning): " << t->count << " messages\n";
  if (!t->has_column("I") || !t->has_column("SType") || !t->has_column("Temp")) return;
  // (instance, 0 accel / 1 gyro) -> temperatures; -1 for a value that is no small whole number
  std::map<std::pair<int, int>, std::vector<double>> temps;
  auto small = [](double v) { return v >= 0 && v <= 255 && v == std::floor(v) ? static_cast<int>(v) : -1; };
  for (std::size_t i = 0; i < t->count; ++i)
    temps[{small(t->column("I")[i]), small(t->column("SType")[i])}].push_back(t->column("Temp")[i]);
  for (const auto& [key, values] : temps)
    std::cout << "  instance " << key.first << " "
              << (key.second == 0   ? "accel"
                  : key.second == 1 ? "gyro "
                                    : "other")
              << ": " << values.size() << " averages, " << span(values, 2, "degC") << "\n";
}

void dataflash_info(const std::string& path) {
  dataflash::ReadOptions options;
  options.keep_types = dataflash::imu_types();
  options.keep_types.push_back("TCLR");
  const dataflash::Log log = dataflash::read(path, options);
  std::size_t with_data = 0;
  std::uint64_t first = 0, last = 0;
  for (const auto& t : log.types) {
    with_data += t.count > 0;
    if (!t.timed || t.count < 2) continue;  // a single message may carry a stale time stamp
    first = first == 0 ? t.first_time_us : std::min(first, t.first_time_us);
    last = std::max(last, t.last_time_us);
  }
  std::cout << path << ": ArduPilot DataFlash log, " << log.file_size << " bytes, " << log.messages << " messages\n";
  if (last > first)
    std::cout << "time span: " << seconds(first) << " to " << seconds(last) << " s since boot ("
              << seconds(last - first) << " s)\n";
  std::cout << "skipped: " << log.skipped_bytes << " bytes of garbage";
  if (log.skipped_runs > 0)
    std::cout << " in " << log.skipped_runs << " places, the first at byte " << log.first_skip_offset;
  std::cout << " (resynchronised on the next message header)\n";
  for (const auto& [type, u] : log.unknown_types)
    std::cout << "unknown message type " << static_cast<int>(type) << " (no FMT): " << u.headers
              << " headers skipped, the first at byte " << u.first_offset << "\n";
  if (log.truncated_bytes > 0)
    std::cout << "the file ends within a message: its last " << log.truncated_bytes << " bytes left out\n";
  std::cout << "parameters: " << log.parameters.size() << " PARM messages\n";
  std::cout << "message types: " << log.types.size() << " defined, " << with_data << " with messages\n";
  char row[256];
  std::snprintf(row, sizeof row, "  %-6s %5s %10s %10s %12s %12s\n", "name", "type", "messages", "rate Hz", "from s",
                "to s");
  std::cout << row;
  for (const auto& t : log.types) {
    if (t.count == 0) continue;
    if (t.timed)
      std::snprintf(row, sizeof row, "  %-6s %5d %10llu %10.1f %12.3f %12.3f\n", t.name.c_str(), t.type,
                    static_cast<unsigned long long>(t.count), rate_hz(t),
                    static_cast<double>(t.first_time_us) * kSecondsPerMicrosecond,
                    static_cast<double>(t.last_time_us) * kSecondsPerMicrosecond);
    else
      std::snprintf(row, sizeof row, "  %-6s %5d %10llu\n", t.name.c_str(), t.type,
                    static_cast<unsigned long long>(t.count));
    std::cout << row;
  }
  dataflash_imu_lines(log);
  dataflash_orientation_line(log);
  dataflash_tcal_lines(log);
  dataflash_tclr_lines(log);
}

void rawlog_info(const std::string& path) {
  const auto info = rawlog::info(path);
  std::cout << path << ": MRPT rawlog (" << info.format << ")\n"
            << "objects: " << info.objects << " (" << info.imu_observations << " IMU observations, "
            << info.sensory_frames << " sensory frames, " << info.odometry_actions << " odometry actions)\n";
  std::cout << "IMU sensors (CObservationIMU by sensor label; --topic LABEL picks one):\n";
  for (const auto& s : info.sensors) {
    std::cout << "  '" << s.label << "': " << s.samples << " observations at "
              << fixed(s.duration_s > 0 ? static_cast<double>(s.samples - 1) / s.duration_s : 0.0, 1) << " Hz over "
              << fixed(s.duration_s, 3) << " s from Unix time " << fixed(s.start_unix_s, 3) << " s";
    if (s.has_temperature)
      std::cout << ", " << fixed(s.temperature_min_c, 2) << " to " << fixed(s.temperature_max_c, 2) << " degC";
    std::cout << "\n    fields:";
    for (const auto& f : s.fields) std::cout << " " << f;
    std::cout << "\n";
  }
}

void info_command(const std::string& path) {
  switch (require_log(path)) {
    case RecordFormat::Ulog:
      return ulog_info(path);
    case RecordFormat::DataFlash:
      return dataflash_info(path);
    case RecordFormat::RosBag:
      return print_bag_info(path, std::cout);
    case RecordFormat::Rawlog:
      return rawlog_info(path);
    case RecordFormat::Csv:
      break;  // refused by require_log
  }
}

struct LogExportOptions {
  std::string path, out;
  LogSelection log;
};

void log_export_command(const LogExportOptions& o) {
  OutputSet outputs({o.path});
  outputs.plan(o.out, "--out");
  require_log(o.path);
  CsvReadOptions options;
  options.required_roles = {};
  options.max_gap_factor = 0.0;  // exported as logged; readers of the CSV check gaps with their own --max-gap
  std::vector<std::string> notes;
  const TimeSeries record = read_record(o.path, options, o.log, &notes);
  outputs.write_csv(o.out, imu_record_columns(record));
  outputs.commit();
  for (const auto& n : notes) std::cerr << "note: " << n << "\n";
  std::cout << "wrote " << o.out << ": " << record.size() << " samples, " << record.channels().size() << " channels\n";
}

}  // namespace

void add_log_command(CLI::App& app, CommandEnv&) {
  auto* log = app.add_subcommand("log",
                                 "read the logs IMUs are recorded in (PX4 ULog, ArduPilot DataFlash, ROS 1 and "
                                 "ROS 2 bags, MRPT rawlogs): list what they hold, export the IMU as CSV");
  log->require_subcommand(1);

  auto path = std::make_shared<std::string>();
  auto* info = log->add_subcommand(
      "info",
      "list a log: topics or message types (messages, rate in Hz, time span in s), IMU instances (device id, "
      "temperature span in degC); ULog: system info, dropouts (ms), parameters; DataFlash: skipped bytes, "
      "INS_TCAL* temperature calibration, TCLR; bags: topic types, the temperature topics of each Imu topic; "
      "rawlogs: objects, IMU sensor labels with their fields");
  info->add_option("file", *path,
                   "PX4 ULog, ArduPilot DataFlash (.bin), ROS 1 bag, ROS 2 bag (.db3, .mcap or its "
                   "directory), MRPT rawlog")
      ->required();
  info->callback([path] { info_command(*path); });

  auto o = std::make_shared<LogExportOptions>();
  auto* exp = log->add_subcommand(
      "export",
      "write a log's IMU record as CSV: t_s (ULog, DataFlash: s since boot; bags: header stamps, s since the "
      "epoch; rawlogs: s since the first IMU observation), gyro*_rad_s (rad/s), accel*_m_s2 (m/s^2), temp*_c (degC), "
      "device_id*; other streams "
      "interpolated onto the first gyro's time stamps");
  exp->add_option("file", o->path,
                  "PX4 ULog, ArduPilot DataFlash (.bin), ROS 1 bag, ROS 2 bag (.db3, .mcap or its "
                  "directory), MRPT rawlog")
      ->required();
  exp->add_option("--out", o->out, "output CSV (written atomically)")->required();
  add_log_selection_options(exp, o->log);
  exp->callback([o] { log_export_command(*o); });
}

}  // namespace driftlab::cli
