// Typed errors thrown by library code. Library code never prints or exits: tools catch these and
// turn them into messages and exit codes (ConfigError -> 2, DataError -> 3, anything else -> 1).
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace driftlab {

// Where a problem was found: any part may be empty / zero when it does not apply.
struct Location {
  std::string file;
  int line = 0;       // 1-based; 0 = unknown
  std::string field;  // column name, YAML key path or parameter name
};

// One problem, with its location. Validation collects many of these before throwing.
struct Diagnostic {
  Location where;
  std::string message;
  std::string to_string() const;  // "file:line: field: message"
};

// `text` quoted for a message: at most `max_chars` bytes (then "... (N bytes in all)"), control and
// non-ASCII bytes escaped as \xNN, so a 2 MB cell or a binary file never floods a terminal.
std::string quoted_excerpt(std::string_view text, std::size_t max_chars = 80);

// A number as messages print it: 6 significant digits (printf "%.6g": 0.0125, 1e+300, nan).
std::string message_number(double x);

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Bad pipeline, device file, parameter or command-line configuration. Holds every problem found.
class ConfigError : public Error {
 public:
  explicit ConfigError(std::vector<Diagnostic> problems);
  ConfigError(Location where, const std::string& message);
  const std::vector<Diagnostic>& problems() const { return problems_; }

 private:
  std::vector<Diagnostic> problems_;
};

// Bad input data (CSV contents, signal too short, NaN, ...).
class DataError : public Error {
 public:
  DataError(Location where, const std::string& message);
  const Location& where() const { return where_; }

 private:
  Location where_;
};

// A plugin name that the registry does not know, or a library that is not a usable plugin.
class UnknownPluginError : public ConfigError {
 public:
  using ConfigError::ConfigError;
};

// predict()/transform() called on a model that has not been fitted.
class NotFittedError : public Error {
 public:
  using Error::Error;
};

}  // namespace driftlab
