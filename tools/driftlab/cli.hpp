// Shared pieces of the `driftlab` command line: global options, the registry, record loading with
// --data/--column/--fs/--max-gap, output-path checks and progress on stderr.
// Each subcommand lives in cmd_<name>.cpp and exposes add_<name>_command(app, env).
// Errors are thrown (ConfigError -> exit 2, DataError -> exit 3, others -> exit 1); run() maps them.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "framework/csv.hpp"
#include "framework/output_set.hpp"
#include "framework/pipeline.hpp"
#include "framework/record_reader.hpp"
#include "framework/registry.hpp"
#include "framework/sampling.hpp"
#include "framework/time_series.hpp"
#include "tools/driftlab/progress.hpp"

namespace driftlab::cli {

inline constexpr int kExitOk = 0, kExitFailure = 1, kExitUsage = 2, kExitData = 3;

struct CommandEnv {
  std::vector<std::string> plugin_dirs;  // --plugin-path (repeatable), after $DRIFTLAB_PLUGIN_PATH
  bool quiet = false;                    // --quiet: no progress output
  unsigned threads = 1;                  // --threads

  // Built-ins plus external plugins, loaded on first use.
  const Registry& registry();
  // Reports that task `label` is `fraction` done ([0, 1]; 1 ends the task) on stderr, as
  // ProgressDisplay says: redrawn in place on a terminal, periodic plain lines otherwise, nothing
  // with --quiet. The mode is chosen at the first call, after the options are parsed.
  void progress(const std::string& label, double fraction);

 private:
  std::unique_ptr<Registry> registry_;
  std::unique_ptr<ProgressDisplay> progress_;
};

using AddCommand = void (*)(CLI::App& app, CommandEnv& env);

// The directory of the running executable (/proc/self/exe); "." when it cannot be read.
std::filesystem::path executable_dir();
// Where an installed driftlab keeps what it loads at run time, found from the executable's own
// directory by the relative paths of the install layout (CMake GNUInstallDirs, fixed at configure
// time; tools/driftlab/CMakeLists.txt): the library directory (libdriftlab_framework.so, the reader
// modules, the fleet's MPI module) and the data directory share/driftlab (devices/, pipelines/).
// In the build tree neither exists; callers fall back to the build and source trees.
std::filesystem::path installed_lib_dir();
std::filesystem::path installed_data_dir();

// The `driftlab` command line: the global options (--plugin-path, --quiet, --threads, --version),
// the given subcommands, and errors mapped to exit codes. Its main() (main.cpp) and that of
// driftlab-mrpt (mrpt_main.cpp, the commands that load MRPT) both call it, so both parse alike.
int run(int argc, char** argv, const std::vector<AddCommand>& commands);

// How a record file is read: the options every record-reading command shares.
struct RecordReadOptions {
  std::vector<std::string> columns;              // --column mappings (see csv.hpp; for a log, record_reader.hpp)
  double sample_rate_hz = 0.0;                   // --fs
  double max_gap_factor = sampling::kGapFactor;  // --max-gap
  LogSelection log;                              // --topic, --instance, --sensor (logs only)
};

// The CSV reader's options for these: the --column mappings parsed (ConfigError naming a bad one),
// --fs and --max-gap; no required roles.
CsvReadOptions csv_read_options(const RecordReadOptions& read);

// The record of a single-record command.
struct DataOptions : RecordReadOptions {
  std::string path;  // --data
};

// Validators for number options (CLI11's Range and PositiveNumber let NaN through): the text must be
// a finite number in [lo, hi] (lo excluded when lo_open); otherwise a usage error, exit 2.
CLI::Validator finite_number(double lo, double hi, bool lo_open = false);
// A whole number in [lo, hi] written as digits: "-1" for an unsigned seed, "1e3" or "2.5" are refused.
CLI::Validator whole_number(double lo, double hi);
inline constexpr double kMaxSeed = 9007199254740992.0;  // 2^53: every seed survives JSON and YAML

// Adds --fs (a finite rate in (0, 1e9] Hz) and --max-gap (a finite factor >= 0) to a subcommand:
// the one definition of the two sampling options every record-reading command shares.
void add_sampling_options(CLI::App* command, double& sample_rate_hz, double& max_gap_factor,
                          const std::string& fs_help = "sample rate in Hz, for files without a time column",
                          const std::string& gap_help =
                              "a time step longer than this multiple of the median step "
                              "is a gap, an error (0 reads gaps; allan, run, compare, "
                              "decompose and entropy still find them at 3x)");
// Adds --column (with the command's help), --fs and --max-gap, and the log options --topic,
// --instance and --sensor, to a subcommand.
void add_record_read_options(CLI::App* command, RecordReadOptions& read, const std::string& column_help);
// Adds --data and the record read options to a subcommand.
void add_data_options(CLI::App* command, DataOptions& data, const std::string& column_help);
// Adds --topic, --instance and --sensor (framework/record_reader.hpp LogSelection).
void add_log_selection_options(CLI::App* command, LogSelection& selection);

// A log's IMU record as CSV columns, in names the CSV reader recognises: t_s (s), gyro*_rad_s
// (rad/s), accel*_m_s2 (m/s^2), temp*_c (degC), device_id* -- what `log export` writes and what
// `compensate` reads a log as.
std::vector<CsvColumn> imu_record_columns(const TimeSeries& record);
// Reads the record, CSV or a log by its content (framework/record_reader.hpp); `required_roles`
// must be present (the role of the first --column that is not the time column replaces "rate").
// A log has no "rate" channel: single-signal commands name one, `--column rate=gyro_z` (the z gyro
// of instance 0, rad/s) or `--column gyro1_x`. What a log reader repaired goes to stderr as notes.
TimeSeries load_record(const DataOptions& data, std::vector<std::string> required_roles = {"rate"});
// The record of a command that assumes even sampling (allan; through load_evenly_sampled_record run,
// compare, decompose and entropy; through load_even_or_bursts_record discrepancy): gaps are read as
// they are and the record's sampling facts (TimeSeries::sampling_facts) classify them with --max-gap's
// factor, the default 3 when --max-gap is 0, so that 0 never makes a gapped record contiguous. What the
// command does with regular bursts or an irregular record is its own business; none reads across a
// gap.
TimeSeries load_record_with_gaps(const DataOptions& data, std::vector<std::string> required_roles = {"rate"});
// The same for a command that takes only an evenly sampled record (run, compare, decompose, entropy):
// any gap is the DataError of sampling::uneven_sampling_error, naming the first gap and, for regular
// bursts, `driftlab allan` (which analyses them per burst). `analysis` names what assumes even sampling.
TimeSeries load_evenly_sampled_record(const DataOptions& data, std::vector<std::string> required_roles,
                                      std::string_view analysis);
// The same for a command that also takes regular bursts as they are (discrepancy: its block means
// never span a gap): an evenly sampled record or regular bursts are returned; an irregular record is
// the DataError of sampling::irregular_sampling_error, with `hint` (the way to accept it anyway).
TimeSeries load_even_or_bursts_record(const DataOptions& data, std::vector<std::string> required_roles,
                                      std::string_view analysis, std::string_view hint);
// Role analysed by single-signal commands: the role of the first --column that is not `time`
// (so --column time=t:s --column rate=r:deg/s analyses rate), else "rate".
std::string primary_role(const DataOptions& data);
// Unit a channel is written back in: the unit it was read in when known ("deg/s" for rates).
std::string display_unit(const TimeSeries& record, const std::string& role, const DataOptions& data);

// The --set STEP.KEY=VALUE option of run and compare (repeatable), and the overrides it gives
// (framework/pipeline.hpp PipelineOverride; a malformed one is a ConfigError naming --set, exit 2).
void add_set_option(CLI::App* command, std::vector<std::string>& sets);
std::vector<PipelineOverride> pipeline_overrides(const std::vector<std::string>& sets);

// The report pair of a command that writes into a directory (run and compare --out, calibrate
// --report): DIR/report.json and DIR/report.html.
struct ReportFiles {
  std::filesystem::path json, html;
};
// Creates `dir` when missing (OutputSet::make_directory: removed again when the command fails) and
// plans both report files in `outputs` under `option`. Throws ConfigError (exit 2) when `dir`
// cannot be created or a report file cannot be planned.
ReportFiles plan_report_files(OutputSet& outputs, const std::filesystem::path& dir, const std::string& option);

}  // namespace driftlab::cli
