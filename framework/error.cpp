#include "framework/error.hpp"

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
