// Records, devices, calibration models and pipelines: the library's readers and workflows behind
// read_record (framework/record_reader.hpp), simulate (devices/simulator.hpp), load_calibration and
// compensate (models/calibration/calibration_model.hpp, exports.hpp) and Pipeline
// (framework/pipeline.hpp). Arrays of a record are views of the record's own storage.
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "devices/device_file.hpp"
#include "devices/discrepancy_options.hpp"
#include "devices/imu_simulation_columns.hpp"
#include "devices/imu_simulator.hpp"
#include "devices/simulator.hpp"
#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/imu.hpp"
#include "framework/number_text.hpp"
#include "framework/parallel.hpp"
#include "framework/pipeline.hpp"
#include "framework/record_reader.hpp"
#include "framework/resources.hpp"
#include "framework/time_series.hpp"
#include "framework/units.hpp"
#include "models/calibration/calibration_model.hpp"
#include "models/calibration/exports.hpp"
#include "models/calibration/fit.hpp"
#include "models/calibration/imu_channels.hpp"
#include "models/calibration/oven_run.hpp"
#include "models/discrepancy/report.hpp"
#include "models/evaluation/run_scores.hpp"
#include "python/src/bindings.hpp"
#include "python/src/convert.hpp"

namespace driftlab::python {
namespace {

// A read-only view of a vector inside an object that `owner` keeps alive for as long as the array
// lives (no copy; read-only because the object is shared: a Record can be run by several pipelines).
template <class Owner>
py::array view_of(const Eigen::VectorXd& values, const std::shared_ptr<Owner>& owner) {
  auto* keep = new std::shared_ptr<Owner>(owner);
  py::capsule capsule(keep, [](void* p) { delete static_cast<std::shared_ptr<Owner>*>(p); });
  py::array array = py::array_t<double>({static_cast<py::ssize_t>(values.size())}, values.data(), capsule);
  array.attr("flags").attr("writeable") = false;
  return array;
}

// A function of the pure-Python part of the package (python/driftlab/__init__.py).
py::object package(const char* name) { return py::module_::import("driftlab").attr(name); }

// ---- records ---------------------------------------------------------------------------------

struct Record {
  std::shared_ptr<const TimeSeries> series;
  std::vector<std::string> notes;
  std::string path;  // the file it was read from
};

py::dict record_channels(const Record& r) {
  py::dict d;
  for (const auto& c : r.series->channels()) d[py::str(c.role)] = view_of(c.values, r.series);
  return d;
}

template <class Field>
py::dict per_channel(const Record& r, Field field) {
  py::dict d;
  for (const auto& c : r.series->channels()) d[py::str(c.role)] = c.*field;
  return d;
}

Record read(const std::filesystem::path& path, const std::vector<std::string>& columns, std::optional<double> fs_hz,
            double max_gap_factor, const std::string& topic, int instance, const std::string& sensor,
            const std::vector<std::string>& required) {
  CsvReadOptions options;
  for (const auto& c : columns) options.columns.push_back(parse_column_mapping(c));
  options.sample_rate_hz = fs_hz.value_or(0.0);
  options.max_gap_factor = max_gap_factor;
  options.required_roles = required;
  const LogSelection selection{.topic = topic, .instance = instance, .sensor = sensor};
  Record r;
  r.path = path.string();
  py::gil_scoped_release release;
  r.series = std::make_shared<const TimeSeries>(read_record(path, options, selection, &r.notes));
  return r;
}

// A record from arrays by role (SI: rates rad/s, temperatures degC, time s), for pipelines.
std::shared_ptr<const TimeSeries> record_from_arrays(const py::dict& arrays, std::optional<double> fs_hz) {
  std::optional<Eigen::VectorXd> time;
  if (arrays.contains("time")) time = vector_view(arrays["time"].cast<InputArray>(), "time");
  if (time.has_value() == fs_hz.has_value())
    throw ConfigError({"", 0, "time"}, "give the time stamps (a 'time' array, s) or fs_hz, not both or neither");
  std::vector<std::pair<std::string, Eigen::VectorXd>> channels;
  for (const auto& [key, value] : arrays) {
    const std::string role = py::str(key);
    if (role != "time") channels.emplace_back(role, vector_view(value.cast<InputArray>(), role.c_str()));
  }
  if (!time) {
    if (!(*fs_hz > 0.0) || !std::isfinite(*fs_hz)) throw ConfigError({"", 0, "fs_hz"}, "must be a finite rate > 0 Hz");
    const auto n = channels.empty() ? Eigen::Index{0} : channels.front().second.size();
    time = Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)) / *fs_hz;
  }
  for (Eigen::Index i = 1; i < time->size(); ++i)
    if (!((*time)[i] > (*time)[i - 1]))
      throw DataError({"", 0, "time"}, "time stamps must increase: sample " + std::to_string(i) +
                                           " is not after sample " + std::to_string(i - 1));
  auto series = std::make_shared<TimeSeries>(std::move(*time));
  for (auto& [role, values] : channels) {
    const auto q = quantity_of_role(role);
    series->set_channel(
        {.role = role, .unit = q ? internal_unit_symbol(*q) : "1", .source = role, .values = std::move(values)});
  }
  return series;
}

// A Record's series, or one made from a dict of arrays by role (record_from_arrays).
std::shared_ptr<const TimeSeries> series_of(const py::object& inputs, std::optional<double> fs_hz) {
  return py::isinstance<Record>(inputs) ? inputs.cast<const Record&>().series
                                        : record_from_arrays(inputs.cast<py::dict>(), fs_hz);
}

// A device file by path or by name in driftlab.devices_dir().
std::filesystem::path device_file(const std::filesystem::path& device) {
  return devices::find_device_file(device.string(), package("devices_dir")().cast<std::filesystem::path>());
}

// ---- devices ---------------------------------------------------------------------------------

// A whole IMU's record (an `imu:` device file): every column `driftlab simulate` writes, by its SI
// name (devices/imu_simulation_columns.hpp).
py::dict simulate_whole_imu(const devices::ImuDefinition& imu, const devices::SimulationProfile& chamber,
                            const devices::SimulationOptions& options) {
  // About 800 bytes per sample and instance, as the command line estimates.
  const double samples = std::floor(options.duration_s.value_or(chamber.duration_s()) * options.sample_rate_hz) + 1.0;
  check_memory_estimate(
      samples * 800.0 * static_cast<double>(imu.instances.size()), {"", 0, "fs_hz, duration_s"},
      std::to_string(samples) + " samples of " + std::to_string(imu.instances.size()) + " IMU instances");
  std::vector<devices::ImuSimulationColumn> columns;
  {
    py::gil_scoped_release release;
    columns = devices::imu_simulation_columns(imu, devices::simulate_imu(imu, chamber, options));
  }
  py::dict d;
  for (auto& c : columns) d[py::str(c.si_name)] = to_numpy(std::move(c.values));
  return d;
}

py::dict simulate_device(const std::filesystem::path& device_name, const std::filesystem::path& profile, double fs_hz,
                         std::uint64_t seed, std::optional<double> duration_s) {
  const auto device = devices::load_device_file(device_file(device_name));
  const auto chamber = profile == "oven" ? devices::default_oven_profile() : devices::load_profile_file(profile);
  devices::SimulationOptions options{.sample_rate_hz = fs_hz, .duration_s = duration_s, .seed = seed};
  if (device.imu) return simulate_whole_imu(*device.imu, chamber, options);
  // The record: 9 series of n doubles (simulator.hpp), refused above the memory limit as by the CLI.
  const double samples = std::floor(duration_s.value_or(chamber.duration_s()) * fs_hz) + 1.0;
  check_memory_estimate(samples * 9.0 * sizeof(double), {"", 0, "fs_hz, duration_s"},
                        std::to_string(samples) + " samples of 9 series");
  devices::SimulationRecord r;
  {
    py::gil_scoped_release release;
    r = devices::simulate(device, chamber, options);
  }
  py::dict d;
  d["time_s"] = to_numpy(std::move(r.time_s));
  d["rate_rad_s"] = to_numpy(std::move(r.rate_rad_s));
  d["temp_c"] = to_numpy(std::move(r.temp_c));
  d["true_rate_rad_s"] = to_numpy(std::move(r.true_rate_rad_s));
  d["systematic_rate_rad_s"] = to_numpy(std::move(r.systematic_rate_rad_s));
  d["die_temp_c"] = to_numpy(std::move(r.die_temp_c));
  d["chamber_temp_c"] = to_numpy(std::move(r.chamber_temp_c));
  if (r.drive_frequency_hz.size() > 0) d["drive_frequency_hz"] = to_numpy(std::move(r.drive_frequency_hz));
  return d;
}

// ---- calibration -----------------------------------------------------------------------------

struct CalibrationModel {
  std::shared_ptr<const calibration::ImuCalibration> model;
  const calibration::ChannelCalibration& channel(const std::optional<std::string>& role) const {
    if (!role) {
      if (model->channels.size() == 1) return model->channels.front();
      throw ConfigError({"", 0, "channel"}, "the model has " + std::to_string(model->channels.size()) +
                                                " channels: name one (CalibrationModel.channels lists their roles)");
    }
    for (const auto& c : model->channels)
      if (c.role == *role) return c;
    throw ConfigError({"", 0, "channel"}, "the model has no channel '" + *role + "'");
  }
};

struct Compensation {
  py::array rate_rad_s, bias_rad_s, extrapolated;
};

Compensation compensate(const CalibrationModel& m, const InputArray& time_s, const InputArray& rate,
                        const InputArray& temp_c, const std::optional<std::string>& role) {
  const auto& channel = m.channel(role);
  const Eigen::VectorXd t = vector_view(time_s, "time_s"), w = vector_view(rate, "rate_rad_s"),
                        temp = vector_view(temp_c, "temp_c");
  if (w.size() != t.size() || temp.size() != t.size())
    throw DataError({"", 0, "time_s"}, "time_s, rate_rad_s and temp_c differ in length");
  calibration::Compensated c;
  {
    py::gil_scoped_release release;
    c = calibration::compensate(channel.model, t, w, temp);
  }
  py::array_t<std::uint8_t> extrapolated(static_cast<py::ssize_t>(c.outside.size()));
  std::copy(c.outside.begin(), c.outside.end(), extrapolated.mutable_data());
  return {to_numpy(std::move(c.rate_rad_s)), to_numpy(std::move(c.bias_rad_s)), extrapolated};
}

// Every channel of the model applied to a record, as `driftlab compensate` applies it: by role, each
// with its instance's temperature (calibration::temperature_of), the record's device id checked
// against the channel's. Keys: the role (compensated, SI), bias_<role> (the correction subtracted)
// and extrapolated (the calibration::kOutside* bits of every channel, ORed: which model inputs were
// outside their fitted range).
py::dict compensate_record(const CalibrationModel& m, const py::object& inputs, std::optional<double> fs_hz) {
  const auto record = series_of(inputs, fs_hz);
  std::vector<calibration::Compensated> results(m.model->channels.size());
  {
    py::gil_scoped_release release;
    for (std::size_t i = 0; i < results.size(); ++i) {
      const auto& c = m.model->channels[i];
      if (!record->has(c.role))
        throw ConfigError({"", 0, c.role}, "the model's channel " + c.role + " (fitted on column '" + c.column +
                                               "') is not in this record; a model applies only to the channels it "
                                               "was fitted on");
      const Channel* temp = calibration::temperature_of(*record, c.id.instance);
      if (!temp)
        throw DataError({"", 0, imu::temperature_role(c.id.instance)},
                        "no temperature for " + c.role + " (the model's is '" + c.temperature_column + "')");
      const std::string& id = record->device_id(c.id.instance);
      if (!id.empty() && !c.device_id.empty() && id != c.device_id)
        throw ConfigError({"", 0, "device_id"}, "this record is device " + id + ", the model's " + c.role +
                                                    " was fitted on device " + c.device_id);
      results[i] = calibration::compensate(c.model, record->time(), record->channel(c.role).values, temp->values);
    }
  }
  py::dict d;
  py::array_t<std::uint8_t> extrapolated(static_cast<py::ssize_t>(record->size()));
  std::fill_n(extrapolated.mutable_data(), record->size(), 0);
  for (std::size_t i = 0; i < results.size(); ++i) {
    const auto& role = m.model->channels[i].role;
    for (std::size_t k = 0; k < results[i].outside.size(); ++k) extrapolated.mutable_data()[k] |= results[i].outside[k];
    d[py::str(role)] = to_numpy(std::move(results[i].rate_rad_s));
    d[py::str("bias_" + role)] = to_numpy(std::move(results[i].bias_rad_s));
  }
  d["extrapolated"] = extrapolated;
  return d;
}

py::list channel_list(const CalibrationModel& m) {
  py::list out;
  for (const auto& c : m.model->channels) {
    py::dict d;
    d["role"] = c.role;
    d["column"] = c.column;
    d["unit"] = c.unit();
    d["read_unit"] = c.read_unit;
    d["temperature_column"] = c.temperature_column;
    d["device_id"] = c.device_id;
    d["kind"] = calibration::to_string(c.model.kind);
    d["order"] = c.model.order();
    d["reference_temp_c"] = c.model.reference_temp_c;
    d["valid_range_c"] = py::make_tuple(c.model.valid_min_c, c.model.valid_max_c);
    d["extrapolation"] = calibration::to_string(c.model.extrapolation);
    d["holdout_rms"] = c.model.fit.holdout_rms_rad_s;
    out.append(d);
  }
  return out;
}

struct Calibration {
  CalibrationModel model;
  py::list gate;  // the oven-run quality gate's findings: dicts of severity, code, message
};

// Fit options as keyword arguments (the CLI's --reference-temp, --min-order, ...), defaults FitOptions'.
struct FitArguments {
  std::string model, extrapolation;
  double reference_temp_c, bin_s, derivative_tau_s;
  int min_order, max_order;
  std::size_t blocks, ga_population, ga_generations;
  bool heating_only;
  std::uint64_t seed;
};

calibration::FitOptions fit_options(const FitArguments& a) {
  calibration::FitOptions f;
  const auto kind = calibration::parse_model_kind(a.model);
  if (!kind) throw ConfigError({"", 0, "model"}, "expected poly, physical or rbf, got '" + a.model + "'");
  const auto policy = calibration::parse_extrapolation(a.extrapolation);
  if (!policy)
    throw ConfigError({"", 0, "extrapolation"}, "expected clamp, linear or evaluate, got '" + a.extrapolation + "'");
  if (a.min_order < 0 || a.max_order > 12 || a.min_order > a.max_order)
    throw ConfigError({"", 0, "min_order"}, "expected 0 <= min_order <= max_order <= 12");
  if (a.blocks < 2 || a.blocks > 1000) throw ConfigError({"", 0, "blocks"}, "must be 2 .. 1000");
  if (!(a.bin_s > 0.0) || !std::isfinite(a.bin_s)) throw ConfigError({"", 0, "bin_s"}, "must be a finite number > 0 s");
  if (!(a.derivative_tau_s > 0.0) || !std::isfinite(a.derivative_tau_s))
    throw ConfigError({"", 0, "derivative_tau_s"}, "must be a finite number > 0 s");
  if (a.ga_population < 2 || a.ga_population > 1000) throw ConfigError({"", 0, "ga_population"}, "must be 2 .. 1000");
  if (a.ga_generations < 1 || a.ga_generations > 1000)
    throw ConfigError({"", 0, "ga_generations"}, "must be 1 .. 1000");
  f.kind = *kind;
  f.extrapolation = *policy;
  f.reference_temp_c = a.reference_temp_c;
  f.min_order = a.min_order;
  f.max_order = a.max_order;
  f.holdout_blocks = a.blocks;
  f.bin_s = a.bin_s;
  f.derivative_tau_s = a.derivative_tau_s;
  f.heating_only = a.heating_only;
  f.ga_population = a.ga_population;
  f.ga_generations = a.ga_generations;
  f.seed = a.seed;
  return f;
}

// The records of calibrate(): a Record, a dict of arrays by role, or a list of those.
std::vector<std::pair<std::shared_ptr<const TimeSeries>, std::string>> records_of(const py::object& records,
                                                                                  std::optional<double> fs_hz) {
  std::vector<std::pair<std::shared_ptr<const TimeSeries>, std::string>> out;
  const auto add = [&](const py::handle& item) {
    const std::string fallback = "record " + std::to_string(out.size() + 1);
    if (py::isinstance<Record>(item)) {
      const auto& r = item.cast<const Record&>();
      out.emplace_back(r.series, r.path.empty() ? fallback : r.path);
    } else if (py::isinstance<py::dict>(item)) {
      out.emplace_back(record_from_arrays(item.cast<py::dict>(), fs_hz), fallback);
    } else {
      throw ConfigError({"", 0, "records"}, "expected a Record, a dict of arrays by role, or a list of those");
    }
  };
  if (py::isinstance<py::list>(records) || py::isinstance<py::tuple>(records)) {
    for (const auto& item : records) add(item);
  } else {
    add(records);
  }
  return out;
}

// Every selected channel of an IMU's records fitted as `driftlab calibrate` fits them
// (models/calibration/imu_channels.hpp: the same channels, quality gate, fits and held-out check).
Calibration calibrate(const py::object& records, const FitArguments& arguments, const std::string& channels, char axis,
                      bool same_device, bool strict, bool force, const std::string& device, int threads,
                      std::optional<double> fs_hz) {
  if (threads < 1) throw ConfigError({"", 0, "threads"}, "must be >= 1");
  if (axis != 'x' && axis != 'y' && axis != 'z') throw ConfigError({"", 0, "axis"}, "expected 'x', 'y' or 'z'");
  const calibration::FitOptions options = fit_options(arguments);
  const auto inputs = records_of(records, fs_hz);
  std::vector<calibration::NamedSeries> named;
  for (const auto& [series, name] : inputs) named.push_back({series.get(), name});
  const calibration::ChannelSelection selection{.channels = channels,
                                                .axis = axis,
                                                .same_device = same_device,
                                                .channels_field = "channels",
                                                .same_device_field = "same_device=True",
                                                .records_field = "records"};
  std::vector<calibration::Finding> findings;
  auto model = std::make_shared<calibration::ImuCalibration>();
  {
    py::gil_scoped_release release;
    const auto fitted = calibration::channel_records(named, selection);
    findings = calibration::run_quality_gate(fitted, options.bin_s, strict, nullptr);
    model->device = device;
    model->channels.resize(fitted.size());
    parallel_for(fitted.size(), static_cast<unsigned>(threads), [&](std::size_t c) {
      model->channels[c] = calibration::fit_channel(fitted[c], fitted[c].records, options);
    });
    model->validate();
    if (!force) calibration::check_holdout_error(*model);
  }
  py::list gate;
  for (const auto& f : findings) {
    py::dict d;
    d["severity"] = calibration::to_string(f.severity);
    d["code"] = f.code;
    d["message"] = f.message;
    gate.append(d);
  }
  return {CalibrationModel{std::move(model)}, gate};
}

py::tuple export_model(const CalibrationModel& m, const std::string& format, bool strict) {
  calibration::ExportOptions options;
  options.strict = strict;
  calibration::ExportResult r;
  if (format == "c-header")
    r = calibration::export_c_header(*m.model, options);
  else if (format == "px4")
    r = calibration::export_px4_params(*m.model, options);
  else if (format == "ardupilot")
    r = calibration::export_ardupilot_params(*m.model, options);
  else if (format == "kalibr")
    r = calibration::export_kalibr_imu_yaml(*m.model, options);
  else
    throw ConfigError({"", 0, "format"}, "'" + format + "': expected c-header, px4, ardupilot or kalibr");
  return py::make_tuple(r.text, r.notes);
}

// ---- discrepancy -----------------------------------------------------------------------------

struct Discrepancy {
  py::dict report;         // report.json's data (models/discrepancy/report.hpp)
  py::list named_effects;  // report["named_effects"]
  double gap_initial_deg_h = 0.0, gap_final_deg_h = 0.0, noise_floor_deg_h = 0.0;
  bool unexplained = false;
  py::array model_initial_rad_s, model_final_rad_s;
};

// The discrepancy workflow on a record, as `driftlab discrepancy` runs it (the same candidates,
// options and report; the record is taken as read: read_record refuses irregular gaps).
Discrepancy find_discrepancy(const py::object& inputs, const std::optional<std::filesystem::path>& device,
                             const std::vector<std::string>& effects, const std::vector<std::string>& sets,
                             std::optional<int> bias_degree, double block_s, double significance, int max_effects,
                             std::optional<double> fs_hz) {
  const auto record = series_of(inputs, fs_hz);
  for (const char* r : {role::kRate, role::kTemperature})
    if (!record->has(r)) throw DataError({"", 0, r}, std::string("the record has no '") + r + "' channel");
  discrepancy::Options options;
  std::string device_path;
  if (device) {
    device_path = device_file(*device).string();
    options = devices::discrepancy_options(devices::load_device_file(device_path));
  }
  if (bias_degree) {
    if (*bias_degree < 0 || *bias_degree > 6) throw ConfigError({"", 0, "bias_degree"}, "must be 0 .. 6");
    options.bias_degree = *bias_degree;
  }
  if (!(block_s >= 0.0) || !std::isfinite(block_s))
    throw ConfigError({"", 0, "block_s"}, "must be a finite number >= 0 s");
  if (!(significance >= 0.0) || !std::isfinite(significance))
    throw ConfigError({"", 0, "significance"}, "must be a finite number >= 0");
  if (max_effects < 0 || max_effects > 20) throw ConfigError({"", 0, "max_effects"}, "must be 0 .. 20");
  options.block_s = block_s;
  options.significance = significance;
  options.max_effects = max_effects;
  const auto candidates = discrepancy::make_candidates(registry(), effects, sets, false);
  std::string data = "<arrays>";
  if (py::isinstance<Record>(inputs)) data = inputs.cast<const Record&>().path;
  discrepancy::Result result;
  nlohmann::json report;
  {
    py::gil_scoped_release release;
    result = discrepancy::find_missing_effects(*record, candidates.candidates, options);
    report = discrepancy::report_json(result, {data, device_path, &options});
  }
  Discrepancy d;
  d.report = to_python(report);
  // The named effects with the units in the gaps' names (the parameters' keys carry theirs).
  for (const auto& e : report["named_effects"]) {
    py::dict named;
    named["effect"] = e["effect"].get<std::string>();
    for (const char* key : {"parameters", "uncertainty", "units", "evidence"}) named[key] = to_python(e[key]);
    named["gap_before_deg_h"] = e["gap_before"].get<double>();
    named["gap_after_deg_h"] = e["gap_after"].get<double>();
    d.named_effects.append(named);
  }
  d.gap_initial_deg_h = report["gap_initial"].get<double>();
  d.gap_final_deg_h = report["gap_final"].get<double>();
  d.noise_floor_deg_h = report["noise_floor"].get<double>();
  d.unexplained = result.unexplained.found;
  d.model_initial_rad_s = to_numpy(std::move(result.model_initial_rad_s));
  d.model_final_rad_s = to_numpy(std::move(result.model_final_rad_s));
  return d;
}

// ---- pipelines -------------------------------------------------------------------------------

struct PipelineHandle {
  std::shared_ptr<const Pipeline> pipeline;
};

struct PipelineRun {
  py::dict outputs, units, report;
  std::string table2_text;  // Table 2 as `driftlab run` prints it; empty when not scored
};

PipelineHandle pipeline_from_yaml(const py::object& source) {
  const Registry& reg = registry();
  if (py::isinstance<py::str>(source)) {
    const std::string text = source.cast<std::string>();
    if (text.find('\n') != std::string::npos)
      return {std::make_shared<const Pipeline>(parse_pipeline(text, "<pipeline text>", reg))};
    const std::filesystem::path shipped = package("pipelines_dir")().cast<std::filesystem::path>() / (text + ".yaml");
    if (!std::filesystem::exists(text) && std::filesystem::exists(shipped))
      return {std::make_shared<const Pipeline>(load_pipeline(shipped, reg))};
  }
  return {std::make_shared<const Pipeline>(load_pipeline(source.cast<std::filesystem::path>(), reg))};
}

PipelineRun run(const PipelineHandle& p, const py::object& inputs, int threads, std::optional<double> fs_hz) {
  const std::shared_ptr<const TimeSeries> record = series_of(inputs, fs_hz);
  if (threads < 1) throw ConfigError({"", 0, "threads"}, "must be >= 1");
  PipelineRunOptions options;
  options.threads = static_cast<unsigned>(threads);
  nlohmann::json report = nlohmann::json::object();
  std::map<std::string, Signal> outputs;
  PipelineRun r;
  {
    py::gil_scoped_release release;
    outputs = run_pipeline(*p.pipeline, registry(), *record, options, report);
    // Table 2, as `driftlab run` scores a record with a rate (tools/driftlab/cmd_run.cpp).
    if (record->has(role::kRate)) {
      try {
        const auto scores = evaluation::score_run(*record, *p.pipeline, outputs);
        report.update(evaluation::scores_json(scores));
        r.table2_text = evaluation::table2_text(scores);
      } catch (const DataError& e) {
        report["table2_skipped"] = e.what();
      }
    }
  }
  for (auto& [name, signal] : outputs) {
    r.units[py::str(name)] = signal.unit;
    const bool single = signal.columns.cols() == 1;
    py::object columns = columns_to_numpy(std::move(signal.columns));
    r.outputs[py::str(name)] = single ? columns[py::int_(0)] : columns;  // one column: a view of its row
  }
  r.report = to_python(report);
  return r;
}

// Record and read_record: a record read from a file.
void bind_record(py::module_& m) {
  py::class_<Record>(m, "Record",
                     "A record read from a file: time stamps and channels by role, in SI units (rad/s, m/s^2, "
                     "degC, Hz), as the command line reads it. Arrays view the record's storage.")
      .def_property_readonly("time_s", [](const Record& r) { return view_of(r.series->time(), r.series); })
      .def_property_readonly("channels", &record_channels, "role -> samples (rate, temperature, gyro_x, ...)")
      .def_property_readonly(
          "units", [](const Record& r) { return per_channel(r, &Channel::unit); },
          "role -> internal (SI) unit of its samples")
      .def_property_readonly(
          "sources", [](const Record& r) { return per_channel(r, &Channel::source); },
          "role -> the column or log field it was read from")
      .def_property_readonly(
          "sample_rate_hz", [](const Record& r) { return r.series->sample_rate_hz(); }, "mean sample rate, Hz")
      .def_readonly("notes", &Record::notes, "what a log reader repaired or left out")
      .def_readonly("path", &Record::path, "the file it was read from")
      .def("__len__", [](const Record& r) { return r.series->size(); })
      .def("__repr__", [](const Record& r) {
        std::string roles;
        for (const auto& c : r.series->channels()) roles += (roles.empty() ? "" : ", ") + c.role;
        return "<driftlab.Record " + std::to_string(r.series->size()) + " samples: " + roles + ">";
      });
  const CsvReadOptions csv_defaults;
  const LogSelection log_defaults;
  m.def("read_record", &read, py::arg("path"), py::arg("columns") = std::vector<std::string>{},
        py::arg("fs_hz") = py::none(), py::arg("max_gap_factor") = csv_defaults.max_gap_factor,
        py::arg("topic") = log_defaults.topic, py::arg("instance") = log_defaults.instance,
        py::arg("sensor") = log_defaults.sensor, py::arg("required") = std::vector<std::string>{},
        R"(Reads a record with the reader its content calls for (framework/record_reader.hpp): a CSV
time series, or a log (PX4 ULog, ArduPilot DataFlash, ROS 1 / ROS 2 bags and MCAP), into SI units.
This is also the log reader: there is no separate read_log.

columns: mappings 'role=column:unit' (e.g. 'rate=gyro_z:rad/s', 'time=timestamp:ms'); empty: the
  default columns (t_s and every unit-suffixed column: rate_dps -> rate, temp_c -> temperature) or,
  for a log, every IMU channel. fs_hz: for a CSV without a time column, t = i / fs_hz.
max_gap_factor: a time step above this times the median step is a DataError (0 reads gaps as they are).
topic, instance, sensor: what to take from a log (ignored for CSV). required: roles that must be
present. Returns Record (time_s, channels, units, sources, sample_rate_hz, notes, path).)");
}

// device_files and simulate: the oven simulator.
void bind_simulation(py::module_& m) {
  m.def(
      "device_files", [] { return devices::list_device_files(package("devices_dir")().cast<std::filesystem::path>()); },
      "The device files (*.yaml) of driftlab.devices_dir(), sorted.");
  const devices::SimulationOptions simulation_defaults;
  m.def("simulate", &simulate_device, py::arg("device"), py::arg("profile") = "oven",
        py::arg("fs_hz") = simulation_defaults.sample_rate_hz, py::arg("seed") = simulation_defaults.seed,
        py::arg("duration_s") = py::none(),
        R"(Runs a device through the oven simulator (devices/simulator.hpp), as `driftlab simulate`.

device: a device file, or the name of one in driftlab.devices_dir(): a single-axis gyro ('fmvmg') or
  a whole IMU ('imu3': instances x gyro + accelerometer x 3 axes, devices/imu_simulator.hpp).
profile: 'oven' (the paper's -30 -> +60 -> -30 degC run, 4.5 h) or a driftlab-profile/1 file.
fs_hz: sample rate, Hz. seed: the noise realization (same seed, same record).
duration_s: default the profile's.
Returns a dict of arrays. Single axis: time_s, rate_rad_s, temp_c, true_rate_rad_s,
systematic_rate_rad_s, die_temp_c, chamber_temp_c, and drive_frequency_hz when the device has that
channel. Whole IMU: every column `driftlab simulate` writes, in SI under its SI name (time_s, gyro rad/s,
accel m/s^2, temperature degC snapped to the instance's resolution): time_s, then per instance i
(no digit for the first) gyro{i}_{x,y,z}_rad_s, accel{i}_{x,y,z}_mps2, temp{i}_c, device_id{i},
true_gyro{i}_*, true_accel{i}_*, systematic_gyro{i}_*, systematic_accel{i}_*; the CSV's gyro columns
(_dps) are these / (pi / 180).)");
}

// Compensation, CalibrationModel, Calibration, calibrate and load_calibration.
void bind_calibration(py::module_& m) {
  py::class_<Compensation>(m, "Compensation", "A compensated record (models/calibration: w = (w_m - bias) / sf)")
      .def_readonly("rate_rad_s", &Compensation::rate_rad_s,
                    "compensated samples, rad/s (m/s^2 for an accelerometer channel)")
      .def_readonly("bias_rad_s", &Compensation::bias_rad_s, "the correction subtracted at each sample, same unit")
      .def_readonly("extrapolated", &Compensation::extrapolated,
                    "per sample, 0 where every model input was inside the range it was fitted on, else the sum of "
                    "the inputs outside: 1 model temperature, 2 dT/dt, 4 branch state, 8 an RBF input (uint8)");
  py::class_<CalibrationModel>(m, "CalibrationModel",
                               "A calibration model (driftlab-calibration/2 or /1): one model per IMU channel")
      .def_property_readonly("channels", &channel_list,
                             "one dict per channel: role, column, unit, read_unit, temperature_column, device_id, "
                             "kind, order, reference_temp_c, valid_range_c, extrapolation, holdout_rms (unit)")
      .def("compensate", &compensate, py::arg("time_s"), py::arg("rate_rad_s"), py::arg("temp_c"),
           py::arg("channel") = py::none(),
           "Compensates one channel with the model's causal compensator, sample by sample as `driftlab compensate` "
           "and firmware do. time_s: s, increasing; rate_rad_s: the channel's samples in its internal unit "
           "(rad/s gyro, m/s^2 accelerometer); temp_c: its temperature, degC. channel: the channel's role "
           "(needed when the model has several). Returns Compensation.")
      .def("compensate", &compensate_record, py::arg("record"), py::arg("fs_hz") = py::none(),
           "Compensates every channel of the model in a whole record, as `driftlab compensate` does: record is a "
           "Record or a dict of arrays by role ('time' s, 'gyro_x' rad/s, 'accel_z' m/s^2, 'temperature' degC, "
           "...; or fs_hz). Each channel uses its instance's temperature (temperature1, ... else temperature); a "
           "record of another device (device_id) is refused. Returns a dict: <role> (compensated, SI), "
           "bias_<role> (the correction subtracted, same unit) per channel, and extrapolated (per sample, the "
           "inputs outside their fitted range over the channels, as in Compensation.extrapolated).")
      .def(
          "to_json", [](const CalibrationModel& c) { return calibration::to_json_text(*c.model); },
          "The model as a driftlab-calibration/2 file's text.")
      .def("export", &export_model, py::arg("format"), py::arg("strict") = false,
           "The model in a firmware / navigation format: 'c-header', 'px4', 'ardupilot' or 'kalibr'. Returns "
           "(text, notes): notes list approximations and dropped terms (strict=True refuses them instead).")
      .def("__repr__", [](const CalibrationModel& c) {
        return "<driftlab.CalibrationModel " + std::to_string(c.model->channels.size()) + " channel(s)>";
      });
  py::class_<Calibration>(m, "Calibration", "What calibrate() fitted: the model and the oven-run quality gate")
      .def_readonly("model", &Calibration::model, "the CalibrationModel (every selected channel)")
      .def_readonly("gate", &Calibration::gate,
                    "the quality gate's findings (models/calibration/oven_run.hpp): dicts of severity "
                    "('note', 'warning'), code and message, each message starting with its temperature column")
      .def("__repr__", [](const Calibration& c) {
        return "<driftlab.Calibration " + std::to_string(c.model.model->channels.size()) + " channel(s), " +
               std::to_string(py::len(c.gate)) + " gate finding(s)>";
      });
  const calibration::FitOptions fit_defaults;
  m.def(
      "calibrate",
      [](const py::object& records, const std::string& model, const py::object& channels, char axis, bool same_device,
         const std::string& extrapolation, double reference_temp_c, int min_order, int max_order, std::size_t blocks,
         double bin_s, double derivative_tau_s, bool heating_only, std::size_t ga_population,
         std::size_t ga_generations, std::uint64_t seed, bool strict, bool force, const std::string& device,
         int threads, std::optional<double> fs_hz) {
        // A selection as text ("gyro,accel1_z") or as a list of its items (["gyro", "accel1_z"]).
        std::string selection;
        if (py::isinstance<py::str>(channels)) {
          selection = channels.cast<std::string>();
        } else {
          for (const auto& item : channels) selection += (selection.empty() ? "" : ",") + item.cast<std::string>();
        }
        return calibrate(records,
                         {model, extrapolation, reference_temp_c, bin_s, derivative_tau_s, min_order, max_order, blocks,
                          ga_population, ga_generations, heating_only, seed},
                         selection, axis, same_device, strict, force, device, threads, fs_hz);
      },
      py::arg("records"), py::arg("model") = "physical", py::kw_only(), py::arg("channels") = "", py::arg("axis") = 'z',
      py::arg("same_device") = false, py::arg("extrapolation") = "clamp",
      py::arg("reference_temp_c") = fit_defaults.reference_temp_c, py::arg("min_order") = fit_defaults.min_order,
      py::arg("max_order") = fit_defaults.max_order, py::arg("blocks") = fit_defaults.holdout_blocks,
      py::arg("bin_s") = fit_defaults.bin_s, py::arg("derivative_tau_s") = fit_defaults.derivative_tau_s,
      py::arg("heating_only") = fit_defaults.heating_only, py::arg("ga_population") = fit_defaults.ga_population,
      py::arg("ga_generations") = fit_defaults.ga_generations, py::arg("seed") = fit_defaults.seed,
      py::arg("strict") = false, py::arg("force") = false, py::arg("device") = "", py::arg("threads") = 1,
      py::arg("fs_hz") = py::none(),
      R"(Fits a causal temperature-calibration model for every selected gyro and accelerometer channel of
an IMU's oven records, as `driftlab calibrate` does (models/calibration/imu_channels.hpp and fit.hpp:
the same channels, quality gate, fits and held-out check; the keyword arguments are its options).

records: a Record (read_record of a CSV or a log), a dict of arrays by role ('time' s, 'gyro_x' ..
  'gyro_z' rad/s, 'accel_x' .. 'accel_z' m/s^2, 'gyro1_x' for instance 1, 'temperature' /
  'temperature1' degC, 'true_gyro_x' a reference input; 'rate' for a single-axis gyro; or fs_hz),
  or a list of those: several oven runs of one IMU.
model: 'physical' (default), 'poly' or 'rbf': the richest kind allowed (--model).
channels: the selection of --channels, as text or a list: 'gyro', 'accel1', 'gyro_x,accel_z' or
  ['gyro_x', 'accel_z'] (empty: every channel).
axis: the axis of a single-axis 'rate' channel. same_device: records whose device ids or bias levels
  differ are one device (--same-device; otherwise refused with ConfigError).
extrapolation, reference_temp_c (T0, degC), min_order, max_order, blocks (held-out time blocks),
  bin_s, derivative_tau_s (s), heating_only, ga_population, ga_generations, seed: as the CLI's options.
strict: quality-gate warnings are errors (--strict); an error finding always raises DataError.
force: keep a model whose held-out error exceeds the uncompensated one (--force; otherwise DataError).
device: the device name stored in the model. threads: channels fitted in parallel (same results).
Returns Calibration: .model (CalibrationModel: compensate, to_json, export) and .gate (the quality
gate's findings that did not stop the fit).)");
  m.def(
      "load_calibration",
      [](const std::filesystem::path& path) {
        return CalibrationModel{
            std::make_shared<const calibration::ImuCalibration>(calibration::read_calibration(path))};
      },
      py::arg("path"), "Reads a calibration model file (driftlab-calibration/2, or /1 as one gyro channel).");
}

// Discrepancy and discrepancy: the missing effects.
void bind_discrepancy(py::module_& m) {
  py::class_<Discrepancy>(m, "Discrepancy", "What discrepancy() found: the named effects and the gaps")
      .def_readonly("report", &Discrepancy::report,
                    "report.json's data as `driftlab discrepancy` writes it (named_effects, gap_initial, gap_final, "
                    "noise_floor in deg/h, criterion, final_scores, unexplained, model, views)")
      .def_readonly("named_effects", &Discrepancy::named_effects,
                    "per named effect, in order: effect, parameters (final model, in a device file's effects: keys, "
                    "which carry their units: amplitude_dph, period_s), uncertainty (1 sigma, same keys), units, "
                    "gap_before_deg_h, gap_after_deg_h, evidence (delta_chi2, delta_bic, chi2_scale, scores, "
                    "runner_up); report['named_effects'] holds the same as report.json writes it")
      .def_readonly("gap_initial_deg_h", &Discrepancy::gap_initial_deg_h,
                    "rms of the block-mean residual with the device's model (or the bias polynomial), deg/h")
      .def_readonly("gap_final_deg_h", &Discrepancy::gap_final_deg_h, "the same after the named effects, deg/h")
      .def_readonly("noise_floor_deg_h", &Discrepancy::noise_floor_deg_h, "what noise alone would leave, deg/h")
      .def_readonly("unexplained", &Discrepancy::unexplained,
                    "True when structure remains that no candidate explains (report['unexplained'] says where)")
      .def_readonly("model_initial_rad_s", &Discrepancy::model_initial_rad_s,
                    "the initial model's systematic rate, rad/s")
      .def_readonly("model_final_rad_s", &Discrepancy::model_final_rad_s, "the final model's systematic rate, rad/s")
      .def("__repr__", [](const Discrepancy& d) {
        return "<driftlab.Discrepancy " + std::to_string(py::len(d.named_effects)) + " named effect(s), gap " +
               format_number(d.gap_initial_deg_h) + " -> " + format_number(d.gap_final_deg_h) + " deg/h>";
      });
  const discrepancy::Options discrepancy_defaults;
  m.def("discrepancy", &find_discrepancy, py::arg("record"), py::arg("device") = py::none(),
        py::arg("effects") = std::vector<std::string>{}, py::arg("sets") = std::vector<std::string>{},
        py::arg("bias_degree") = py::none(), py::arg("block_s") = discrepancy_defaults.block_s,
        py::arg("significance") = discrepancy_defaults.significance,
        py::arg("max_effects") = discrepancy_defaults.max_effects, py::arg("fs_hz") = py::none(),
        R"(Fits the device's model to a measured record, shows where it misses and names the physical
effects it lacks (models/discrepancy/discrepancy.hpp), as `driftlab discrepancy` does: the same
candidates, options and report.

record: a Record (read_record) or a dict of arrays by role with 'time' (s) or fs_hz: 'rate' (rad/s)
  and 'temperature' (degC) needed, 'true_rate' and 'drive_frequency' used when present.
device: a device file or the name of one in driftlab.devices_dir(): its model is the prior, its noise
  terms the covariance (None: a bias polynomial with noise terms estimated from the record).
effects: candidate effect/* plugins (default: all). sets: 'effect/NAME.key=value' search bounds and
  options, validated by the plugin's table (the CLI's --set). bias_degree: of the fitted correction
  polynomial, 0..6 (default: the device file's, at least 1; 2 without a device). block_s: block
  length, s (0: duration / 400). significance: delta BIC needed to name an effect. max_effects: 0..20.
The record is taken as given (read_record refuses irregular gaps unless max_gap_factor=0).
Returns Discrepancy (report, named_effects, gap_initial_deg_h, gap_final_deg_h, noise_floor_deg_h,
unexplained, model_initial_rad_s, model_final_rad_s).)");
}

// PipelineRun and Pipeline.
void bind_pipeline(py::module_& m) {
  py::class_<PipelineRun>(m, "PipelineRun", "The outputs of a pipeline run and its report")
      .def_readonly("outputs", &PipelineRun::outputs,
                    "output name -> samples (one column: shape (N,); several: (columns, N)), SI units")
      .def_readonly("units", &PipelineRun::units, "output name -> unit of its samples")
      .def_readonly("report", &PipelineRun::report,
                    "report.json's data as `driftlab run` writes it: per step its status, seconds and the plugin's "
                    "diagnostics ('steps'); for a record with a rate, Table 2 (models/evaluation/run_scores.hpp): "
                    "'table2' (per stage B_deg_h with B_ci and B_resolved, or B_upper_deg_h within B_within_tau_s; "
                    "N_deg_h_rtHz; bandwidth_hz; residual_drift_deg_h with a truth; systematic_error_deg_h with the "
                    "systematic rate; the paper's row), 'allan' (curves, deg/h), 'intrinsic_floor', 'baselines' (by "
                    "stage), 'units', 'readings'; 'table2_skipped' when "
                    "the record is too short for them")
      .def_readonly("table2_text", &PipelineRun::table2_text,
                    "Table 2 as `driftlab run` prints it (empty when the record has no rate or is too short)");
  py::class_<PipelineHandle>(m, "Pipeline", "A validated pipeline description (driftlab-pipeline/1)")
      .def_static("from_yaml", &pipeline_from_yaml, py::arg("source"),
                  "A pipeline from a file path, the name of a pipeline shipped with driftlab "
                  "(driftlab.pipelines_dir(): 'li2023'), or YAML text (anything with a line break). Validated "
                  "before any data is touched: ConfigError lists every problem with its line and key.")
      .def_property_readonly(
          "inputs", [](const PipelineHandle& p) { return p.pipeline->inputs; },
          "input name -> the record's channel role it reads")
      .def_property_readonly("outputs", [](const PipelineHandle& p) { return p.pipeline->output_order; })
      .def_property_readonly(
          "steps",
          [](const PipelineHandle& p) {
            std::vector<std::pair<std::string, std::string>> steps;
            for (const auto& s : p.pipeline->steps) steps.emplace_back(s.name, s.plugin.empty() ? "sum" : s.plugin);
            return steps;
          },
          "(name, plugin) per step, in execution order")
      .def_property_readonly("seed", [](const PipelineHandle& p) { return p.pipeline->seed; })
      .def(
          "effective_yaml", [](const PipelineHandle& p) { return effective_pipeline_yaml(*p.pipeline, registry()); },
          "The pipeline with every parameter and seed written out; loading it gives the same run.")
      .def(
          "run", &run, py::arg("inputs"), py::arg("threads") = 1, py::arg("fs_hz") = py::none(),
          "Runs the steps on a Record, or on a dict of arrays by channel role ('rate' rad/s, 'temperature' degC, "
          "...) with 'time' (s) or fs_hz. threads: worker threads (results do not depend on them). "
          "Returns PipelineRun (outputs, units, report, table2_text); a record with a rate is scored as `driftlab run` "
          "scores it (Table 2 in report).");
}

}  // namespace

void bind_data(py::module_& m) {
  bind_record(m);
  bind_simulation(m);
  bind_calibration(m);
  bind_discrepancy(m);
  bind_pipeline(m);
}

}  // namespace driftlab::python
