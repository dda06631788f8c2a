// OutputSet: every output planned and checked before the work, committed together or not at all.
#include "framework/output_set.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "framework/error.hpp"

namespace driftlab {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

fs::path fresh_dir(const std::string& name) {
  const auto dir = fs::temp_directory_path() / ("driftlab_output_set_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string text_of(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::size_t files_in(const fs::path& dir) {
  std::size_t n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += e.is_regular_file();
  return n;
}

TEST(OutputSet, CommitsEveryPlannedOutputTogether) {
  const auto dir = fresh_dir("commit");
  {
    OutputSet outputs;
    outputs.plan(dir / "a.txt", "--a");
    outputs.plan(dir / "b.csv", "--b");
    outputs.plan("", "--unused");  // an option not given: nothing planned
    outputs.write(dir / "a.txt", "alpha\n");
    outputs.write_csv(dir / "b.csv", {{"t_s", Eigen::VectorXd::LinSpaced(3, 0.0, 2.0), "s"}});
    EXPECT_FALSE(fs::exists(dir / "a.txt")) << "nothing appears before commit";
    outputs.commit();
  }
  EXPECT_EQ(text_of(dir / "a.txt"), "alpha\n");
  EXPECT_EQ(text_of(dir / "b.csv"), "t_s\n0\n1\n2\n");
  EXPECT_EQ(files_in(dir), 2u) << "no temporary file is left";
}

TEST(OutputSet, AnOutputSetLeftWithoutCommitLeavesNothing) {
  const auto dir = fresh_dir("abandon");
  {
    std::ofstream(dir / "old.txt") << "earlier\n";
    OutputSet outputs;
    outputs.plan(dir / "old.txt", "--out");
    outputs.plan(dir / "new.txt", "--json");
    outputs.write(dir / "old.txt", "replaced\n");
  }  // e.g. an exception on the way
  EXPECT_EQ(text_of(dir / "old.txt"), "earlier\n");
  EXPECT_FALSE(fs::exists(dir / "new.txt"));
  EXPECT_EQ(files_in(dir), 1u);
}

TEST(OutputSet, RefusesBadPathsBeforeAnyWork) {
  const auto dir = fresh_dir("plan");
  std::ofstream(dir / "input.csv") << "t_s\n0\n";
  OutputSet outputs({dir / "input.csv"});
  outputs.plan(dir / "out.csv", "--out");
  const auto refused = [&](const fs::path& path, const std::string& message) {
    try {
      outputs.plan(path, "--json");
      ADD_FAILURE() << path << " was accepted";
    } catch (const ConfigError& e) {
      EXPECT_THAT(e.what(), HasSubstr(message)) << path;
    }
  };
  refused(dir / "input.csv", "inputs are never overwritten");
  refused(dir / "." / "out.csv", "the same file is also given as --out");
  refused(dir / "missing" / "x.json", "does not exist");
  refused(dir, "is a directory");
  if (::geteuid() != 0) {  // root writes anywhere
    fs::create_directories(dir / "ro");
    fs::permissions(dir / "ro", fs::perms::owner_read | fs::perms::owner_exec);
    refused(dir / "ro" / "x.json", "cannot write to the output directory");
  }
}

TEST(OutputSet, CommitRequiresEveryPlannedOutputToBeWritten) {
  const auto dir = fresh_dir("unwritten");
  OutputSet outputs;
  outputs.plan(dir / "a.txt", "--a");
  outputs.plan(dir / "b.txt", "--b");
  outputs.write(dir / "a.txt", "a");
  EXPECT_THROW(outputs.commit(), std::logic_error);
  EXPECT_THROW(outputs.write(dir / "c.txt", "c"), std::logic_error);
}

TEST(OutputSet, AFailedRenameRestoresTheOutputsAlreadyCommitted) {
  const auto dir = fresh_dir("rollback");
  std::ofstream(dir / "a.txt") << "earlier a\n";
  {
    OutputSet outputs;
    outputs.plan(dir / "a.txt", "--a");
    outputs.plan(dir / "b.txt", "--b");
    outputs.write(dir / "a.txt", "new a\n");
    outputs.write(dir / "b.txt", "new b\n");
    fs::create_directories(dir / "b.txt" / "occupied");  // b's rename onto a non-empty directory fails
    EXPECT_THROW(outputs.commit(), Error);
  }
  EXPECT_EQ(text_of(dir / "a.txt"), "earlier a\n");
  EXPECT_TRUE(fs::is_directory(dir / "b.txt"));
  EXPECT_EQ(files_in(dir), 1u);
}

}  // namespace
}  // namespace driftlab
