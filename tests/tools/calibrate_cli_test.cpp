// End to end: `driftlab calibrate` and `driftlab compensate` (batch and streaming).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>
#include <vector>

#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
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
  std::ofstream(dir_ + "/bad.json")
      << R"({"format": "driftlab-calibration/1", "kind": "poly", "reference_temp_c": 25})";
  const auto r =
      run_driftlab("compensate --model " + dir_ + "/bad.json --data " + dir_ + "/oven.csv --out " + dir_ + "/x.csv");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("valid_range_c"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/x.csv"));
}

TEST_F(CalibrateCli, AMissingTemperatureColumnIsADataError) {
  std::ofstream(dir_ + "/notemp.csv") << "t_s,rate_dps\n0,0.1\n1,0.2\n";
  const auto r =
      run_driftlab("compensate --model " + dir_ + "/poly.json --data " + dir_ + "/notemp.csv --out " + dir_ + "/y.csv");
  EXPECT_EQ(r.exit_code, 3) << r.err;
  const std::string command = std::string(DRIFTLAB_EXE) + " compensate --model " + dir_ + "/poly.json --stream < " +
                              dir_ + "/notemp.csv > /dev/null 2>" + dir_ + "/err.txt";
  EXPECT_EQ(WEXITSTATUS(std::system(command.c_str())), 3);
  EXPECT_NE(read_text(dir_ + "/err.txt").find("temp_c"), std::string::npos);
}

TEST_F(CalibrateCli, ABadStreamedRowStopsTheStreamWithItsLineNumber) {
  std::ofstream(dir_ + "/badrow.csv") << "t_s,rate_dps,temp_c\n0,0.1,20\n1,abc,20\n2,0.1,20\n";
  const std::string command = std::string(DRIFTLAB_EXE) + " compensate --model " + dir_ + "/poly.json --stream < " +
                              dir_ + "/badrow.csv > " + dir_ + "/badrow_out.csv 2>" + dir_ + "/badrow_err.txt";
  EXPECT_EQ(WEXITSTATUS(std::system(command.c_str())), 3);
  const std::string err = read_text(dir_ + "/badrow_err.txt");
  EXPECT_NE(err.find("<stdin>:3"), std::string::npos) << err;
  EXPECT_NE(err.find("abc"), std::string::npos) << err;
}

TEST_F(CalibrateCli, CalibrateRefusesToOverwriteItsInput) {
  const auto r = run_driftlab("calibrate --data " + dir_ + "/oven.csv --out " + dir_ + "/oven.csv");
  EXPECT_EQ(r.exit_code, 2);
}

// Peak resident memory (KiB) of one `compensate --stream` run over `rows` generated rows.
long stream_peak_kib(const std::string& dir, const std::string& model, int rows) {
  const std::string csv = dir + "/rows" + std::to_string(rows) + ".csv";
  {
    std::ofstream out(csv);
    out << "t_s,rate_dps,temp_c\n";
    for (int i = 0; i < rows; ++i) out << 0.01 * i << "," << 0.001 * (i % 7) << "," << 20.0 + 1e-4 * i << "\n";
  }
  const std::string command =
      "exec " + std::string(DRIFTLAB_EXE) + " compensate --model " + model + " --stream < " + csv + " > /dev/null";
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  int status = 0;
  struct rusage usage {};
  ::wait4(pid, &status, 0, &usage);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  return usage.ru_maxrss;
}

TEST_F(CalibrateCli, StreamingMemoryDoesNotGrowWithInputLength) {
  // 8x more rows: a batch run would hold ~16 MB more (time, rate, temperature and output text).
  constexpr long kSlackKib = 2048;  // allocator and page-cache noise
  const long small = stream_peak_kib(dir_, dir_ + "/poly.json", 50'000);
  const long large = stream_peak_kib(dir_, dir_ + "/poly.json", 400'000);
  EXPECT_LT(large - small, kSlackKib) << small << " KiB vs " << large << " KiB";
}

TEST_F(CalibrateCli, TheKalmanStageSmoothsAndStreamsLikeTheBatch) {
  const std::string k = " --kalman --kalman-q 1e-14 --kalman-r 1e-6";
  const auto b = run_driftlab("compensate --model " + dir_ + "/poly.json --data " + dir_ + "/oven.csv --out " + dir_ +
                              "/kf.csv" + k);
  ASSERT_EQ(b.exit_code, 0) << b.err;
  const std::string command = std::string(DRIFTLAB_EXE) + " compensate --model " + dir_ + "/poly.json --stream" + k +
                              " < " + dir_ + "/oven.csv > " + dir_ + "/kf_stream.csv";
  ASSERT_EQ(std::system(command.c_str()), 0);
  const std::string batch = read_text(dir_ + "/kf.csv");
  EXPECT_EQ(batch, read_text(dir_ + "/kf_stream.csv"));
  // Every input column stays; the rate column holds the filtered output, the appended columns the
  // correction and the compensated rate before the Kalman stage.
  EXPECT_EQ(batch.substr(0, batch.find('\n')),
            "t_s,rate_dps,temp_c,true_rate_dps,systematic_dps,die_temp_c,drive_freq_hz,bias_rate_dps,"
            "compensated_rate_dps,extrapolated");
  // The filtered column varies less than the compensated one.
  std::istringstream in(batch);
  std::string line;
  std::getline(in, line);
  double n = 0, s_out = 0, ss_out = 0, s_in = 0, ss_in = 0;
  while (std::getline(in, line)) {
    std::vector<double> v;
    std::istringstream f(line);
    std::string cell;
    while (std::getline(f, cell, ',')) v.push_back(std::stod(cell));
    ASSERT_EQ(v.size(), 10u) << line;
    n += 1;
    s_out += v[1];
    ss_out += v[1] * v[1];
    s_in += v[8];
    ss_in += v[8] * v[8];
  }
  EXPECT_LT(ss_out / n - (s_out / n) * (s_out / n), 0.1 * (ss_in / n - (s_in / n) * (s_in / n)));
  const auto missing = run_driftlab("compensate --model " + dir_ + "/poly.json --data " + dir_ + "/oven.csv --out " +
                                    dir_ + "/kf2.csv --kalman --kalman-r 1e-6");
  EXPECT_EQ(missing.exit_code, 2) << "no q and no rate-random-walk term in the model: refused";
}

// The Kalman stage models a static gyro: on a record that moves (a 50-deg/s rate-table step) it would
// read 0.05 deg/s at the step, so it refuses, naming the line and column; without --kalman the same
// record compensates.
TEST_F(CalibrateCli, TheKalmanStageRefusesARecordThatMoves) {
  {
    std::ofstream out(dir_ + "/step.csv");
    out << "t_s,rate_dps,temp_c\n";
    for (int i = 0; i < 600; ++i) out << 0.1 * i << "," << (i < 300 ? 0.0 : 50.0) + 0.01 * (i % 3) << ",25\n";
  }
  const std::string k = " --kalman --kalman-q 1e-14 --kalman-r 1e-6";
  const auto moving = run_driftlab("compensate --model " + dir_ + "/poly.json --data " + dir_ + "/step.csv --out " +
                                   dir_ + "/m.csv" + k);
  EXPECT_EQ(moving.exit_code, 3) << moving.err;
  EXPECT_THAT(moving.err, HasSubstr(dir_ + "/step.csv:302: rate_dps: the compensated rate jumps by 49.99 deg/s"));
  EXPECT_THAT(moving.err, HasSubstr("the gyro moves"));
  EXPECT_FALSE(fs::exists(dir_ + "/m.csv"));
  const auto plain =
      run_driftlab("compensate --model " + dir_ + "/poly.json --data " + dir_ + "/step.csv --out " + dir_ + "/m.csv");
  EXPECT_EQ(plain.exit_code, 0) << plain.err;
}

TEST_F(CalibrateCli, TheReportScoresEveryModelOnAHeldOutRunOfAnotherProfile) {
  const auto sim =
      run_driftlab("simulate --device fmvmg --fs 2 --seed 4 --profile " + std::string(DRIFTLAB_SOURCE_DIR) +
                   "/models/calibration/heldout_profile.yaml --out " + dir_ + "/heldout.csv");
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const auto r = run_driftlab("-q calibrate --data " + dir_ + "/oven.csv --model physical --out " + dir_ +
                              "/phys.json --evaluate " + dir_ + "/heldout.csv --report " + dir_ + "/report");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(read_text(dir_ + "/report/report.json"));
  EXPECT_EQ(j["format"], "driftlab-calibrate-report/1");
  ASSERT_EQ(j["evaluations"].size(), 1u);
  std::vector<std::string> names;
  for (const auto& m : j["evaluations"][0]["methods"]) names.push_back(m["name"]);
  EXPECT_EQ(names, (std::vector<std::string>{"none", "PX4-style poly", "poly", "physical", "rbf"}));
  const auto& methods = j["evaluations"][0]["methods"];
  EXPECT_LT(methods[3]["residual_drift_dph"].get<double>(), methods[0]["residual_drift_dph"].get<double>());
  EXPECT_THAT(j["chosen"].get<std::string>(), ::testing::StartsWith("rate: poly (")) << "the model written, and why";
  EXPECT_TRUE(j["quality_gate"].is_array());

  // The held-out profile has three legs (up to 50 degC, down to -10, back up); every method is scored
  // on each, and a record's residual drift lies between its legs' (the blocks are the legs' blocks).
  const auto& legs = j["evaluations"][0]["legs"];
  std::vector<std::string> directions;
  for (const auto& leg : legs) directions.push_back(leg["direction"]);
  EXPECT_EQ(directions, (std::vector<std::string>{"heating", "cooling", "heating"}));
  for (const auto& m : methods) {
    const auto by_leg = m["residual_drift_by_leg_dph"].get<std::vector<double>>();
    ASSERT_EQ(by_leg.size(), legs.size()) << m["name"];
    const double whole = m["residual_drift_dph"];
    EXPECT_LE(*std::min_element(by_leg.begin(), by_leg.end()), whole * (1 + 1e-9)) << m["name"];
    EXPECT_GE(*std::max_element(by_leg.begin(), by_leg.end()), whole * (1 - 1e-9)) << m["name"];
  }

  // Four figures per held-out record when gnuplot is there: bias against temperature, |residual|
  // against temperature and time, Allan deviation of the residuals.
  const std::string html = read_text(dir_ + "/report/report.html");
  EXPECT_NE(html.find("Held-out record"), std::string::npos);
  EXPECT_NE(html.find("Oven-run quality gate"), std::string::npos);
  std::size_t figures = 0;
  for (auto at = html.find("<svg"); at != std::string::npos; at = html.find("<svg", at + 1)) ++figures;
  EXPECT_EQ(figures, 4u);
  for (const char* caption : {"Bias (measured - true rate) of the calibration records", "against temperature",
                              "against time", "Allan deviation of every method"})
    EXPECT_NE(html.find(caption), std::string::npos) << caption;
}

// --gmwm: every method's residual carries a GMWM fit of the model beside B and N, in `driftlab allan
// --gmwm`'s JSON; the white noise of the chosen model's residual is the simulator's (devices/fmvmg.yaml:
// N = 99.6 deg/h/sqrt(Hz) = 1.66 deg/sqrt(h)), within 3 % (the flicker and the drift left in the residual
// lift the short-tau curve a little).
TEST_F(CalibrateCli, TheReportFitsAGmwmNoiseModelToEveryResidual) {
  const auto sim = run_driftlab("simulate --device fmvmg --fs 2 --seed 6 --out " + dir_ + "/heldout_gmwm.csv");
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const auto r =
      run_driftlab("calibrate --data " + dir_ + "/oven.csv --model poly --out " + dir_ + "/gmwm.json --evaluate " +
                   dir_ + "/heldout_gmwm.csv --report " + dir_ + "/report_gmwm --gmwm wn+rw --gmwm-bootstrap 20");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("GMWM wn+rw (Guerrier et al. 2013; one-sigma intervals: bootstrap"));
  const auto j = nlohmann::json::parse(read_text(dir_ + "/report_gmwm/report.json"));
  EXPECT_TRUE(j["metrics"].contains("gmwm"));
  const auto& methods = j["evaluations"][0]["methods"];
  ASSERT_EQ(methods.size(), 5u);
  for (const auto& m : methods) {
    SCOPED_TRACE(m["name"].get<std::string>());
    const auto& g = m["gmwm"];
    ASSERT_TRUE(g.is_object());
    EXPECT_EQ(g["model"], "wn+rw");
    EXPECT_THAT(g["intervals"].get<std::string>(), HasSubstr("bootstrap"));
    ASSERT_EQ(g["components"].size(), 2u);
    const auto& n = g["components"][0]["parameters"][0];
    EXPECT_EQ(n["name"], "N");
    EXPECT_EQ(n["unit"], "deg/sqrt(h)");
    ASSERT_TRUE(n["resolved"].get<bool>());
    EXPECT_LE(n["interval"][0].get<double>(), n["value"].get<double>());
    EXPECT_GE(n["interval"][1].get<double>(), n["value"].get<double>());
  }
  const auto& poly = methods[2];
  ASSERT_EQ(poly["name"], "poly");
  EXPECT_NEAR(poly["gmwm"]["components"][0]["parameters"][0]["value"].get<double>(), 99.6 / 60.0, 0.03 * 99.6 / 60.0);
  const std::string html = read_text(dir_ + "/report_gmwm/report.html");
  EXPECT_THAT(html, HasSubstr("GMWM wn+rw of every method&#39;s residual"));
  EXPECT_THAT(html, HasSubstr("wn N (deg/sqrt(h))"));

  const auto bad = run_driftlab("calibrate --data " + dir_ + "/oven.csv --out " + dir_ + "/bad.json --report " + dir_ +
                                "/report_bad --gmwm wn+flicker");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_THAT(bad.err, HasSubstr("--gmwm"));
  EXPECT_THAT(bad.err, HasSubstr("flicker"));
  EXPECT_FALSE(fs::exists(dir_ + "/bad.json")) << "a bad model is refused before anything is written";
  const auto no_report =
      run_driftlab("calibrate --data " + dir_ + "/oven.csv --out " + dir_ + "/bad.json --gmwm wn+rw");
  EXPECT_EQ(no_report.exit_code, 2);
  EXPECT_THAT(no_report.err, HasSubstr("--report"));
}

TEST_F(CalibrateCli, ThePaperPipelineIsScoredOnTheHeldOutRecordByItsFinalStage) {
  // The main job's pipeline as the offline reference: its final stage (the last rate output,
  // rbf_ga_kf in li2023.yaml) is scored beside the causal models.
  const auto sim =
      run_driftlab("simulate --device fmvmg --fs 2 --seed 5 --profile " + std::string(DRIFTLAB_SOURCE_DIR) +
                   "/models/calibration/heldout_profile.yaml --out " + dir_ + "/heldout_paper.csv");
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const auto r =
      run_driftlab("-q calibrate --data " + dir_ + "/oven.csv --model poly --out " + dir_ +
                   "/poly_paper.json --evaluate " + dir_ + "/heldout_paper.csv --report " + dir_ +
                   "/report_paper --paper-pipeline " + DRIFTLAB_SOURCE_DIR + "/models/pipelines/li2023.yaml");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(read_text(dir_ + "/report_paper/report.json"));
  const auto& methods = j["evaluations"][0]["methods"];
  const auto& paper = methods.back();
  EXPECT_EQ(paper["name"], "paper pipeline (offline, stage rbf_ga_kf)") << methods.dump(1);
  EXPECT_LT(paper["residual_drift_dph"].get<double>(), methods[0]["residual_drift_dph"].get<double>());
}

// The oven-run quality gate: a record without temperature variation is refused (exit 3, naming
// the span); a cooling-only run is fitted with a named warning, which --strict makes an error; a
// model worse than no compensation on held-out bins (a bias-free gyro: pure noise) is not written
// without --force.
TEST_F(CalibrateCli, TheQualityGateNamesWhatTheOvenRunLacksAndStrictRefusesIt) {
  const auto write = [&](const std::string& name, double t_from, double t_to, double bias_per_k) {
    std::ofstream f(dir_ + "/" + name);
    f << "t_s,gyro_z_rps,temp\n";
    std::uint64_t state = 7;
    for (int i = 0; i < 7200; ++i) {
      state = state * 6364136223846793005ULL + 1442695040888963407ULL;
      const double noise = (static_cast<double>(state >> 11) * 0x1.0p-53 - 0.5) * 2e-3;
      const double temp = t_from + (t_to - t_from) * i / 7199.0;
      f << i << "," << bias_per_k * (temp - 25) + noise << "," << temp << "\n";
    }
  };
  write("flat.csv", 25.0, 25.0, 1e-4);
  write("cooling.csv", 40.0, 10.0, 1e-4);
  const auto flat = run_driftlab("calibrate --data " + dir_ + "/flat.csv --out " + dir_ + "/flat.json");
  EXPECT_EQ(flat.exit_code, 3);
  EXPECT_NE(flat.err.find("temperature span 0.000 K"), std::string::npos) << flat.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/flat.json"));

  const auto cooling = run_driftlab("calibrate --data " + dir_ + "/cooling.csv --out " + dir_ + "/cooling.json");
  EXPECT_EQ(cooling.exit_code, 0) << cooling.err;
  EXPECT_NE(cooling.out.find("quality gate warning [one_direction] temp: cooling only"), std::string::npos)
      << cooling.out;
  const auto model = nlohmann::json::parse(read_text(dir_ + "/cooling.json"));
  EXPECT_EQ(model["channels"][0]["model"]["kind"], "poly") << "no history terms from one direction";
  const auto reported = run_driftlab("-q calibrate --data " + dir_ + "/cooling.csv --train-until 5000 --out " + dir_ +
                                     "/cooling_r.json --report " + dir_ + "/cooling_report");
  ASSERT_EQ(reported.exit_code, 0) << reported.err;
  const auto report = nlohmann::json::parse(read_text(dir_ + "/cooling_report/report.json"));
  ASSERT_FALSE(report["quality_gate"].empty()) << "the report carries the gate's findings";
  EXPECT_EQ(report["quality_gate"][0]["code"], "one_direction");
  EXPECT_EQ(report["quality_gate"][0]["severity"], "warning");
  const auto strict = run_driftlab("calibrate --strict --data " + dir_ + "/cooling.csv --out " + dir_ + "/strict.json");
  EXPECT_EQ(strict.exit_code, 3);
  EXPECT_NE(strict.err.find("quality gate (--strict)"), std::string::npos) << strict.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/strict.json"));
}

TEST_F(CalibrateCli, EveryCommandHasHelp) {
  EXPECT_EQ(run_driftlab("calibrate --help").exit_code, 0);
  EXPECT_EQ(run_driftlab("compensate --help").exit_code, 0);
  EXPECT_EQ(run_driftlab("export --help").exit_code, 0);
}

TEST_F(CalibrateCli, AModelOfASingleAxisRecordExportsToItsAxisOfInstanceZero) {
  const auto r = run_driftlab("export --model " + dir_ + "/poly.json --format px4 --out " + dir_ + "/single.params");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string text = read_text(dir_ + "/single.params");
  EXPECT_NE(text.find("\tTC_G0_X0_2\t"), std::string::npos) << text;
  EXPECT_NE(text.find("\tTC_G0_X1_0\t0\t9"), std::string::npos) << "the axes the model lacks: no correction";
  EXPECT_EQ(text.find("TC_A_ENABLE"), std::string::npos) << "no accelerometer in the model";
  EXPECT_EQ(text.find("TC_G1_"), std::string::npos);
}

// A simulated 2-instance IMU (imu3: gyro + accelerometer, 3 axes each), calibrated in one call and
// exported in every format.
class ExportCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = scratch_dir("export").string();
    const auto s = run_driftlab("simulate --device " + std::string(DRIFTLAB_SOURCE_DIR) +
                                "/devices/imu3.yaml --fs 2 --seed 1 --out " + dir_ + "/imu.csv");
    ASSERT_EQ(s.exit_code, 0) << s.err;
    const auto c = run_driftlab("-q calibrate --data " + dir_ + "/imu.csv --channels gyro,accel --model poly --out " +
                                dir_ + "/m.json");
    ASSERT_EQ(c.exit_code, 0) << c.err;
    model_ = nlohmann::json::parse(read_text(dir_ + "/m.json"));
    ASSERT_EQ(model_["channels"].size(), 12u);
  }
  static std::string exported(const std::string& format, const std::string& extra = "") {
    const std::string out = dir_ + "/out." + format;
    const auto r = run_driftlab("export --model " + dir_ + "/m.json --format " + format + " --out " + out + extra);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return read_text(out);
  }
  // The model's channel of this role.
  static const nlohmann::json& channel(const std::string& role) {
    for (const auto& c : model_["channels"]) {
      if (c["role"] == role) return c;
    }
    throw std::runtime_error("no channel " + role);
  }
  // Value of a parameter line "<prefix><name><separator><value>".
  static double value(const std::string& text, const std::string& prefix, const std::string& name, char separator) {
    const auto at = text.find(prefix + name + separator);
    if (at == std::string::npos) throw std::runtime_error(name + " missing");
    return std::stod(text.substr(at + prefix.size() + name.size() + 1));
  }
  static std::string dir_;
  static nlohmann::json model_;
};
std::string ExportCli::dir_;
nlohmann::json ExportCli::model_;

constexpr double kText = 1e-8;  // relative: parameters are written with 9 significant digits

TEST_F(ExportCli, Px4ParamsCarryEveryAxisOfBothGyrosAndAccelerometers) {
  const std::string text = exported("px4");
  EXPECT_NE(text.find("\tTC_G_ENABLE\t1\t6"), std::string::npos);
  EXPECT_NE(text.find("\tTC_A_ENABLE\t1\t6"), std::string::npos);
  for (const std::string role : {"gyro_x", "gyro1_y", "accel_z", "accel1_x"}) {
    const auto& c = channel(role);
    const std::string block =
        std::string("TC_") + (c["sensor"] == "gyro" ? "G" : "A") + std::to_string(c["instance"].get<int>()) + "_";
    const int axis = c["axis"].get<std::string>()[0] - 'x';
    const auto& bias = c["model"]["bias"].begin().value();  // polynomial_rad_s_per_k_i / _m_s2_per_k_i
    EXPECT_EQ(value(text, "1\t1\t", block + "TREF", '\t'), c["model"]["reference_temp_c"].get<double>());
    // TREF = T0: X0 and X1 are the model's own a0 and a1.
    for (int k = 0; k < 2; ++k) {
      const double expected = bias[static_cast<std::size_t>(k)].get<double>();
      EXPECT_NEAR(value(text, "1\t1\t", block + "X" + std::to_string(k) + "_" + std::to_string(axis), '\t'), expected,
                  std::abs(expected) * kText)
          << role;
    }
  }
}

TEST_F(ExportCli, ArduPilotParmCarriesBothImusAtThe35DegreeReference) {
  const std::string text = exported("ardupilot");
  for (const std::string role : {"gyro_x", "gyro1_z", "accel_y", "accel1_z"}) {
    const auto& c = channel(role);
    const int n = c["instance"].get<int>() + 1;
    const auto& a = c["model"]["bias"].begin().value();
    const double d = 35.0 - c["model"]["reference_temp_c"].get<double>();
    double slope = 0.0;  // the coefficient of (T - 35)^1: the derivative at 35 degC
    for (std::size_t i = 1; i < a.size(); ++i)
      slope += static_cast<double>(i) * a[i].get<double>() * std::pow(d, i - 1.0);
    const std::string name = "INS_TCAL" + std::to_string(n) + "_" + (c["sensor"] == "gyro" ? "GYR" : "ACC") + "1_" +
                             static_cast<char>(std::toupper(c["axis"].get<std::string>()[0]));
    if (a.size() <= 4) {  // order <= 3 is exact (a higher order is a least-squares cubic: calibration_exports_test)
      EXPECT_NEAR(value(text, "", name, ','), 1e6 * slope, std::abs(1e6 * slope) * kText) << role;
    }
  }
  EXPECT_NE(text.find("INS_TCAL2_ENABLE,1"), std::string::npos);
  EXPECT_NE(text.find("INS_GYR2OFFS_X,"), std::string::npos);
  EXPECT_NE(text.find("INS_GYR2_CALTEMP,35"), std::string::npos);
}

// The 2-Hz calibration record does not resolve the accelerometers' random walk: the model keeps only
// its bound (noise.unresolved_upper), the export refuses to write it as a value (exit 2) and, with
// --allow-bounds, writes it marked as a bound.
TEST_F(ExportCli, KalibrYamlHoldsTheMeasuredAccelerometerNoiseOfTheChosenInstance) {
  bool bounded = false;
  for (const std::string role : {"accel_x", "accel_y", "accel_z"}) {
    const auto& noise = channel(role)["model"]["noise"];
    bounded = bounded || (noise.contains("unresolved_upper") &&
                          noise["unresolved_upper"].contains("acceleration_random_walk_m_s2_sqrt_s"));
  }
  ASSERT_TRUE(bounded);
  const auto refused =
      run_driftlab("export --model " + dir_ + "/m.json --format kalibr --instance 0 --out " + dir_ + "/refused.yaml");
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.err.find("not resolved"), std::string::npos) << refused.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/refused.yaml"));
  const std::string text = exported("kalibr", " --instance 0 --allow-bounds");
  const auto walk = text.substr(text.find("accelerometer_random_walk: "));
  EXPECT_NE(walk.substr(0, walk.find('\n')).find("UPPER BOUND"), std::string::npos) << text;
  double vrw = 0.0;
  for (const std::string role : {"accel_x", "accel_y", "accel_z"}) {
    vrw = std::max(vrw, channel(role)["model"]["noise"]["vrw_m_s_sqrt_s"].get<double>());
  }
  ASSERT_GT(vrw, 0.0);
  EXPECT_NEAR(value(text, "", "accelerometer_noise_density", ':'), vrw, vrw * kText) << text;
  EXPECT_NE(text.find("accelerometer_random_walk: "), std::string::npos);
  EXPECT_NE(text.find("gyroscope_random_walk: "), std::string::npos);
}

TEST_F(ExportCli, TheCHeaderAndTheJsonCoverEveryChannel) {
  const std::string header = exported("c-header", " --prefix imu");
  for (const auto& c : model_["channels"]) {
    EXPECT_NE(header.find("static const imu_model imu_" + c["role"].get<std::string>() + " = {"), std::string::npos);
  }
  EXPECT_NE(header.find("imu_CHANNELS = 12, imu_TEMPERATURES = 2"), std::string::npos);
  EXPECT_EQ(exported("json"), read_text(dir_ + "/m.json")) << "the model file itself";
}

}  // namespace
}  // namespace driftlab
