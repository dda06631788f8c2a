// The core `driftlab` executable starts without MRPT and MPI: its whole shared-library closure (as
// the dynamic loader resolves it) holds no MRPT, OpenCV, GDAL, assimp or MPI library; `driftlab mrpt`
// and `driftlab nav` still work, through driftlab-mrpt (tools/driftlab/cmd_mrpt_forward.cpp), and
// `mpirun ... driftlab fleet` loads the MPI engine then (fleet_cli_test).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;
using namespace testing_cli;

TEST(Startup, TheCoreExecutablesLibraryClosureHasNoMrptNorWhatItPullsIn) {
  const auto r = run_driftlab("", "LD_TRACE_LOADED_OBJECTS=1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("libdriftlab_framework"));  // the loader did list the closure
  EXPECT_THAT(r.out, AllOf(Not(HasSubstr("libmrpt")), Not(HasSubstr("libopencv")), Not(HasSubstr("libgdal")),
                           Not(HasSubstr("libassimp")), Not(HasSubstr("libmpi"))));
}

#if DRIFTLAB_HAVE_MRPT
TEST(Startup, MrptAndNavRunInTheirOwnExecutableWithTheGlobalOptionsPassedOn) {
  const auto help = run_driftlab("mrpt --help");
  EXPECT_EQ(help.exit_code, 0) << help.err;
  EXPECT_THAT(help.out, AllOf(HasSubstr("import"), HasSubstr("compensate"), HasSubstr("info")));
  const auto nav = run_driftlab("--quiet --threads 2 nav --help");
  EXPECT_EQ(nav.exit_code, 0) << nav.err;
  EXPECT_THAT(nav.out, HasSubstr("--scenario"));
  const auto bad = run_driftlab("--threads 2 mrpt info");  // the usage error of driftlab-mrpt, exit 2
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_THAT(bad.err, HasSubstr("rawlog is required"));
}
#endif

}  // namespace
}  // namespace driftlab
