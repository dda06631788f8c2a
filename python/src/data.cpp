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
#include "devices/simulator.hpp"
#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/pipeline.hpp"
#include "framework/record_reader.hpp"
#include "framework/resources.hpp"
#include "framework/time_series.hpp"
#include "framework/units.hpp"
#include "models/calibration/calibration_model.hpp"
#include "models/calibration/exports.hpp"
#include "models/calibration/fit.hpp"
#include "models/calibration/oven_run.hpp"
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

// ---- devices ---------------------------------------------------------------------------------

py::dict simulate_device(const std::filesystem::path& device_name, const std::filesystem::path& profile, double fs_hz,
                         std::uint64_t seed, std::optional<double> duration_s) {
  const auto devices_dir = package("devices_dir")().cast<std::filesystem::path>();
  const auto device = devices::load_device_file(devices::find_device_file(device_name.string(), devices_dir));
  const auto chamber = profile == "oven" ? devices::default_oven_profile() : devices::load_profile_file(profile);
  devices::SimulationOptions options{.sample_rate_hz = fs_hz, .duration_s = duration_s, .seed = seed};
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
  py::array_t<bool> extrapolated(static_cast<py::ssize_t>(c.extrapolated.size()));
  std::copy(c.extrapolated.begin(), c.extrapolated.end(), extrapolated.mutable_data());
  return {to_numpy(std::move(c.rate_rad_s)), to_numpy(std::move(c.bias_rad_s)), extrapolated};
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

// One gyro channel's model from its oven runs, as `driftlab calibrate` fits it (fit_calibration,
// with the quality gate of oven_run.hpp reported, not enforced).
Calibration calibrate(const py::list& runs, const std::string& model, const std::string& extrapolation,
                      double reference_temp_c, double bin_s, std::size_t blocks, std::uint64_t seed, char axis) {
  calibration::FitOptions options;
  const auto kind = calibration::parse_model_kind(model);
  if (!kind) throw ConfigError({"", 0, "model"}, "'" + model + "': expected poly, physical or rbf");
  const auto policy = calibration::parse_extrapolation(extrapolation);
  if (!policy) throw ConfigError({"", 0, "extrapolation"}, "'" + extrapolation + "': expected clamp, linear or evaluate");
  options.kind = *kind;
  options.extrapolation = *policy;
  options.reference_temp_c = reference_temp_c;
  options.bin_s = bin_s;
  options.holdout_blocks = blocks;
  options.seed = seed;
  std::vector<calibration::Record> records;
  for (const auto& item : runs) {
    const auto run = item.cast<py::dict>();
    calibration::Record r;
    r.name = run.contains("name") ? run["name"].cast<std::string>() : "run " + std::to_string(records.size() + 1);
    for (const char* key : {"time_s", "rate_rad_s", "temp_c"})
      if (!run.contains(key)) throw DataError({r.name, 0, key}, std::string("a run needs '") + key + "'");
    r.time_s = vector_view(run["time_s"].cast<InputArray>(), "time_s");
    r.rate_rad_s = vector_view(run["rate_rad_s"].cast<InputArray>(), "rate_rad_s");
    r.temp_c = vector_view(run["temp_c"].cast<InputArray>(), "temp_c");
    if (run.contains("true_rate_rad_s")) r.true_rate_rad_s = vector_view(run["true_rate_rad_s"].cast<InputArray>(), "true_rate_rad_s");
    if (r.rate_rad_s.size() != r.time_s.size() || r.temp_c.size() != r.time_s.size() ||
        (r.true_rate_rad_s.size() > 0 && r.true_rate_rad_s.size() != r.time_s.size()))
      throw DataError({r.name, 0, "time_s"}, "the run's arrays differ in length");
    records.push_back(std::move(r));
  }
  if (records.empty()) throw ConfigError({"", 0, "runs"}, "no run given");
  std::vector<calibration::Finding> findings;
  calibration::CalibrationModel fitted;
  {
    py::gil_scoped_release release;
    std::vector<calibration::OvenRun> oven;
    for (const auto& r : records) oven.push_back(calibration::analyse_oven_run(r.name, r.time_s, r.temp_c, options.bin_s));
    findings = calibration::quality_gate(oven);
    fitted = calibration::fit_calibration(records, options);
  }
  py::list gate;
  for (const auto& f : findings) {
    py::dict d;
    d["severity"] = calibration::to_string(f.severity);
    d["code"] = f.code;
    d["message"] = f.message;
    gate.append(d);
  }
  return {CalibrationModel{std::make_shared<const calibration::ImuCalibration>(
              calibration::single_axis(std::move(fitted), axis))},
          gate};
}

py::tuple export_model(const CalibrationModel& m, const std::string& format, bool strict) {
  calibration::ExportOptions options;
  options.strict = strict;
  calibration::ExportResult r;
  if (format == "c-header") r = calibration::export_c_header(*m.model, options);
  else if (format == "px4") r = calibration::export_px4_params(*m.model, options);
  else if (format == "ardupilot") r = calibration::export_ardupilot_params(*m.model, options);
  else if (format == "kalibr") r = calibration::export_kalibr_imu_yaml(*m.model, options);
  else throw ConfigError({"", 0, "format"}, "'" + format + "': expected c-header, px4, ardupilot or kalibr");
  return py::make_tuple(r.text, r.notes);
}

// ---- pipelines -------------------------------------------------------------------------------

struct PipelineHandle {
  std::shared_ptr<const Pipeline> pipeline;
};

struct PipelineRun {
  py::dict outputs, units, report;
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
  const std::shared_ptr<const TimeSeries> record =
      py::isinstance<Record>(inputs) ? inputs.cast<const Record&>().series
                                     : record_from_arrays(inputs.cast<py::dict>(), fs_hz);
  if (threads < 1) throw ConfigError({"", 0, "threads"}, "must be >= 1");
  PipelineRunOptions options;
  options.threads = static_cast<unsigned>(threads);
  nlohmann::json report = nlohmann::json::object();
  std::map<std::string, Signal> outputs;
  {
    py::gil_scoped_release release;
    outputs = run_pipeline(*p.pipeline, registry(), *record, options, report);
  }
  PipelineRun r;
  for (auto& [name, signal] : outputs) {
    r.units[py::str(name)] = signal.unit;
    const bool single = signal.columns.cols() == 1;
    py::object columns = columns_to_numpy(std::move(signal.columns));
    r.outputs[py::str(name)] = single ? columns[py::int_(0)] : columns;  // one column: a view of its row
  }
  r.report = to_python(report);
  return r;
}

}  // namespace

void bind_data(py::module_& m) {
  py::class_<Record>(m, "Record",
                     "A record read from a file: time stamps and channels by role, in SI units (rad/s, m/s^2, "
                     "degC, Hz), as the command line reads it. Arrays view the record's storage.")
      .def_property_readonly("time_s", [](const Record& r) { return view_of(r.series->time(), r.series); })
      .def_property_readonly("channels", &record_channels, "role -> samples (rate, temperature, gyro_x, ...)")
      .def_property_readonly("units", [](const Record& r) { return per_channel(r, &Channel::unit); },
                             "role -> internal (SI) unit of its samples")
      .def_property_readonly("sources", [](const Record& r) { return per_channel(r, &Channel::source); },
                             "role -> the column or log field it was read from")
      .def_property_readonly("sample_rate_hz", [](const Record& r) { return r.series->sample_rate_hz(); },
                             "mean sample rate, Hz")
      .def_readonly("notes", &Record::notes, "what a log reader repaired or left out")
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
time series, or a log (PX4 ULog, and whatever readers the registry gains), into SI units.

columns: mappings 'role=column:unit' (e.g. 'rate=gyro_z:rad/s', 'time=timestamp:ms'); empty: the
  default columns (t_s and every unit-suffixed column: rate_dps -> rate, temp_c -> temperature) or,
  for a log, every IMU channel. fs_hz: for a CSV without a time column, t = i / fs_hz.
max_gap_factor: a time step above this times the median step is a DataError (0 reads gaps as they are).
topic, instance, sensor: what to take from a log (ignored for CSV). required: roles that must be
present. Returns Record (time_s, channels, units, sources, sample_rate_hz, notes).)");

  m.def(
      "device_files",
      [] { return devices::list_device_files(package("devices_dir")().cast<std::filesystem::path>()); },
      "The device files (*.yaml) of driftlab.devices_dir(), sorted.");
  const devices::SimulationOptions simulation_defaults;
  m.def("simulate", &simulate_device, py::arg("device"), py::arg("profile") = "oven",
        py::arg("fs_hz") = simulation_defaults.sample_rate_hz, py::arg("seed") = simulation_defaults.seed,
        py::arg("duration_s") = py::none(),
        R"(Runs a device through the oven simulator (devices/simulator.hpp), as `driftlab simulate`.

device: a device file, or the name of one in driftlab.devices_dir() ('fmvmg'); single-axis gyros.
profile: 'oven' (the paper's -30 -> +60 -> -30 degC run, 4.5 h) or a driftlab-profile/1 file.
fs_hz: sample rate, Hz. seed: the noise realization (same seed, same record).
duration_s: default the profile's.
Returns a dict of arrays: time_s, rate_rad_s, temp_c, true_rate_rad_s, systematic_rate_rad_s,
die_temp_c, chamber_temp_c, and drive_frequency_hz when the device has that channel.)");

  py::class_<Compensation>(m, "Compensation", "A compensated record (models/calibration: w = (w_m - bias) / sf)")
      .def_readonly("rate_rad_s", &Compensation::rate_rad_s,
                    "compensated samples, rad/s (m/s^2 for an accelerometer channel)")
      .def_readonly("bias_rad_s", &Compensation::bias_rad_s, "the correction subtracted at each sample, same unit")
      .def_readonly("extrapolated", &Compensation::extrapolated,
                    "True where the model temperature was outside the calibrated range");
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
      .def("to_json", [](const CalibrationModel& c) { return calibration::to_json_text(*c.model); },
           "The model as a driftlab-calibration/2 file's text.")
      .def("export", &export_model, py::arg("format"), py::arg("strict") = false,
           "The model in a firmware / navigation format: 'c-header', 'px4', 'ardupilot' or 'kalibr'. Returns "
           "(text, notes): notes list approximations and dropped terms (strict=True refuses them instead).")
      .def("__repr__", [](const CalibrationModel& c) {
        return "<driftlab.CalibrationModel " + std::to_string(c.model->channels.size()) + " channel(s)>";
      });
  py::class_<Calibration>(m, "Calibration", "What calibrate() fitted: the model and the oven-run quality gate")
      .def_readonly("model", &Calibration::model, "the CalibrationModel (one gyro channel)")
      .def_readonly("gate", &Calibration::gate,
                    "the quality gate's findings (models/calibration/oven_run.hpp): dicts of severity "
                    "('note', 'warning', 'error'), code and message; the CLI refuses a run with an error")
      .def("__repr__", [](const Calibration& c) {
        return "<driftlab.Calibration " + calibration::to_string(c.model.model->channels.front().model.kind) + ", " +
               std::to_string(py::len(c.gate)) + " gate finding(s)>";
      });
  m.def("calibrate", &calibrate, py::arg("runs"), py::arg("model") = "physical", py::arg("extrapolation") = "clamp",
        py::arg("reference_temp_c") = 25.0, py::arg("bin_s") = 10.0, py::arg("blocks") = 8, py::arg("seed") = 1,
        py::arg("axis") = 'z',
        R"(Fits one gyro channel's temperature-calibration model to its oven runs, as `driftlab calibrate`
does for each channel (models/calibration/fit.hpp: the order and the history terms -- lag, dT/dt,
hysteresis -- kept only when determinable from the runs, significant and better on held-out time blocks
and, with several runs or legs, on held-out runs or legs; the RBF part likewise).

runs: a list of dicts, one per oven run of the same unit: time_s (s, increasing), rate_rad_s (rad/s),
  temp_c (degC), optionally true_rate_rad_s (a rate table's rate; a scale factor is then fitted) and name.
model: 'physical' (default), 'poly' or 'rbf': the richest kind allowed. extrapolation: 'clamp',
  'linear' or 'evaluate' outside the fitted temperature range. reference_temp_c: T0, degC.
bin_s: fitting bins, s. blocks: held-out time blocks per run. seed: the RBF tuning's. axis: the
  channel's label in the model ('x', 'y', 'z').
Returns Calibration: .model (CalibrationModel: compensate, to_json, export) and .gate (the
quality gate's findings, reported here, not enforced).)");
  m.def("load_calibration", [](const std::filesystem::path& path) {
    return CalibrationModel{std::make_shared<const calibration::ImuCalibration>(calibration::read_calibration(path))};
  }, py::arg("path"), "Reads a calibration model file (driftlab-calibration/2, or /1 as one gyro channel).");

  py::class_<PipelineRun>(m, "PipelineRun", "The outputs of a pipeline run and its report")
      .def_readonly("outputs", &PipelineRun::outputs,
                    "output name -> samples (one column: shape (N,); several: (columns, N)), SI units")
      .def_readonly("units", &PipelineRun::units, "output name -> unit of its samples")
      .def_readonly("report", &PipelineRun::report, "per step: status, seconds and the plugin's diagnostics");
  py::class_<PipelineHandle>(m, "Pipeline", "A validated pipeline description (driftlab-pipeline/1)")
      .def_static("from_yaml", &pipeline_from_yaml, py::arg("source"),
                  "A pipeline from a file path, the name of a pipeline shipped with driftlab "
                  "(driftlab.pipelines_dir(): 'li2023'), or YAML text (anything with a line break). Validated "
                  "before any data is touched: ConfigError lists every problem with its line and key.")
      .def_property_readonly("inputs", [](const PipelineHandle& p) { return p.pipeline->inputs; },
                             "input name -> the record's channel role it reads")
      .def_property_readonly("outputs", [](const PipelineHandle& p) { return p.pipeline->output_order; })
      .def_property_readonly("steps", [](const PipelineHandle& p) {
        std::vector<std::pair<std::string, std::string>> steps;
        for (const auto& s : p.pipeline->steps) steps.emplace_back(s.name, s.plugin.empty() ? "sum" : s.plugin);
        return steps;
      }, "(name, plugin) per step, in execution order")
      .def_property_readonly("seed", [](const PipelineHandle& p) { return p.pipeline->seed; })
      .def("effective_yaml", [](const PipelineHandle& p) { return effective_pipeline_yaml(*p.pipeline, registry()); },
           "The pipeline with every parameter and seed written out; loading it gives the same run.")
      .def("run", &run, py::arg("inputs"), py::arg("threads") = 1, py::arg("fs_hz") = py::none(),
           "Runs the steps on a Record, or on a dict of arrays by channel role ('rate' rad/s, 'temperature' degC, "
           "...) with 'time' (s) or fs_hz. threads: worker threads (results do not depend on them). "
           "Returns PipelineRun (outputs, units, report).");
}

}  // namespace driftlab::python
