// OutputSet: every output planned and checked before the work, committed together or not at all.
#include "framework/output_set.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "framework/csv.hpp"
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

void write_via_output_set(const fs::path& path) {
  OutputSet outputs;
  outputs.plan(path, "--out");
  outputs.write(path, "text\n");
  outputs.commit();
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

TEST(OutputSet, RefusesAnExistingPathThatIsNotARegularFileAndLeavesItAsItWas) {
  const auto dir = fresh_dir("nodes");
  ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0600), 0);
  fs::create_symlink(dir / "fifo", dir / "link_to_fifo");
  const int sock = ::socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  const std::string sock_path = (dir / "sock").string();
  ASSERT_LT(sock_path.size(), sizeof addr.sun_path);
  std::copy(sock_path.begin(), sock_path.end(), addr.sun_path);
  ASSERT_EQ(::bind(sock, reinterpret_cast<const sockaddr*>(&addr), sizeof addr), 0);
  // A character device with /dev/null's numbers, made here (never the system's own /dev/null).
  const bool device = ::mknod((dir / "null").c_str(), S_IFCHR | 0666, ::makedev(1, 3)) == 0;
  if (!device) EXPECT_NE(::geteuid(), 0u) << "root can make a device node";
  const auto refused = [&](const fs::path& path, const std::string& kind) {
    try {
      write_via_output_set(path);
      ADD_FAILURE() << path << " was accepted";
    } catch (const ConfigError& e) {
      EXPECT_THAT(e.what(), HasSubstr(path.string())) << path;
      EXPECT_THAT(e.what(), HasSubstr("is " + kind + "; outputs are written only as regular files")) << path;
    }
  };
  refused(dir / "fifo", "a FIFO (named pipe)");
  refused(dir / "link_to_fifo", "a FIFO (named pipe)");
  refused(dir / "sock", "a socket");
  if (device) refused(dir / "null", "a character device");
  ::close(sock);
  EXPECT_TRUE(fs::is_fifo(fs::symlink_status(dir / "fifo")));
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir / "link_to_fifo")));
  EXPECT_TRUE(fs::is_socket(fs::symlink_status(dir / "sock")));
  if (device) EXPECT_TRUE(fs::is_character_file(fs::symlink_status(dir / "null")));
  EXPECT_EQ(files_in(dir), 0u) << "no temporary file is left";
}

TEST(OutputSet, CommitRefusesANodeMadeAfterPlanning) {
  const auto dir = fresh_dir("late_fifo");
  {
    OutputSet outputs;
    outputs.plan(dir / "out.csv", "--out");
    outputs.write(dir / "out.csv", "t_s\n");
    ASSERT_EQ(::mkfifo((dir / "out.csv").c_str(), 0600), 0);
    EXPECT_THROW(outputs.commit(), ConfigError);
  }
  EXPECT_TRUE(fs::is_fifo(fs::symlink_status(dir / "out.csv")));
  EXPECT_EQ(files_in(dir), 0u);
}

TEST(OutputSet, DirectoriesMadeForAFailedCommandAreRemovedAndOnlyThose) {
  const auto dir = fresh_dir("dirs");
  fs::create_directories(dir / "existing");
  {
    OutputSet outputs;
    outputs.make_directory(dir / "existing", "--report");
    outputs.make_directory(dir / "new" / "deeper", "--out");
    outputs.plan(dir / "new" / "deeper" / "report.json", "--out");
    EXPECT_TRUE(fs::is_directory(dir / "new" / "deeper"));
  }  // not committed: the command failed
  EXPECT_FALSE(fs::exists(dir / "new"));
  EXPECT_TRUE(fs::is_directory(dir / "existing")) << "a directory that was there stays";
  {
    OutputSet outputs;
    outputs.make_directory(dir / "kept", "--out");
    outputs.plan(dir / "kept" / "a.txt", "--out");
    outputs.write(dir / "kept" / "a.txt", "a");
    outputs.commit();
  }
  EXPECT_EQ(text_of(dir / "kept" / "a.txt"), "a");
  std::ofstream(dir / "file") << "x";
  OutputSet outputs;
  EXPECT_THROW(outputs.make_directory(dir / "file", "--out"), ConfigError);
}

TEST(OutputSet, TemporaryFilesAreHiddenNextToTheirOutput) {
  const auto dir = fresh_dir("hidden");
  OutputSet outputs;
  outputs.plan(dir / "o.rawlog", "--out");
  const fs::path temp = outputs.stage_path(dir / "o.rawlog");
  EXPECT_EQ(temp.parent_path(), dir);
  EXPECT_EQ(temp.filename().string().rfind(".o.rawlog.tmp-", 0), 0u) << temp;
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

TEST(OutputSet, ARetiredOutputIsRemovedByTheCommitAndOnlyThen) {
  const auto dir = fresh_dir("retire");
  std::ofstream(dir / "model.json") << "earlier model\n";
  std::ofstream(dir / "status.json") << "earlier status\n";
  {
    OutputSet outputs;
    outputs.retire(dir / "model.json", "model.json");
    outputs.retire(dir / "never_written.json", "never_written.json");  // nothing there: nothing to do
    outputs.plan(dir / "status.json", "status.json");
    outputs.write(dir / "status.json", "failed\n");
  }  // not committed: the earlier files stay as they were
  EXPECT_EQ(text_of(dir / "model.json"), "earlier model\n");
  EXPECT_EQ(text_of(dir / "status.json"), "earlier status\n");
  OutputSet outputs({dir / "input.csv"});
  outputs.retire(dir / "model.json", "model.json");
  outputs.plan(dir / "status.json", "status.json");
  outputs.write(dir / "status.json", "failed\n");
  outputs.commit();
  EXPECT_FALSE(fs::exists(dir / "model.json"));
  EXPECT_EQ(text_of(dir / "status.json"), "failed\n");
  EXPECT_EQ(files_in(dir), 1u);
  // Checked as an output is: never an input, never a node, never also written.
  OutputSet checks({dir / "input.csv"});
  EXPECT_THROW(checks.retire(dir / "input.csv", "model.json"), ConfigError);
  fs::create_directories(dir / "folder");
  EXPECT_THROW(checks.retire(dir / "folder", "model.json"), ConfigError);
  checks.retire(dir / "status.json", "status.json");
  EXPECT_THROW(checks.plan(dir / "status.json", "status.json"), ConfigError);
}

TEST(OutputSet, StaleTemporariesOfAKilledRunAreRemovedAndNothingElse) {
  const auto dir = fresh_dir("stale");
  for (const char* name : {".model.json.tmp-a1B2c3", ".model.json.tmp-a1B2c3.old", "model.json", ".model.json.tmp-",
                           ".model.json.tmp-toolong1", ".status.json.tmp-a1B2c3", "notes.txt"})
    std::ofstream(dir / name) << "x";
  OutputSet::remove_stale_temporaries(dir / "model.json");
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir)) left.push_back(e.path().filename().string());
  std::sort(left.begin(), left.end());
  EXPECT_EQ(left, (std::vector<std::string>{".model.json.tmp-", ".model.json.tmp-toolong1", ".status.json.tmp-a1B2c3",
                                            "model.json", "notes.txt"}));
}

TEST(OutputSet, AStreamedCsvEqualsItsTextAndAFailureHalfWayLeavesTheOldFile) {
  const auto dir = fresh_dir("streamed_csv");
  // Enough rows for several of stream_csv's 1-MiB pieces; viewed columns are not copied.
  const Eigen::Index rows = 200000;
  const Eigen::VectorXd time = Eigen::VectorXd::LinSpaced(rows, 0.0, 1999.99);
  Eigen::MatrixXd imfs(rows, 2);
  imfs.col(0) = (time.array() * 0.37).sin();
  imfs.col(1) = (time.array() * 0.011).cos() * 1e-3;
  const std::vector<CsvColumn> columns{CsvColumn::view("t_s", time, "s"),
                                       CsvColumn::view("imf1", imfs.col(0), "1"),
                                       {"imf2", imfs.col(1), "deg/s", false}};
  const std::string text = format_csv(columns, "out.csv");
  ASSERT_GT(text.size(), std::size_t{3} << 20);
  {
    OutputSet outputs;
    outputs.plan(dir / "out.csv", "--out");
    outputs.write_csv(dir / "out.csv", columns);
    outputs.commit();
  }
  EXPECT_EQ(text_of(dir / "out.csv"), text);

  Eigen::VectorXd broken = imfs.col(0);
  broken[rows - 10] = std::numeric_limits<double>::infinity();  // after the first pieces were written
  try {
    OutputSet outputs;
    outputs.plan(dir / "out.csv", "--out");
    outputs.write_csv(dir / "out.csv", {CsvColumn::view("t_s", time, "s"), CsvColumn::view("imf1", broken, "1")});
    ADD_FAILURE() << "a non-finite value was written";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("row " + std::to_string(rows - 9) + " is not finite"));
  }
  EXPECT_EQ(text_of(dir / "out.csv"), text);
  EXPECT_EQ(files_in(dir), 1u);  // no temporary left
  fs::remove_all(dir);
}

}  // namespace
}  // namespace driftlab
