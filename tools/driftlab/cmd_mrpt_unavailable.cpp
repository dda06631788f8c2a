// `driftlab mrpt` and `driftlab nav` in a build without MRPT: the commands exist (so --help lists
// them) and say how to get them.
#include "framework/error.hpp"
#include "tools/driftlab/cli.hpp"

namespace driftlab::cli {
namespace {
[[noreturn]] void unavailable(const std::string& command) {
  throw ConfigError(Location{"", 0, command},
                    "this driftlab was built without MRPT; install libmrpt-obs-dev (bash tools/install-deps.sh) "
                    "and rebuild to get the MRPT bridge");
}
}  // namespace

void add_mrpt_command(CLI::App& app, CommandEnv&) {
  auto* cmd = app.add_subcommand("mrpt", "MRPT rawlog bridge (not built: MRPT was not found)");
  cmd->allow_extras();
  cmd->callback([] { unavailable("mrpt"); });
}

void add_nav_command(CLI::App& app, CommandEnv&) {
  auto* cmd = app.add_subcommand("nav", "vehicle navigation demonstration (not built: MRPT was not found)");
  cmd->allow_extras();
  cmd->callback([] { unavailable("nav"); });
}

}  // namespace driftlab::cli
