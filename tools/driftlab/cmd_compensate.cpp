// `driftlab compensate`: applies a calibration model (driftlab-calibration/2, or /1) sample by
// sample (CausalCompensator per channel), to a file (--data in.csv --out out.csv) or as a pipe
// (--stream: CSV rows on standard input, compensated rows on standard output, one by one, constant
// memory: at most one line of --max-line-bytes, 1 MiB by default, is held). Optional causal Kalman
// stage on the gyro channels (plugins/kalman scalar random-walk filter). Both modes run one row
// engine and one line rule (CsvLineCursor), so streaming output equals batch output byte for byte.
// A log (PX4 ULog, ArduPilot DataFlash; --data, recognised by content) is read as its IMU record in
// the columns `driftlab log export` writes (cli.hpp imu_record_columns), --topic/--instance/--sensor
// picking what to read; --column then names those columns.
//
// Output: every input column in its own name, unit and order; the columns of the channels the model
// covers hold the compensated values (in the column's own unit), every other cell is passed through
// as it was. Appended: bias_<column> (the correction subtracted, same unit) per corrected column,
// with --kalman compensated_<column> (before the Kalman stage) per gyro column, and extrapolated
// (1 when some channel's model temperature was outside its calibrated range).
#include <algorithm>
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

// The cells of one row as they are, untrimmed (passed through byte for byte).
void raw_cells(std::string_view line, std::vector<std::string_view>& cells) {
  cells.clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    cells.push_back(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
}

void append_number(double v, std::string& out) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, res.ptr);
}

// The per-row engine shared by batch and stream: from the header row, which column each model
// channel corrects; then row by row, the compensated row.
class Engine {
 public:
  Engine(const calibration::ImuCalibration& model, const CompensateOptions& o, std::string file)
      : model_(model), options_(o), file_(std::move(file)) {}

  // Plans the columns from the header line and returns the output header line.
  std::string header(std::string_view line, int line_number) {
    CsvReadOptions read;
    for (const auto& c : options_.data.columns) read.columns.push_back(parse_column_mapping(c));
    read.required_roles = {};
    read.sample_rate_hz = options_.data.sample_rate_hz;
    const auto names = split_csv_row(line);
    double number = 0.0;
    if (std::all_of(names.begin(), names.end(), [&](std::string_view c) { return parse_csv_number(c, number); }))
      throw DataError({file_, line_number, ""}, "missing header row (the first row holds only numbers)");
    const auto planned = plan_columns(names, read, file_, line_number);
    names_.assign(names.begin(), names.end());
    const auto find = [&](const std::string& role) -> const PlannedColumn* {
      for (const auto& p : planned)
        if (p.mapping.role == role) return &p;
      return nullptr;
    };
    if (const auto* t = find("time")) time_ = {t->index, t->unit};
    columns_ = names.size();
    std::string out(line);
    std::vector<std::string> appended;
    for (const auto& c : model_.channels) {
      const auto* value = find(c.role);
      if (!value) {
        std::string have;
        for (const auto& p : planned)
          if (p.mapping.role != "time")
            have += (have.empty() ? "" : ", ") + p.mapping.role + " (" + p.mapping.column + ")";
        throw ConfigError({file_, line_number, c.role},
                          "the model's channel " + c.role + " (fitted on column '" + c.column +
                              "') is not in this record, which has: " + (have.empty() ? "no channel" : have) +
                              "; a model applies only to the channels it was fitted on");
      }
      const auto* temp = find(imu::temperature_role(c.id.instance));
      if (!temp) temp = find(role::kTemperature);
      if (!temp)
        throw DataError({file_, line_number, imu::temperature_role(c.id.instance)},
                        "no temperature column for " + c.role + " (the model's is '" + c.temperature_column + "')");
      const auto* device = find(c.id.instance ? "device_id" + std::to_string(c.id.instance) : std::string("device_id"));
      Corrected k{&c,
                  value->index,
                  value->unit,
                  temp->index,
                  temp->unit,
                  device ? std::optional(device->index) : std::nullopt,
                  calibration::CausalCompensator(c.model),
                  kalman_model(c, options_),
                  std::nullopt};
      appended.push_back("bias_" + std::string(names[value->index]));
      if (k.kalman) appended.push_back("compensated_" + std::string(names[value->index]));
      corrected_.push_back(std::move(k));
    }
    appended.push_back("extrapolated");
    for (const auto& a : appended) {
      for (const auto& n : names)
        if (n == a)
          throw ConfigError({file_, line_number, a}, "the record already has a column '" + a +
                                                         "', which the compensated output appends; rename it");
      out += "," + a;
    }
    return out + "\n";
  }

  // Appends the output row for one input row (`line` without its line end).
  void row(std::string_view line, int line_number, std::string& out) {
    raw_cells(line, cells_);
    if (cells_.size() != columns_)
      throw DataError({file_, line_number, ""}, "row has " + std::to_string(cells_.size()) + " cells, the header has " +
                                                    std::to_string(columns_));
    const double t = time_ ? value(time_->first, &time_->second, line_number)
                           : static_cast<double>(sample_) / options_.data.sample_rate_hz;
    ++sample_;
    replaced_.assign(cells_.size(), std::string());
    std::string tail;
    bool extrapolated = false;
    for (auto& k : corrected_) {
      const double measured = value(k.value_index, &k.value_unit, line_number);
      const double temp = value(k.temp_index, &k.temp_unit, line_number);
      if (k.device_index && !k.channel->device_id.empty()) {
        std::string id;
        append_number(value(*k.device_index, nullptr, line_number), id);
        if (id != k.channel->device_id)
          throw ConfigError({file_, line_number, "device_id"}, "this record is device " + id + ", the model's " +
                                                                   k.channel->role + " was fitted on device " +
                                                                   k.channel->device_id);
      }
      double w;
      try {
        w = k.compensator.step(t, measured, temp);
      } catch (const DataError& e) {
        throw DataError({file_, line_number, e.where().field}, e.what());
      }
      double y = w;
      if (k.kalman) {
        if (!k.filter) k.filter.emplace(*k.kalman, w, k.kalman->r);
        y = k.filter->step(w);
      }
      extrapolated = extrapolated || k.compensator.last_extrapolated();
      append_number(from_internal(y, k.value_unit), replaced_[k.value_index]);
      tail += ',';
      append_number(difference_from_internal(k.compensator.last_bias_rad_s(), k.value_unit), tail);
      if (k.kalman) {
        tail += ',';
        append_number(from_internal(w, k.value_unit), tail);
      }
    }
    for (std::size_t i = 0; i < cells_.size(); ++i) {
      if (i) out += ',';
      if (replaced_[i].empty())
        out.append(cells_[i]);
      else
        out += replaced_[i];
    }
    out += tail;
    out += extrapolated ? ",1\n" : ",0\n";
  }

 private:
  struct Corrected {
    const calibration::ChannelCalibration* channel;
    std::size_t value_index;
    Unit value_unit;
    std::size_t temp_index;
    Unit temp_unit;
    std::optional<std::size_t> device_index;
    calibration::CausalCompensator compensator;
    std::optional<kalman::ScalarModel> kalman;
    std::optional<kalman::ScalarFilter> filter;
  };

  // The cell as a number in internal units (`unit` null: the number as written); a bad cell is
  // named by its column with the batch reader's messages (parse_csv, which batch runs first).
  double value(std::size_t index, const Unit* unit, int line_number) const {
    const std::string& field = names_[index];
    std::string_view text = cells_[index];
    while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
    while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
    double v = 0.0;
    if (text.empty()) throw DataError({file_, line_number, field}, "empty cell (expected a number)");
    if (!parse_csv_number(text, v))
      throw DataError({file_, line_number, field}, "expected a number, got " + quoted_excerpt(text));
    if (!std::isfinite(v))
      throw DataError({file_, line_number, field}, "value is " + quoted_excerpt(text) + " (NaN/Inf not allowed)");
    const double internal = unit ? to_internal(v, *unit) : v;
    if (!(std::abs(internal) <= kMaxMagnitude))
      throw DataError({file_, line_number, field}, "value " + quoted_excerpt(text) + " is too large to compute with");
    return internal;
  }

  const calibration::ImuCalibration& model_;
  const CompensateOptions& options_;
  std::string file_;
  std::optional<std::pair<std::size_t, Unit>> time_;
  std::size_t columns_ = 0;
  std::vector<std::string> names_;  // the header's cells
  std::vector<Corrected> corrected_;
  std::vector<std::string_view> cells_;
  std::vector<std::string> replaced_;
  long sample_ = 0;
};

void batch(const calibration::ImuCalibration& model, const CompensateOptions& o) {
  if (o.out.empty()) throw ConfigError({"", 0, "--out"}, "--out is required without --stream");
  const std::string& path = o.data.paths.front();
  OutputSet outputs({path, o.model});
  outputs.plan(o.out, "--out");
  // The reader's checks first (cells, time order, gaps: errors naming line and column) ...
  CsvReadOptions read;
  for (const auto& c : o.data.columns) read.columns.push_back(parse_column_mapping(c));
  read.required_roles = {};
  read.sample_rate_hz = o.data.sample_rate_hz;
  read.max_gap_factor = o.data.max_gap_factor;
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
  parse_csv(text, input_name(path), read);
  // ... then every row through the engine.
  Engine engine(model, o, input_name(path));
  CsvLineCursor cursor(text);
  std::string_view line;
  cursor.next(line);
  std::string out = engine.header(line, cursor.line_number());
  out.reserve(text.size() * 2 + 64);
  while (cursor.next(line)) engine.row(line, cursor.line_number(), out);
  outputs.write(o.out, out);
  outputs.commit();
}

void stream(const calibration::ImuCalibration& model, const CompensateOptions& o) {
  Engine engine(model, o, "<stdin>");
  std::string out;
  out.reserve(1 << 17);
  std::vector<char> buffer(1 << 20);
  // Bytes read and not yet processed: after each read, the complete lines go through the batch
  // reader's line cursor (byte-order mark, LF / CR LF / CR line ends, blank and '#' lines: one
  // rule), and at most one incomplete line of at most --max-line-bytes stays.
  std::string pending;
  int lines_before = 0, header_line = 0;
  bool have_header = false;
  long rows = 0;
  const auto too_long = [&](std::size_t bytes, int line) {
    if (bytes > o.max_line_bytes)
      throw DataError({"<stdin>", line, ""}, "the line is longer than " + std::to_string(o.max_line_bytes) +
                                                 " bytes (--max-line-bytes): --stream holds one line at a time, "
                                                 "and a CSV row is far shorter");
  };
  const auto flush = [&] {
    if (!out.empty() && std::fwrite(out.data(), 1, out.size(), stdout) != out.size()) {
      throw Error("write to standard output failed");
    }
    out.clear();
  };
  bool end = false;
  while (!end) {
    const std::size_t got = std::fread(buffer.data(), 1, buffer.size(), stdin);
    end = got == 0;
    pending.append(buffer.data(), got);
    // The complete lines: up to the last line end, unless that is a CR at the end of what was read
    // (a CR LF may be split between two reads); at the end, everything.
    std::size_t complete = pending.size();
    if (!end) {
      std::size_t last = pending.find_last_of("\r\n");
      if (last != std::string::npos && pending[last] == '\r' && last + 1 == pending.size())
        last = last == 0 ? std::string::npos : pending.find_last_of("\r\n", last - 1);
      complete = last == std::string::npos ? 0 : last + 1;
    }
    if (complete > 0) {
      const std::string block = pending.substr(0, complete);
      pending.erase(0, complete);
      CsvLineCursor cursor(block);
      std::string_view text;
      while (cursor.next(text)) {
        const int line = lines_before + cursor.line_number();
        too_long(text.size(), line);
        if (!have_header) {
          out += engine.header(text, line);
          have_header = true;
          header_line = line;
          continue;
        }
        engine.row(text, line, out);
        ++rows;
        if (out.size() > (1 << 16)) flush();
      }
      lines_before += cursor.line_number();
    }
    too_long(pending.size(), lines_before + 1);
    // Rows are emitted as they complete; a pipe reader sees them after each read.
    flush();
    std::fflush(stdout);
  }
  // The batch reader's messages for an input without rows.
  if (!have_header) throw DataError({"<stdin>", 0, ""}, "file is empty (expected a header row and data rows)");
  if (rows == 0) throw DataError({"<stdin>", header_line, ""}, "no data rows after the header");
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
