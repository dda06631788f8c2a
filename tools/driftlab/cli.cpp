#include "tools/driftlab/cli.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <cstdlib>
#include <iostream>

#include "plugins/builtins.hpp"
#include "framework/output_set.hpp"
#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/imu.hpp"
#include "framework/record_reader.hpp"
#include "tools/driftlab/version.hpp"

namespace driftlab::cli {

const Registry& CommandEnv::registry() {
  if (!registry_) {
    registry_ = std::make_unique<Registry>();
    register_builtin_plugins(*registry_);
    if (const char* env_path = std::getenv("DRIFTLAB_PLUGIN_PATH")) registry_->load_path_list(env_path);
    for (const auto& dir : plugin_dirs) registry_->load_directory(dir);
  }
  return *registry_;
}

std::filesystem::path executable_dir() {
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path(".") : self.parent_path();
}

std::filesystem::path installed_lib_dir() { return executable_dir() / DRIFTLAB_LIB_FROM_BIN; }

std::filesystem::path installed_data_dir() { return executable_dir() / DRIFTLAB_DATA_FROM_BIN; }

void CommandEnv::progress(const std::string& label, double fraction) {
  if (!progress_)
    progress_ = std::make_unique<ProgressDisplay>(ProgressDisplay::mode_for(quiet), stderr,
                                                  ProgressDisplay::line_interval_from_environment());
  progress_->update(label, fraction);
}

CLI::Validator finite_number(double lo, double hi, bool lo_open) {
  std::ostringstream desc;
  desc << (lo_open ? "(" : "[") << lo << ", " << hi << "]";
  return CLI::Validator(
      [lo, hi, lo_open, d = desc.str()](std::string& text) -> std::string {
        double v = 0.0;
        const char* end = text.data() + text.size();
        const auto res = std::from_chars(text.data(), end, v);
        if (res.ec != std::errc() || res.ptr != end) return "expected a number, got " + quoted_excerpt(text);
        if (!std::isfinite(v)) return "expected a finite number, got " + quoted_excerpt(text);
        if ((lo_open ? !(v > lo) : !(v >= lo)) || !(v <= hi)) return "value " + message_number(v) + " is not in " + d;
        return "";
      },
      "NUMBER in " + desc.str());
}

CLI::Validator whole_number(double lo, double hi) {
  std::ostringstream desc;
  desc << "[" << static_cast<long long>(lo) << ", " << static_cast<long long>(hi) << "]";
  return CLI::Validator(
      [lo, hi, d = desc.str()](std::string& text) -> std::string {
        const bool digits = !text.empty() && text.size() <= 20 &&
                            text.find_first_not_of("0123456789", text.front() == '-' ? 1 : 0) == std::string::npos &&
                            text != "-";
        if (!digits) return "expected a whole number, got " + quoted_excerpt(text);
        const double v = std::strtod(text.c_str(), nullptr);
        if (v < lo || v > hi) return "value " + text + " is not in " + d;
        return "";
      },
      "INTEGER in " + desc.str());
}

void add_data_options(CLI::App* command, DataOptions& data, const std::string& column_help) {
  command->add_option(
      "--data", data.path,
      "input record: CSV (header row; default columns t_s, rate_dps, temp_c), a PX4 ULog (.ulg), an "
      "ArduPilot DataFlash log (.bin), a ROS bag (ROS 1 .bag, ROS 2 .db3 / .mcap or its directory) or an "
      "MRPT rawlog, recognised by content; for a log name the channel to analyse, e.g. --column rate=gyro_z for the "
      "z gyro in rad/s");
  add_record_read_options(command, data, column_help);
}

void add_record_read_options(CLI::App* command, RecordReadOptions& read, const std::string& column_help) {
  command->add_option("--column", read.columns, column_help);
  add_sampling_options(command, read.sample_rate_hz, read.max_gap_factor);
  add_log_selection_options(command, read.log);
}

void add_log_selection_options(CLI::App* command, LogSelection& selection) {
  command->add_option(
      "--topic", selection.topic,
      "log topic to read the IMU from. ULog: sensor_gyro, sensor_accel, sensor_gyro_fifo, sensor_accel_fifo, "
      "vehicle_imu or sensor_combined (default: sensor_gyro + sensor_accel when the log has them, else the two FIFO "
      "topics, else vehicle_imu, else sensor_combined). DataFlash: IMU. Bags: comma-separated sensor_msgs/Imu topics "
      "(instances 0, 1, ... in this order) and temperature topics paired with them (default: every Imu topic, by "
      "name, with the temperature topics of their namespaces). Rawlog: a CObservationIMU sensor label (default: the "
      "only one)");
  command
      ->add_option("--instance", selection.instance,
                   "log IMU instance (PX4 multi_id, ArduPilot IMU's I; bags: Imu topic number) to read; its gyro is "
                   "the time base (default: every instance, on the time base of the first gyro)")
      ->check(CLI::Range(0, 255));
  command->add_option("--sensor", selection.sensor,
                      "log channels to read: gyro, accel, gyro1, gyro_z, ... comma-separated (default: all)");
}

namespace {

// Column name and unit of an IMU record channel in the export.
CsvColumn export_column(const Channel& c) {
  if (const auto id = imu::parse_role(c.role)) {
    const bool gyro = id->sensor == imu::Sensor::Gyro;
    return {c.role + (gyro ? "_rad_s" : "_m_s2"), c.values, gyro ? "rad/s" : "m/s^2"};
  }
  const int instance = imu::parse_temperature_role(c.role).value_or(0);
  return {instance ? "temp" + std::to_string(instance) + "_c" : "temp_c", c.values, "degC"};
}

}  // namespace

std::vector<CsvColumn> imu_record_columns(const TimeSeries& record) {
  std::vector<CsvColumn> columns{{"t_s", record.time(), "s"}};
  for (const auto& c : record.channels()) columns.push_back(export_column(c));
  for (int instance = 0; instance <= imu::kMaxInstance; ++instance) {
    const auto& id = record.device_id(instance);
    if (id.empty()) continue;
    columns.push_back({instance ? "device_id" + std::to_string(instance) : "device_id",
                       Eigen::VectorXd::Constant(record.size(), std::stod(id)), "1"});
  }
  return columns;
}

void add_sampling_options(CLI::App* command, double& sample_rate_hz, double& max_gap_factor, const std::string& fs_help,
                          const std::string& gap_help) {
  command->add_option("--fs", sample_rate_hz, fs_help)->check(finite_number(0.0, 1e9, true));
  command->add_option("--max-gap", max_gap_factor, gap_help)->check(finite_number(0.0, 1e12))->capture_default_str();
}

std::string primary_role(const DataOptions& data) {
  for (const auto& c : data.columns)
    if (auto m = parse_column_mapping(c); m.role != "time") return m.role;
  return role::kRate;
}

CsvReadOptions csv_read_options(const RecordReadOptions& read) {
  CsvReadOptions options;
  for (const auto& c : read.columns) options.columns.push_back(parse_column_mapping(c));
  options.required_roles = {};
  options.sample_rate_hz = read.sample_rate_hz;
  options.max_gap_factor = read.max_gap_factor;
  return options;
}

TimeSeries load_record(const DataOptions& data, std::vector<std::string> required_roles) {
  if (data.path.empty()) throw ConfigError({"", 0, "--data"}, "--data is required");
  CsvReadOptions options = csv_read_options(data);
  if (!required_roles.empty() && required_roles.front() == role::kRate) required_roles.front() = primary_role(data);
  options.required_roles = std::move(required_roles);
  std::vector<std::string> notes;
  TimeSeries record = read_record(data.path, options, data.log, &notes);
  for (const auto& n : notes) std::cerr << "note: " << n << "\n";
  return record;
}

TimeSeries load_record_with_gaps(const DataOptions& data, std::vector<std::string> required_roles) {
  DataOptions with_gaps = data;
  with_gaps.max_gap_factor = 0.0;
  TimeSeries record = load_record(with_gaps, std::move(required_roles));
  if (data.max_gap_factor > 0.0) record.set_gap_factor(data.max_gap_factor);
  return record;
}

TimeSeries load_evenly_sampled_record(const DataOptions& data, std::vector<std::string> required_roles,
                                      std::string_view analysis) {
  TimeSeries record = load_record_with_gaps(data, std::move(required_roles));
  const auto& facts = record.sampling_facts();
  if (!facts.evenly_sampled())
    throw sampling::uneven_sampling_error(facts, record.time(), data.path, analysis,
                                          facts.regular_bursts()
                                              ? "for these regular bursts, `driftlab allan` gives the "
                                                "noise per burst"
                                              : "");
  return record;
}

TimeSeries load_even_or_bursts_record(const DataOptions& data, std::vector<std::string> required_roles,
                                      std::string_view analysis, std::string_view hint) {
  TimeSeries record = load_record_with_gaps(data, std::move(required_roles));
  if (record.sampling_facts().layout() == sampling::Layout::Irregular)
    throw sampling::irregular_sampling_error(record.sampling_facts(), record.time(), data.path, analysis, hint);
  return record;
}

std::string display_unit(const TimeSeries& record, const std::string& role, const DataOptions& data) {
  for (const auto& c : data.columns) {
    const auto m = parse_column_mapping(c);
    if (m.role == role) return m.unit;
  }
  const auto& unit = record.channel(role).unit;
  return unit == "rad/s" ? "deg/s" : unit;
}

void add_set_option(CLI::App* command, std::vector<std::string>& sets) {
  command->add_option("--set", sets,
                      "override a step of the pipeline without editing it (repeatable): STEP.PARAM=VALUE sets a "
                      "parameter (checked as in the file), STEP.PARAM.NESTED=VALUE a nested plugin's (e.g. "
                      "mixed_rbf_ga.optimizer.population=40), STEP.plugin=KIND/NAME swaps the plugin for one of the "
                      "same kind (e.g. decompose.plugin=decomposition/ceemdan); VALUE is YAML. The report lists the "
                      "overrides and the stage labels name them");
}

std::vector<PipelineOverride> pipeline_overrides(const std::vector<std::string>& sets) {
  std::vector<PipelineOverride> overrides;
  for (const auto& text : sets) overrides.push_back(parse_pipeline_override(text));
  return overrides;
}

ReportFiles plan_report_files(OutputSet& outputs, const std::filesystem::path& dir, const std::string& option) {
  outputs.make_directory(dir, option);
  ReportFiles files{dir / "report.json", dir / "report.html"};
  outputs.plan(files.json, option);
  outputs.plan(files.html, option);
  return files;
}

int run(int argc, char** argv, const std::vector<AddCommand>& commands) {
  CLI::App app{"driftlab: MEMS gyroscope error modelling and temperature-drift compensation", "driftlab"};
  app.set_version_flag("--version", std::string("driftlab ") + kVersion);
  app.require_subcommand(1);
  CommandEnv env;
  app.add_option("--plugin-path", env.plugin_dirs,
                 "directory of external plugin libraries (*.so); repeatable; also $DRIFTLAB_PLUGIN_PATH")
      ->check(CLI::ExistingDirectory);
  app.add_flag("--quiet,-q", env.quiet,
               "no progress on stderr (otherwise drawn in place on a terminal, and written as a line when a step "
               "starts or ends and at most every 5 s, $DRIFTLAB_PROGRESS_INTERVAL_S, when stderr is a file or a pipe)");
  app.add_option("--threads", env.threads, "worker threads (results do not depend on it)")
      ->check(CLI::Range(1u, 256u))
      ->capture_default_str();
  for (const auto add : commands) add(app, env);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitUsage;
  } catch (const ConfigError& e) {
    std::cerr << "driftlab: configuration error:\n" << e.what() << "\n";
    return kExitUsage;
  } catch (const DataError& e) {
    std::cerr << "driftlab: bad input data: " << e.what() << "\n";
    return kExitData;
  } catch (const std::exception& e) {
    std::cerr << "driftlab: failed: " << e.what() << "\n";
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace driftlab::cli
