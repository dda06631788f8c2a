#include "framework/csv.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <optional>
#include <string_view>
#include <unordered_map>

#include "framework/error.hpp"
#include "framework/imu.hpp"
#include "framework/regular_file.hpp"
#include "framework/resources.hpp"
#include "framework/sampling.hpp"
#include "framework/units.hpp"

namespace driftlab {
namespace {

struct Suffix {
  std::string_view suffix;
  std::string_view unit;
};
constexpr Suffix kSuffixes[] = {{"_dps", "deg/s"}, {"_rps", "rad/s"}, {"_dph", "deg/h"}, {"_c", "degC"},
                                {"_k", "K"},       {"_hz", "Hz"},     {"_s", "s"},       {"_mps2", "m/s^2"}};

std::string role_of_stem(const std::string& stem) {
  if (stem == "temp") return role::kTemperature;
  if (stem == "die_temp") return role::kDieTemperature;
  if (stem == "drive_freq") return role::kDriveFrequency;
  if (stem == "t") return "time";
  return stem;
}

// Time columns people log, by header (case-insensitive): t_s, time_s, time, time_ms, time_us,
// timeus (ArduPilot TimeUS), timestamp (PX4/pyulog, us), time_ns.
std::optional<ColumnMapping> time_mapping_of(const std::string& column) {
  std::string h(column);
  std::transform(h.begin(), h.end(), h.begin(), [](unsigned char c) { return std::tolower(c); });
  static const std::pair<std::string_view, std::string_view> known[] = {
      {"t_s", "s"},     {"time_s", "s"},     {"time", "s"},          {"time_ms", "ms"}, {"time_us", "us"},
      {"timeus", "us"}, {"timestamp", "us"}, {"timestamp_us", "us"}, {"time_ns", "ns"}, {"timestamp_ns", "ns"}};
  for (const auto& [name, unit] : known)
    if (h == name) return ColumnMapping{"time", column, std::string(unit)};
  return std::nullopt;
}

std::optional<ColumnMapping> mapping_from_suffix(const std::string& column) {
  if (device_id_instance(column)) return ColumnMapping{column, column, "1"};
  if (auto m = imu::recognize_imu_column(column)) return ColumnMapping{m->role, column, m->unit};
  for (const auto& s : kSuffixes) {
    if (column.size() > s.suffix.size() && column.ends_with(s.suffix))
      return ColumnMapping{role_of_stem(column.substr(0, column.size() - s.suffix.size())), column,
                           std::string(s.unit)};
  }
  return std::nullopt;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = s.substr(1, s.size() - 2);
  return s;
}

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    out.push_back(trim(line.substr(start, comma == std::string_view::npos ? line.npos : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return out;
}

bool parse_number(std::string_view cell, double& value) {
  if (!cell.empty() && cell.front() == '+') cell.remove_prefix(1);
  const auto res = std::from_chars(cell.data(), cell.data() + cell.size(), value);
  return res.ec == std::errc() && res.ptr == cell.data() + cell.size();
}

std::string quantity_text(Quantity q) {
  switch (q) {
    case Quantity::AngularRate:
      return "an angular-rate unit (rad/s, deg/s, deg/h, mrad/s, mdps)";
    case Quantity::Acceleration:
      return "an acceleration unit (m/s^2, g, mg)";
    case Quantity::Temperature:
      return "a temperature unit (degC, K)";
    case Quantity::Time:
      return "a time unit (s, ms, us, ns, h)";
    case Quantity::Frequency:
      return "a frequency unit (Hz, kHz)";
    case Quantity::Dimensionless:
      return "unit 1";
  }
  return "a unit";
}

// The one place where a mapping's unit is looked up and checked against its role.
Unit unit_or_throw(const ColumnMapping& m) {
  auto u = find_unit(m.unit);
  if (!u) {
    std::string known;
    for (const auto& k : known_unit_spellings()) known += (known.empty() ? "" : ", ") + k;
    throw ConfigError({"", 0, m.column}, "unknown unit " + quoted_excerpt(m.unit) + " (known: " + known + ")");
  }
  if (const auto q = quantity_of_role(m.role); q && *q != u->quantity)
    throw ConfigError({"", 0, m.column}, "unit '" + u->symbol + "' does not fit the role '" + m.role +
                                             "', which needs " + quantity_text(*q));
  return *u;
}

// "a, b, c" for a message, at most ~200 bytes of it.
std::string names_excerpt(const std::vector<std::string_view>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (out.size() > 200) return out + ", ... (" + std::to_string(names.size()) + " columns)";
    out += (i ? ", " : "") + std::string(names[i].substr(0, 80));
  }
  return out;
}

DataError line_too_long(const std::string& file, int line, std::size_t max_line_bytes) {
  return DataError({file, line, ""}, "the line is longer than " + std::to_string(max_line_bytes) +
                                         " bytes (--max-line-bytes): --stream holds one line at a time, and a CSV "
                                         "row is far shorter");
}

}  // namespace

std::optional<int> device_id_instance(std::string_view role) {
  if (!role.starts_with("device_id")) return std::nullopt;
  role.remove_prefix(9);
  if (role.empty()) return 0;
  int instance = 0;
  const auto res = std::from_chars(role.data(), role.data() + role.size(), instance);
  if (res.ec != std::errc() || res.ptr != role.data() + role.size() || instance < 1 || instance > 99)
    return std::nullopt;
  return instance;
}

std::optional<Quantity> quantity_of_role(const std::string& role) {
  if (role == "time") return Quantity::Time;
  for (const std::string_view prefix : {"", "true_", "systematic_"}) {
    if (const auto id = imu::parse_role(role, prefix))
      return id->sensor == imu::Sensor::Gyro ? Quantity::AngularRate : Quantity::Acceleration;
  }
  if (imu::parse_temperature_role(role)) return Quantity::Temperature;
  if (role == role::kRate || role == role::kTrueRate) return Quantity::AngularRate;
  if (role == role::kTemperature || role == role::kDieTemperature) return Quantity::Temperature;
  if (role == role::kDriveFrequency) return Quantity::Frequency;
  return std::nullopt;
}

ColumnMapping parse_column_mapping(const std::string& text) {
  const Location where{"--column", 0, text};
  ColumnMapping m;
  std::string rest = text;
  if (const auto eq = rest.find('='); eq != std::string::npos) {
    m.role = rest.substr(0, eq);
    rest = rest.substr(eq + 1);
  }
  if (const auto colon = rest.rfind(':'); colon != std::string::npos) {
    m.column = rest.substr(0, colon);
    m.unit = rest.substr(colon + 1);
    // Raw counts: column:lsb*FACTOR:unit (e.g. gx:lsb*0.061:mdps) is the unit "lsb*FACTOR*unit".
    if (const auto lsb = m.column.rfind(":lsb*"); lsb != std::string::npos) {
      m.unit = m.column.substr(lsb + 1) + "*" + m.unit;
      m.column.resize(lsb);
    }
  } else if (auto s = mapping_from_suffix(rest)) {
    m.column = s->column;
    m.unit = s->unit;
    if (m.role.empty()) m.role = s->role;
  } else {
    throw ConfigError(where,
                      "expected role=column:unit, column:lsb*FACTOR:unit, column:unit or a column name "
                      "with a unit suffix (_dps, _rps, _dph, _c, _k, _hz, _s) or an IMU name (gyro_x, "
                      "accel_z_mps2, temp, ...)");
  }
  if (m.role.empty()) m.role = m.column;
  if (m.column.empty()) throw ConfigError(where, "empty column name");
  try {
    unit_or_throw(m);
  } catch (const ConfigError& e) {
    throw ConfigError(where, e.problems().front().message);
  }
  return m;
}

CsvLineCursor::CsvLineCursor(const std::string& text, bool at_start) : text_(text) {
  if (at_start && text_.size() >= 3 && text_.compare(0, 3, "\xEF\xBB\xBF") == 0) pos_ = 3;
}

bool CsvLineCursor::next(std::string_view& line) {
  while (pos_ < text_.size()) {
    const char* begin = text_.data() + pos_;
    const void* nl = std::memchr(begin, '\n', text_.size() - pos_);
    std::size_t len = nl ? static_cast<std::size_t>(static_cast<const char*>(nl) - begin) : text_.size() - pos_;
    std::size_t advance = len + 1;
    if (const void* cr = std::memchr(begin, '\r', len)) {  // CR LF, or a CR-only line end
      len = static_cast<std::size_t>(static_cast<const char*>(cr) - begin);
      advance = len + 1 + (len + 1 < text_.size() - pos_ && begin[len + 1] == '\n' ? 1 : 0);
    }
    pos_ += advance;
    ++line_;
    line = std::string_view(begin, len);
    if (line.empty() || line.front() == '#' || trim(line).empty()) continue;
    return true;
  }
  return false;
}

std::vector<std::string_view> split_csv_row(std::string_view line) { return split(line); }

CsvLineStream::CsvLineStream(Read read, std::string file, std::size_t max_line_bytes, std::size_t read_bytes)
    : read_(std::move(read)),
      file_(std::move(file)),
      max_line_bytes_(max_line_bytes),
      read_bytes_(std::max<std::size_t>(1, read_bytes)) {}

bool CsvLineStream::next(std::string_view& line) {
  for (;;) {
    if (cursor_ && cursor_->next(line)) {
      if (line.size() > max_line_bytes_) throw line_too_long(file_, line_number(), max_line_bytes_);
      return true;
    }
    if (cursor_) {
      before_ += cursor_->line_number();
      cursor_.reset();
    }
    if (ended_) return false;
    refill();
  }
}

// Reads until pending_ holds a complete line (or the end), then moves the complete lines to block_.
// A CR at the very end of what has arrived may be the first half of a CR LF: it waits for the next read.
void CsvLineStream::refill() {
  for (;;) {
    std::size_t complete = 0;
    if (const auto last = pending_.find_last_of("\r\n"); last != std::string::npos) {
      complete = last + 1;
      if (pending_[last] == '\r' && last + 1 == pending_.size()) {
        const auto before = last == 0 ? std::string::npos : pending_.find_last_of("\r\n", last - 1);
        complete = before == std::string::npos ? 0 : before + 1;
      }
    }
    if (complete > 0 || ended_) {
      if (ended_) complete = pending_.size();
      block_.assign(pending_, 0, complete);
      pending_.erase(0, complete);
      cursor_.emplace(block_, !started_);
      started_ = true;
      return;
    }
    // One incomplete line (its CR, when it ends the bytes so far, may be its line end), already too long.
    const std::size_t held = pending_.size() - (!pending_.empty() && pending_.back() == '\r' ? 1 : 0);
    if (held > max_line_bytes_) throw line_too_long(file_, before_ + 1, max_line_bytes_);
    const std::size_t size = pending_.size();
    pending_.resize(size + read_bytes_);
    const std::size_t got = read_(pending_.data() + size, read_bytes_);
    pending_.resize(size + std::min(got, read_bytes_));
    ended_ = got == 0;
  }
}

std::vector<PlannedColumn> plan_columns(const std::vector<std::string_view>& header, const CsvReadOptions& options,
                                        const std::string& file, int header_line) {
  const std::string available = names_excerpt(header);
  std::unordered_map<std::string_view, std::size_t> index_of;  // linear in the number of columns
  index_of.reserve(header.size());
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (header[i].empty()) continue;
    if (!index_of.emplace(header[i], i).second)
      throw DataError({file, header_line, ""}, "duplicated column name " + quoted_excerpt(header[i]) + " (columns " +
                                                   std::to_string(index_of[header[i]] + 1) + " and " +
                                                   std::to_string(i + 1) + ")");
  }
  const auto find_index = [&](const std::string& column, bool required) -> std::optional<std::size_t> {
    if (auto it = index_of.find(column); it != index_of.end()) return it->second;
    if (required) throw DataError({file, header_line, column}, "missing column (the header has: " + available + ")");
    return std::nullopt;
  };

  std::vector<PlannedColumn> wanted;
  std::optional<ColumnMapping> time_mapping;
  const auto add_wanted = [&](const ColumnMapping& m, std::size_t index) {
    if (m.role == "time") {
      time_mapping = m;
    }
    try {
      wanted.push_back({m, unit_or_throw(m), index});
    } catch (const ConfigError& e) {
      throw ConfigError({file, header_line, m.column}, e.problems().front().message);
    }
  };
  // A role read from two columns, or a column read as two roles, is an error naming both.
  const auto check_unique = [&](const ColumnMapping& m) {
    for (const auto& w : wanted) {
      if (w.mapping.role == m.role)
        throw ConfigError({file, header_line, m.column},
                          "the '" + m.role +
                              "' channel is claimed by two columns: " + quoted_excerpt(w.mapping.column) + " and " +
                              quoted_excerpt(m.column) + " (map one of them with --column)");
      if (w.mapping.column == m.column)
        throw ConfigError({file, header_line, m.column}, "column " + quoted_excerpt(m.column) +
                                                             " is claimed by two channels: '" + w.mapping.role +
                                                             "' and '" + m.role + "'");
    }
  };
  if (options.columns.empty()) {
    std::optional<std::size_t> time_index;
    for (std::size_t i = 0; i < header.size(); ++i) {
      const std::string name(header[i]);
      if (name == "t_s" || (!time_index && time_mapping_of(name))) time_index = i;
    }
    for (std::size_t i = 0; i < header.size(); ++i) {
      const std::string name(header[i]);
      std::optional<ColumnMapping> m = i == time_index ? time_mapping_of(name) : std::nullopt;
      if (!m && !time_mapping_of(name)) m = mapping_from_suffix(name);
      if (!m) continue;
      check_unique(*m);
      add_wanted(*m, i);
    }
  } else {
    bool has_time = false;
    for (const auto& m : options.columns) has_time = has_time || m.role == "time";
    if (!has_time && options.sample_rate_hz <= 0.0) add_wanted({"time", "t_s", "s"}, *find_index("t_s", true));
    for (const auto& m : options.columns) {
      check_unique(m);
      add_wanted(m, *find_index(m.column, true));
    }
  }
  if (!time_mapping && options.sample_rate_hz <= 0.0)
    throw DataError({file, header_line, "t_s"}, "missing time column (the header has: " + available +
                                                    "); give one with --column "
                                                    "time=NAME:UNIT or a sample rate with --fs");
  for (const auto& r : options.required_roles) {
    const bool found =
        std::any_of(wanted.begin(), wanted.end(), [&](const PlannedColumn& w) { return w.mapping.role == r; });
    if (!found)
      throw DataError({file, header_line, r}, "no column for the '" + r + "' channel (the header has: " + available +
                                                  "); name one with --column " + r + "=COLUMN:UNIT");
  }
  if (time_mapping && options.sample_rate_hz > 0.0)
    throw ConfigError({file, header_line, time_mapping->column}, "the file has a time column; do not also give --fs");

  return wanted;
}

std::string read_text_file(const std::filesystem::path& path) {
  // The text and the parsed values of every column: at most about three times the text's size.
  if (is_stdin(path)) return read_stdin_text("data", static_cast<std::uintmax_t>(memory_limit_bytes() / 3.0));
  const auto size = check_data_input(path);
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw DataError({path.string(), 0, ""}, std::string("cannot open: ") + std::strerror(errno));
  check_memory_estimate(3.0 * static_cast<double>(size), {path.string(), 0, ""},
                        "reading a " + std::to_string(size >> 20) + " MB file");
  std::string buffer(size, '\0');
  const auto n = std::fread(buffer.data(), 1, buffer.size(), f);
  std::fclose(f);
  buffer.resize(n);
  return buffer;
}

CsvRowParser::CsvRowParser(std::string file, CsvReadOptions options)
    : file_(std::move(file)), options_(std::move(options)) {
  if (!std::isfinite(options_.sample_rate_hz) || options_.sample_rate_hz > 1.0 / kMinTimeStep)
    throw ConfigError({file_, 0, "--fs"}, "the sample rate must be finite and at most 1e9 Hz");
  if (!std::isfinite(options_.max_gap_factor)) throw ConfigError({file_, 0, "--max-gap"}, "must be a finite number");
}

void CsvRowParser::header(std::string_view line, int line_number) {
  const auto header = split_csv_row(line);
  double dummy;
  if (std::all_of(header.begin(), header.end(), [&](std::string_view c) { return parse_number(c, dummy); }))
    throw DataError({file_, line_number, ""}, "missing header row (the first row holds only numbers)");
  columns_ = plan_columns(header, options_, file_, line_number);
  names_.assign(header.begin(), header.end());
  for (std::size_t k = 0; k < columns_.size(); ++k) {
    by_index_.emplace_back(columns_[k].index, k);
    if (columns_[k].mapping.role == "time") time_column_ = k;
  }
  std::sort(by_index_.begin(), by_index_.end());
  values_.assign(columns_.size(), 0.0);
  first_device_ids_.assign(columns_.size(), std::numeric_limits<double>::quiet_NaN());
  header_line_ = line_number;
}

const PlannedColumn* CsvRowParser::find(const std::string& role) const {
  for (const auto& c : columns_)
    if (c.mapping.role == role) return &c;
  return nullptr;
}

void CsvRowParser::row(std::string_view line, int line_number) {
  cells_.clear();
  for (std::size_t pos = 0;;) {
    const auto comma = line.find(',', pos);
    cells_.push_back(line.substr(pos, comma == std::string_view::npos ? std::string_view::npos : comma - pos));
    if (comma == std::string_view::npos) break;
    pos = comma + 1;
  }
  if (cells_.size() != names_.size())
    throw DataError({file_, line_number, ""}, "row has " + std::to_string(cells_.size()) + " cells, the header has " +
                                                  std::to_string(names_.size()));
  for (const auto& [index, k] : by_index_) {
    const PlannedColumn& c = columns_[k];
    const auto cell = trim(cells_[index]);
    double v;
    if (cell.empty()) throw DataError({file_, line_number, c.mapping.column}, "empty cell (expected a number)");
    if (!parse_number(cell, v))
      throw DataError({file_, line_number, c.mapping.column}, "expected a number, got " + quoted_excerpt(cell));
    if (!std::isfinite(v))
      throw DataError({file_, line_number, c.mapping.column},
                      "value is " + quoted_excerpt(cell) + " (NaN/Inf not allowed)");
    const double internal = to_internal(v, c.unit);
    if (!(std::abs(internal) <= kMaxMagnitude))
      throw DataError({file_, line_number, c.mapping.column},
                      "value " + quoted_excerpt(cell) + " is too large to compute with (at most 1e100 " +
                          internal_unit_symbol(c.unit.quantity) +
                          " in magnitude; its squares and sums would overflow)");
    values_[k] = internal;
  }
  for (std::size_t k = 0; k < columns_.size(); ++k) {
    if (!device_id_instance(columns_[k].mapping.role)) continue;
    if (rows_ == 0)
      first_device_ids_[k] = values_[k];
    else if (values_[k] != first_device_ids_[k])
      throw DataError({file_, line_number, columns_[k].mapping.column},
                      "the device id changes within the record (one file holds one device)");
  }
  if (time_column_) {
    const double t = values_[*time_column_];
    const std::string& column = columns_[*time_column_].mapping.column;
    if (rows_ > 0) {
      if (t == time_s_)
        throw DataError({file_, line_number, column},
                        "duplicated time stamp (same as line " + std::to_string(previous_line_) + ")");
      if (t < time_s_)
        throw DataError({file_, line_number, column}, "time stamps must increase (this one is earlier than line " +
                                                          std::to_string(previous_line_) + ")");
      if (t - time_s_ < kMinTimeStep)
        throw DataError({file_, line_number, column},
                        "time step of " + std::to_string(t - time_s_) + " s after line " +
                            std::to_string(previous_line_) +
                            " is below 1 ns (a sample rate above 1 GHz; its rates and deviations would overflow)");
    }
    time_s_ = t;
  } else {
    time_s_ = static_cast<double>(rows_) / options_.sample_rate_hz;
  }
  previous_line_ = line_number;
  ++rows_;
}

void CsvRowParser::finish() const {
  if (!has_header()) throw DataError({file_, 0, ""}, "file is empty (expected a header row and data rows)");
  if (rows_ == 0) throw DataError({file_, header_line_, ""}, "no data rows after the header");
}

namespace {

// The rows of `lines` (a CsvLineCursor or a CsvLineStream over `bytes` of text) as a record.
template <class Lines>
TimeSeries parse_lines(Lines& cursor, std::size_t bytes, const std::string& file, const CsvReadOptions& options) {
  CsvRowParser parser(file, options);
  std::string_view line;
  if (cursor.next(line))
    parser.header(line, cursor.line_number());
  else
    parser.finish();  // "file is empty"
  const auto& columns = parser.columns();
  std::vector<std::vector<double>> values(columns.size());
  std::vector<double> time;
  std::vector<int> line_of_row;
  std::vector<std::size_t> kept;  // the columns held in `values`; the time is in `time`
  for (std::size_t k = 0; k < columns.size(); ++k)
    if (columns[k].mapping.role != "time") kept.push_back(k);
  const std::size_t estimated_rows = bytes / std::max<std::size_t>(1, line.size() + 1);
  for (std::size_t k : kept) values[k].reserve(estimated_rows);
  time.reserve(estimated_rows);
  line_of_row.reserve(estimated_rows);
  while (cursor.next(line)) {
    parser.row(line, cursor.line_number());
    for (std::size_t k : kept) values[k].push_back(parser.values()[k]);
    time.push_back(parser.time_s());
    line_of_row.push_back(cursor.line_number());
  }
  parser.finish();
  const std::size_t rows = time.size();
  const PlannedColumn* time_column = parser.find("time");
  TimeSeries series(Eigen::Map<const Eigen::VectorXd>(time.data(), static_cast<Eigen::Index>(rows)),
                    options.max_gap_factor > 0.0 ? options.max_gap_factor : sampling::kGapFactor);
  if (time_column && options.max_gap_factor > 0.0) {
    const auto& facts = series.sampling_facts();
    if (!facts.evenly_sampled()) {
      const auto i = static_cast<std::size_t>(facts.first_gap_index);
      throw DataError({file, line_of_row[i + 1], time_column->mapping.column},
                      "gap of " + std::to_string(facts.first_gap_s) + " s after line " +
                          std::to_string(line_of_row[i]) + " (median step " + std::to_string(facts.median_step_s) +
                          " s; allowed up to " + std::to_string(options.max_gap_factor) + " x median, see --max-gap)");
    }
  }

  std::vector<double>().swap(time);
  std::vector<int>().swap(line_of_row);
  for (std::size_t k = 0; k < columns.size(); ++k) {
    const PlannedColumn& c = columns[k];
    if (c.mapping.role == "time") continue;
    if (const auto instance = device_id_instance(c.mapping.role)) {
      char id[32];
      const auto res = std::to_chars(id, id + sizeof id, values[k][0]);
      series.set_device_id(*instance, std::string(id, res.ptr));
      continue;
    }
    series.set_channel(Channel{c.mapping.role, internal_unit_symbol(c.unit.quantity), c.mapping.column,
                               Eigen::Map<const Eigen::VectorXd>(values[k].data(), static_cast<Eigen::Index>(rows)),
                               c.unit.symbol});
    std::vector<double>().swap(values[k]);  // one column's copy at a time
  }
  return series;
}

}  // namespace

TimeSeries parse_csv(const std::string& text, const std::string& file, const CsvReadOptions& options) {
  CsvLineCursor cursor(text);
  return parse_lines(cursor, text.size(), file, options);
}

TimeSeries read_csv(const std::filesystem::path& path, const CsvReadOptions& options) {
  if (is_stdin(path)) return parse_csv(read_text_file(path), path.string(), options);
  // Streamed: the parsed columns (8 bytes per value, about half the text's bytes) are held, the
  // text never is.
  const auto size = check_data_input(path);
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw DataError({path.string(), 0, ""}, std::string("cannot open: ") + std::strerror(errno));
  check_memory_estimate(1.0 * static_cast<double>(size), {path.string(), 0, ""},
                        "reading a " + std::to_string(size >> 20) + " MB file");
  // No line cap of its own: a line may be the whole file, as when the text was held whole, and the
  // row parser names a cell that is too long.
  CsvLineStream lines([&](char* buffer, std::size_t n) { return std::fread(buffer, 1, n, f.get()); }, path.string(),
                      static_cast<std::size_t>(size) + 1);
  return parse_lines(lines, size, path.string(), options);
}

void stream_csv(const std::vector<CsvColumn>& columns, const std::string& label,
                const std::function<void(std::string_view)>& sink) {
  std::vector<Unit> units;
  std::vector<Eigen::Map<const Eigen::VectorXd>> values;
  Eigen::Index rows = columns.empty() ? 0 : columns.front().data().size();
  std::unordered_map<std::string_view, std::size_t> seen;
  for (const auto& c : columns) {
    const auto bad = c.name.empty() || c.name.find_first_of(",\"\r\n") != std::string::npos || c.name.front() == ' ' ||
                     c.name.back() == ' ' || c.name.front() == '#';
    if (bad)
      throw ConfigError({label, 0, ""}, "column name " + quoted_excerpt(c.name) +
                                            " is not a valid CSV header cell (empty, a comma, quote or line "
                                            "break, surrounding spaces, or a leading #)");
    if (!seen.emplace(c.name, seen.size()).second)
      throw ConfigError({label, 0, c.name}, "two output columns have this name; column names must be unique");
    auto u = find_unit(c.unit);
    if (!u) throw ConfigError({label, 0, c.name}, "unknown output unit '" + c.unit + "'");
    values.push_back(c.data());
    if (values.back().size() != rows)
      throw DataError({label, 0, c.name}, "column length differs from the first column");
    units.push_back(*u);
  }
  constexpr std::size_t kPiece = std::size_t{1} << 20;
  std::string out;
  out.reserve(kPiece + 64 * columns.size() + 256);
  for (std::size_t j = 0; j < columns.size(); ++j) out += (j ? "," : "") + columns[j].name;
  out += '\n';
  char buf[32];
  for (Eigen::Index i = 0; i < rows; ++i) {
    for (std::size_t j = 0; j < columns.size(); ++j) {
      if (j) out += ',';
      const double v = columns[j].absolute ? from_internal(values[j][i], units[j])
                                           : difference_from_internal(values[j][i], units[j]);
      if (!std::isfinite(v))
        throw Error(Diagnostic{{label, 0, columns[j].name},
                               "computed value in row " + std::to_string(i + 1) +
                                   " is not finite (the computation overflowed); nothing was written"}
                        .to_string());
      const auto res = std::to_chars(buf, buf + sizeof buf, v);
      out.append(buf, res.ptr);
    }
    out += '\n';
    if (out.size() >= kPiece) {
      sink(out);
      out.clear();
    }
  }
  if (!out.empty()) sink(out);
}

std::string format_csv(const std::vector<CsvColumn>& columns, const std::string& label) {
  std::string text;
  stream_csv(columns, label, [&](std::string_view piece) { text += piece; });
  return text;
}

}  // namespace driftlab
