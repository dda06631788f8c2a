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
// header, missing column, wrong number of cells, non-numeric or empty cell, NaN/Inf,
// duplicated or decreasing time stamps, a gap larger than max_gap_factor x the median step, a
// unit the mapping does not know (ConfigError). Parsing uses std::from_chars on one in-memory
// buffer: O(file size), about 0.1 s per million 3-column rows on one core.
//
// Writing goes through write_file_atomically (temporary file + rename).
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

#include "framework/time_series.hpp"

namespace driftlab {

struct ColumnMapping {
  std::string role;    // channel role, or "time"
  std::string column;  // header name in the file
  std::string unit;    // unit spelling (see units.hpp)
};

// Parses `role=column:unit`, `column:unit` (role = column) or a suffixed name such as `rate_dps`.
// Throws ConfigError for malformed text or an unknown unit.
ColumnMapping parse_column_mapping(const std::string& text);

struct CsvReadOptions {
  std::vector<ColumnMapping> columns;  // empty: the default columns described above
  double sample_rate_hz = 0.0;         // > 0: the file has no time column; t = i / fs
  double max_gap_factor = 3.0;         // a step > factor x median step is a gap error; <= 0 allows gaps
  std::vector<std::string> required_roles{"rate"};
};

TimeSeries read_csv(const std::filesystem::path& path, const CsvReadOptions& options = {});

// One output column: header name, values in internal units, and the unit to write them in
// (e.g. {"rate_dps", values_rad_s, "deg/s"}).
struct CsvColumn {
  std::string name;
  Eigen::VectorXd values;
  std::string unit = "1";
};

// Writes columns of equal length with shortest round-trip formatting, atomically.
void write_csv(const std::filesystem::path& path, const std::vector<CsvColumn>& columns);

}  // namespace driftlab
