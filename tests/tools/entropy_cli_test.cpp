// End-to-end tests of `driftlab entropy` on PhysioNet's sampentest signal.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

using ::testing::HasSubstr;
using namespace testing_cli;

const std::filesystem::path kSampentest =
    std::filesystem::path(DRIFTLAB_SHARED_DATA) / "real" / "physionet-sampen" / "sampentest.txt";

// Writes sampentest.txt as a CSV record (t_s at 100 Hz plus one value column) and returns its path.
std::filesystem::path sampentest_csv(const std::string& test, const std::string& value_column) {
  std::ifstream in(kSampentest);
  std::vector<double> values;
  double v = 0.0;
  while (in >> v) values.push_back(v);
  const auto path = scratch_dir(test) / "sampentest.csv";
  std::ofstream out(path);
  out << "t_s," << value_column << "\n";
  char line[64];
  for (std::size_t i = 0; i < values.size(); ++i) {
    std::snprintf(line, sizeof line, "%.2f,%.17g\n", static_cast<double>(i) / 100.0, values[i]);
    out << line;
  }
  return path;
}

TEST(EntropyCommand, PrintsThePublishedPhysioNetValueWithItsCounts) {
  if (!std::filesystem::exists(kSampentest)) GTEST_SKIP() << "PhysioNet data not found: " << kSampentest;
  const auto csv = sampentest_csv("entropy_published", "rate_dps");
  const auto r = run_driftlab("entropy --data " + csv.string() + " --m 2 --r 0.2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("SampEn(m=2, r=0.2) = 2.197225\n"));  // PhysioNet sampen.c output
  EXPECT_THAT(r.out, HasSubstr("A = 699 "));
  EXPECT_THAT(r.out, HasSubstr("B = 6291 "));
  EXPECT_THAT(r.out, HasSubstr("N = 1024 samples of rate"));
}

TEST(EntropyCommand, ReportsInfinityClearlyWhenNoLongerTemplatesMatch) {
  if (!std::filesystem::exists(kSampentest)) GTEST_SKIP() << "PhysioNet data not found: " << kSampentest;
  const auto csv = sampentest_csv("entropy_inf", "rate_dps");
  const auto r = run_driftlab("entropy --data " + csv.string() + " --m 5 --r 0.2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("SampEn(m=5, r=0.2) = Inf  (no template pairs match over m+1 = 6 samples: A = 0)"));
  EXPECT_THAT(r.out, HasSubstr("B = 8 "));
}

TEST(EntropyCommand, AnalysesAMappedColumnAndRejectsBadInput) {
  if (!std::filesystem::exists(kSampentest)) GTEST_SKIP() << "PhysioNet data not found: " << kSampentest;
  const auto csv = sampentest_csv("entropy_column", "signal");
  const auto r = run_driftlab("entropy --data " + csv.string() + " --column signal=signal:1 --m 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("SampEn(m=1, r=0.2) = 2.224817\n"));
  EXPECT_THAT(r.out, HasSubstr("samples of signal"));

  EXPECT_EQ(run_driftlab("entropy --data " + csv.string() + "_missing").exit_code, 3);
  EXPECT_EQ(run_driftlab("entropy --data " + csv.string() + " --r -1").exit_code, 2);
}

}  // namespace
}  // namespace driftlab
