// CSV time series I/O (DESIGN.md §5).
//
// Reading. A header row, then one row per sample, numbers in the C locale; '#' lines and blank
// lines are skipped. By default the time column is `t_s` and every column whose name ends in a
// unit suffix is loaded as a channel whose role is the name without the suffix:
//   _dps deg/s, _rps rad/s, _dph deg/h, _c degC, _k K, _hz Hz, _s s
//   (roles: rate_dps -> rate, temp_c -> temperature, true_rate_dps -> true_rate,
//    die_temp_c -> die_temperature, drive_freq_hz -> drive_frequency; other stems stay as they are)
// Any other file is read with explicit mappings `role=column:unit` (e.g. `rate=gyro_z:rad/s`,
// `time=timestamp:ms`); then only the mapped columns (and the time column) are read.
// Values are converted to internal units at this boundary (rate rad/s, temperature degC, time s).
//
// Every problem is a DataError naming file, line and column: missing file, empty file, missing
// header, missing column, wrong number of cells, non-numeric or empty cell, NaN/Inf, a value
// beyond kMaxMagnitude (its arithmetic would overflow), a time step below kMinTimeStep,
// duplicated or decreasing time stamps, a gap larger than max_gap_factor x the median step, a
// unit the mapping does not know or one of another dimension than the role (ConfigError).
// Messages quote at most 80 bytes of a bad cell, control bytes escaped (quoted_excerpt).
// A UTF-8 byte-order mark is skipped; lines end in LF, CR LF or CR. Parsing uses std::from_chars:
// O(file size), about 0.1 s per million 3-column rows on one core (the header check is linear in
// the number of columns too). read_csv reads a file in 1-MiB pieces: it holds the parsed columns,
// never the whole text (standard input and parse_csv take the text whole).
//
// Writing: an OutputSet (output_set.hpp) streams the text (stream_csv) to its temporary file and
// commits it with every other output of the command; format_csv() gives it whole. Column names
// must be valid, unique CSV header cells (ConfigError); values must be finite (Error: a
// computation overflowed).
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "framework/sampling.hpp"
#include "framework/time_series.hpp"
#include "framework/units.hpp"

namespace driftlab {

struct ColumnMapping {
  std::string role;    // channel role, or "time"
  std::string column;  // header name in the file
  std::string unit;    // unit spelling (see units.hpp)
};

// Largest magnitude of a value in internal units: squares and sums over 1e8 samples stay finite.
inline constexpr double kMaxMagnitude = 1e100;
// Smallest time step (s): a 1 GHz sample rate; 1/step and 1/step^2 stay finite.
inline constexpr double kMinTimeStep = 1e-9;

// The quantity a well-known role must carry (time, rate, true_rate, temperature, die_temperature,
// drive_frequency); empty for other roles, which accept any unit.
std::optional<Quantity> quantity_of_role(const std::string& role);

// Parses `role=column:unit`, `column:unit` (role = column) or a suffixed name such as `rate_dps`.
// Throws ConfigError for malformed text, an unknown unit or a unit of another dimension than the role.
ColumnMapping parse_column_mapping(const std::string& text);

struct CsvReadOptions {
  std::vector<ColumnMapping> columns;            // empty: the default columns described above
  double sample_rate_hz = 0.0;                   // > 0: the file has no time column; t = i / fs
  double max_gap_factor = sampling::kGapFactor;  // a step > factor x median step is a gap error; <= 0 reads gaps as
                                                 // they are (never as contiguous: analyses that assume even sampling
                                                 // still find them, framework/sampling.hpp)
  std::vector<std::string> required_roles{"rate"};
};

// The lines of a CSV text as the reader walks them: a UTF-8 byte-order mark skipped at the start of
// the text (`at_start` false: the text continues a file, no mark is looked for); LF, CR LF or CR
// line ends; blank and '#' lines skipped. `text` must outlive the cursor.
class CsvLineCursor {
 public:
  explicit CsvLineCursor(const std::string& text, bool at_start = true);
  bool next(std::string_view& line);         // the next line (without its end); false at the end
  int line_number() const { return line_; }  // 1-based number of the last line returned

 private:
  const std::string& text_;
  std::size_t pos_ = 0;
  int line_ = 0;
};

// The same lines from a source that arrives in pieces (standard input for `compensate --stream`):
// `read` fills up to `size` bytes and returns how many (0 at the end); it is called only when no
// complete line is left, so a caller may flush its output there. At most one incomplete line is
// held: a line longer than `max_line_bytes` (a CSV row is far shorter) is a DataError naming `file`
// and its line, raised once that many bytes of it have arrived. Memory: the longest line plus one
// read. The lines, their numbers and the byte-order mark are exactly CsvLineCursor's on the whole
// text, however the pieces are cut (a CR LF split between two reads stays one line end).
class CsvLineStream {
 public:
  using Read = std::function<std::size_t(char* buffer, std::size_t size)>;
  CsvLineStream(Read read, std::string file, std::size_t max_line_bytes, std::size_t read_bytes = std::size_t{1} << 20);
  bool next(std::string_view& line);  // valid until the next call
  int line_number() const { return before_ + (cursor_ ? cursor_->line_number() : 0); }

 private:
  void refill();

  Read read_;
  std::string file_;
  std::size_t max_line_bytes_, read_bytes_;
  std::string pending_;  // bytes after the last complete line
  std::string block_;    // complete lines, walked by cursor_
  std::optional<CsvLineCursor> cursor_;
  int before_ = 0;  // lines of earlier blocks
  bool started_ = false, ended_ = false;
};

// The cells of one row, surrounding blanks and quotes trimmed (as the header is read).
std::vector<std::string_view> split_csv_row(std::string_view line);
// A column a read takes: its mapping, unit and position in the row.
struct PlannedColumn {
  ColumnMapping mapping;
  Unit unit;
  std::size_t index = 0;
};
// The columns read_csv takes from a header row (the time column unless options.sample_rate_hz > 0,
// and every channel), with the errors read_csv gives (a role or a column claimed twice, a missing
// column, a required role absent, a unit of the wrong dimension), naming `file` and `header_line`.
// "device_id[N]" columns (constant per file) become the record's device ids, not channels.
std::vector<PlannedColumn> plan_columns(const std::vector<std::string_view>& header, const CsvReadOptions& options,
                                        const std::string& file, int header_line);
// "device_id" -> 0, "device_id3" -> 3: the IMU instance whose numeric identity a column carries.
std::optional<int> device_id_instance(std::string_view role);

// The one row parser of CSV time series (issue 28: batch and stream, one acceptance, one set of
// messages, one set of values): parse_csv runs it over a whole text, `driftlab compensate --stream`
// over the lines of a CsvLineStream. Feed it the lines of a CsvLineCursor or CsvLineStream: the
// first is the header, every later one a row. Errors name `file`, the line and the column:
//   header(): a first row of numbers only ("missing header row"), and plan_columns' errors;
//   row():    a cell count other than the header's; in every planned column an empty cell, a cell
//             that is not a number (C locale, optional leading '+', the whole cell), NaN/Inf, a
//             value beyond kMaxMagnitude in internal units; a time stamp equal to, earlier than or
//             less than kMinTimeStep after the previous row's; a device id other than the first row's;
//   finish(): no header ("file is empty") or no row after it.
// What needs the whole record (the gap test, max_gap_factor, against the median step) is
// parse_csv's, after the last row. Cost: one pass over the line, O(cells).
class CsvRowParser {
 public:
  // ConfigError for a sample rate that is not finite or above 1e9 Hz, a gap factor that is not finite.
  CsvRowParser(std::string file, CsvReadOptions options);

  void header(std::string_view line, int line_number);
  void row(std::string_view line, int line_number);
  void finish() const;

  bool has_header() const { return header_line_ > 0; }
  int header_line() const { return header_line_; }
  const std::string& file() const { return file_; }
  const std::vector<std::string>& header_names() const { return names_; }  // every header cell, trimmed
  const std::vector<PlannedColumn>& columns() const { return columns_; }   // plan_columns' order
  const PlannedColumn* find(const std::string& role) const;                // the planned column of a role, or null
  std::size_t rows() const { return rows_; }                               // rows parsed so far
  // The last row: its time (s; row index / sample rate without a time column), the value of every
  // planned column in internal units (columns() order), and every cell untrimmed, as written (the
  // views point into the line given to row()).
  double time_s() const { return time_s_; }
  const std::vector<double>& values() const { return values_; }
  const std::vector<std::string_view>& cells() const { return cells_; }

 private:
  std::string file_;
  CsvReadOptions options_;
  int header_line_ = 0;
  std::vector<std::string> names_;
  std::vector<PlannedColumn> columns_;
  std::vector<std::pair<std::size_t, std::size_t>> by_index_;  // (cell index, column) sorted by cell
  std::optional<std::size_t> time_column_;
  std::vector<double> first_device_ids_;  // per column; NaN for columns that are not device ids
  std::size_t rows_ = 0;
  double time_s_ = 0.0;
  int previous_line_ = 0;
  std::vector<double> values_;
  std::vector<std::string_view> cells_;
};

TimeSeries read_csv(const std::filesystem::path& path, const CsvReadOptions& options = {});
// The whole text of an input file, with read_csv's checks (a regular file, check_data_input in
// regular_file.hpp; enough memory for it and its parsed columns); DataError naming the file otherwise.
// "-" reads standard input (regular_file.hpp), at most a third of the memory limit.
std::string read_text_file(const std::filesystem::path& path);
// The same on text already in memory; `file` names it in messages.
TimeSeries parse_csv(const std::string& text, const std::string& file, const CsvReadOptions& options = {});

// One output column: header name, values in internal units, and the unit to write them in
// (e.g. {"rate_dps", values_rad_s, "deg/s"}). `absolute` false: the values are differences
// (deviations, IMFs, standard deviations): a unit with an offset (K) converts them by its scale
// only, so a 1 degC deviation is written as 1 K, not 274.15 K.
// A column owns its values, or (CsvColumn::view) refers to values the caller keeps alive until the
// CSV is written, so that a large output (a record's IMFs) is not copied to be written.
struct CsvColumn {
  std::string name;
  Eigen::VectorXd values;  // owned values; empty for a view
  std::string unit = "1";
  bool absolute = true;
  const double* viewed = nullptr;  // a view's values (set by view())
  Eigen::Index viewed_size = 0;

  static CsvColumn view(std::string name, const Eigen::Ref<const Eigen::VectorXd>& values, std::string unit,
                        bool absolute = true) {
    return {std::move(name), {}, std::move(unit), absolute, values.data(), values.size()};
  }
  // The values, owned or viewed.
  Eigen::Map<const Eigen::VectorXd> data() const {
    return viewed != nullptr ? Eigen::Map<const Eigen::VectorXd>(viewed, viewed_size)
                             : Eigen::Map<const Eigen::VectorXd>(values.data(), values.size());
  }
};

// The CSV text of equal-length columns (shortest round-trip formatting); `label` names the
// output in messages. Throws ConfigError for a bad or repeated column name, Error for a
// non-finite value.
std::string format_csv(const std::vector<CsvColumn>& columns, const std::string& label);
// The same text handed to `sink` in pieces of about 1 MiB, in order, so that it is never held
// whole. The names and units are checked before the first piece; a non-finite value throws after
// the pieces before its row.
void stream_csv(const std::vector<CsvColumn>& columns, const std::string& label,
                const std::function<void(std::string_view)>& sink);

}  // namespace driftlab
