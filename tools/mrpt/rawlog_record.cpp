// libdriftlab_rawlog.so: the rawlog reader of the reader registry. What it reads and the errors it
// gives: framework/rawlog.hpp; how a rawlog is read: tools/mrpt/rawlog_io.hpp.
#include <algorithm>
#include <cmath>

#include "framework/error.hpp"
#include "framework/imu.hpp"
#include "framework/imu_streams.hpp"
#include "framework/rawlog.hpp"
#include "tools/mrpt/rawlog_io.hpp"

namespace driftlab::rawlog {
namespace {

namespace fs = std::filesystem;

std::string label_list(const std::vector<std::string>& labels) {
  std::string out;
  for (const auto& l : labels) out += (out.empty() ? "'" : ", '") + l + "'";
  return out.empty() ? "none" : out;
}

std::string chosen_label(const fs::path& path, const std::vector<std::string>& labels, const LogSelection& selection) {
  if (selection.instance > 0)
    throw ConfigError({path.string(), 0, "--instance"},
                      "a rawlog's IMU is instance 0 (one sensor label; pick another "
                      "label with --topic): its labels are " +
                          label_list(labels));
  if (labels.empty()) throw DataError({path.string(), 0, ""}, "the rawlog has no CObservationIMU observations");
  if (!selection.topic.empty()) {
    if (std::find(labels.begin(), labels.end(), selection.topic) == labels.end())
      throw ConfigError({path.string(), 0, "--topic"}, "no IMU observation labelled '" + selection.topic +
                                                           "'; the rawlog's IMU sensor labels: " + label_list(labels));
    return selection.topic;
  }
  if (labels.size() > 1)
    throw ConfigError({path.string(), 0, "--topic"}, "the rawlog has IMU observations of several sensors (" +
                                                         label_list(labels) + "); choose one with --topic LABEL");
  return labels.front();
}

struct Field {
  const char* column;  // rawlog_io's CSV name
  const char* role;
};
constexpr Field kFields[] = {{"wx_rps", "gyro_x"},      {"wy_rps", "gyro_y"},      {"rate_rps", "gyro_z"},
                             {"acc_x_mps2", "accel_x"}, {"acc_y_mps2", "accel_y"}, {"acc_z_mps2", "accel_z"}};

std::string field_name(const std::string& column) {
  for (const auto& c : mrpt_bridge::imu_columns())
    if (c.column == column) return c.field_name;
  return column;
}

}  // namespace
}  // namespace driftlab::rawlog

extern "C" void driftlab_rawlog_read_imu(const std::filesystem::path& path, const driftlab::LogSelection& selection,
                                         std::vector<std::string>* notes, driftlab::TimeSeries* out) {
  using namespace driftlab;
  using namespace driftlab::rawlog;
  const std::string file = path.string();
  mrpt_bridge::RawlogStats stats;
  const auto tables = mrpt_bridge::import_rawlog_sensors(path, &stats);
  const std::string label = chosen_label(path, stats.imu_labels, selection);
  const auto& table = *std::find_if(tables.begin(), tables.end(),
                                    [&](const mrpt_bridge::ImuTable& t) { return t.sensor_label == label; });
  const imu::Selection sel =
      selection.sensor.empty() ? imu::Selection{} : imu::parse_selection(selection.sensor, "--sensor");

  TimeSeries record(table.time_s);
  std::string have;
  for (const auto& f : kFields) {
    if (!table.has(f.column)) continue;
    const auto id = imu::parse_role(f.role);
    have += (have.empty() ? "" : ", ") + std::string(f.role);
    if (!sel.selects(*id)) continue;
    const std::string source = label + "." + field_name(f.column);
    const Eigen::VectorXd& v = table.values(f.column);
    for (Eigen::Index i = 0; i < v.size(); ++i)
      if (!imu::usable_value(v[i]))
        throw DataError({file, 0, source},
                        imu::unusable_value(v[i]) + " at t = " + std::to_string(table.time_s[i]) + " s");
    const std::string unit = imu::internal_unit(id->sensor);
    record.set_channel({f.role, unit, source, v, unit});
  }
  if (record.channels().empty())
    throw DataError({file, 0, "--sensor"},
                    "the selection (sensor '" + (selection.sensor.empty() ? std::string("all") : selection.sensor) +
                        "') matches no channel of IMU sensor '" + label +
                        "' (it has: " + (have.empty() ? std::string("no gyro or accelerometer field") : have) + ")");
  if (table.has("temp_c")) {
    std::vector<double> t(table.values("temp_c").data(), table.values("temp_c").data() + table.values("temp_c").size());
    imu::check_temperature(t, file, label + ".IMU_TEMPERATURE", "IMU sensor '" + label + "'", notes);
    if (!t.empty())
      record.set_channel({imu::temperature_role(0), "degC", label + ".IMU_TEMPERATURE",
                          Eigen::Map<const Eigen::VectorXd>(t.data(), static_cast<Eigen::Index>(t.size())), "degC"});
  } else if (notes) {
    notes->push_back("IMU sensor '" + label + "' carries no IMU_TEMPERATURE; no temperature channel");
  }
  if (notes && stats.odometry_actions > 0)
    notes->push_back(std::to_string(stats.odometry_actions) +
                     " odometry actions are not part of the IMU record (driftlab nav --rawlog reads them)");
  *out = std::move(record);
}

extern "C" void driftlab_rawlog_info(const std::filesystem::path& path, driftlab::rawlog::Info* out) {
  using namespace driftlab;
  mrpt_bridge::RawlogStats stats;
  const auto tables = mrpt_bridge::import_rawlog_sensors(path, &stats);
  rawlog::Info info;
  info.format = stats.format;
  info.objects = stats.objects;
  info.imu_observations = stats.imu_observations;
  info.odometry_actions = stats.odometry_actions;
  info.sensory_frames = stats.sensory_frames;
  for (const auto& table : tables) {
    rawlog::Info::Sensor s;
    s.label = table.sensor_label;
    s.samples = static_cast<std::size_t>(table.time_s.size());
    s.start_unix_s = table.start_unix_s;
    s.duration_s = table.time_s.size() > 0 ? table.time_s[table.time_s.size() - 1] : 0.0;
    for (const auto& c : table.columns)
      if (!c.name.starts_with("odom_")) s.fields.push_back(rawlog::field_name(c.name));
    if (table.has("temp_c") && table.values("temp_c").size() > 0) {
      s.has_temperature = true;
      s.temperature_min_c = table.values("temp_c").minCoeff();
      s.temperature_max_c = table.values("temp_c").maxCoeff();
    }
    info.sensors.push_back(std::move(s));
  }
  *out = std::move(info);
}
