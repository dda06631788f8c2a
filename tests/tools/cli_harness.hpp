// Runs the real `driftlab` executable for end-to-end tests and captures exit code and output.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace driftlab::testing_cli {

struct CliResult {
  int exit_code = -1;
  std::string out, err;
};

inline std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The scratch directories of this test process, removed when it exits (a fleet test's is 350 MB;
// set DRIFTLAB_KEEP_SCRATCH=1 to keep them for a look after a failure). Only the process that made
// them removes them: a forked child that exits leaves them to its parent.
class ScratchDirs {
 public:
  static ScratchDirs& instance() {
    static ScratchDirs dirs;
    return dirs;
  }
  void add(const std::filesystem::path& dir) { dirs_.push_back(dir); }
  ~ScratchDirs() {
    if (::getpid() != owner_ || std::getenv("DRIFTLAB_KEEP_SCRATCH")) return;
    std::error_code ignored;
    for (const auto& dir : dirs_) std::filesystem::remove_all(dir, ignored);
  }

 private:
  ScratchDirs() : owner_(::getpid()) {}
  pid_t owner_;
  std::vector<std::filesystem::path> dirs_;
};

// A fresh, empty scratch directory for one test, removed when the test process exits.
inline std::filesystem::path scratch_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("driftlab_cli_" + std::to_string(::getpid()) + "_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  ScratchDirs::instance().add(dir);
  return dir;
}

// `args` is appended to the executable path as shell words (quote paths with spaces yourself);
// standard input is the file `input`.
inline CliResult run_driftlab(const std::string& args, const std::string& env = "",
                              const std::string& input = "/dev/null") {
  static int calls = 0;  // ctest runs test processes in parallel: name captures by pid and call
  const auto dir = scratch_dir("capture_" + std::to_string(::getpid()) + "_" + std::to_string(++calls));
  const auto out = dir / "stdout", err = dir / "stderr";
  const std::string command = env + (env.empty() ? "" : " ") + std::string(DRIFTLAB_EXE) + " " + args + " >" +
                              out.string() + " 2>" + err.string() + " <" + input;
  const int status = std::system(command.c_str());
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = read_text(out);
  r.err = read_text(err);
  std::filesystem::remove_all(dir);
  return r;
}

}  // namespace driftlab::testing_cli
