// `driftlab log info FILE`: what a PX4 ULog holds (system info, topics with message counts, rates
// and time spans, IMU instances with device ids and temperature spans, dropouts, parameters), or a
// ROS bag (tools/driftlab/bag_info.hpp).
// `driftlab log export FILE --out x.csv`: its IMU record (framework/ulog_imu.hpp, ros_imu.hpp) as
// CSV, in column names the CSV reader recognises: t_s, gyro_x_rad_s, accel1_z_m_s2, temp_c, temp1_c,
// device_id.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <memory>

#include "framework/error.hpp"
#include "framework/imu.hpp"
#include "framework/output_set.hpp"
#include "framework/record_reader.hpp"
#include "framework/ulog.hpp"
#include "framework/ulog_imu.hpp"
#include "tools/driftlab/bag_info.hpp"
#include "tools/driftlab/cli.hpp"

namespace driftlab::cli {
namespace {

constexpr double kSecondsPerMicrosecond = 1e-6;
constexpr std::size_t kInfoValueChars = 60;  // longer info values are cut in the listing
constexpr int kMaxInstance = 99;

RecordFormat require_log(const std::string& path) {
  std::error_code ec;
  const auto format = sniff_record_format(path);
  if (format == RecordFormat::RosBag) return format;  // a file, or a rosbag2 directory
  if (!std::filesystem::is_regular_file(path, ec)) throw DataError({path, 0, ""}, "not a readable file (missing, or a directory)");
  if (format == RecordFormat::Csv)
    throw DataError({path, 0, ""}, "not a log driftlab reads (a PX4 ULog, a ROS 1 bag, a ROS 2 bag (.db3, .mcap, or its "
                                   "directory)); CSV records are read by the other commands directly");
  return format;
}

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

double rate_hz(const ulog::Topic& t) {
  if (t.count < 2 || t.last_timestamp_us <= t.first_timestamp_us) return 0.0;
  return static_cast<double>(t.count - 1) / (static_cast<double>(t.last_timestamp_us - t.first_timestamp_us) * kSecondsPerMicrosecond);
}

std::string seconds(std::uint64_t us) { return fixed(static_cast<double>(us) * kSecondsPerMicrosecond, 3); }

// "device_id 2424842 (0x25000a), 6 messages at 1.0 Hz, 40.03 to 40.36 degC"
std::string imu_line(const ulog::Topic& t) {
  std::string out;
  if (t.has_column("device_id") && !t.column("device_id").empty()) {
    const auto id = static_cast<unsigned long long>(t.column("device_id").front());
    char hex[32];
    std::snprintf(hex, sizeof hex, "0x%llx", id);
    out += "device_id " + std::to_string(id) + " (" + hex + "), ";
  }
  out += std::to_string(t.count) + " messages at " + fixed(rate_hz(t), 1) + " Hz";
  if (t.has_column("temperature") && !t.column("temperature").empty()) {
    const auto& temp = t.column("temperature");
    const auto [lo, hi] = std::minmax_element(temp.begin(), temp.end());
    out += ", " + fixed(*lo, 2) + " to " + fixed(*hi, 2) + " degC";
  }
  return out;
}

void info_command(const std::string& path) {
  if (require_log(path) == RecordFormat::RosBag) return print_bag_info(path, std::cout);
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
  if (!log.dropouts.empty()) std::cout << ", " << fixed(static_cast<double>(dropped_ms) * 1e-3, 3) << " s in all, longest " << longest_ms << " ms";
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
  std::snprintf(row, sizeof row, "  %-36s %8s %10s %10s %12s %12s\n", "name", "multi_id", "messages", "rate Hz", "from s", "to s");
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

  const auto gyros = log.instances("sensor_gyro"), accels = log.instances("sensor_accel");
  if (!gyros.empty() || !accels.empty()) {
    std::cout << "IMU instances (sensor_gyro / sensor_accel, temperature in degC):\n";
    for (int instance = 0; instance <= kMaxInstance; ++instance) {
      const auto* g = log.find("sensor_gyro", instance);
      const auto* a = log.find("sensor_accel", instance);
      if (!g && !a) continue;
      std::cout << "  instance " << instance << ":\n";
      if (g) std::cout << "    gyro:  " << imu_line(*g) << "\n";
      if (a) std::cout << "    accel: " << imu_line(*a) << "\n";
    }
  } else if (const auto* c = log.find("sensor_combined", 0)) {
    std::cout << "IMU: sensor_combined only (gyro and accelerometer of instance 0, no temperature): " << c->count
              << " messages at " << fixed(rate_hz(*c), 1) << " Hz\n";
  } else {
    std::cout << "IMU: none of sensor_gyro, sensor_accel, sensor_combined\n";
  }
}

struct ExportOptions {
  std::string path, out;
  LogSelection log;
};

// Column name and unit of an IMU record channel in the export.
CsvColumn export_column(const Channel& c) {
  if (const auto id = imu::parse_role(c.role)) {
    const bool gyro = id->sensor == imu::Sensor::Gyro;
    return {c.role + (gyro ? "_rad_s" : "_m_s2"), c.values, gyro ? "rad/s" : "m/s^2"};
  }
  const int instance = imu::parse_temperature_role(c.role).value_or(0);
  return {instance ? "temp" + std::to_string(instance) + "_c" : "temp_c", c.values, "degC"};
}

void export_command(const ExportOptions& o) {
  OutputSet outputs({o.path});
  outputs.plan(o.out, "--out");
  require_log(o.path);
  CsvReadOptions options;
  options.required_roles = {};
  options.max_gap_factor = 0.0;  // exported as logged; readers of the CSV check gaps with their own --max-gap
  std::vector<std::string> notes;
  const TimeSeries record = read_record(o.path, options, o.log, &notes);
  std::vector<CsvColumn> columns{{"t_s", record.time(), "s"}};
  for (const auto& c : record.channels()) columns.push_back(export_column(c));
  for (int instance = 0; instance <= kMaxInstance; ++instance) {
    const auto& id = record.device_id(instance);
    if (id.empty()) continue;
    columns.push_back({instance ? "device_id" + std::to_string(instance) : "device_id",
                       Eigen::VectorXd::Constant(record.size(), std::stod(id)), "1"});
  }
  outputs.write_csv(o.out, columns);
  outputs.commit();
  for (const auto& n : notes) std::cerr << "note: " << n << "\n";
  std::cout << "wrote " << o.out << ": " << record.size() << " samples, " << record.channels().size() << " channels\n";
}

}  // namespace

void add_log_command(CLI::App& app, CommandEnv&) {
  auto* log = app.add_subcommand("log", "read the logs IMUs are recorded in (PX4 ULog, ROS 1 and ROS 2 bags): list what they "
                                        "hold, export the IMU as CSV");
  log->require_subcommand(1);

  auto path = std::make_shared<std::string>();
  auto* info = log->add_subcommand(
      "info", "list a log: ULog system info, topics (messages, rate in Hz, time span in s since boot), IMU instances "
              "(device id, temperature span in degC), dropouts (ms), parameters; a bag's topics (type, messages, rate, "
              "time span in s), IMU instances (one per sensor_msgs/Imu topic) with their temperature topics");
  info->add_option("file", *path, "PX4 ULog, ROS 1 bag, ROS 2 bag (.db3, .mcap or its directory)")->required();
  info->callback([path] { info_command(*path); });

  auto o = std::make_shared<ExportOptions>();
  auto* exp = log->add_subcommand(
      "export", "write a log's IMU record as CSV: t_s (ULog: s since boot; bags: header stamps, s since the epoch), "
                "gyro*_rad_s (rad/s), accel*_m_s2 (m/s^2), temp*_c (degC), device_id*; other streams interpolated onto "
                "the first gyro's time stamps");
  exp->add_option("file", o->path, "PX4 ULog, ROS 1 bag, ROS 2 bag (.db3, .mcap or its directory)")->required();
  exp->add_option("--out", o->out, "output CSV (written atomically)")->required();
  add_log_selection_options(exp, o->log);
  exp->callback([o] { export_command(*o); });
}

}  // namespace driftlab::cli
