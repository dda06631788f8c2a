// The `driftlab` command: subcommands are added by cmd_<name>.cpp files.
#include <iostream>

#include "framework/error.hpp"
#include "tools/driftlab/cli.hpp"
#include "tools/driftlab/version.hpp"

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
  CLI::App app{"driftlab: MEMS gyroscope error modelling and temperature-drift compensation"};
  app.set_version_flag("--version", std::string("driftlab ") + driftlab::kVersion);
  app.require_subcommand(1);
  CommandEnv env;
  app.add_option("--plugin-path", env.plugin_dirs,
                 "directory of external plugin libraries (*.so); repeatable; also $DRIFTLAB_PLUGIN_PATH")
      ->check(CLI::ExistingDirectory);
  app.add_flag("--quiet,-q", env.quiet, "no progress output on stderr");
  app.add_option("--threads", env.threads, "worker threads (results do not depend on it)")
      ->check(CLI::Range(1u, 256u))
      ->capture_default_str();

  add_plugins_command(app, env);
  add_run_command(app, env);
  add_devices_command(app, env);
  add_simulate_command(app, env);
  add_entropy_command(app, env);
  add_allan_command(app, env);
  add_decompose_command(app, env);
  add_discrepancy_command(app, env);
  add_mrpt_command(app, env);
  add_nav_command(app, env);
  add_calibrate_command(app, env);
  add_compensate_command(app, env);
  add_export_command(app, env);
  add_compare_command(app, env);
  add_log_command(app, env);
  add_fleet_command(app, env);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitUsage;
  } catch (const driftlab::ConfigError& e) {
    std::cerr << "driftlab: configuration error:\n" << e.what() << "\n";
    return kExitUsage;
  } catch (const driftlab::DataError& e) {
    std::cerr << "driftlab: bad input data: " << e.what() << "\n";
    return kExitData;
  } catch (const std::exception& e) {
    std::cerr << "driftlab: failed: " << e.what() << "\n";
    return kExitFailure;
  }
  return kExitOk;
}
