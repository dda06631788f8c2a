#include "framework/record_reader.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>

#include "framework/dataflash.hpp"
#include "framework/dataflash_imu.hpp"
#include "framework/error.hpp"
#include "framework/imu.hpp"
#include "framework/rawlog.hpp"
#include "framework/regular_file.hpp"
#include "framework/ros_imu.hpp"
#include "framework/rosbag.hpp"
#include "framework/sampling.hpp"
#include "framework/signal.hpp"
#include "framework/ulog.hpp"
#include "framework/ulog_imu.hpp"

namespace driftlab {
namespace {

std::string role_list(const TimeSeries& record) {
  std::string out;
  for (const auto& c : record.channels()) out += (out.empty() ? "" : ", ") + c.role;
  return out.empty() ? "none" : out;
}

// The channel of the log's IMU record a mapping's column names: the role itself, or what
// recognize_imu_column makes of it ("temp" -> temperature).
std::string named_channel(const TimeSeries& imu_record, const ColumnMapping& m, const std::string& file) {
  if (imu_record.has(m.column)) return m.column;
  if (const auto match = imu::recognize_imu_column(m.column); match && imu_record.has(match->role)) return match->role;
  throw DataError({file, 0, m.column},
                  "the log has no channel '" + m.column + "' (it has: " + role_list(imu_record) + ")");
}

TimeSeries mapped_record(const TimeSeries& imu_record, const CsvReadOptions& options, const std::string& file) {
  TimeSeries record(imu_record.time());
  for (const auto& m : options.columns) {
    if (m.role == "time")
      throw ConfigError({file, 0, m.column}, "a log's time comes from its own time stamps; leave out the time mapping");
    const Channel& c = imu_record.channel(named_channel(imu_record, m, file));
    const auto unit = find_unit(m.unit);
    if (!unit || unit->symbol != c.unit)
      throw ConfigError({file, 0, m.column}, "the log holds '" + c.role + "' in " + c.unit + "; give that unit (" +
                                                 m.role + "=" + m.column + ":" + c.unit + ") or none");
    if (record.has(m.role)) throw ConfigError({file, 0, m.column}, "the role '" + m.role + "' is mapped twice");
    Channel copy = c;
    copy.role = m.role;
    record.set_channel(std::move(copy));
  }
  for (int instance = 0; instance <= imu::kMaxInstance; ++instance)
    if (!imu_record.device_id(instance).empty()) record.set_device_id(instance, imu_record.device_id(instance));
  return record;
}

void check_gaps(TimeSeries& record, double max_gap_factor, const std::string& file) {
  if (max_gap_factor <= 0.0) return;
  record.set_gap_factor(max_gap_factor);
  const auto& facts = record.sampling_facts();
  if (!facts.evenly_sampled())
    throw DataError({file, 0, "time"}, "gap of " + std::to_string(facts.first_gap_s) + " s after t = " +
                                           std::to_string(facts.first_gap_time_s) + " s (median step " +
                                           std::to_string(facts.median_step_s) + " s; allowed up to " +
                                           std::to_string(max_gap_factor) + " x median, see --max-gap; 0 reads gaps)");
}

using LogReader = TimeSeries (*)(const std::filesystem::path&, const LogSelection&, std::vector<std::string>*);

TimeSeries read_log_record(LogReader reader, const std::filesystem::path& path, const CsvReadOptions& options,
                           const LogSelection& selection, std::vector<std::string>* notes) {
  const std::string file = path.string();
  if (options.sample_rate_hz > 0.0)
    throw ConfigError({file, 0, "--fs"},
                      "a log carries its own time stamps; --fs is for CSV files without a time column");
  if (!std::isfinite(options.max_gap_factor)) throw ConfigError({file, 0, "--max-gap"}, "must be a finite number");
  const TimeSeries imu_record = reader(path, selection, notes);
  TimeSeries record = options.columns.empty() ? imu_record : mapped_record(imu_record, options, file);
  for (const auto& r : options.required_roles)
    if (!record.has(r))
      throw DataError({file, 0, r}, "no channel for the '" + r + "' role (the log's record has: " + role_list(record) +
                                        "); name one with --column " + r + "=gyro_z (any channel of the log)");
  check_gaps(record, options.max_gap_factor, file);
  return record;
}

}  // namespace

RecordFormat sniff_record_format(const std::filesystem::path& path) {
  // A rosbag2 directory is a bag; any other path that is not a regular file (a FIFO would block
  // here) goes to the CSV reader, which refuses it.
  if (!non_regular_kind(path).empty()) {
    std::error_code ec;
    return std::filesystem::is_directory(path, ec) && rosbag::sniff(path) ? RecordFormat::RosBag : RecordFormat::Csv;
  }
  std::ifstream in(path, std::ios::binary);
  char first[std::max(ulog::kMagicSize, dataflash::kMagicSize)] = {};
  in.read(first, sizeof first);
  const std::string_view head(first, static_cast<std::size_t>(in.gcount()));
  // A file that cannot be read goes to the CSV reader, whose errors name it as before.
  if (ulog::has_magic(head)) return RecordFormat::Ulog;
  if (dataflash::has_magic(head)) return RecordFormat::DataFlash;
  if (rosbag::sniff(path)) return RecordFormat::RosBag;
  return rawlog::sniff(path) ? RecordFormat::Rawlog : RecordFormat::Csv;
}

TimeSeries read_record(const std::filesystem::path& path, const CsvReadOptions& options, const LogSelection& selection,
                       std::vector<std::string>* notes) {
  switch (sniff_record_format(path)) {
    case RecordFormat::Ulog:
      return read_log_record(ulog::read_imu, path, options, selection, notes);
    case RecordFormat::DataFlash:
      return read_log_record(dataflash::read_imu, path, options, selection, notes);
    case RecordFormat::RosBag:
      return read_log_record(ros::read_imu, path, options, selection, notes);
    case RecordFormat::Rawlog:
      return read_log_record(rawlog::read_imu, path, options, selection, notes);
    case RecordFormat::Csv:
      break;
  }
  return read_csv(path, options);
}

}  // namespace driftlab
