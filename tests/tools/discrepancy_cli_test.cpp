// End-to-end tests of `driftlab discrepancy` on records made by `driftlab simulate`.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <algorithm>
#include <functional>
#include <iomanip>
#include <sstream>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/tools/cli_harness.hpp"
#include "framework/units.hpp"

namespace driftlab {
namespace {

using ::testing::HasSubstr;
using namespace testing_cli;

// The default oven run (4.5 h) at 1 Hz: 16 200 samples.
std::filesystem::path simulated(const std::filesystem::path& dir, const std::string& effect) {
  const auto csv = dir / "measured.csv";
  const auto r = run_driftlab("simulate --device fmvmg --fs 1 --seed 11 --out " + csv.string() +
                              (effect.empty() ? "" : " --effect " + effect));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return csv;
}

TEST(DiscrepancyCommand, NamesASimulatedDisturbanceAndWritesReportSeriesAndHtml) {
  const auto dir = scratch_dir("discrepancy_named");
  const auto csv = simulated(dir, "periodic_disturbance:amplitude_dph=80,period_s=900,phase_deg=30");
  const auto r =
      run_driftlab("discrepancy --data " + csv.string() + " --device fmvmg --report " + (dir / "report.json").string() +
                   " --series " + (dir / "series.csv").string() + " --html " + (dir / "report.html").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("named periodic_disturbance"));

  const auto report = nlohmann::json::parse(read_text(dir / "report.json"));
  ASSERT_EQ(report["named_effects"].size(), 1u) << report.dump(2);
  const auto& effect = report["named_effects"][0];
  EXPECT_EQ(effect["effect"], "periodic_disturbance");
  constexpr double kPeriodTolerance = 9.0;  // 1 %: a tenth of a periodogram bin over 4.5 h
  EXPECT_NEAR(effect["parameters"]["period_s"].get<double>(), 900.0, kPeriodTolerance);
  EXPECT_TRUE(effect["uncertainty"]["amplitude_dph"].is_number());
  EXPECT_LT(effect["gap_after"].get<double>(), effect["gap_before"].get<double>());
  EXPECT_DOUBLE_EQ(report["gap_initial"].get<double>(), effect["gap_before"].get<double>());
  EXPECT_DOUBLE_EQ(report["gap_final"].get<double>(), effect["gap_after"].get<double>());
  EXPECT_THAT(report["gap_metric"].get<std::string>(), HasSubstr("deg/h"));
  EXPECT_TRUE(report["views"]["initial"]["spectrum_peaks"].is_array());

  std::ifstream series(dir / "series.csv");
  std::string header, line;
  std::getline(series, header);
  EXPECT_EQ(header, "t_s,measured_dps,model_initial_dps,model_final_dps");
  std::size_t rows = 0;
  while (std::getline(series, line)) ++rows;
  EXPECT_EQ(rows, 16200u);

  const std::string html = read_text(dir / "report.html");
  EXPECT_THAT(html, HasSubstr("<svg"));
  EXPECT_THAT(html, HasSubstr("periodic_disturbance"));
}

// A copy of a simulated record with `step_dph` added to rate_dps where die_temp_c is above level_c:
// an effect no candidate describes.
std::filesystem::path with_bias_step(const std::filesystem::path& csv, double level_c, double step_dph) {
  std::ifstream in(csv);
  std::string header, line;
  std::getline(in, header);
  const auto split = [](const std::string& text) {
    std::vector<std::string> cells;
    std::stringstream stream(text);
    for (std::string cell; std::getline(stream, cell, ',');) cells.push_back(cell);
    return cells;
  };
  const auto names = split(header);
  const auto column = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
  };
  const std::size_t rate = column("rate_dps"), die = column("die_temp_c");
  const auto out_path = csv.parent_path() / "with_step.csv";
  std::ofstream out(out_path);
  out << header << "\n" << std::setprecision(17);
  while (std::getline(in, line)) {
    auto cells = split(line);
    if (std::stod(cells.at(die)) > level_c)
      cells[rate] = std::to_string(std::stod(cells[rate]) + step_dph / kSecondsPerHour);
    for (std::size_t i = 0; i < cells.size(); ++i) out << (i ? "," : "") << cells[i];
    out << "\n";
  }
  return out_path;
}

TEST(DiscrepancyCommand, ReportsABiasStepAtOneTemperatureAsUnexplainedWithItsLevelAndSize) {
  // degC: well inside the spacing of the level search (64 equal-count levels, refined between
  // neighbours by golden section); measured 0.02.
  constexpr double kStepLevel = 0.5;
  constexpr double kStepSizeDph = 30.0;  // 10 %: the joint fit's size scatters with the noise; measured -3 .. +1.4 %
  const auto dir = scratch_dir("discrepancy_step");
  const auto csv = with_bias_step(simulated(dir, ""), 20.0, 300.0);
  for (const std::string device : {" --device fmvmg",
                                   " --column time=t_s:s --column rate=rate_dps:deg/s "
                                   "--column temperature=temp_c:degC --column true_rate=true_rate_dps:deg/s"}) {
    const auto r =
        run_driftlab("discrepancy --data " + csv.string() + device + " --report " + (dir / "r.json").string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_THAT(r.out, HasSubstr("unexplained: structure remains that no candidate explains, in the temperature view"));
    EXPECT_THAT(r.out, ::testing::Not(HasSubstr("named "))) << device;
    const auto report = nlohmann::json::parse(read_text(dir / "r.json"));
    EXPECT_TRUE(report["named_effects"].empty()) << device;
    const auto& best = report["unexplained"]["views"][0];
    ASSERT_EQ(best["view"], "temperature") << best.dump();
    EXPECT_NEAR(best["step"]["level_c"].get<double>(), 20.0, kStepLevel) << device;
    EXPECT_NEAR(best["step"]["size_dph"].get<double>(), 300.0, kStepSizeDph) << device;
  }
}

TEST(DiscrepancyCommand, SaysNothingIsMissingWhenTheDeviceFileIsTheTruth) {
  const auto dir = scratch_dir("discrepancy_nothing");
  const auto csv = simulated(dir, "");
  const auto r =
      run_driftlab("discrepancy --data " + csv.string() + " --device fmvmg --report " + (dir / "report.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("nothing significant is missing"));
  const auto report = nlohmann::json::parse(read_text(dir / "report.json"));
  EXPECT_TRUE(report["named_effects"].is_array());
  EXPECT_TRUE(report["named_effects"].empty());
  EXPECT_DOUBLE_EQ(report["gap_initial"].get<double>(), report["gap_final"].get<double>());
}

TEST(DiscrepancyCommand, WithoutADeviceFitsABiasPolynomialAndEstimatesTheNoiseTermsFromTheRecord) {
  const auto dir = scratch_dir("discrepancy_no_device");
  const auto csv = simulated(dir, "periodic_disturbance:amplitude_dph=80,period_s=900,phase_deg=30");
  const auto r = run_driftlab("discrepancy --data " + csv.string() + " --report " + (dir / "report.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto report = nlohmann::json::parse(read_text(dir / "report.json"));
  EXPECT_TRUE(report["model"]["noise_estimated"].get<bool>());
  // The FMVMG's white noise is N = 99.6 deg/h/sqrt(Hz); the Allan fit of the residual finds it.
  constexpr double kArwTolerance = 10.0;  // deg/h/sqrt(Hz): the fit's spread over one 4.5-h record
  EXPECT_NEAR(report["model"]["noise"]["arw_dph_rthz"].get<double>(), 99.6, kArwTolerance);
  ASSERT_GE(report["named_effects"].size(), 1u) << report.dump(2);
  EXPECT_EQ(report["named_effects"][0]["effect"], "periodic_disturbance");
  // Without the device file the workflow does not know that the case sensor lags the die by 5 s
  // (devices/fmvmg.yaml, thermal.sensor_time_constant_s). With the FMVMG's bias slope of ~50 deg/h
  // per degC that lag is visible, and the drive frequency shows it as the resonator running away from
  // the sensor: a second name, if any, is that real effect and nothing else.
  for (std::size_t i = 1; i < report["named_effects"].size(); ++i)
    EXPECT_EQ(report["named_effects"][i]["effect"], "mode_split_drift") << report.dump(2);
}

TEST(DiscrepancyCommand, EstimatesTheNoiseTermsByGmwmWhenAskedAndRefusesWhatItCannotUse) {
  const auto dir = scratch_dir("discrepancy_gmwm");
  const auto csv = simulated(dir, "periodic_disturbance:amplitude_dph=80,period_s=900,phase_deg=30");
  const auto report_path = (dir / "report.json").string();
  const auto r = run_driftlab("discrepancy --data " + csv.string() + " --noise-gmwm wn+rw+gm --report " + report_path);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto report = nlohmann::json::parse(read_text(dir / "report.json"));
  EXPECT_EQ(report["model"]["noise_estimator"], "GMWM wn+rw+gm of the residual's OADEV");
  EXPECT_EQ(report["model"]["noise"]["gauss_markov"].size(), 1u) << report["model"].dump(2);
  EXPECT_EQ(report["model"]["noise"]["bias_instability_dph"].get<double>(), 0.0);
  // The same white noise as the slope fit reads (N = 99.6 deg/h/sqrt(Hz) in devices/fmvmg.yaml).
  constexpr double kArwTolerance = 10.0;  // deg/h/sqrt(Hz): the fit's spread over one 4.5-h record
  EXPECT_NEAR(report["model"]["noise"]["arw_dph_rthz"].get<double>(), 99.6, kArwTolerance);
  ASSERT_GE(report["named_effects"].size(), 1u) << report.dump(2);
  EXPECT_EQ(report["named_effects"][0]["effect"], "periodic_disturbance");

  const auto quantization =
      run_driftlab("discrepancy --data " + csv.string() + " --noise-gmwm wn+qn --report " + (dir / "q.json").string());
  EXPECT_EQ(quantization.exit_code, 2);
  EXPECT_THAT(quantization.err, HasSubstr("noise_gmwm"));
  EXPECT_THAT(quantization.err, HasSubstr("'qn' is not a noise term of the discrepancy model"));
  const auto with_device = run_driftlab("discrepancy --data " + csv.string() +
                                        " --device fmvmg --noise-gmwm wn+rw+gm --report " + (dir / "d.json").string());
  EXPECT_EQ(with_device.exit_code, 2);
  EXPECT_THAT(with_device.err, HasSubstr("the device file gives the noise terms"));
  EXPECT_FALSE(std::filesystem::exists(dir / "q.json"));
  EXPECT_FALSE(std::filesystem::exists(dir / "d.json"));
}

// Keeps the header and the rows whose time stamp (first column, s) passes `keep`.
std::filesystem::path filtered(const std::filesystem::path& csv, const std::string& name,
                               const std::function<bool(double)>& keep) {
  std::ifstream in(csv);
  const auto out_path = csv.parent_path() / name;
  std::ofstream out(out_path);
  std::string line;
  std::getline(in, line);
  out << line << "\n";
  while (std::getline(in, line))
    if (keep(std::stod(line.substr(0, line.find(','))))) out << line << "\n";
  return out_path;
}

TEST(DiscrepancyCommand, TakesSearchBoundsFromTheCommandLineValidatedByTheParameterTables) {
  const auto dir = scratch_dir("discrepancy_set");
  const auto csv = simulated(dir, "");
  const std::string base =
      "discrepancy --data " + csv.string() + " --device fmvmg --report " + (dir / "r.json").string();
  const auto bad = run_driftlab(base + " --set effect/thermal_lag.tau_max_s=-3 --set thermal_lag.tau_typo=1");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_THAT(bad.err, HasSubstr("--set effect/thermal_lag.tau_max_s: value -3 is out of range"));
  EXPECT_THAT(bad.err, HasSubstr("--set effect/thermal_lag.tau_typo: unknown parameter"));
  EXPECT_THAT(run_driftlab(base + " --set effect/thermal_lag.tau_min_s=9000").err, HasSubstr("tau_min_s < tau_max_s"));
  EXPECT_THAT(run_driftlab(base + " --effects hysteresis --set thermal_lag.tau_max_s=100").err,
              HasSubstr("effect/thermal_lag is not a candidate"));
  EXPECT_EQ(run_driftlab(base + " --set effect/thermal_lag.tau_max_s=20000 --set periodic_disturbance.period_min_s=60")
                .exit_code,
            0);
}

TEST(DiscrepancyCommand, ReadsARecordOfRegularBurstsWithoutFlagsAndRefusesIrregularGaps) {
  const auto dir = scratch_dir("discrepancy_bursts");
  const auto csv = simulated(dir, "periodic_disturbance:amplitude_dph=150,period_s=2400,phase_deg=30");
  // One minute every five, like a logger that wakes up for a burst.
  const auto bursts = filtered(csv, "bursts.csv", [](double t) { return std::fmod(t, 300.0) < 60.0; });
  const auto r = run_driftlab("discrepancy --data " + bursts.string() + " --device fmvmg --report " +
                              (dir / "bursts.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("named periodic_disturbance"));

  const auto holes =
      filtered(csv, "holes.csv", [](double t) { return t < 3000.0 || (t > 4000 && t < 6500) || t > 12000; });
  const std::string holes_args =
      "discrepancy --data " + holes.string() + " --device fmvmg --report " + (dir / "holes.json").string();
  const auto refused = run_driftlab(holes_args);
  EXPECT_EQ(refused.exit_code, 3);
  EXPECT_THAT(refused.err, HasSubstr("not regular bursts"));
  EXPECT_THAT(refused.err, HasSubstr("--max-gap 0"));
  EXPECT_EQ(run_driftlab(holes_args + " --max-gap 0").exit_code, 0);
}

std::vector<double> rate_column(const std::filesystem::path& csv) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  std::vector<double> rate;
  while (std::getline(in, line)) {
    const auto first = line.find(',');
    rate.push_back(std::stod(line.substr(first + 1, line.find(',', first + 1) - first - 1)));
  }
  return rate;
}

TEST(DiscrepancyCommand, UpdatesACopyOfTheDeviceFileWhoseSimulationReproducesTheRecord) {
  const auto dir = scratch_dir("discrepancy_update");
  const auto csv = simulated(dir, "hysteresis:height_dph=250,width_c=2");
  const auto updated = dir / "new.yaml";
  const auto r = run_driftlab("discrepancy --data " + csv.string() + " --device fmvmg --report " +
                              (dir / "report.json").string() + " --update-device " + updated.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("named hysteresis"));
  const std::string original = read_text(std::filesystem::path(DRIFTLAB_SOURCE_DIR) / "devices" / "fmvmg.yaml");
  const std::string text = read_text(updated);
  EXPECT_EQ(text.substr(0, original.size()), original);  // the rest of the file, comments included, as it was
  EXPECT_THAT(text.substr(original.size()), HasSubstr("effects:\n  hysteresis: {height_dph: "));
  ASSERT_EQ(run_driftlab("devices describe " + updated.string()).exit_code, 0);

  // Same profile and seed: the new device's record differs from the measured one by its systematic
  // part only; block means of that difference stay well inside the noise floor.
  const auto resimulated = dir / "resimulated.csv";
  ASSERT_EQ(run_driftlab("simulate --device " + updated.string() + " --fs 1 --seed 11 --out " + resimulated.string())
                .exit_code,
            0);
  const auto measured = rate_column(csv), again = rate_column(resimulated);
  ASSERT_EQ(measured.size(), again.size());
  const auto report = nlohmann::json::parse(read_text(dir / "report.json"));
  const std::size_t block = static_cast<std::size_t>(report["criterion"]["block_s"].get<double>());
  double sum_squares = 0.0;
  std::size_t blocks = 0;
  for (std::size_t start = 0; start + block <= measured.size(); start += block, ++blocks) {
    double mean = 0.0;
    for (std::size_t k = start; k < start + block; ++k)
      mean += (measured[k] - again[k]) * kSecondsPerHour / block;  // deg/h
    sum_squares += mean * mean;
  }
  EXPECT_LT(std::sqrt(sum_squares / blocks), report["noise_floor"].get<double>());

  EXPECT_EQ(run_driftlab("discrepancy --data " + csv.string() + " --report " + (dir / "r.json").string() +
                         " --update-device " + (dir / "x.yaml").string())
                .exit_code,
            2);  // needs --device
}

TEST(DiscrepancyCommand, RejectsMissingDataAMissingReportAndOverwritingTheInput) {
  const auto dir = scratch_dir("discrepancy_bad");
  const auto csv = simulated(dir, "");
  EXPECT_EQ(run_driftlab("discrepancy --data " + (dir / "nope.csv").string() + " --report " + (dir / "r.json").string())
                .exit_code,
            3);
  EXPECT_EQ(run_driftlab("discrepancy --data " + csv.string()).exit_code, 2);
  EXPECT_EQ(run_driftlab("discrepancy --data " + csv.string() + " --report " + csv.string()).exit_code, 2);
  EXPECT_EQ(run_driftlab("discrepancy --data " + csv.string() + " --report " + (dir / "r.json").string() +
                         " --effects effect/nope")
                .exit_code,
            2);
}

}  // namespace
}  // namespace driftlab
