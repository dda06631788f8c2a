// `driftlab compensate`: applies a calibration model (driftlab-calibration/2, or /1) sample by
// sample (CausalCompensator per channel), to a file (--data in.csv --out out.csv) or as a pipe
// (--stream: CSV rows on standard input, compensated rows on standard output, one by one, constant
// memory: at most one line of --max-line-bytes, 1 MiB by default, is held). Optional causal Kalman
// stage on the gyro channels (plugins/kalman scalar random-walk filter) for a static gyro: a
// compensated rate that jumps away from its estimate (motion) is a DataError. Both modes run one row
// engine on the one CSV row parser and line rule (framework/csv.hpp: CsvRowParser, CsvLineCursor,
// CsvLineStream), so they accept the same rows with the same messages and streaming output equals
// batch output byte for byte; only the gap test (--max-gap), which needs the whole record, is batch's.
// A log (PX4 ULog, ArduPilot DataFlash; --data, recognised by content) is read as its IMU record in
// the columns `driftlab log export` writes (cli.hpp imu_record_columns), --topic/--instance/--sensor
// picking what to read; --column then names those columns.
//
// Output: every input column in its own name, unit and order; the columns of the channels the model
// covers hold the compensated values (in the column's own unit), every other cell is passed through
// as it was. Appended: bias_<column> (the correction subtracted, same unit) per corrected column,
// with --kalman compensated_<column> (before the Kalman stage) per gyro column, and extrapolated:
// 0 when every model input of every channel was inside the range it was fitted on, else the sum of
// the inputs outside (calibration::kOutside*: 1 model temperature, 2 dT/dt, 4 branch state, 8 an
// RBF input), over the channels.
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/imu.hpp"
#include "framework/output_set.hpp"
#include "framework/record_reader.hpp"
#include "framework/regular_file.hpp"
#include "framework/units.hpp"
#include "models/calibration/calibration_model.hpp"
#include "plugins/kalman/kalman.hpp"
#include "tools/driftlab/calibration_cli.hpp"
#include "tools/driftlab/cli.hpp"

namespace driftlab::cli {
namespace {

struct CompensateOptions {
  std::string model;
  CalibrationDataOptions data;
  std::string out;
  bool stream = false;
  bool kalman = false;
  double kalman_q = 0.0, kalman_r = 0.0;              // (rad/s)^2 per sample; 0: from the model's noise terms
  double kalman_fs = 0.0;                             // Hz, for the noise-term conversion; 0: the model's
  std::size_t max_line_bytes = std::size_t{1} << 20;  // --stream: the one line it holds at most
};

std::optional<kalman::ScalarModel> kalman_model(const calibration::ChannelCalibration& c, const CompensateOptions& o) {
  if (!o.kalman || c.id.sensor != imu::Sensor::Gyro) return std::nullopt;
  const auto& model = c.model;
  double q = o.kalman_q, r = o.kalman_r;
  const double fs = o.kalman_fs > 0 ? o.kalman_fs : model.noise.sample_rate_hz;
  if (r <= 0) {
    if (!(model.noise.arw_rad_sqrt_s > 0 && fs > 0)) {
      throw ConfigError({o.model, 0, c.role + ".noise.arw_rad_sqrt_s"},
                        "--kalman needs --kalman-r, or a model with an ARW noise term and a sample rate");
    }
    r = kalman::measurement_variance_from_arw(model.noise.arw_rad_sqrt_s, fs);
  }
  if (q <= 0) {
    if (!(model.noise.rate_random_walk_rad_s_sqrt_s > 0 && fs > 0)) {
      throw ConfigError({o.model, 0, c.role + ".noise.rate_random_walk_rad_s_sqrt_s"},
                        "--kalman needs --kalman-q, or a model with a rate-random-walk term and a sample rate");
    }
    q = kalman::process_variance_from_rrw(model.noise.rate_random_walk_rad_s_sqrt_s, fs);
  }
  return kalman::ScalarModel{q, r};
}

void append_number(double v, std::string& out) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, res.ptr);
}

CsvReadOptions read_options(const CompensateOptions& o) {
  CsvReadOptions read;
  for (const auto& c : o.data.columns) read.columns.push_back(parse_column_mapping(c));
  read.required_roles = {};
  read.sample_rate_hz = o.data.sample_rate_hz;
  read.max_gap_factor = o.data.max_gap_factor;
  return read;
}

// The per-row engine shared by batch and stream, on the rows of the one CSV row parser
// (framework/csv.hpp CsvRowParser: its checks and messages): from the header, which column each
// model channel corrects; then row by row, the compensated row.
class Engine {
 public:
  Engine(const calibration::ImuCalibration& model, const CompensateOptions& o, CsvRowParser& parser)
      : model_(model), options_(o), parser_(parser) {}

  // Parses the header line and returns the output header line.
  std::string header(std::string_view line, int line_number) {
    parser_.header(line, line_number);
    const std::string& file = parser_.file();
    const auto& names = parser_.header_names();
    std::string out(line);
    std::vector<std::string> appended;
    for (const auto& c : model_.channels) {
      const auto value = column(c.role);
      if (!value) {
        std::string have;
        for (const auto& p : parser_.columns())
          if (p.mapping.role != "time")
            have += (have.empty() ? "" : ", ") + p.mapping.role + " (" + p.mapping.column + ")";
        throw ConfigError({file, line_number, c.role},
                          "the model's channel " + c.role + " (fitted on column '" + c.column +
                              "') is not in this record, which has: " + (have.empty() ? "no channel" : have) +
                              "; a model applies only to the channels it was fitted on");
      }
      auto temp = column(imu::temperature_role(c.id.instance));
      if (!temp) temp = column(role::kTemperature);
      if (!temp)
        throw DataError({file, line_number, imu::temperature_role(c.id.instance)},
                        "no temperature column for " + c.role + " (the model's is '" + c.temperature_column + "')");
      const auto device =
          column(c.id.instance ? "device_id" + std::to_string(c.id.instance) : std::string("device_id"));
      Corrected k{
          &c, *value, *temp, device, calibration::CausalCompensator(c.model), kalman_model(c, options_), std::nullopt};
      appended.push_back("bias_" + names[parser_.columns()[*value].index]);
      if (k.kalman) appended.push_back("compensated_" + names[parser_.columns()[*value].index]);
      corrected_.push_back(std::move(k));
    }
    appended.push_back("extrapolated");
    for (const auto& a : appended) {
      for (const auto& n : names)
        if (n == a)
          throw ConfigError({file, line_number, a}, "the record already has a column '" + a +
                                                        "', which the compensated output appends; rename it");
      out += "," + a;
    }
    return out + "\n";
  }

  // Parses one row (`line` without its line end) and appends its output row.
  void row(std::string_view line, int line_number, std::string& out) {
    parser_.row(line, line_number);
    const auto& columns = parser_.columns();
    const auto& values = parser_.values();
    const auto& cells = parser_.cells();
    const double t = parser_.time_s();
    replaced_.assign(cells.size(), std::string());
    std::string tail;
    unsigned outside = 0;
    for (auto& k : corrected_) {
      const Unit& unit = columns[k.value].unit;
      if (k.device && !k.channel->device_id.empty()) {
        std::string id;
        append_number(values[*k.device], id);
        if (id != k.channel->device_id)
          throw ConfigError({parser_.file(), line_number, "device_id"},
                            "this record is device " + id + ", the model's " + k.channel->role +
                                " was fitted on device " + k.channel->device_id);
      }
      double w;
      try {
        w = k.compensator.step(t, values[k.value], values[k.temp]);
      } catch (const DataError& e) {
        throw DataError({parser_.file(), line_number, e.where().field}, e.what());
      }
      double y = w;
      if (k.kalman) {
        if (!k.filter) k.filter.emplace(*k.kalman, w, k.kalman->r);
        check_static(*k.filter, *k.kalman, w, columns[k.value], line_number);
        y = k.filter->step(w);
      }
      outside |= k.compensator.last_outside();
      append_number(from_internal(y, unit), replaced_[columns[k.value].index]);
      tail += ',';
      append_number(difference_from_internal(k.compensator.last_bias_rad_s(), unit), tail);
      if (k.kalman) {
        tail += ',';
        append_number(from_internal(w, unit), tail);
      }
    }
    for (std::size_t i = 0; i < cells.size(); ++i) {
      if (i) out += ',';
      if (replaced_[i].empty())
        out.append(cells[i]);
      else
        out += replaced_[i];
    }
    out += tail;
    out += ',';
    out += std::to_string(outside);
    out += '\n';
  }

 private:
  // The Kalman stage models a static gyro (a random walk plus white noise): a compensated rate
  // further than kMotionSigmas standard deviations of its innovation (prior variance + q + r) from
  // the filter's estimate is motion, which the filter would smear over its time constant (a 50-deg/s
  // step read as 0.05 deg/s at the step): a DataError naming the line and column. For Gaussian
  // noise such a jump has probability ~1e-15 per sample.
  static constexpr double kMotionSigmas = 8.0;
  void check_static(const kalman::ScalarFilter& filter, const kalman::ScalarModel& model, double w,
                    const PlannedColumn& column, int line_number) const {
    const double innovation = w - filter.state();
    const double sigma = std::sqrt(filter.variance() + model.q + model.r);
    if (std::abs(innovation) <= kMotionSigmas * sigma) return;
    char text[160];
    std::snprintf(text, sizeof text,
                  "the compensated rate jumps by %.4g %s against the Kalman stage's %.3g %s (1 sigma) ",
                  difference_from_internal(innovation, column.unit), column.unit.symbol.c_str(),
                  difference_from_internal(sigma, column.unit), column.unit.symbol.c_str());
    throw DataError({parser_.file(), line_number, column.mapping.column},
                    std::string(text) +
                        "of a static gyro: the gyro moves. --kalman assumes a static gyro and would "
                        "smear the motion over its time constant; compensate without --kalman");
  }

  // Positions in parser_.columns().
  struct Corrected {
    const calibration::ChannelCalibration* channel;
    std::size_t value, temp;
    std::optional<std::size_t> device;
    calibration::CausalCompensator compensator;
    std::optional<kalman::ScalarModel> kalman;
    std::optional<kalman::ScalarFilter> filter;
  };

  std::optional<std::size_t> column(const std::string& role) const {
    const PlannedColumn* p = parser_.find(role);
    if (!p) return std::nullopt;
    return static_cast<std::size_t>(p - parser_.columns().data());
  }

  const calibration::ImuCalibration& model_;
  const CompensateOptions& options_;
  CsvRowParser& parser_;
  std::vector<Corrected> corrected_;
  std::vector<std::string> replaced_;
};

void batch(const calibration::ImuCalibration& model, const CompensateOptions& o) {
  if (o.out.empty()) throw ConfigError({"", 0, "--out"}, "--out is required without --stream");
  const std::string& path = o.data.paths.front();
  OutputSet outputs({path, o.model});
  outputs.plan(o.out, "--out");
  const CsvReadOptions read = read_options(o);
  std::string text;
  if (is_stdin(path) || sniff_record_format(path) == RecordFormat::Csv) {  // "-": CSV on standard input
    text = read_text_file(path);
  } else {
    CsvReadOptions log_read = read;
    log_read.columns.clear();
    std::vector<std::string> notes;
    text = format_csv(imu_record_columns(read_record(path, log_read, o.data.log, &notes)), path);
    for (const auto& n : notes) std::cerr << "note: " << n << "\n";
  }
  // The whole record's checks first (the gap test needs every time stamp; errors naming line and
  // column) ...
  parse_csv(text, input_name(path), read);
  // ... then every row through the engine.
  CsvRowParser parser(input_name(path), read);
  Engine engine(model, o, parser);
  CsvLineCursor cursor(text);
  std::string_view line;
  cursor.next(line);
  std::string out = engine.header(line, cursor.line_number());
  out.reserve(text.size() * 2 + 64);
  while (cursor.next(line)) engine.row(line, cursor.line_number(), out);
  outputs.write(o.out, out);
  outputs.commit();
}

// Rows are written as they complete: the output is flushed before every read of standard input
// (which may block until the next row arrives).
void stream(const calibration::ImuCalibration& model, const CompensateOptions& o) {
  std::string out;
  const auto flush = [&] {
    if (!out.empty() && std::fwrite(out.data(), 1, out.size(), stdout) != out.size())
      throw Error("write to standard output failed");
    out.clear();
    std::fflush(stdout);
  };
  CsvLineStream lines(
      [&](char* buffer, std::size_t size) -> std::size_t {
        flush();
        for (;;) {
          const ssize_t got = ::read(STDIN_FILENO, buffer, size);
          if (got >= 0) return static_cast<std::size_t>(got);
          if (errno != EINTR) throw DataError({"<stdin>", 0, ""}, std::string("cannot read: ") + std::strerror(errno));
        }
      },
      "<stdin>", o.max_line_bytes);
  CsvRowParser parser("<stdin>", read_options(o));
  Engine engine(model, o, parser);
  std::string_view line;
  while (lines.next(line)) {
    if (!parser.has_header()) {
      out += engine.header(line, lines.line_number());
      continue;
    }
    engine.row(line, lines.line_number(), out);
    if (out.size() > (1 << 16)) flush();
  }
  flush();
  parser.finish();
}

}  // namespace

void add_compensate_command(CLI::App& app, CommandEnv&) {
  auto o = std::make_shared<CompensateOptions>();
  auto* cmd = app.add_subcommand(
      "compensate", "apply a calibration model sample by sample (causal), to a file or as a stdin -> stdout pipe");
  cmd->add_option("--model", o->model, "calibration model JSON (from driftlab calibrate); - reads standard input")
      ->required();
  cmd->add_option("--data", o->data.paths,
                  "input CSV (the columns the model was fitted on; every other column is "
                  "passed through), or a PX4 ULog / ArduPilot DataFlash log, read as "
                  "`driftlab log export` writes it; - reads CSV from standard input")
      ->expected(1);
  cmd->add_option(
      "--column", o->data.columns,
      "column mapping role=column:unit, as for driftlab calibrate (gyro_x=gx:deg/s, temperature=T:degC, ...)");
  add_log_selection_options(cmd, o->data.log);
  add_sampling_options(cmd, o->data.sample_rate_hz, o->data.max_gap_factor,
                       "sample rate in Hz, for input without a time column",
                       "batch: largest allowed time step, as a multiple of the median step (0 allows gaps)");
  cmd->add_option("--out", o->out, "output CSV (written atomically)");
  cmd->add_flag("--stream", o->stream,
                "read CSV rows from standard input and write compensated rows to standard output, one by one");
  cmd->add_option("--max-line-bytes", o->max_line_bytes,
                  "--stream: longest input line held, bytes; a longer one is a data error (exit 3)")
      ->check(CLI::Range(std::size_t{16}, std::size_t{1} << 30))
      ->capture_default_str();
  cmd->add_flag("--kalman", o->kalman,
                "add a causal Kalman stage to each gyro channel (random walk + white noise, plugins/kalman)");
  const std::vector<CLI::Option*> kalman_options{
      cmd->add_option("--kalman-q", o->kalman_q,
                      "Kalman random-walk variance per sample, (rad/s)^2 (default: K^2/fs "
                      "from the model's noise terms)")
          ->check(finite_number(0.0, 1e12)),
      cmd->add_option("--kalman-r", o->kalman_r, "Kalman measurement variance, (rad/s)^2 (default: N^2 fs)")
          ->check(finite_number(0.0, 1e12)),
      cmd->add_option("--kalman-fs", o->kalman_fs,
                      "sample rate for the noise-term conversion, Hz (default: the model's)")
          ->check(finite_number(0.0, 1e12))};
  cmd->callback([o, kalman_options] {
    if (o->stream == !o->data.paths.empty()) {
      throw ConfigError({"", 0, "--data"}, "give either --data (with --out) or --stream");
    }
    if (o->stream && !o->out.empty())
      throw ConfigError({"", 0, "--out"}, "--stream writes to standard output; drop --out");
    if (o->stream && is_stdin(o->model))
      throw ConfigError({"<stdin>", 0, "--model"},
                        "--stream reads the rows from standard input; the model cannot be - too");
    for (const CLI::Option* option : kalman_options)  // given at all, even as 0, it would be ignored
      if (!o->kalman && option->count() > 0)
        throw ConfigError({"", 0, option->get_name()}, option->get_name() +
                                                           " needs --kalman (without it no Kalman "
                                                           "stage runs and the value would be ignored)");
    const auto model = calibration::read_calibration(o->model);
    if (o->stream) {
      stream(model, *o);
    } else {
      batch(model, *o);
    }
  });
}

}  // namespace driftlab::cli
