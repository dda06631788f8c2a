// The bad-input matrix (issue 17): every class of bad input, tried on every command that can meet
// it, must end with the documented exit code (2 usage/configuration, 3 bad data), a message that
// names the file, line and key or column, and no output file (nor a temporary one) left behind.
// Fixtures are written by the tests into a scratch directory, one per class.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;
using namespace testing_cli;

void write(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// 512 samples at 10 Hz: rate (deg/s) with a slow wave and deterministic jitter, temperature.
std::string good_rows(const std::string& eol = "\n", int rows = 512) {
  std::string text;
  char line[160];
  for (int i = 0; i < rows; ++i) {
    const double t = i * 0.1;
    std::snprintf(line, sizeof line, "%.1f,%.9f,%.6f", t, 0.01 * std::sin(0.05 * t) + 1e-3 * std::sin(7.3 * i * i),
                  20.0 + 0.01 * t);
    text += line + eol;
  }
  return text;
}

// Files left in `dir` that a command may have written (everything but the inputs we put there).
std::vector<std::string> stray_files(const fs::path& dir, const std::vector<std::string>& inputs) {
  std::vector<std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    const auto name = e.path().filename().string();
    if (std::find(inputs.begin(), inputs.end(), name) == inputs.end()) out.push_back(e.path().string());
  }
  return out;
}

class BadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = scratch_dir(::testing::UnitTest::GetInstance()->current_test_info()->name());
    write(dir_ / "good.csv", "t_s,rate_dps,temp_c\n" + good_rows());
    write(dir_ / "smooth.yaml", R"(format: driftlab-pipeline/1
inputs: {rate: rate}
steps:
  - name: smooth
    plugin: filter/kalman
    inputs: {signal: rate}
outputs: {smoothed: smooth.signal}
)");
    inputs_ = {"good.csv", "smooth.yaml"};
  }
  std::string p(const std::string& name) const { return (dir_ / name).string(); }
  // Every command that reads a record, with all its outputs in the scratch directory.
  std::vector<std::string> data_commands(const std::string& csv) const {
    return {"allan --data " + csv + " --out " + p("a.csv") + " --json " + p("a.json") + " --plot " + p("a.svg"),
            "entropy --data " + csv,
            "decompose --data " + csv + " --out " + p("d.csv") + " --json " + p("d.json"),
            "discrepancy --data " + csv + " --report " + p("r.json") + " --series " + p("s.csv"),
            "run --pipeline " + p("smooth.yaml") + " --data " + csv + " --out " + p("run"),
            "calibrate --data " + csv + " --bin 1 --out " + p("m.json") + " --report " + p("report"),
            "compensate --data " + csv + " --model " + p("model.json") + " --out " + p("c.csv")};
  }
  // A calibration model of good.csv, for compensate.
  void make_model() {
    const auto r = run_driftlab("calibrate --data " + p("good.csv") + " --bin 1 --out " + p("model.json"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    inputs_.push_back("model.json");
  }
  void expect_clean(const std::string& what) { EXPECT_THAT(stray_files(dir_, inputs_), ::testing::IsEmpty()) << what; }
  fs::path dir_;
  std::vector<std::string> inputs_;
};

struct CsvClass {
  std::string name;
  std::string text;
  std::string location;  // "file.csv:LINE: column"
  std::string message;
};

TEST_F(BadInput, EveryDataCommandRefusesEveryBadCsvClassWithFileLineColumnAndNoOutput) {
  const std::string header = "t_s,rate_dps,temp_c\n";
  std::string rows = good_rows();
  const auto replace_line = [&](int line, const std::string& text) {  // line 1 is the header
    std::istringstream in(rows);
    std::string out, l;
    for (int i = 2; std::getline(in, l); ++i) out += (i == line ? text : l) + "\n";
    return header + out;
  };
  make_model();
  const std::string huge(2 << 20, 'x');
  const std::vector<CsvClass> classes{
      {"non_numeric.csv", replace_line(7, "0.5,abc,20"), "non_numeric.csv:7: rate_dps", "expected a number"},
      {"nan.csv", replace_line(9, "0.7,nan,20"), "nan.csv:9: rate_dps", "NaN/Inf"},
      {"huge_cell.csv", replace_line(5, "0.3," + huge + "\x01\x02,20"), "huge_cell.csv:5: rate_dps", "bytes in all"},
      {"binary_cell.csv", replace_line(6, std::string("0.4,\x1b[31m\x7f\x80,20")), "binary_cell.csv:6: rate_dps",
       "\\x1b[31m\\x7f\\x80"},
      {"overflow.csv", replace_line(11, "0.9,1e308,20"), "overflow.csv:11: rate_dps", "too large to compute with"},
      {"tiny_step.csv", header + "0,1,20\n1e-300,1,20\n2e-300,1,20\n", "tiny_step.csv:3: t_s", "below 1 ns"},
      {"ragged.csv", replace_line(4, "0.2,1"), "ragged.csv:4:", "row has 2 cells"},
  };
  for (const auto& c : classes) {
    write(dir_ / c.name, c.text);
    inputs_.push_back(c.name);
    for (const auto& command : data_commands(p(c.name))) {
      const auto r = run_driftlab(command);
      EXPECT_EQ(r.exit_code, 3) << command << "\n" << r.err;
      EXPECT_THAT(r.err, HasSubstr(c.location)) << command;
      EXPECT_THAT(r.err, HasSubstr(c.message)) << command;
      EXPECT_LT(r.err.size(), 2000u) << "a bad cell is quoted whole: " << command;
      expect_clean(command);
      fs::remove_all(dir_ / "run");
      fs::remove_all(dir_ / "report");
    }
  }
}

TEST_F(BadInput, ByteOrderMarkAndEveryLineEndingAreAccepted) {
  const std::vector<std::pair<std::string, std::string>> files{
      {"bom.csv", "\xEF\xBB\xBFt_s,rate_dps,temp_c\n" + good_rows()},
      {"crlf.csv", "t_s,rate_dps,temp_c\r\n" + good_rows("\r\n")},
      {"cr.csv", "t_s,rate_dps,temp_c\r" + good_rows("\r")}};
  for (const auto& [name, text] : files) {
    write(dir_ / name, text);
    const auto r = run_driftlab("entropy --data " + p(name));
    EXPECT_EQ(r.exit_code, 0) << name << ": " << r.err;
    EXPECT_THAT(r.out, HasSubstr("N = 512 samples")) << name;
  }
}

TEST_F(BadInput, AnOffsetUnitConvertsOnlyAbsoluteValues) {
  // A temperature record in kelvin: deviations and IMFs are differences, the residue is absolute.
  std::string text = "t_s,temp_k\n";
  char line[96];
  for (int i = 0; i < 512; ++i) {
    std::snprintf(line, sizeof line, "%.1f,%.9f\n", i * 0.1,
                  300.0 + 0.5 * std::sin(0.37 * i) + 1e-3 * std::sin(7.3 * i * i));
    text += line;
  }
  write(dir_ / "kelvin.csv", text);
  auto r = run_driftlab("allan --data " + p("kelvin.csv") + " --column temperature=temp_k:K --out " + p("a.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream allan(dir_ / "a.csv");
  std::string header, first;
  std::getline(allan, header);
  std::getline(allan, first);
  const double dev = std::stod(first.substr(first.find(',') + 1));
  EXPECT_LT(dev, 2.0) << "the 273.15 K offset was applied to a deviation: " << first;

  // The IMFs and the residue add up to the input: to the rounding of the written digits (~1e-13 at
  // 300 K); an offset applied to a difference would be 273.15 K off.
  constexpr double kSumTolerance = 1e-6;
  r = run_driftlab("decompose --data " + p("kelvin.csv") + " --column temperature=temp_k:K --out " + p("d.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream imfs(dir_ / "d.csv");
  std::getline(imfs, header);
  std::istringstream in(text);
  std::string row, input;
  std::getline(in, input);  // the input's header
  int checked = 0;
  while (std::getline(imfs, row) && std::getline(in, input)) {
    std::istringstream cells(row);
    std::string cell;
    std::getline(cells, cell, ',');
    double sum = 0.0;
    while (std::getline(cells, cell, ',')) sum += std::stod(cell);
    EXPECT_NEAR(sum, std::stod(input.substr(input.find(',') + 1)), kSumTolerance) << row;
    ++checked;
  }
  EXPECT_EQ(checked, 512);
}

TEST_F(BadInput, ARoleAcceptsOnlyUnitsOfItsDimension) {
  const auto r = run_driftlab("allan --data " + p("good.csv") + " --column rate=rate_dps:K --out " + p("a.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("unit 'K' does not fit the role 'rate'"));
  expect_clean("role/unit");
}

TEST_F(BadInput, TheColumnOrderOfTheReadmeWorksForEverySingleChannelCommand) {
  const std::string columns = " --column time=t_s:s --column rate=rate_dps:deg/s";
  for (const auto& command :
       {"allan --data " + p("good.csv") + columns + " --out " + p("a.csv"), "entropy --data " + p("good.csv") + columns,
        "decompose --data " + p("good.csv") + columns + " --out " + p("d.csv")}) {
    const auto r = run_driftlab(command);
    EXPECT_EQ(r.exit_code, 0) << command << "\n" << r.err;
  }
}

TEST_F(BadInput, PipelineDuplicateKeysAndWrongTypesAreConfigErrorsWithFileLineKey) {
  const std::vector<std::tuple<std::string, std::string, std::string>> cases{
      {"duplicate.yaml",
       "format: driftlab-pipeline/1\nsteps:\n  - name: s\n    plugin: filter/kalman\n    inputs: {signal: rate}\n"
       "    params: {q: 1e-9, q: 1e-3}\noutputs: {o: s.signal}\n",
       "duplicate.yaml:6: steps[0].params.q: duplicate key"},
      {"list_for_text.yaml",
       "format: driftlab-pipeline/1\nsteps:\n  - name: s\n    plugin: filter/kalman\n    inputs: {signal: rate}\n"
       "outputs: {o: [s.signal, x]}\n",
       "list_for_text.yaml:6: outputs.o: expected a step.output reference, got a list"},
      {"map_for_reference.yaml",
       "format: driftlab-pipeline/1\nsteps:\n  - name: s\n    plugin: filter/kalman\n    inputs: {signal: {a: 1}}\n"
       "outputs: {o: s.signal}\n",
       "map_for_reference.yaml:5: s.inputs.signal: expected a reference"},
      {"map_key.yaml",
       "format: driftlab-pipeline/1\nsteps:\n  - name: s\n    plugin: filter/kalman\n    inputs: {signal: rate}\n"
       "    params: {[a]: 1}\noutputs: {o: s.signal}\n",
       "map_key.yaml:6: s.params.a"},
      {"nested_plugin_list.yaml",
       "format: driftlab-pipeline/1\ninputs: {rate: rate, temperature: temperature}\nsteps:\n  - name: s\n"
       "    plugin: regressor/rbf\n    inputs: {target: rate, features: temperature}\n"
       "    params: {optimizer: {plugin: [optimizer/ga]}}\noutputs: {o: s.fitted}\n",
       "nested_plugin_list.yaml:7: s.params.optimizer.plugin: expected a plugin name"},
      {"comma_output.yaml",
       "format: driftlab-pipeline/1\nsteps:\n  - name: s\n    plugin: filter/kalman\n    inputs: {signal: rate}\n"
       "outputs: {'a,b': s.signal}\n",
       "comma_output.yaml:6: outputs: output name 'a,b' must be an identifier"},
      {"time_output.yaml",
       "format: driftlab-pipeline/1\nsteps:\n  - name: s\n    plugin: filter/kalman\n    inputs: {signal: rate}\n"
       "outputs: {t: s.signal}\n",
       "time_output.yaml:6: outputs.t: output name is reserved"},
      {"absurd_population.yaml",
       "format: driftlab-pipeline/1\ninputs: {rate: rate, temperature: temperature}\nsteps:\n  - name: s\n"
       "    plugin: regressor/rbf\n    inputs: {target: rate, features: temperature}\n"
       "    params: {tune: true, optimizer: {plugin: optimizer/ga, params: {population: 100000000}}}\n"
       "outputs: {o: s.fitted}\n",
       "absurd_population.yaml:7: s.params.optimizer.params.population"},
  };
  for (const auto& [name, text, expected] : cases) {
    write(dir_ / name, text);
    inputs_.push_back(name);
    for (const std::string& extra :
         {std::string(" --validate-only"), " --data " + p("good.csv") + " --out " + p("run")}) {
      const auto r = run_driftlab("run --pipeline " + p(name) + extra);
      EXPECT_EQ(r.exit_code, 2) << name << ": " << r.err;
      EXPECT_THAT(r.err, HasSubstr(expected)) << name;
      EXPECT_FALSE(fs::exists(dir_ / "run" / "outputs.csv")) << name;
    }
  }
  expect_clean("pipelines");
}

TEST_F(BadInput, DeviceFilesAreCheckedAgainstThePhysics) {
  std::ifstream in(std::string(DRIFTLAB_SOURCE_DIR) + "/devices/fmvmg.yaml");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string device = buffer.str();
  const auto variant = [&](const std::string& from, const std::string& to) {
    std::string s = device;
    const auto at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return s.replace(at, from.size(), to);
  };
  const auto line =
      std::to_string(std::count(device.begin(), device.begin() + device.find("reference_temp_c:"), '\n') + 1);
  const auto next_line = std::to_string(std::stoi(line) + 1);
  const std::vector<std::tuple<std::string, std::string, std::string>> cases{
      {"absolute_zero.yaml", variant("reference_temp_c: 25", "reference_temp_c: -273.15"),
       "absolute_zero.yaml:" + line + ": reference_temp_c: must be in (-273.15, 500]"},
      {"negative_frequency.yaml", variant("frequency_tc_ppm_per_k: -30.0", "frequency_tc_ppm_per_k: -1e6"),
       "modes.drive: at "},
      {"duplicate_key.yaml", variant("reference_temp_c: 25", "reference_temp_c: 25\nreference_temp_c: 30"),
       "duplicate_key.yaml:" + next_line + ": reference_temp_c: duplicate key"},
  };
  for (const auto& [name, text, expected] : cases) {
    write(dir_ / name, text);
    inputs_.push_back(name);
    for (const std::string& command :
         {"devices describe " + p(name), "simulate --device " + p(name) + " --duration 10 --out " + p("sim.csv"),
          "discrepancy --device " + p(name) + " --data " + p("good.csv") + " --report " + p("r.json")}) {
      const auto r = run_driftlab(command);
      EXPECT_EQ(r.exit_code, 2) << command << "\n" << r.err;
      EXPECT_THAT(r.err, HasSubstr(expected)) << command;
    }
  }
  expect_clean("devices");
}

TEST_F(BadInput, OutputsArePlannedUpFrontAndAppearTogetherOrNotAtAll) {
  const std::string missing = p("no-such-dir") + "/x";
  const std::vector<std::pair<std::string, std::string>> cases{
      {"allan --data " + p("good.csv") + " --out " + p("a.csv") + " --json " + missing + ".json", "--json"},
      {"allan --data " + p("good.csv") + " --out " + p("a.csv") + " --plot " + missing + ".svg", "--plot"},
      {"decompose --data " + p("good.csv") + " --out " + p("d.csv") + " --plot " + missing + ".svg", "--plot"},
      {"discrepancy --data " + p("good.csv") + " --report " + p("r.json") + " --html " + missing + ".html", "--html"},
      {"simulate --device fmvmg --duration 10 --out " + missing + ".csv", "--out"},
      {"allan --data " + p("good.csv") + " --out " + p("same.csv") + " --json " + p("same.csv"), "--json"},
      {"decompose --data " + p("good.csv") + " --out " + p("d.csv") + " --json " + p(".") + "/d.csv", "--json"},
      {"discrepancy --data " + p("good.csv") + " --report " + p("r.json") + " --series " + p("good.csv"), ""},
      {"allan --data " + p("good.csv") + " --out " + p("."), "--out"},
      {"calibrate --data " + p("good.csv") + " --bin 1 --out " + missing + ".json", "--out"},
      {"calibrate --data " + p("good.csv") + " --bin 1 --out " + p("m.json") + " --report " + p("good.csv"),
       "--report"},
      {"compensate --data " + p("good.csv") + " --model " + p("model.json") + " --out " + p("model.json"), "--out"},
      {"run --pipeline " + p("smooth.yaml") + " --data " + p("good.csv") + " --out " + p("good.csv"), "--out"},
      {"compare --data " + p("good.csv") + " --pipeline " + p("smooth.yaml") + " --out " + p("smooth.yaml"), "--out"},
  };
  make_model();
  for (const auto& [command, option] : cases) {
    const auto r = run_driftlab(command, "DRIFTLAB_DEVICES_DIR=" + std::string(DRIFTLAB_SOURCE_DIR) + "/devices");
    EXPECT_EQ(r.exit_code, 2) << command << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr(option)) << command;
    expect_clean(command);
  }
}

TEST_F(BadInput, CommandLineNumbersMustBeFiniteAndInRange) {
  for (const std::string& command :
       {"allan --data " + p("good.csv") + " --max-gap nan --out " + p("a.csv"),
        "allan --data " + p("good.csv") + " --confidence nan --out " + p("a.csv"),
        "entropy --data " + p("good.csv") + " --fs nan", "entropy --data " + p("good.csv") + " --r inf",
        "simulate --device fmvmg --fs nan --out " + p("s.csv"), "simulate --device fmvmg --seed -1 --out " + p("s.csv"),
        "simulate --device fmvmg --duration -5 --out " + p("s.csv"),
        "discrepancy --data " + p("good.csv") + " --significance nan --report " + p("r.json"),
        "calibrate --data " + p("good.csv") + " --bin nan --out " + p("m.json"),
        "compensate --data " + p("good.csv") + " --model x.json --fs inf --out " + p("c.csv")}) {
    const auto r = run_driftlab(command, "DRIFTLAB_DEVICES_DIR=" + std::string(DRIFTLAB_SOURCE_DIR) + "/devices");
    EXPECT_EQ(r.exit_code, 2) << command << "\n" << r.err;
    expect_clean(command);
  }
}

TEST_F(BadInput, AbsurdResourceNeedsAreRefusedBeforeTheWork) {
  auto r = run_driftlab("simulate --device fmvmg --fs 1e7 --duration 1e6 --out " + p("s.csv"),
                        "DRIFTLAB_DEVICES_DIR=" + std::string(DRIFTLAB_SOURCE_DIR) + "/devices");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("above the limit of"));
  r = run_driftlab("decompose --data " + p("good.csv") +
                   " --plugin decomposition/ceemdan --set ensemble_size=10000000 --out " + p("d.csv"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("ensemble_size"));
  expect_clean("resources");
}

TEST_F(BadInput, AConstantRecordGetsAClearAnswer) {
  std::string text = "t_s,rate_dps\n";
  for (int i = 0; i < 512; ++i) text += std::to_string(i) + ",0.25\n";
  write(dir_ / "constant.csv", text);
  inputs_.push_back("constant.csv");
  auto r = run_driftlab("entropy --data " + p("constant.csv"));
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_THAT(r.err, HasSubstr("constant"));
  r = run_driftlab("allan --data " + p("constant.csv") + " --out " + p("a.csv") + " --json " + p("a.json"));
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_THAT(r.err, HasSubstr("the record is constant"));
  expect_clean("constant");
}

TEST_F(BadInput, HostilePluginLibrariesAreRefusedWithTheLibraryNamed) {
  const fs::path hostile = DRIFTLAB_TEST_HOSTILE_PLUGIN_DIR;
  const std::vector<std::tuple<std::string, std::string, std::string>> cases{
      {"truncated", "libdriftlab_test_truncated.so", "truncated"},
      {"data_symbol", "libdriftlab_test_data_symbol.so", "driftlab_register_plugins is not a function"},
      {"throwing", "libdriftlab_test_throwing.so", "the hostile fixture refuses to register"},
  };
  for (const auto& [dir, library, message] : cases) {
    for (const auto& how :
         {std::string("--plugin-path ") + (hostile / dir).string() + " plugins list", std::string("plugins list")}) {
      const auto env = how.starts_with("--") ? std::string() : "DRIFTLAB_PLUGIN_PATH=" + (hostile / dir).string();
      const auto r = run_driftlab(how, env);
      EXPECT_EQ(r.exit_code, 2) << dir << "\n" << r.err;
      EXPECT_THAT(r.err, HasSubstr(library)) << dir;
      EXPECT_THAT(r.err, HasSubstr(message)) << dir;
      EXPECT_THAT(r.err, Not(HasSubstr("driftlab: failed:"))) << dir;
    }
  }
}

}  // namespace
}  // namespace driftlab
