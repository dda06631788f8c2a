// Readers for the Allan-variance reference data in ../shared/data/real (allantools-stable32,
// smac-imudata-static): one-number-per-line data files (optionally gzip'ed, '#' comments), the
// comma-separated expected-value tables, and the shared-data root (DRIFTLAB_SHARED_DATA).
#pragma once

#include <Eigen/Core>
#include <zlib.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace driftlab::allan::testing {

inline std::filesystem::path shared_data() { return DRIFTLAB_SHARED_DATA; }

inline std::filesystem::path stable32_dir() { return shared_data() / "real" / "allantools-stable32"; }

inline std::filesystem::path smac_dir() { return shared_data() / "real" / "smac-imudata-static"; }

inline std::string read_text(const std::filesystem::path& path) {
  gzFile file = gzopen(path.c_str(), "rb");  // reads plain files too
  if (file == nullptr) throw std::runtime_error("cannot open " + path.string());
  std::string text;
  char buffer[1 << 16];
  int got = 0;
  while ((got = gzread(file, buffer, sizeof buffer)) > 0) text.append(buffer, got);
  gzclose(file);
  return text;
}

// First number of every non-comment line.
inline Eigen::VectorXd read_values(const std::filesystem::path& path) {
  std::istringstream in(read_text(path));
  std::vector<double> values;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    values.push_back(std::strtod(line.c_str(), nullptr));
  }
  return Eigen::Map<Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
}

// The first `count` numeric columns of a header-led CSV (fast path for large records).
inline std::vector<Eigen::VectorXd> read_columns(const std::filesystem::path& path, std::size_t count) {
  const std::string text = read_text(path);
  std::vector<std::vector<double>> columns(count);
  const char* p = text.c_str();
  p = std::strchr(p, '\n');
  while (p != nullptr && *++p != '\0') {
    char* end = nullptr;
    for (std::size_t c = 0; c < count; ++c) {
      columns[c].push_back(std::strtod(p, &end));
      p = *end == ',' ? end + 1 : end;
    }
    p = std::strchr(p, '\n');
  }
  std::vector<Eigen::VectorXd> out;
  for (auto& c : columns) {
    out.push_back(Eigen::Map<Eigen::VectorXd>(c.data(), static_cast<Eigen::Index>(c.size())));
  }
  return out;
}

// Rows of a header-led CSV without quoting, as column name -> text.
inline std::vector<std::map<std::string, std::string>> read_table(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path.string());
  const auto split = [](const std::string& line) {
    std::vector<std::string> cells;
    std::stringstream s(line);
    std::string cell;
    while (std::getline(s, cell, ',')) cells.push_back(cell);
    return cells;
  };
  std::string line;
  const auto next_line = [&in, &line] {
    if (!std::getline(in, line)) return false;
    if (!line.empty() && line.back() == '\r') line.pop_back();  // the tables have CRLF endings
    return true;
  };
  next_line();
  const auto header = split(line);
  std::vector<std::map<std::string, std::string>> rows;
  while (next_line()) {
    if (line.empty()) continue;
    const auto cells = split(line);
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < header.size() && i < cells.size(); ++i) row[header[i]] = cells[i];
    rows.push_back(std::move(row));
  }
  return rows;
}

inline double number(const std::map<std::string, std::string>& row, const std::string& key) {
  return std::stod(row.at(key));
}

}  // namespace driftlab::allan::testing
