// `driftlab mrpt` and `driftlab nav` in a build with MRPT: each executes driftlab-mrpt (found next
// to the driftlab executable; mrpt_main.cpp) with the global options given to driftlab and every
// argument after the command name, `--help` included. The MRPT libraries (about 180 shared
// libraries with OpenCV, GDAL, assimp) are then loaded by the commands that use them only; every
// other command starts without them.
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <iostream>

#include "framework/error.hpp"
#include "tools/driftlab/cli.hpp"

namespace driftlab::cli {
namespace {

std::filesystem::path mrpt_executable() { return executable_dir() / "driftlab-mrpt"; }

[[noreturn]] void execute(const std::string& command, const CommandEnv& env, const std::vector<std::string>& rest) {
  const auto program = mrpt_executable();
  std::vector<std::string> args{program.string()};
  for (const auto& dir : env.plugin_dirs) args.insert(args.end(), {"--plugin-path", dir});
  if (env.quiet) args.emplace_back("--quiet");
  args.insert(args.end(), {"--threads", std::to_string(env.threads), command});
  args.insert(args.end(), rest.begin(), rest.end());
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::cout.flush();
  std::cerr.flush();
  execv(program.c_str(), argv.data());
  throw ConfigError({program.string(), 0, command},
                    std::string("cannot run the MRPT commands' executable (") + std::strerror(errno) +
                        "); it is built and installed with driftlab when MRPT is found");
}

void add_forwarding_command(CLI::App& app, CommandEnv& env, const std::string& name, const std::string& description) {
  auto* cmd = app.add_subcommand(name, description + " (run `driftlab " + name + " --help` for its options)");
  cmd->set_help_flag();
  cmd->prefix_command();
  cmd->callback([cmd, name, &env] { execute(name, env, cmd->remaining()); });
}

}  // namespace

void add_mrpt_command(CLI::App& app, CommandEnv& env) {
  add_forwarding_command(app, env, "mrpt", "MRPT rawlog bridge: import, export, compensate, info");
}

void add_nav_command(CLI::App& app, CommandEnv& env) {
  add_forwarding_command(app, env, "nav",
                         "vehicle navigation demonstration: an MRPT EKF on raw and compensated yaw rates");
}

}  // namespace driftlab::cli
