// The `driftlab` command: subcommands are added by cmd_<name>.cpp files. `mrpt` and `nav` run in
// driftlab-mrpt (mrpt_main.cpp; cmd_mrpt_forward.cpp), so that no other command loads MRPT.
#include "tools/driftlab/cli.hpp"

namespace driftlab::cli {
void add_plugins_command(CLI::App& app, CommandEnv& env);
void add_run_command(CLI::App& app, CommandEnv& env);
void add_devices_command(CLI::App& app, CommandEnv& env);
void add_simulate_command(CLI::App& app, CommandEnv& env);
void add_entropy_command(CLI::App& app, CommandEnv& env);
void add_allan_command(CLI::App& app, CommandEnv& env);
void add_decompose_command(CLI::App& app, CommandEnv& env);
void add_discrepancy_command(CLI::App& app, CommandEnv& env);
void add_mrpt_command(CLI::App& app, CommandEnv& env);
void add_nav_command(CLI::App& app, CommandEnv& env);
void add_calibrate_command(CLI::App& app, CommandEnv& env);
void add_compensate_command(CLI::App& app, CommandEnv& env);
void add_export_command(CLI::App& app, CommandEnv& env);
void add_compare_command(CLI::App& app, CommandEnv& env);
void add_log_command(CLI::App& app, CommandEnv& env);
void add_fleet_command(CLI::App& app, CommandEnv& env);
}  // namespace driftlab::cli

int main(int argc, char** argv) {
  using namespace driftlab::cli;
  return run(argc, argv,
             {add_plugins_command, add_run_command, add_devices_command, add_simulate_command, add_entropy_command,
              add_allan_command, add_decompose_command, add_discrepancy_command, add_mrpt_command, add_nav_command,
              add_calibrate_command, add_compensate_command, add_export_command, add_compare_command, add_log_command,
              add_fleet_command});
}
