// driftlab-mrpt: the commands that load MRPT (`mrpt`, `nav`; cmd_mrpt.cpp, cmd_nav.cpp). `driftlab
// mrpt ...` and `driftlab nav ...` execute it with their own arguments (cmd_mrpt_forward.cpp); it
// parses them as driftlab does (cli::run), so it can also be run directly.
#include "tools/driftlab/cli.hpp"

namespace driftlab::cli {
void add_mrpt_command(CLI::App& app, CommandEnv& env);
void add_nav_command(CLI::App& app, CommandEnv& env);
}  // namespace driftlab::cli

int main(int argc, char** argv) {
  using namespace driftlab::cli;
  return run(argc, argv, {add_mrpt_command, add_nav_command});
}
