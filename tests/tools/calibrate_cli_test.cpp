// End to end: `driftlab calibrate` and `driftlab compensate` (batch and streaming).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

using testing_cli::read_text;
using testing_cli::run_driftlab;
using testing_cli::scratch_dir;

class CalibrateCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = scratch_dir("calibrate").string();
    const auto r = run_driftlab("simulate --device fmvmg --fs 2 --seed 3 --out " + dir_ + "/oven.csv");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto c = run_driftlab("-q calibrate --data " + dir_ + "/oven.csv --model poly --out " + dir_ + "/poly.json");
    ASSERT_EQ(c.exit_code, 0) << c.err;
  }
  static std::string dir_;
};
std::string CalibrateCli::dir_;

TEST_F(CalibrateCli, StreamingOutputEqualsBatchOutputRowForRow) {
  const auto b = run_driftlab("compensate --model " + dir_ + "/poly.json --data " + dir_ + "/oven.csv --out " + dir_ +
                              "/batch.csv");
  ASSERT_EQ(b.exit_code, 0) << b.err;
  const std::string command = std::string(DRIFTLAB_EXE) + " compensate --model " + dir_ + "/poly.json --stream < " +
                              dir_ + "/oven.csv > " + dir_ + "/stream.csv";
  ASSERT_EQ(std::system(command.c_str()), 0);
  const std::string batch = read_text(dir_ + "/batch.csv"), stream = read_text(dir_ + "/stream.csv");
  EXPECT_GT(batch.size(), 100000u);
  EXPECT_EQ(batch, stream);
}

TEST_F(CalibrateCli, ABadModelFileIsAConfigurationErrorNamingTheKey) {
  std::ofstream(dir_ + "/bad.json") << R"({"format": "driftlab-calibration/1", "kind": "poly", "reference_temp_c": 25})";
  const auto r = run_driftlab("compensate --model " + dir_ + "/bad.json --data " + dir_ + "/oven.csv --out " + dir_ +
                              "/x.csv");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("valid_range_c"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/x.csv"));
}

TEST_F(CalibrateCli, AMissingTemperatureColumnIsADataError) {
  std::ofstream(dir_ + "/notemp.csv") << "t_s,rate_dps\n0,0.1\n1,0.2\n";
  const auto r = run_driftlab("compensate --model " + dir_ + "/poly.json --data " + dir_ + "/notemp.csv --out " + dir_ +
                              "/y.csv");
  EXPECT_EQ(r.exit_code, 3) << r.err;
  const std::string command = std::string(DRIFTLAB_EXE) + " compensate --model " + dir_ + "/poly.json --stream < " +
                              dir_ + "/notemp.csv > /dev/null 2>" + dir_ + "/err.txt";
  EXPECT_EQ(WEXITSTATUS(std::system(command.c_str())), 3);
  EXPECT_NE(read_text(dir_ + "/err.txt").find("temp_c"), std::string::npos);
}

TEST_F(CalibrateCli, CalibrateRefusesToOverwriteItsInput) {
  const auto r = run_driftlab("calibrate --data " + dir_ + "/oven.csv --out " + dir_ + "/oven.csv");
  EXPECT_EQ(r.exit_code, 2);
}

TEST_F(CalibrateCli, EveryCommandHasHelp) {
  EXPECT_EQ(run_driftlab("calibrate --help").exit_code, 0);
  EXPECT_EQ(run_driftlab("compensate --help").exit_code, 0);
}

}  // namespace
}  // namespace driftlab
