#include "tools/driftlab/cli.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>

#include "framework/atomic_file.hpp"
#include "framework/csv.hpp"
#include "framework/error.hpp"

namespace driftlab::cli {

const Registry& CommandEnv::registry() {
  if (!registry_) {
    registry_ = std::make_unique<Registry>();
    register_builtin_plugins(*registry_);
    if (const char* env_path = std::getenv("DRIFTLAB_PLUGIN_PATH")) registry_->load_path_list(env_path);
    for (const auto& dir : plugin_dirs) registry_->load_directory(dir);
  }
  return *registry_;
}

bool CommandEnv::show_progress() const { return !quiet && ::isatty(STDERR_FILENO); }

void CommandEnv::progress(const std::string& label, double fraction) const {
  if (!show_progress()) return;
  std::fprintf(stderr, "\r%-40s %3d%%", label.c_str(), static_cast<int>(fraction * 100.0 + 0.5));
  if (fraction >= 1.0) std::fputc('\n', stderr);
  std::fflush(stderr);
}

void add_data_options(CLI::App* command, DataOptions& data, const std::string& column_help) {
  command->add_option("--data", data.path, "input CSV (header row; default columns t_s, rate_dps, temp_c)");
  command->add_option("--column", data.columns, column_help);
  command->add_option("--fs", data.sample_rate_hz, "sample rate in Hz, for files without a time column")
      ->check(CLI::PositiveNumber);
  command->add_option("--max-gap", data.max_gap_factor,
                      "largest allowed time step, as a multiple of the median step (0 allows gaps)")
      ->capture_default_str();
}

std::string primary_role(const DataOptions& data) {
  return data.columns.empty() ? std::string(role::kRate) : parse_column_mapping(data.columns.front()).role;
}

TimeSeries load_record(const DataOptions& data, std::vector<std::string> required_roles) {
  if (data.path.empty()) throw ConfigError({"", 0, "--data"}, "--data is required");
  CsvReadOptions options;
  for (const auto& c : data.columns) options.columns.push_back(parse_column_mapping(c));
  if (!options.columns.empty() && !required_roles.empty() && required_roles.front() == role::kRate)
    required_roles.front() = options.columns.front().role;
  options.required_roles = std::move(required_roles);
  options.sample_rate_hz = data.sample_rate_hz;
  options.max_gap_factor = data.max_gap_factor;
  return read_csv(data.path, options);
}

std::string display_unit(const TimeSeries& record, const std::string& role, const DataOptions& data) {
  for (const auto& c : data.columns) {
    const auto m = parse_column_mapping(c);
    if (m.role == role) return m.unit;
  }
  const auto& unit = record.channel(role).unit;
  return unit == "rad/s" ? "deg/s" : unit;
}

void check_output(const std::string& output, const std::vector<std::string>& inputs) {
  std::vector<std::filesystem::path> paths(inputs.begin(), inputs.end());
  ensure_not_an_input(output, paths);
}

}  // namespace driftlab::cli
