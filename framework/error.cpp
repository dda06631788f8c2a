#include "framework/error.hpp"

#include <algorithm>
#include <cstdio>

namespace driftlab {
namespace {

std::string join_problems(const std::vector<Diagnostic>& problems) {
  std::string text;
  for (const auto& p : problems) {
    if (!text.empty()) text += '\n';
    text += p.to_string();
  }
  return text;
}

}  // namespace

std::string message_number(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", x);
  return text;
}

std::string quoted_excerpt(std::string_view text, std::size_t max_chars) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out = "'";
  const std::size_t shown = std::min(text.size(), max_chars);
  for (std::size_t i = 0; i < shown; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c >= 0x7f || c == '\\') {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    } else {
      out += static_cast<char>(c);
    }
  }
  out += "'";
  if (shown < text.size()) out += "... (" + std::to_string(text.size()) + " bytes in all)";
  return out;
}

std::string Diagnostic::to_string() const {
  std::string text;
  if (!where.file.empty()) text += where.file + ":";
  if (where.line > 0) text += std::to_string(where.line) + ":";
  if (!text.empty()) text += " ";
  if (!where.field.empty()) text += where.field + ": ";
  return text + message;
}

ConfigError::ConfigError(std::vector<Diagnostic> problems)
    : Error(join_problems(problems)), problems_(std::move(problems)) {}

ConfigError::ConfigError(Location where, const std::string& message)
    : ConfigError(std::vector<Diagnostic>{Diagnostic{std::move(where), message}}) {}

DataError::DataError(Location where, const std::string& message)
    : Error(Diagnostic{where, message}.to_string()), where_(std::move(where)) {}

}  // namespace driftlab
