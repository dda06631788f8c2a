// `driftlab compensate`: applies a driftlab-calibration/1 model sample by sample (CausalCompensator),
// to a file (--data in.csv --out out.csv) or as a pipe (--stream: CSV rows on standard input,
// compensated rows on standard output, one by one, constant memory). Optional causal Kalman stage
// (plugins/kalman scalar random-walk filter). Both modes format rows identically, so streaming
// output equals batch output byte for byte.
//
// Output columns: t_s, rate_dps (the final output), bias_dps (the correction subtracted), temp_c,
// extrapolated (1 when the model temperature was outside the calibrated range), and with --kalman
// also compensated_dps (before the Kalman stage).
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

#include "framework/output_set.hpp"
#include "framework/csv.hpp"
#include "framework/error.hpp"
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
  double kalman_q = 0.0, kalman_r = 0.0;  // (rad/s)^2 per sample; 0: from the model's noise terms
  double kalman_fs = 0.0;                 // Hz, for the noise-term conversion; 0: the model's
};

const Unit& unit_of(const char* spelling) {
  static const Unit deg_s = *find_unit("deg/s"), deg_c = *find_unit("degC"), s = *find_unit("s"), one = *find_unit("1");
  const std::string_view u(spelling);
  return u == "deg/s" ? deg_s : u == "degC" ? deg_c : u == "s" ? s : one;
}

// The per-sample engine shared by batch and stream: compensator + optional Kalman + row formatting.
class Engine {
 public:
  Engine(const calibration::CalibrationModel& model, const CompensateOptions& o) : comp_(model) {
    if (o.kalman) {
      double q = o.kalman_q, r = o.kalman_r;
      const double fs = o.kalman_fs > 0 ? o.kalman_fs : model.noise.sample_rate_hz;
      if (r <= 0) {
        if (!(model.noise.arw_rad_sqrt_s > 0 && fs > 0)) {
          throw ConfigError({o.model, 0, "noise.arw_rad_sqrt_s"},
                            "--kalman needs --kalman-r, or a model with an ARW noise term and a sample rate");
        }
        r = model.noise.arw_rad_sqrt_s * model.noise.arw_rad_sqrt_s * fs;  // R = N^2 fs
      }
      if (q <= 0) {
        if (!(model.noise.rate_random_walk_rad_s_sqrt_s > 0 && fs > 0)) {
          throw ConfigError({o.model, 0, "noise.rate_random_walk_rad_s_sqrt_s"},
                            "--kalman needs --kalman-q, or a model with a rate-random-walk term and a sample rate");
        }
        q = model.noise.rate_random_walk_rad_s_sqrt_s * model.noise.rate_random_walk_rad_s_sqrt_s / fs;  // Q = K^2/fs
      }
      kalman_model_ = kalman::ScalarModel{q, r};
    }
  }

  std::string header() const {
    return kalman_model_ ? "t_s,rate_dps,bias_dps,temp_c,extrapolated,compensated_dps\n"
                         : "t_s,rate_dps,bias_dps,temp_c,extrapolated\n";
  }

  // Appends one output row for one input sample (internal units).
  void row(double t_s, double rate_rad_s, double temp_c, std::string& out) {
    const double w = comp_.step(t_s, rate_rad_s, temp_c);
    double y = w;
    if (kalman_model_) {
      if (!filter_) filter_.emplace(*kalman_model_, w, kalman_model_->r);
      y = filter_->step(w);
    }
    number(t_s, unit_of("s"), out);
    out += ',';
    number(y, unit_of("deg/s"), out);
    out += ',';
    number(comp_.last_bias_rad_s(), unit_of("deg/s"), out);
    out += ',';
    number(temp_c, unit_of("degC"), out);
    out += comp_.last_extrapolated() ? ",1" : ",0";
    if (kalman_model_) {
      out += ',';
      number(w, unit_of("deg/s"), out);
    }
    out += '\n';
  }

 private:
  static void number(double v, const Unit& u, std::string& out) {
    char buf[32];
    const auto res = std::to_chars(buf, buf + sizeof buf, from_internal(v, u));
    out.append(buf, res.ptr);
  }

  calibration::CausalCompensator comp_;
  std::optional<kalman::ScalarModel> kalman_model_;
  std::optional<kalman::ScalarFilter> filter_;
};

void batch(const calibration::CalibrationModel& model, const CompensateOptions& o) {
  if (o.out.empty()) throw ConfigError({"", 0, "--out"}, "--out is required without --stream");
  OutputSet outputs({o.data.paths.front(), o.model});
  outputs.plan(o.out, "--out");
  const auto record = load_calibration_record(o.data.paths.front(), o.data);
  Engine engine(model, o);
  std::string text = engine.header();
  text.reserve(static_cast<std::size_t>(record.time_s.size()) * 64 + 64);
  for (Eigen::Index i = 0; i < record.time_s.size(); ++i) {
    try {
      engine.row(record.time_s[i], record.rate_rad_s[i], record.temp_c[i], text);
    } catch (const DataError& e) {
      throw DataError({record.name, static_cast<int>(i) + 2, e.where().field}, e.what());
    }
  }
  outputs.write(o.out, text);
  outputs.commit();
}

// ---- streaming ------------------------------------------------------------------------------

struct StreamColumns {
  int time = -1, rate = -1, temp = -1;
  Unit time_unit, rate_unit, temp_unit;
  std::size_t count = 0;
};

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> cells;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    cells.push_back(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return cells;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

StreamColumns stream_columns(std::string_view header, const CompensateOptions& o) {
  const auto names = split(header);
  StreamColumns c;
  c.count = names.size();
  std::vector<ColumnMapping> maps{{"time", "t_s", "s"}, {role::kRate, "rate_dps", "deg/s"},
                                  {role::kTemperature, "temp_c", "degC"}};
  for (const auto& text : o.data.columns) {
    const auto m = parse_column_mapping(text);
    for (auto& d : maps) {
      if (d.role == m.role) d = m;
    }
  }
  for (const auto& m : maps) {
    if (m.role == "time" && o.data.sample_rate_hz > 0) continue;
    int index = -1;
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (trim(names[i]) == m.column) index = static_cast<int>(i);
    }
    if (index < 0) throw DataError({"<stdin>", 1, m.column}, "missing column '" + m.column + "' in the header");
    const auto unit = find_unit(m.unit);
    if (!unit) throw ConfigError({"", 0, "--column"}, "unknown unit '" + m.unit + "'");
    if (m.role == "time") {
      c.time = index;
      c.time_unit = *unit;
    } else if (m.role == role::kRate) {
      c.rate = index;
      c.rate_unit = *unit;
    } else {
      c.temp = index;
      c.temp_unit = *unit;
    }
  }
  return c;
}

double cell(const std::vector<std::string_view>& cells, int index, long line, const char* name) {
  const std::string_view text = trim(cells[static_cast<std::size_t>(index)]);
  double v = 0.0;
  const auto res = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || res.ec != std::errc() || res.ptr != text.data() + text.size()) {
    throw DataError({"<stdin>", static_cast<int>(line), name}, "not a number: " + quoted_excerpt(text));
  }
  if (!std::isfinite(v)) throw DataError({"<stdin>", static_cast<int>(line), name}, "NaN or Inf");
  return v;
}

void stream(const calibration::CalibrationModel& model, const CompensateOptions& o) {
  Engine engine(model, o);
  std::string out;
  out.reserve(1 << 17);
  std::vector<char> buffer(1 << 20);
  std::string carry;
  long line = 0;
  std::optional<StreamColumns> cols;
  std::vector<std::string_view> cells;
  long sample = 0;
  const auto flush = [&] {
    if (!out.empty() && std::fwrite(out.data(), 1, out.size(), stdout) != out.size()) {
      throw Error("write to standard output failed");
    }
    out.clear();
  };
  const auto handle = [&](std::string_view text) {
    ++line;
    if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
    if (trim(text).empty() || text.front() == '#') return;
    if (!cols) {
      cols = stream_columns(text, o);
      out += engine.header();
      return;
    }
    cells = split(text);
    if (cells.size() != cols->count) {
      throw DataError({"<stdin>", static_cast<int>(line), ""},
                      "expected " + std::to_string(cols->count) + " cells, got " + std::to_string(cells.size()));
    }
    const double t = cols->time >= 0 ? to_internal(cell(cells, cols->time, line, "time"), cols->time_unit)
                                     : static_cast<double>(sample) / o.data.sample_rate_hz;
    ++sample;
    const double rate = to_internal(cell(cells, cols->rate, line, "rate"), cols->rate_unit);
    const double temp = to_internal(cell(cells, cols->temp, line, "temperature"), cols->temp_unit);
    try {
      engine.row(t, rate, temp, out);
    } catch (const DataError& e) {
      throw DataError({"<stdin>", static_cast<int>(line), e.where().field}, e.what());
    }
    if (out.size() > (1 << 16)) flush();
  };
  while (true) {
    const std::size_t got = std::fread(buffer.data(), 1, buffer.size(), stdin);
    if (got == 0) break;
    std::string_view chunk(buffer.data(), got);
    std::size_t start = 0;
    while (true) {
      const std::size_t nl = chunk.find('\n', start);
      if (nl == std::string_view::npos) {
        carry.append(chunk.substr(start));
        break;
      }
      if (!carry.empty()) {
        carry.append(chunk.substr(start, nl - start));
        handle(carry);
        carry.clear();
      } else {
        handle(chunk.substr(start, nl - start));
      }
      start = nl + 1;
    }
    // Rows are emitted as they complete; a pipe reader sees them after each read.
    flush();
    std::fflush(stdout);
  }
  if (!carry.empty()) handle(carry);
  if (!cols) throw DataError({"<stdin>", 1, ""}, "empty input: no header row");
  flush();
  std::fflush(stdout);
}

}  // namespace

void add_compensate_command(CLI::App& app, CommandEnv&) {
  auto o = std::make_shared<CompensateOptions>();
  auto* cmd = app.add_subcommand(
      "compensate", "apply a calibration model sample by sample (causal), to a file or as a stdin -> stdout pipe");
  cmd->add_option("--model", o->model, "driftlab-calibration/1 model JSON (from driftlab calibrate)")->required();
  cmd->add_option("--data", o->data.paths, "input CSV (default columns t_s, rate_dps, temp_c)")->expected(1);
  cmd->add_option("--column", o->data.columns, "column mapping role=column:unit for rate, temperature, time");
  add_sampling_options(cmd, o->data.sample_rate_hz, o->data.max_gap_factor,
                       "sample rate in Hz, for input without a time column",
                       "batch: largest allowed time step, as a multiple of the median step (0 allows gaps)");
  cmd->add_option("--out", o->out, "output CSV (written atomically)");
  cmd->add_flag("--stream", o->stream,
                "read CSV rows from standard input and write compensated rows to standard output, one by one");
  cmd->add_flag("--kalman", o->kalman, "add a causal Kalman stage (random walk + white noise, plugins/kalman)");
  cmd->add_option("--kalman-q", o->kalman_q, "Kalman random-walk variance per sample, (rad/s)^2 (default: K^2/fs "
                                             "from the model's noise terms)")
      ->check(finite_number(0.0, 1e12));
  cmd->add_option("--kalman-r", o->kalman_r, "Kalman measurement variance, (rad/s)^2 (default: N^2 fs)")
      ->check(finite_number(0.0, 1e12));
  cmd->add_option("--kalman-fs", o->kalman_fs, "sample rate for the noise-term conversion, Hz (default: the model's)")
      ->check(finite_number(0.0, 1e12));
  cmd->callback([o] {
    if (o->stream == !o->data.paths.empty()) {
      throw ConfigError({"", 0, "--data"}, "give either --data (with --out) or --stream");
    }
    if (o->stream && !o->out.empty()) throw ConfigError({"", 0, "--out"}, "--stream writes to standard output; drop --out");
    const auto model = calibration::read_calibration_model(o->model);
    if (o->stream) {
      stream(model, *o);
    } else {
      batch(model, *o);
    }
  });
}

}  // namespace driftlab::cli
