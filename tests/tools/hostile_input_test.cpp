// Hostile input on the newer surfaces (issue 28), the commands without MRPT (the rawlog and nav
// cases are in mrpt_bridge_test): outputs are regular files, always; inputs are checked before they
// are read; models are validated as physics. Every case ends with exit 2 or 3, a message naming the
// file and what was expected, and nothing new left behind. FIFOs and device nodes are made in the
// scratch directory (never the system's /dev/null).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <tuple>
#include <vector>

#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using namespace testing_cli;

void write(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// 600 samples at 1 Hz: rate (deg/s) with a temperature trend, temperature ramping 20 -> 50 degC.
std::string oven_rows(bool zero_rate = false, bool truth = false) {
  std::string text = std::string("t_s,rate_dps,temp_c") + (truth ? ",true_rate_dps" : "") + "\n";
  char line[200];
  for (int i = 0; i < 600; ++i) {
    const double temp = 20.0 + 0.05 * i;
    const double true_rate = truth ? 10.0 * std::sin(0.05 * i) : 0.0;
    const double rate = zero_rate ? 0.0 : true_rate + 0.01 + 2e-4 * (temp - 20.0) + 1e-4 * std::sin(7.3 * i * i);
    if (truth)
      std::snprintf(line, sizeof line, "%d,%.9f,%.6f,%.9f\n", i, rate, temp, true_rate);
    else
      std::snprintf(line, sizeof line, "%d,%.9f,%.6f\n", i, rate, temp);
    text += line;
  }
  return text;
}

class Hostile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = scratch_dir(std::string("hostile_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    write(dir_ / "oven.csv", oven_rows());
  }
  void TearDown() override { fs::remove_all(dir_); }  // FIFOs and device nodes do not stay behind
  std::string p(const std::string& name) const { return (dir_ / name).string(); }
  void make_fifo(const std::string& name) const { ASSERT_EQ(::mkfifo(p(name).c_str(), 0600), 0); }
  // A calibration model of oven.csv.
  void make_model() const {
    const auto r = run_driftlab("calibrate --data " + p("oven.csv") + " --bin 10 --out " + p("model.json"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  // Every entry of the scratch directory, for "nothing new is left".
  std::vector<std::string> entries() const {
    std::vector<std::string> out;
    for (const auto& e : fs::recursive_directory_iterator(dir_)) out.push_back(e.path().string());
    std::sort(out.begin(), out.end());
    return out;
  }
  fs::path dir_;
};

TEST_F(Hostile, AnOutputThatIsAFifoOrADeviceNodeIsRefusedAndLeftAsItWas) {
  make_model();
  make_fifo("fifo");
  fs::create_symlink(p("fifo"), p("link"));
  // A character device with /dev/null's numbers, made here: the command must not replace it.
  const bool device = ::mknod(p("null").c_str(), S_IFCHR | 0666, ::makedev(1, 3)) == 0;
  std::vector<std::string> targets{"fifo", "link"};
  if (device) targets.push_back("null");
  for (const auto& target : targets) {
    const std::string out = p(target);
    const std::vector<std::string> commands{
        "allan --data " + p("oven.csv") + " --out " + out,
        "allan --data " + p("oven.csv") + " --out " + p("a.csv") + " --json " + out,
        "compensate --data " + p("oven.csv") + " --model " + p("model.json") + " --out " + out,
        "calibrate --data " + p("oven.csv") + " --bin 10 --out " + out,
        "export --model " + p("model.json") + " --format px4 --out " + out,
        "simulate --device fmvmg --duration 10 --out " + out,
    };
    const auto before = entries();
    for (const auto& command : commands) {
      const auto r = run_driftlab(command, "DRIFTLAB_DEVICES_DIR=" + std::string(DRIFTLAB_SOURCE_DIR) + "/devices");
      EXPECT_EQ(r.exit_code, 2) << command << "\n" << r.err;
      EXPECT_THAT(r.err, HasSubstr(out + ":")) << command;
      EXPECT_THAT(r.err, HasSubstr("outputs are written only as regular files")) << command;
      EXPECT_EQ(entries(), before) << command;
    }
  }
  EXPECT_TRUE(fs::is_fifo(fs::symlink_status(p("fifo"))));
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(p("link"))));
  if (device) {
    EXPECT_TRUE(fs::is_character_file(fs::symlink_status(p("null"))));
  }
}

TEST_F(Hostile, DirectoriesMadeForAFailedRunAreRemoved) {
  write(dir_ / "smooth.yaml", R"(format: driftlab-pipeline/1
inputs: {rate: rate}
steps:
  - name: smooth
    plugin: filter/kalman
    inputs: {signal: rate}
outputs: {smoothed: smooth.signal}
)");
  write(dir_ / "nan.csv", "t_s,rate_dps,temp_c\n0,0.1,20\n1,nan,20\n2,0.1,20\n");
  const auto before = entries();
  // The data fails after the output directory was made.
  const std::vector<std::string> commands{
      "calibrate --data " + p("nan.csv") + " --bin 1 --out " + p("m.json") + " --report " + p("new/report"),
      "compare --data " + p("nan.csv") + " --pipeline " + p("smooth.yaml") + " --out " + p("new/compare"),
      "run --pipeline " + p("smooth.yaml") + " --data " + p("nan.csv") + " --out " + p("new/run"),
  };
  for (const auto& command : commands) {
    const auto r = run_driftlab(command);
    EXPECT_EQ(r.exit_code, 3) << command << "\n" << r.err;
    EXPECT_EQ(entries(), before) << command << "\n" << r.err;
  }
}

TEST_F(Hostile, InputsThatAreNotRegularFilesAreRefusedBeforeTheyAreRead) {
  make_model();
  make_fifo("fifo");
  const std::string fifo = p("fifo");
  // "timeout": a reader that opens the FIFO blocks forever (no writer); the test must still end.
  const std::vector<std::tuple<std::string, int, std::string>> cases{
      {"compensate --data " + p("oven.csv") + " --model " + fifo + " --out " + p("c.csv"), 2,
       "cannot read the calibration model file: it is a FIFO (named pipe); expected a regular file"},
      {"export --model " + fifo + " --format px4 --out " + p("x.params"), 2, "cannot read the calibration model file"},
      {"run --pipeline " + fifo + " --data " + p("oven.csv") + " --out " + p("run"), 2,
       "cannot read the pipeline file: it is a FIFO"},
      {"compare --data " + p("oven.csv") + " --pipeline " + fifo + " --out " + p("cmp"), 2,
       "cannot read the pipeline file: it is a FIFO"},
      {"simulate --device " + fifo + " --duration 10 --out " + p("s.csv"), 2,
       "cannot read the device file: it is a FIFO"},
      {"allan --data " + fifo + " --out " + p("a.csv"), 3, "is a FIFO (named pipe); expected a regular file"},
      {"calibrate --data " + fifo + " --bin 10 --out " + p("m.json"), 3,
       "is a FIFO (named pipe); expected a regular file"},
      {"log info " + fifo, 3, "is a FIFO (named pipe); expected a regular file"},
  };
  const auto before = entries();
  for (const auto& [command, code, message] : cases) {
    const auto r = run_driftlab(command, "timeout 20");
    EXPECT_EQ(r.exit_code, code) << command << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr(fifo)) << command;
    EXPECT_THAT(r.err, HasSubstr(message)) << command;
    EXPECT_EQ(entries(), before) << command;
  }
}

TEST_F(Hostile, ASmallTextFormatAboveItsSizeLimitIsRefusedUnread) {
  std::ofstream(p("huge.json")) << "{";
  fs::resize_file(p("huge.json"), (std::uintmax_t{64} << 20) + 1);  // sparse: no disk used
  std::ofstream(p("huge.yaml")) << "#";
  fs::resize_file(p("huge.yaml"), (std::uintmax_t{64} << 20) + 1);
  for (const auto& command :
       {"compensate --data " + p("oven.csv") + " --model " + p("huge.json") + " --out " + p("c.csv"),
        "run --pipeline " + p("huge.yaml") + " --data " + p("oven.csv") + " --out " + p("run")}) {
    const auto r = run_driftlab(command, "timeout 20");
    EXPECT_EQ(r.exit_code, 2) << command << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr("has 67108865 bytes; expected at most 64 MiB")) << command;
  }
}

TEST_F(Hostile, CalibrateOnARateThatIgnoresAMovingTruthWritesNoModel) {
  write(dir_ / "zero.csv", oven_rows(/*zero_rate=*/true, /*truth=*/true));
  const auto r = run_driftlab("calibrate --data " + p("zero.csv") + " --bin 10 --out " + p("m.json"));
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_THAT(r.err, HasSubstr(p("zero.csv") + ": scale_factor.polynomial_per_k_j: the calibration records give a "
                                               "model that is not physical: the scale factor is "));
  EXPECT_THAT(r.err, HasSubstr("expected 0.1 to 10 over the valid range"));  // it was 0 (2e-15)
  EXPECT_FALSE(fs::exists(p("m.json")));
  // The same record with a rate that follows the truth calibrates.
  write(dir_ / "moving.csv", oven_rows(false, true));
  const auto ok = run_driftlab("calibrate --data " + p("moving.csv") + " --bin 10 --out " + p("m.json"));
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
}

TEST_F(Hostile, AnUnphysicalModelIsRefusedByEveryReaderWithFileAndKey) {
  make_model();
  std::string text = read_text(p("model.json"));
  const auto at = text.find("\"reference_temp_c\": ");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, text.find(',', at) - at, "\"reference_temp_c\": 1e300");
  write(dir_ / "hot.json", text);
  const std::string expected = p("hot.json") + ": channels[0].model.reference_temp_c: expected a temperature within";
  for (const auto& command :
       {"compensate --data " + p("oven.csv") + " --model " + p("hot.json") + " --out " + p("c.csv"),
        "export --model " + p("hot.json") + " --format ardupilot --out " + p("x.parm")}) {
    const auto r = run_driftlab(command);
    EXPECT_EQ(r.exit_code, 2) << command << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr(expected)) << command;
    EXPECT_FALSE(fs::exists(p("c.csv")) || fs::exists(p("x.parm"))) << command;
  }
}

TEST_F(Hostile, FirmwareExportsWriteOnlyRealThirtyTwoValues) {
  make_model();
  // A finite bias of 1e300 rad/s (a valid model: finite everywhere) is no REAL32 parameter.
  const std::string text = std::regex_replace(
      read_text(p("model.json")), std::regex("(\"polynomial_rad_s_per_k_i\": \\[\\s*)[^,\\]\\s]+"), "$011e300");
  ASSERT_NE(text.find("1e300"), std::string::npos);
  write(dir_ / "big.json", text);
  for (const auto& format : {"px4", "ardupilot"}) {
    const std::string command = "export --model " + p("big.json") + " --format " + format + " --out " + p("x.params");
    const auto r = run_driftlab(command);
    EXPECT_EQ(r.exit_code, 2) << command << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr("is not a finite REAL32 number")) << command;
    EXPECT_THAT(r.err, HasSubstr(p("big.json") + ": ")) << "the model's file named: " << command;
    EXPECT_FALSE(fs::exists(p("x.params"))) << command;
  }
}

TEST_F(Hostile, AChamberTemperatureOutsideThePhysicalRangeIsRefused) {
  write(dir_ / "hot.yaml", "format: driftlab-profile/1\nchamber: {start_c: 1e6}\n");
  const auto r =
      run_driftlab("simulate --device fmvmg --profile " + p("hot.yaml") + " --duration 10 --out " + p("s.csv"),
                   "DRIFTLAB_DEVICES_DIR=" + std::string(DRIFTLAB_SOURCE_DIR) + "/devices");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr(p("hot.yaml") + ":2: chamber.start_c: must be in [-273.15, 1000], got '1e6'"));
  EXPECT_FALSE(fs::exists(p("s.csv")));
}

// A record with a 1e9-s pause between two 300-sample runs at 1 Hz: the model's sample rate is the
// rate while it samples (1 Hz), not the mean over the pause (6e-7 Hz), which would scale N, K, the
// Kalman variances and Kalibr's update_rate wrongly.
TEST_F(Hostile, AHugeGapDoesNotLowerTheModelsSampleRate) {
  std::string text = oven_rows();
  std::string shifted;
  std::size_t line_start = text.find('\n') + 1, row = 0;
  shifted = text.substr(0, line_start);
  while (line_start < text.size()) {
    const std::size_t end = text.find('\n', line_start);
    std::string line = text.substr(line_start, end - line_start + 1);
    if (row++ >= 300) {
      const std::size_t comma = line.find(',');
      line = std::to_string(std::stol(line.substr(0, comma)) + 1000000000L) + line.substr(comma);
    }
    shifted += line;
    line_start = end + 1;
  }
  write(dir_ / "gap.csv", shifted);
  const auto r = run_driftlab("calibrate --data " + p("gap.csv") + " --max-gap 0 --bin 10 --out " + p("m.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string model = read_text(p("m.json"));
  const std::smatch m = [&] {
    std::smatch found;
    std::regex_search(model, found, std::regex("\"sample_rate_hz\": ([^,\\s}]+)"));
    return found;
  }();
  ASSERT_FALSE(m.empty()) << model;
  EXPECT_DOUBLE_EQ(std::stod(m[1].str()), 1.0) << model;
}

TEST_F(Hostile, TheCalibrationRecordIsNotScoredAsHeldOut) {
  write(dir_ / "copy.csv", oven_rows());
  fs::create_symlink(p("oven.csv"), p("link.csv"));
  for (const std::string held : {"oven.csv", "link.csv"}) {
    const auto r = run_driftlab("calibrate --data " + p("oven.csv") + " --evaluate " + p(held) + " --bin 10 --out " +
                                p("m.json") + " --report " + p("report"));
    EXPECT_EQ(r.exit_code, 2) << held << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr(p(held) + ": --evaluate: is also a --data record")) << held;
    EXPECT_THAT(r.err, HasSubstr("would not be held out")) << held;
    EXPECT_FALSE(fs::exists(p("m.json")) || fs::exists(p("report"))) << held;
  }
  // Another file (here a copy of the same rows, which the command cannot tell apart) is scored.
  const auto ok = run_driftlab("calibrate --data " + p("oven.csv") + " --evaluate " + p("copy.csv") +
                               " --bin 10 --out " + p("m.json"));
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
}

TEST_F(Hostile, KalmanOptionsWithoutKalmanAreAnError) {
  make_model();
  for (const std::string option : {"--kalman-r 0", "--kalman-r 1e-6", "--kalman-q 0", "--kalman-fs 100"}) {
    const auto r = run_driftlab("compensate --data " + p("oven.csv") + " --model " + p("model.json") + " --out " +
                                p("c.csv") + " " + option);
    EXPECT_EQ(r.exit_code, 2) << option << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr(option.substr(0, option.find(' ')) + ": " + option.substr(0, option.find(' ')) +
                                 " needs --kalman"))
        << option;
    EXPECT_FALSE(fs::exists(p("c.csv"))) << option;
  }
}

// "-" is standard input, explicitly (framework/regular_file.hpp): the same result as the file, one
// input per command, bounded like a file.
TEST_F(Hostile, ADashReadsStandardInputOnceAndBounded) {
  make_model();
  const auto file =
      run_driftlab("compensate --data " + p("oven.csv") + " --model " + p("model.json") + " --out " + p("f.csv"));
  ASSERT_EQ(file.exit_code, 0) << file.err;
  const auto data =
      run_driftlab("compensate --data - --model " + p("model.json") + " --out " + p("d.csv"), "", p("oven.csv"));
  EXPECT_EQ(data.exit_code, 0) << data.err;
  EXPECT_EQ(read_text(p("d.csv")), read_text(p("f.csv")));
  const auto model =
      run_driftlab("compensate --data " + p("oven.csv") + " --model - --out " + p("m.csv"), "", p("model.json"));
  EXPECT_EQ(model.exit_code, 0) << model.err;
  EXPECT_EQ(read_text(p("m.csv")), read_text(p("f.csv")));
  // A bad row on standard input is named as <stdin> with its line.
  write(dir_ / "bad.csv", "t_s,rate_dps,temp_c\n0,0.1,20\n1,x,20\n");
  const auto bad =
      run_driftlab("compensate --data - --model " + p("model.json") + " --out " + p("b.csv"), "", p("bad.csv"));
  EXPECT_EQ(bad.exit_code, 3) << bad.err;
  EXPECT_THAT(bad.err, HasSubstr("<stdin>:3: rate_dps:"));
  // The model is read first, the data would be read from what is left: refused.
  const std::vector<std::pair<std::string, std::string>> refused{
      {"compensate --data - --model - --out " + p("x.csv"),
       "<stdin>: standard input is already read as the calibration model file; only one input can be -, not the data "
       "too"},
      {"compensate --stream --model -", "--stream reads the rows from standard input; the model cannot be - too"},
  };
  for (const auto& [command, message] : refused) {
    const auto r = run_driftlab(command, "", p("model.json"));
    EXPECT_EQ(r.exit_code, 2) << command << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr(message)) << command;
  }
  std::ofstream(p("huge.json")) << "{";
  fs::resize_file(p("huge.json"), (std::uintmax_t{64} << 20) + 1);  // sparse
  const auto huge =
      run_driftlab("compensate --data " + p("oven.csv") + " --model - --out " + p("h.csv"), "", p("huge.json"));
  EXPECT_EQ(huge.exit_code, 2) << huge.err;
  EXPECT_THAT(huge.err,
              HasSubstr("<stdin>: the calibration model file on standard input has more than 67108864 bytes"));
  EXPECT_FALSE(fs::exists(p("x.csv")) || fs::exists(p("h.csv")) || fs::exists(p("b.csv")));
}

// --stream holds at most one line of --max-line-bytes (1 MiB by default): a 3-MB line (no newline
// in it) is refused with exit 3 naming its line once it passes the cap, and the rows before it were
// written.
TEST_F(Hostile, StreamRefusesALineLongerThanItsCap) {
  make_model();
  std::string text = "t_s,rate_dps,temp_c\n0,0.1,20\n1,0.1,20\n";
  text += "2,0.1," + std::string(3 << 20, '7') + "\n3,0.1,20\n";
  write(dir_ / "long.csv", text);
  const auto r = run_driftlab("compensate --stream --model " + p("model.json"), "", p("long.csv"));
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_THAT(r.err, HasSubstr("<stdin>:4: the line is longer than 1048576 bytes (--max-line-bytes)"));
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 3) << "the header and the two rows before it";
  // The cap is an option: a lower one refuses a shorter line, the same record passes under a higher one.
  const auto low =
      run_driftlab("compensate --stream --max-line-bytes 16 --model " + p("model.json"), "", p("oven.csv"));
  EXPECT_EQ(low.exit_code, 3) << low.err;
  EXPECT_THAT(low.err, HasSubstr("<stdin>:1: the line is longer than 16 bytes")) << "the header has 19";
  // 20 degC written with 2 MiB of leading zeros: a valid row, read whole under a 4-MiB cap.
  write(dir_ / "rows.csv", "t_s,rate_dps,temp_c\n0,0.1,20\n1,0.1," + std::string(2 << 20, '0') + "20\n");
  const auto high =
      run_driftlab("compensate --stream --max-line-bytes 4194304 --model " + p("model.json"), "", p("rows.csv"));
  EXPECT_EQ(high.exit_code, 0) << high.err;
  EXPECT_EQ(std::count(high.out.begin(), high.out.end(), '\n'), 3);
}

// Cost is estimated from the parameters before any work (framework/resources.hpp): absurd ones are
// refused at once with the estimate and the option named; no wall clock is measured here.
TEST_F(Hostile, AbsurdParametersAreRefusedOnTheirCostEstimate) {
  const std::string devices = "DRIFTLAB_DEVICES_DIR=" + std::string(DRIFTLAB_SOURCE_DIR) + "/devices";
  const std::string simulate = "simulate --device fmvmg --fs 1000 --duration 1e7 --out " + p("s.csv");
  // 1e10 samples: the memory first, then (with a memory limit far above it) the time budget.
  const auto memory = run_driftlab(simulate, devices);
  EXPECT_EQ(memory.exit_code, 2) << memory.err;
  EXPECT_THAT(memory.err, HasSubstr("--fs, --duration: 1e+10 samples (--fs x --duration) at 250 bytes each: about"));
  const auto time = run_driftlab(simulate, devices + " DRIFTLAB_MEMORY_LIMIT_MB=1e12");
  EXPECT_EQ(time.exit_code, 2) << time.err;
  EXPECT_THAT(time.err,
              HasSubstr("--fs, --duration: 1e+10 samples (--fs x --duration) at 4e-06 s each: about 4e+04 s (11.1 h)"));
  EXPECT_THAT(time.err, HasSubstr("above the budget of 4 h (the default; DRIFTLAB_TIME_LIMIT_S raises it)"));
  // The budget is an environment variable; a malformed one is a usage error naming it.
  const auto lowered = run_driftlab("simulate --device fmvmg --fs 100 --duration 100 --out " + p("s.csv"),
                                    devices + " DRIFTLAB_TIME_LIMIT_S=0.01");
  EXPECT_EQ(lowered.exit_code, 2) << lowered.err;
  EXPECT_THAT(lowered.err, HasSubstr("above the budget of 2.78e-06 h (DRIFTLAB_TIME_LIMIT_S)"));
  for (const std::string env :
       {"DRIFTLAB_MEMORY_LIMIT_MB=abc", "DRIFTLAB_TIME_LIMIT_S=-1", "DRIFTLAB_TIME_LIMIT_S=inf"}) {
    const auto r =
        run_driftlab("simulate --device fmvmg --fs 100 --duration 10 --out " + p("s.csv"), devices + " " + env);
    EXPECT_EQ(r.exit_code, 2) << env << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr(env.substr(0, env.find('=')) + ": expected a finite number > 0, got '" +
                                 env.substr(env.find('=') + 1) + "'"));
  }
  EXPECT_FALSE(fs::exists(p("s.csv")));
  // The GA of calibrate --model rbf: 1000 x 1001 evaluations over the bins of a 10-h record.
  std::string rows = "t_s,rate_dps,temp_c\n";
  for (int i = 0; i <= 36000; i += 2) rows += std::to_string(i) + ",0.01," + std::to_string(20.0 + i / 1200.0) + "\n";
  write(dir_ / "long.csv", rows);
  const auto ga = run_driftlab("calibrate --data " + p("long.csv") +
                               " --model rbf --bin 1 --ga-population 1000 "
                               "--ga-generations 1000 --out " +
                               p("m.json"));
  EXPECT_EQ(ga.exit_code, 2) << ga.err;
  EXPECT_THAT(ga.err,
              HasSubstr("--ga-population, --ga-generations: 1e+06 GA evaluations per channel over 1.8e+04 bins"));
  EXPECT_FALSE(fs::exists(p("m.json")));
  // A GA inside a pipeline (a tuned RBF step): 1e6 x (1e9 + 1) evaluations over the tuning rows,
  // refused before the first fit with the step's plugin and the estimate named; 2 x 3 runs.
  const auto ga_pipeline = [&](const std::string& name, const std::string& population, const std::string& generations) {
    write(dir_ / name,
          "format: driftlab-pipeline/1\ninputs: {rate: rate, temperature: temperature}\nsteps:\n"
          "  - name: s\n    plugin: regressor/rbf\n    inputs: {target: rate, features: temperature}\n"
          "    params: {tune: true, optimizer: {plugin: optimizer/ga, params: {population: " +
              population + ", generations: " + generations + ", elites: 1}}}\noutputs: {o: s.fitted}\n");
    return run_driftlab("run --pipeline " + p(name) + " --data " + p("oven.csv") + " --out " + p("run"));
  };
  const auto absurd = ga_pipeline("absurd_ga.yaml", "1000000", "1000000000");
  EXPECT_EQ(absurd.exit_code, 2) << absurd.err;
  EXPECT_THAT(absurd.err, HasSubstr("optimizer: regressor/rbf: 1e+15 objective evaluations x 600 rows at 1e-07 s per "
                                    "row and evaluation: about 6e+10 s"));
  EXPECT_THAT(absurd.err, HasSubstr("above the budget of 4 h"));
  // `run` records a failed step in its report (docs/reliability.md: the one documented exception).
  EXPECT_THAT(read_text(p("run") + "/report.json"), HasSubstr("\"status\": \"failed\""));
  const auto small = ga_pipeline("small_ga.yaml", "2", "2");
  EXPECT_EQ(small.exit_code, 0) << small.err;
  // An ensemble decomposition: 1e5 members over 1e5 samples, refused before the first member.
  std::string signal = "t_s,rate_dps\n";
  for (int i = 0; i < 100000; ++i) signal += std::to_string(i) + "," + std::to_string(std::sin(0.01 * i)) + "\n";
  write(dir_ / "signal.csv", signal);
  for (const std::string plugin : {"eemd", "ceemdan"}) {
    const auto r = run_driftlab("decompose --data " + p("signal.csv") + " --plugin decomposition/" + plugin +
                                " --set ensemble_size=100000 --out " + p("imfs.csv"));
    EXPECT_EQ(r.exit_code, 2) << plugin << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr("ensemble_size: 100000 members x 100000 samples at 2e-06 s per sample and member: "
                                 "about 2e+04 s (5.56 h) of computing, above the budget of 4 h"))
        << plugin;
    EXPECT_FALSE(fs::exists(p("imfs.csv"))) << plugin;
  }
}

// Messages name what was given, in a readable form: the unknown plugin's own name beside the known
// ones, a 309-digit number as a number.
TEST_F(Hostile, MessagesNameTheGivenPluginAndWriteHugeNumbersShort) {
  write(dir_ / "unknown.yaml",
        "format: driftlab-pipeline/1\ninputs: {rate: rate}\nsteps:\n  - name: d\n"
        "    plugin: decomposition/does_not_exist\n    inputs: {signal: rate}\noutputs: {o: d.signal}\n");
  const auto unknown =
      run_driftlab("run --pipeline " + p("unknown.yaml") + " --data " + p("oven.csv") + " --out " + p("run"));
  EXPECT_EQ(unknown.exit_code, 2) << unknown.err;
  EXPECT_THAT(unknown.err,
              HasSubstr(p("unknown.yaml") + ":5: d.plugin: unknown plugin 'decomposition/does_not_exist' (known: "));
  const auto huge =
      run_driftlab("simulate --device fmvmg --duration 1 --out " + p("s.csv") + " --fs 1" + std::string(308, '0'),
                   "DRIFTLAB_DEVICES_DIR=" + std::string(DRIFTLAB_SOURCE_DIR) + "/devices");
  EXPECT_EQ(huge.exit_code, 2) << huge.err;
  EXPECT_THAT(huge.err, HasSubstr("--fs: value 1e+308 is not in (0, 1e+09]"));
  EXPECT_FALSE(fs::exists(p("run")) || fs::exists(p("s.csv")));
}

// Stream and batch read CSV by one rule (CsvLineCursor, plan_columns, the cell messages): the same
// hostile inputs give the same exit code and the same message (the file named <stdin> in the
// stream), and, when accepted, the same bytes.
TEST_F(Hostile, StreamAndBatchAgreeOnHostileCsv) {
  make_model();
  const std::string rows = "0,0.1,20\n1,0.1,20.5\n2,0.1,21\n";
  const std::vector<std::tuple<std::string, std::string, std::string, int>> cases{
      {"bom", "\xEF\xBB\xBFt_s,rate_dps,temp_c\n" + rows, "", 0},
      {"cr_only", "t_s,rate_dps,temp_c\r0,0.1,20\r1,0.1,20.5\r\r# note\r2,0.1,21\r", "", 0},
      {"crlf", "t_s,rate_dps,temp_c\r\n0,0.1,20\r\n1,0.1,20.5\r\n", "", 0},
      {"plus", "t_s,rate_dps,temp_c\n0,+0.1,+20\n1,+0.1,20.5\n", "", 0},
      {"header_only", "t_s,rate_dps,temp_c\n", "", 3},
      {"empty", "\n# nothing\n", "", 3},
      {"numbers_only", "0,0.1,20\n1,0.1,20\n", "", 3},
      {"lone_time_column", "t_s,rate_dps,temp_c\n" + rows, "--column time=t_s:s", 2},
      {"duplicate_columns", "t_s,rate_dps,rate_dps,temp_c\n0,0.1,0.2,20\n1,0.1,0.2,20\n", "", 3},
      {"fs_with_time", "t_s,rate_dps,temp_c\n" + rows, "--fs 10", 2},
      {"minus_inf", "t_s,rate_dps,temp_c\n0,0.1,20\n1,-inf,20\n", "", 3},
      {"empty_cell", "t_s,rate_dps,temp_c\n0,0.1,20\n1,,20\n", "", 3},
      {"text_cell", "t_s,rate_dps,temp_c\n0,0.1,20\n1,0x1,20\n", "", 3},
      {"short_row", "t_s,rate_dps,temp_c\n0,0.1,20\n1,0.1\n", "", 3},
  };
  for (const auto& [name, text, options, code] : cases) {
    write(dir_ / (name + ".csv"), text);
    const std::string file = p(name + ".csv");
    const auto batch = run_driftlab("compensate --data " + file + " --model " + p("model.json") + " --out " +
                                    p(name + ".out") + " " + options);
    const auto stream = run_driftlab("compensate --stream --model " + p("model.json") + " " + options, "", file);
    EXPECT_EQ(batch.exit_code, code) << name << "\n" << batch.err;
    EXPECT_EQ(stream.exit_code, code) << name << "\n" << stream.err;
    if (code == 0) {
      EXPECT_EQ(stream.out, read_text(p(name + ".out"))) << name;
      EXPECT_EQ(std::count(stream.out.begin(), stream.out.end(), '\n'),
                1 + std::count(rows.begin(), rows.end(), '\n') - (name == "crlf" || name == "plus" ? 1 : 0))
          << name;
    } else {
      std::string expected = batch.err;
      for (std::size_t at; (at = expected.find(file)) != std::string::npos;)
        expected.replace(at, file.size(), "<stdin>");
      EXPECT_EQ(stream.err, expected) << name;
    }
  }
}

// SIGKILL at any point of a long write (compensate of 300 000 rows, about 20 MB out) leaves no
// visible temporary file and no partial output under the final name: either nothing, a hidden
// .c.csv.tmp-XXXXXX, or the whole output. The kill points are spread over the run; the property is
// checked whichever point each lands on.
TEST_F(Hostile, SigkillLeavesNoVisibleTemporaryAndNoPartialOutput) {
  make_model();
  std::string rows = "t_s,rate_dps,temp_c\n";
  char line[96];
  for (int i = 0; i < 300000; ++i) {
    std::snprintf(line, sizeof line, "%.2f,%.9f,%.6f\n", 0.01 * i, 0.01 + 1e-4 * std::sin(0.37 * i),
                  20.0 + 30.0 * i / 300000.0);
    rows += line;
  }
  write(dir_ / "big.csv", rows);
  const auto full =
      run_driftlab("compensate --data " + p("big.csv") + " --model " + p("model.json") + " --out " + p("ref.csv"));
  ASSERT_EQ(full.exit_code, 0) << full.err;
  const std::string reference = read_text(p("ref.csv"));
  fs::remove(p("ref.csv"));
  const auto before = entries();
  int killed = 0;
  for (const int delay_us : {0, 2000, 10000, 30000, 60000, 100000, 150000, 250000, 400000, 700000}) {
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      const std::string data = p("big.csv"), model = p("model.json"), out = p("c.csv");
      ::execl(DRIFTLAB_EXE, DRIFTLAB_EXE, "compensate", "--data", data.c_str(), "--model", model.c_str(), "--out",
              out.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    ::usleep(delay_us);
    ::kill(pid, SIGKILL);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    killed += WIFSIGNALED(status) ? 1 : 0;
    for (const auto& e : fs::directory_iterator(dir_)) {
      const std::string name = e.path().filename().string();
      if (name == "c.csv") {
        EXPECT_EQ(read_text(e.path()), reference)
            << "a partial output under the final name, kill after " << delay_us << " us";
        continue;
      }
      if (name.rfind(".c.csv.tmp-", 0) == 0) continue;  // the documented hidden temporary
      EXPECT_NE(std::find(before.begin(), before.end(), e.path().string()), before.end())
          << name << " left visible, kill after " << delay_us << " us";
    }
    for (const auto& e : fs::directory_iterator(dir_))
      if (e.path().filename().string().rfind(".c.csv.tmp-", 0) == 0 || e.path().filename() == "c.csv")
        fs::remove(e.path());
  }
  EXPECT_GT(killed, 0) << "no kill landed while the command ran";
}

}  // namespace
}  // namespace driftlab
