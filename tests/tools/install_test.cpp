// `cmake --install` (tools/driftlab/CMakeLists.txt) into a fresh prefix gives a driftlab that runs
// from any directory with only PREFIX/bin on the PATH: it loads its shared library from the prefix
// and reads the devices and pipelines installed beside it, not the source or build tree.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

using ::testing::HasSubstr;
using namespace testing_cli;
namespace fs = std::filesystem;

TEST(Install, AnInstalledDriftlabRunsFromAnotherDirectoryWithItsOwnLibraryDevicesAndPipelines) {
  const auto dir = scratch_dir("install");
  const auto prefix = dir / "prefix", elsewhere = dir / "elsewhere";
  fs::create_directories(elsewhere);
  const std::string install = std::string(DRIFTLAB_CMAKE_COMMAND) + " --install " + DRIFTLAB_BUILD_DIR + " --prefix " +
                              prefix.string() + " >" + (dir / "install.log").string() + " 2>&1";
  ASSERT_EQ(std::system(install.c_str()), 0) << read_text(dir / "install.log");
  const auto share = prefix / "share" / "driftlab";
  ASSERT_TRUE(fs::exists(prefix / "bin" / "driftlab"));
  EXPECT_TRUE(fs::exists(share / "devices" / "fmvmg.yaml"));
  EXPECT_TRUE(fs::exists(share / "pipelines" / "li2023.yaml"));
  // A device file only the installed directory has: `devices list` shows that it reads it.
  fs::copy_file(share / "devices" / "fmvmg.yaml", share / "devices" / "installed_probe.yaml");

  // `driftlab ARGS` in `elsewhere`, with the prefix's bin first on the PATH and no DRIFTLAB_ variables.
  const auto installed = [&](const std::string& args) {
    const std::string command =
        "cd " + elsewhere.string() +
        " && env -u DRIFTLAB_DEVICES_DIR -u DRIFTLAB_PLUGIN_PATH PATH=" + (prefix / "bin").string() +
        ":/usr/bin:/bin driftlab " + args + " >" + (dir / "stdout").string() + " 2>" + (dir / "stderr").string();
    const int status = std::system(command.c_str());
    return CliResult{WIFEXITED(status) ? WEXITSTATUS(status) : -1, read_text(dir / "stdout"),
                     read_text(dir / "stderr")};
  };
  const auto version = installed("--version");
  EXPECT_EQ(version.exit_code, 0) << version.err;
  EXPECT_THAT(version.out, HasSubstr("driftlab 0."));
  const auto plugins = installed("plugins list");
  EXPECT_EQ(plugins.exit_code, 0) << plugins.err;
  EXPECT_THAT(plugins.out, HasSubstr("decomposition/emd"));
  const auto devices = installed("devices list");
  EXPECT_EQ(devices.exit_code, 0) << devices.err;
  EXPECT_THAT(devices.out, HasSubstr("installed_probe.yaml"));

  const auto simulated =
      installed("--quiet simulate --device fmvmg --profile oven --fs 1 --duration 1800 --out rec.csv");
  ASSERT_EQ(simulated.exit_code, 0) << simulated.err;
  // A pipeline by name is the installed one; an unknown name lists the installed directory.
  const auto run = installed("--quiet run --pipeline polynomial_baseline --data rec.csv --out run");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(fs::exists(elsewhere / "run" / "outputs.csv"));
  const auto unknown = installed("run --validate-only --pipeline no_such_pipeline");
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_THAT(unknown.err, HasSubstr((share / "pipelines").string()));

  // The executable loads the prefix's libdriftlab_framework.so (its RUNPATH), not the build tree's.
  const std::string ldd = "ldd " + (prefix / "bin" / "driftlab").string() + " >" + (dir / "ldd").string();
  ASSERT_EQ(std::system(ldd.c_str()), 0);
  const auto libraries = read_text(dir / "ldd");
  EXPECT_THAT(libraries, HasSubstr((prefix / "bin" / ".." / "lib" / "libdriftlab_framework.so").string()));
}

}  // namespace
}  // namespace driftlab
