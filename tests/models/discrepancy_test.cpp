// The discrepancy workflow (models/discrepancy) on simulated oven records with hidden effects
// (tests/models/oven_records.hpp: seeded, different ramp rates per record, FMVMG noise), plus its
// building blocks: block means, the noise covariance of block means, the residual views.
//
// Record counts (1 Hz, 3.2-5.8 h each): 36 with one hidden effect drawn at random, 16 with none,
// 10 with two, 1 with a drive-frequency channel; the three checks on the single-effect records
// share one test (one run over them). DRIFTLAB_DISCREPANCY_SCALE=k multiplies the counts by k for an
// offline validation (the tests print a one-line summary of each check).
#include "models/discrepancy/discrepancy.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <map>
#include <set>

#include "plugins/builtins.hpp"
#include "framework/effect_catalogue.hpp"
#include "framework/params_io.hpp"
#include "framework/registry.hpp"
#include "framework/signal.hpp"
#include "tests/models/oven_records.hpp"
#include "devices/discrepancy_options.hpp"

namespace driftlab {
namespace {

constexpr std::uint64_t kSeed = 2026;

int scale() {
  const char* text = std::getenv("DRIFTLAB_DISCREPANCY_SCALE");
  return text ? std::max(1, std::atoi(text)) : 1;
}
const int kSingleEffectRecords = 36 * scale();
const int kNoiseOnlyRecords = 16 * scale();
const int kTwoEffectRecords = 10 * scale();
constexpr double kNearlyAll = 0.9;  // fraction of records in which the hidden effect must be named first

// Parameter tolerances: relative error, or 3 reported standard deviations when that is larger.
constexpr double kTimeConstantTolerance = 0.05;  // the rate table's scale-factor signature pins tau to ~1 %
constexpr double kScaleFactorTolerance = 0.05;   // the basis leaves out the device's own s_dev(T) = 1 +- 1.5 %
constexpr double kPeriodTolerance = 0.01;        // ~ one tenth of a periodogram bin over 4 h
constexpr double kAmplitudeTolerance = 0.30;     // amplitudes of the order of the flicker noise: 10-20 % at 1 sigma
constexpr double kSigmas = 3.0;

devices::DeviceDefinition fmvmg(bool with_drive_frequency) {
  auto device = devices::load_device_file(std::filesystem::path(DRIFTLAB_SOURCE_DIR) / "devices" / "fmvmg.yaml");
  // The seeded set is drawn at the noise level it was designed and measured at: flicker B = 34.7 and
  // K = 20 deg/h/sqrt(h), the paper's raw B taken as intrinsic noise (the FMVMG file before issue 12).
  // With the file's own small intrinsic noise (B = 1) the workflow is more sensitive (both hidden
  // effects named in 9 of 10 two-effect records, no extra name): see docs/evidence.md, discrepancy.
  device.error_model.noise.bias_instability_rad_s = 34.7 * kRadPerSecPerDph;
  device.error_model.noise.rate_random_walk_rad_s_sqrt_s = 20.0 * kRadPerSecPerDph / 60.0;
  if (!with_drive_frequency)
    std::erase_if(device.channels, [](const auto& c) { return c.role == role::kDriveFrequency; });
  return device;
}

struct Candidates {
  Candidates() {
    register_builtin_plugins(registry);
    for (const auto* info : registry.list("effect")) {
      owned.push_back(registry.create_as<Effect>({info->name, params_from_assignments(registry, info->name, {})}));
      list.push_back({info->name.substr(7), owned.back().get()});
    }
  }
  Registry registry;
  std::vector<std::unique_ptr<Effect>> owned;
  std::vector<discrepancy::Candidate> list;
};

const Candidates& candidates() {
  static const Candidates c;
  return c;
}

struct RecordRun {
  testing_oven::OvenRecord record;
  discrepancy::Result result;
};

RecordRun run_record(std::uint64_t index, const std::vector<std::string>& hidden, bool with_drive_frequency = false) {
  const auto device = fmvmg(with_drive_frequency);
  RecordRun r{testing_oven::make_record(device, kSeed, index, hidden), {}};
  r.result =
      discrepancy::find_missing_effects(r.record.series, candidates().list, devices::discrepancy_options(device));
  return r;
}

// The same record without the device file: a free bias and scale-factor polynomial, noise terms
// estimated from the record.
discrepancy::Result run_without_device(const testing_oven::OvenRecord& record) {
  discrepancy::Options options;
  options.reference_temp_c = fmvmg(false).error_model.reference_temp_c;
  return discrepancy::find_missing_effects(record.series, candidates().list, options);
}

std::vector<std::string> named(const discrepancy::Result& r) {
  std::vector<std::string> out;
  for (const auto& s : r.steps) out.push_back(s.effect);
  return out;
}

// RMS of (model - truth) about its mean: the systematic gap, leaving the constant that the noise's
// random-walk start sets aside.
double gap_to_truth(const Eigen::VectorXd& model, const Eigen::VectorXd& truth) {
  const Eigen::ArrayXd d = (model - truth).array();
  return std::sqrt((d - d.mean()).square().mean());
}

const discrepancy::ReportedValue& value(const discrepancy::Step& step, const std::string& key) {
  for (const auto& p : step.parameters)
    if (p.key == key) return p;
  throw std::runtime_error("no parameter " + key + " in " + step.effect);
}

// (fitted, sigma, truth, relative tolerance) of the parameters that characterize the hidden effect.
struct Check {
  std::string what;
  double fitted, sigma, truth, tolerance;
};
std::vector<Check> parameter_checks(const discrepancy::Step& step, const error_model::Effects& e) {
  auto check = [&](const std::string& key, double truth, double tolerance) {
    const auto& v = value(step, key);
    return Check{step.effect + "." + key, v.values[0], v.sigmas[0], truth, tolerance};
  };
  const double dph = kRadPerSecPerDph;
  if (step.effect == "thermal_lag") return {check("tau_s", e.thermal_lag->tau_s, kTimeConstantTolerance)};
  if (step.effect == "temperature_rate")
    return {check("coefficient_dph_per_c_per_min", e.temperature_rate->coefficient_rad_s_per_k_s / dph / 60.0,
                  kAmplitudeTolerance)};
  if (step.effect == "hysteresis") return {check("height_dph", e.hysteresis->height_rad_s / dph, kAmplitudeTolerance)};
  if (step.effect == "warmup_transient")
    return {check("amplitude_dph", e.warmup_transient->amplitude_rad_s / dph, kAmplitudeTolerance)};
  if (step.effect == "periodic_disturbance")
    return {check("amplitude_dph", e.periodic_disturbance->amplitude_rad_s / dph, kAmplitudeTolerance),
            check("period_s", e.periodic_disturbance->period_s, kPeriodTolerance)};
  if (step.effect == "scale_factor_temperature")
    return {check("coefficients_ppm", e.scale_factor_temperature->coefficients_per_k[0] * 1e6, kScaleFactorTolerance)};
  return {};
}

// The three checks on the single-effect records share one run of the workflow over them.
void expect_named_first_in_nearly_all_and_no_other_effect_ever(const std::vector<RecordRun>& runs) {
  int first_is_hidden = 0;
  for (const auto& run : runs) {
    const auto names = named(run.result);
    if (!names.empty() && names.front() == run.record.hidden.front()) ++first_is_hidden;
    for (const auto& n : names)
      EXPECT_EQ(n, run.record.hidden.front()) << devices::describe_effects(run.record.effects)[0];
  }
  EXPECT_GE(first_is_hidden, static_cast<int>(std::ceil(kNearlyAll * kSingleEffectRecords)))
      << first_is_hidden << " of " << kSingleEffectRecords;
  std::printf("[ summary  ] hidden effect named first in %d of %d records\n", first_is_hidden, kSingleEffectRecords);
}

void expect_fitted_parameters_near_the_truth(const std::vector<RecordRun>& runs) {
  std::map<std::string, std::vector<double>> relative_errors;
  for (const auto& run : runs) {
    if (run.result.steps.empty()) continue;
    for (const auto& c : parameter_checks(run.result.steps.front(), run.record.effects)) {
      const double allowed = std::max(c.tolerance * std::abs(c.truth), kSigmas * c.sigma);
      EXPECT_LE(std::abs(c.fitted - c.truth), allowed)
          << c.what << ": fitted " << c.fitted << " +- " << c.sigma << ", truth " << c.truth;
      relative_errors[c.what].push_back(std::abs(c.fitted / c.truth - 1.0));
    }
  }
  for (auto& [what, errors] : relative_errors) {
    std::sort(errors.begin(), errors.end());
    std::printf("[ summary  ] %s: %zu records, relative error median %.3f, max %.3f\n", what.c_str(), errors.size(),
                errors[errors.size() / 2], errors.back());
  }
}

void expect_gap_to_truth_halved_in_nearly_all(const std::vector<RecordRun>& runs) {
  // What is left after the effect is mostly the slow noise that the bias polynomial absorbed (the
  // same before and after); where the effect is weak, that floor can exceed half the initial gap.
  int halved = 0;
  std::string not_halved;
  for (const auto& run : runs) {
    const double before = gap_to_truth(run.result.model_initial_rad_s, run.record.truth_rad_s);
    const double after = gap_to_truth(run.result.model_final_rad_s, run.record.truth_rad_s);
    if (after <= 0.5 * before)
      ++halved;
    else
      not_halved += devices::describe_effects(run.record.effects)[0] + ": " +
                    std::to_string(before / kRadPerSecPerDph) + " -> " + std::to_string(after / kRadPerSecPerDph) +
                    " deg/h\n";
  }
  EXPECT_GE(halved, static_cast<int>(std::ceil(kNearlyAll * kSingleEffectRecords))) << not_halved;
  std::printf("[ summary  ] systematic gap to the truth halved in %d of %d records\n", halved, kSingleEffectRecords);
}

TEST(HiddenEffect, IsNamedFirstWithParametersNearTheTruthAndTheGapHalvedInNearlyAllOvenRecords) {
  std::vector<RecordRun> runs;
  for (int i = 0; i < kSingleEffectRecords; ++i)
    runs.push_back(
        run_record(static_cast<std::uint64_t>(i), testing_oven::draw_effects(kSeed, static_cast<std::uint64_t>(i), 1)));
  expect_named_first_in_nearly_all_and_no_other_effect_ever(runs);
  expect_fitted_parameters_near_the_truth(runs);
  expect_gap_to_truth_halved_in_nearly_all(runs);
}

TEST(NoHiddenEffect, NothingIsNamedInRecordsWithOnlyColouredNoise) {
  double largest = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < kNoiseOnlyRecords; ++i) {
    const auto run = run_record(100000 + static_cast<std::uint64_t>(i), {});
    EXPECT_THAT(named(run.result), ::testing::IsEmpty()) << "record " << i;
    EXPECT_FALSE(run.result.unexplained.found) << "record " << i << ": " << run.result.unexplained.views.front().view;
    ASSERT_FALSE(run.result.final_scores.empty());
    largest = std::max(largest, run.result.final_scores.front().delta_bic);
  }
  std::printf("[ summary  ] %d noise-only records: largest delta BIC of any candidate %.1f (names above 10)\n",
              kNoiseOnlyRecords, largest);
}

TEST(TwoHiddenEffects, BothAreNamedInNearlyAllRecordsAndNothingElseEver) {
  int both = 0;
  for (int i = 0; i < kTwoEffectRecords; ++i) {
    const auto index = 200000 + static_cast<std::uint64_t>(i);
    const auto hidden = testing_oven::draw_effects(kSeed, index, 2);
    const auto run = run_record(index, hidden);
    const auto list = named(run.result);
    const std::set<std::string> names(list.begin(), list.end());
    if (names == std::set<std::string>(hidden.begin(), hidden.end())) ++both;
    for (const auto& n : names)
      EXPECT_THAT(hidden, ::testing::Contains(n))
          << ::testing::PrintToString(devices::describe_effects(run.record.effects));
  }
  EXPECT_GE(both, static_cast<int>(std::ceil(kNearlyAll * kTwoEffectRecords))) << both << " of " << kTwoEffectRecords;
  std::printf("[ summary  ] both hidden effects named in %d of %d records\n", both, kTwoEffectRecords);
}

// Without the device file the model's free scale-factor polynomial absorbs a scale factor that
// varies with temperature (there is no device scale factor for it to differ from): those records
// cannot name scale_factor_temperature and are left out of the naming comparison.
TEST(WithoutTheDeviceFile, HiddenEffectsAreNamedAsOftenAsWithItAndNothingWrongIsNamed) {
  const int records = kSingleEffectRecords / 2;
  int with_device = 0, without_device = 0, nameable = 0, shrunk_with = 0, shrunk_without = 0;
  for (int i = 0; i < records; ++i) {
    const auto index = static_cast<std::uint64_t>(i);
    const auto run = run_record(index, testing_oven::draw_effects(kSeed, index, 1));
    const auto& hidden = run.record.hidden.front();
    const auto result = run_without_device(run.record);
    for (const auto& n : named(result)) EXPECT_EQ(n, hidden) << devices::describe_effects(run.record.effects)[0];
    const auto truth_gap = [&](const discrepancy::Result& r) {
      return gap_to_truth(r.model_final_rad_s, run.record.truth_rad_s) /
             gap_to_truth(r.model_initial_rad_s, run.record.truth_rad_s);
    };
    shrunk_with += truth_gap(run.result) <= 0.5;
    shrunk_without += truth_gap(result) <= 0.5;
    if (hidden == "scale_factor_temperature") continue;
    ++nameable;
    with_device += !run.result.steps.empty() && run.result.steps.front().effect == hidden;
    without_device += !result.steps.empty() && result.steps.front().effect == hidden;
  }
  constexpr double kPoints = 0.03;  // the allowance: 3 percentage points
  EXPECT_GE(without_device, with_device - static_cast<int>(std::floor(kPoints * nameable)))
      << without_device << " vs " << with_device << " of " << nameable;
  std::printf(
      "[ summary  ] named first: %d of %d with the device file, %d of %d without (scale-factor records "
      "left out); truth gap halved: %d / %d of %d\n",
      with_device, nameable, without_device, nameable, shrunk_with, shrunk_without, records);
}

TEST(WithoutTheDeviceFile, NothingIsNamedInRecordsWithOnlyColouredNoise) {
  double largest = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < kNoiseOnlyRecords / 2; ++i) {
    const auto record = testing_oven::make_record(fmvmg(false), kSeed, 100000 + static_cast<std::uint64_t>(i), {});
    const auto result = run_without_device(record);
    EXPECT_THAT(named(result), ::testing::IsEmpty()) << "record " << i;
    if (!result.final_scores.empty()) largest = std::max(largest, result.final_scores.front().delta_bic);
  }
  std::printf("[ summary  ] %d noise-only records without the device file: largest delta BIC %.1f\n",
              kNoiseOnlyRecords / 2, largest);
}

// Gauss-Markov bias noise (the bump of a MEMS bias instability: one first-order process of
// correlation time log-uniform in [100, 400] s and std log-uniform in [10, 30] deg/h, on the FMVMG
// file's own small flicker and random walk): a device file that lists it (noise.gauss_markov) puts
// it into the likelihood, and nothing is named on noise-only records; a hidden effect is still named
// first through it. Without the device file the noise is estimated from the residual that the
// candidates leave, and they absorb part of a slow wander: measured, 2 of these 8 records then name
// an effect (docs/methods.md, discrepancy workflow) -- printed here, not asserted.
testing_oven::OvenRecord gauss_markov_record(std::uint64_t index, const std::vector<std::string>& hidden,
                                             devices::DeviceDefinition& device) {
  testing_oven::Draw d(kSeed ^ 0x474D, index);
  device = devices::load_device_file(std::filesystem::path(DRIFTLAB_SOURCE_DIR) / "devices" / "fmvmg.yaml");
  std::erase_if(device.channels, [](const auto& c) { return c.role == role::kDriveFrequency; });
  device.error_model.noise.gauss_markov.push_back(
      {d.log_uniform(100.0, 400.0), d.log_uniform(10.0, 30.0) * kRadPerSecPerDph});
  return testing_oven::make_record(device, kSeed, index, hidden);
}

TEST(GaussMarkovNoise, ADeviceFileThatListsItNamesNothingInNoiseOnlyRecords) {
  double largest_with = -std::numeric_limits<double>::infinity();
  int named_without = 0;
  for (int i = 0; i < kNoiseOnlyRecords / 2; ++i) {
    devices::DeviceDefinition device;
    const auto record = gauss_markov_record(700000 + static_cast<std::uint64_t>(i), {}, device);
    const auto with =
        discrepancy::find_missing_effects(record.series, candidates().list, devices::discrepancy_options(device));
    EXPECT_THAT(named(with), ::testing::IsEmpty()) << "record " << i;
    if (!with.final_scores.empty()) largest_with = std::max(largest_with, with.final_scores.front().delta_bic);
    named_without += !run_without_device(record).steps.empty();
  }
  std::printf(
      "[ summary  ] %d noise-only records with Gauss-Markov bias noise: largest delta BIC %.1f with the device "
      "file listing it; without the device file %d of them name an effect\n",
      kNoiseOnlyRecords / 2, largest_with, named_without);
}

// Without the device file, the noise terms can be read by GMWM with a Gauss-Markov term
// (noise_gmwm "wn+rw+gm") instead of the slope fit: the bias noise then enters the covariance as a
// Gauss-Markov term, not as flicker. Measured on the records above (printed, not asserted): it
// does not remove the false alarms -- 2 of the 8 noise-only records still name an effect, as with
// the slope fit (the candidates absorb part of the wander before the noise is read, and one
// record's wander resembles a dT/dt term even under the fitted Gauss-Markov term) -- and the
// hidden effect is named first in 8 of 9 records. Asserted: the terms are GMWM's (one
// Gauss-Markov term, no flicker) and nothing wrong is named when an effect is hidden.
discrepancy::Options gmwm_options() {
  discrepancy::Options options;
  options.reference_temp_c = fmvmg(false).error_model.reference_temp_c;
  options.noise_gmwm = "wn+rw+gm";
  return options;
}

TEST(GaussMarkovNoise, WithoutTheDeviceFileGmwmReadsOneGaussMarkovTermAndNoFlicker) {
  int named_records = 0;
  for (int i = 0; i < kNoiseOnlyRecords / 2; ++i) {
    devices::DeviceDefinition device;
    const auto record = gauss_markov_record(700000 + static_cast<std::uint64_t>(i), {}, device);
    const auto result = discrepancy::find_missing_effects(record.series, candidates().list, gmwm_options());
    EXPECT_TRUE(result.noise_estimated);
    EXPECT_EQ(result.noise.gauss_markov.size(), 1u) << "record " << i;
    EXPECT_EQ(result.noise.bias_instability_rad_s, 0.0) << "record " << i;
    EXPECT_GT(result.noise.arw_rad_sqrt_s, 0.0) << "record " << i;
    named_records += !result.steps.empty();
  }
  std::printf("[ summary  ] %d noise-only records with Gauss-Markov bias noise, GMWM noise terms: %d name an effect\n",
              kNoiseOnlyRecords / 2, named_records);
}

// Records with Gauss-Markov bias noise and one hidden effect, run with the options `options_of`
// gives for each record's device: nothing but the hidden effect is named (asserted); returns in how
// many the hidden effect is named first.
int hidden_effect_named_first(int records,
                              const std::function<discrepancy::Options(const devices::DeviceDefinition&)>& options_of) {
  int named_first = 0;
  for (int i = 0; i < records; ++i) {
    const auto index = 800000 + static_cast<std::uint64_t>(i);
    devices::DeviceDefinition device;
    const auto hidden = testing_oven::draw_effects(kSeed, index, 1);
    const auto record = gauss_markov_record(index, hidden, device);
    const auto result = discrepancy::find_missing_effects(record.series, candidates().list, options_of(device));
    for (const auto& n : named(result)) EXPECT_EQ(n, hidden.front()) << devices::describe_effects(record.effects)[0];
    named_first += !result.steps.empty() && result.steps.front().effect == hidden.front();
  }
  return named_first;
}

TEST(GaussMarkovNoise, WithoutTheDeviceFileGmwmNoiseTermsNameNothingWrongWhenAnEffectIsHidden) {
  const int records = kSingleEffectRecords / 4;
  const int named_first =
      hidden_effect_named_first(records, [](const devices::DeviceDefinition&) { return gmwm_options(); });
  std::printf(
      "[ summary  ] Gauss-Markov noise, no device file, GMWM noise terms: the hidden effect named first in %d of %d\n",
      named_first, records);
}

TEST(GaussMarkovNoise, HiddenEffectsAreStillNamedThroughIt) {
  const int records = kSingleEffectRecords / 4;
  const int named_first = hidden_effect_named_first(
      records, [](const devices::DeviceDefinition& device) { return devices::discrepancy_options(device); });
  std::printf("[ summary  ] Gauss-Markov noise in the device file: the hidden effect named first in %d of %d\n",
              named_first, records);
  EXPECT_GE(named_first, static_cast<int>(std::ceil(kNearlyAll * records))) << named_first << " of " << records;
}

// Effects outside the library, added to the simulated rate as functions of the resonator
// temperature: the workflow must not name a candidate, and must say which view holds the rest.
void expect_unexplained_in(const std::string& view,
                           const std::function<double(double t, double temp, double rate)>& bias,
                           const std::function<void(const discrepancy::StructureTest&)>& check_view = {}) {
  constexpr int kRecords = 4;
  for (int i = 0; i < kRecords; ++i) {
    const auto device = fmvmg(false);
    auto record = testing_oven::make_record(device, kSeed, 500000 + static_cast<std::uint64_t>(i), {});
    const Eigen::VectorXd& t = record.series.time();
    const Eigen::VectorXd die = record.series.channel(role::kDieTemperature).values;
    const Eigen::VectorXd die_rate = signal::time_derivative(t, die);
    Eigen::VectorXd rate = record.series.channel(role::kRate).values;
    for (Eigen::Index k = 0; k < rate.size(); ++k) rate[k] += bias(t[k], die[k], die_rate[k]);
    record.series.set_channel({role::kRate, "rad/s", "rate with an effect outside the library", rate});
    for (const auto& [label, result] :
         {std::pair{"with the device file", discrepancy::find_missing_effects(record.series, candidates().list,
                                                                              devices::discrepancy_options(device))},
          std::pair{"without it", run_without_device(record)}}) {
      EXPECT_THAT(named(result), ::testing::IsEmpty()) << label << ", record " << i;
      EXPECT_TRUE(result.unexplained.found) << label << ", record " << i;
      EXPECT_EQ(result.unexplained.views.front().view, view)
          << label << ", record " << i << ": " << result.unexplained.views.front().where;
      if (check_view) check_view(result.unexplained.views.front());
      std::printf("[ summary  ] %s, record %d: unexplained in %s (delta BIC %.0f, %.0f deg/h rms): %s\n", label, i,
                  result.unexplained.views.front().view.c_str(), result.unexplained.views.front().delta_bic,
                  result.unexplained.views.front().size_rad_s / kRadPerSecPerDph,
                  result.unexplained.views.front().where.c_str());
    }
  }
}

// A 1000-deg/h step at 20 degC: the bias polynomial absorbs most of it and 8 temperature bins
// cannot follow its edge, so the temperature view's step form finds it (level and size measured:
// 19.9 .. 20.0 degC, 941 .. 1080 deg/h over the 4 records with and without the device file).
TEST(EffectOutsideTheLibrary, ABiasStepAtOneTemperatureIsUnexplainedInTheTemperatureView) {
  // degC: well inside the spacing of the level search (64 equal-count levels, refined between
  // neighbours by golden section); measured 0.01 .. 0.04.
  constexpr double kStepLevel = 0.5;
  constexpr double kStepSize = 0.15;              // relative: the joint fit's size scatters with the noise, -6 .. +8 %
  const double step = 1000.0 * kRadPerSecPerDph;  // above 20 degC
  expect_unexplained_in(
      "temperature", [&](double, double temp, double) { return temp > 20.0 ? step : 0.0; },
      [&](const discrepancy::StructureTest& view) {
        ASSERT_TRUE(view.step.has_value()) << view.where;
        EXPECT_NEAR(view.step->level_c, 20.0, kStepLevel);
        EXPECT_NEAR(view.step->size_rad_s, step, kStepSize * step);
      });
}

TEST(EffectOutsideTheLibrary, ABiasProportionalToTSquaredTimesDtDtIsUnexplainedInTheTemperatureRateView) {
  const double c = 3.0 * kRadPerSecPerDph;  // deg/h per degC^2 K/s: up to ~600 deg/h on the fast legs
  expect_unexplained_in("temperature_rate", [&](double, double temp, double rate) { return c * temp * temp * rate; });
}

TEST(HiddenThermalLag, IsSeenThroughTheDriveFrequencyWhenTheRecordHasIt) {
  constexpr double kFromTheFile = 1e-9;  // ppm/K: the device file's coefficient, reported in ppm
  // With a drive-frequency channel the resonator's own temperature is measured: the lag needs no
  // time constant, and mode_split_drift (0 added parameters) explains it.
  const auto run = run_record(300000, {"thermal_lag"}, true);
  ASSERT_THAT(named(run.result), ::testing::ElementsAre("mode_split_drift"));
  EXPECT_LE(gap_to_truth(run.result.model_final_rad_s, run.record.truth_rad_s),
            0.5 * gap_to_truth(run.result.model_initial_rad_s, run.record.truth_rad_s));
  EXPECT_NEAR(value(run.result.steps.front(), "drive_frequency_tc_ppm_per_k").values[0], -30.0, kFromTheFile);
}

TEST(OneSystematicRate, TheWorkflowsDevicePriorIsTheSimulatorsSystematicRateWithEveryEffectOn) {
  const auto plain = fmvmg(false);
  auto device = plain;
  // Every catalogue effect at a realistic size, in file units (slow enough for 40-s blocks).
  const std::map<std::string, std::vector<double>> file_values{{"thermal_lag", {300}},
                                                               {"temperature_rate", {60}},
                                                               {"hysteresis", {200, 2}},
                                                               {"warmup_transient", {300, 600}},
                                                               {"periodic_disturbance", {100, 1200, 30}},
                                                               {"scale_factor_temperature", {40}}};
  for (const auto& info : effect_catalogue()) {
    std::vector<std::vector<double>> si;
    for (std::size_t i = 0; i < info.keys.size(); ++i)
      si.push_back({file_values.at(info.name)[i] * info.keys[i].to_si});
    error_model::set_effect(device.error_model.effects, info.name, si);
  }
  testing_oven::Draw draw(kSeed, 400000);
  std::array<double, 3> rates{};
  const auto profile = testing_oven::oven_profile(draw, rates);
  devices::SimulationOptions sim_options;
  sim_options.sample_rate_hz = 1.0;
  sim_options.seed = 7;
  const auto sim = devices::simulate(device, profile, sim_options);
  const auto options = devices::discrepancy_options(device);
  const Eigen::VectorXd die =
      signal::first_order_lag(sim.time_s, sim.chamber_temp_c, device.thermal.die_time_constant_s);
  const Eigen::VectorXd prior = options.prior(sim.time_s, die, sim.true_rate_rad_s);
  EXPECT_EQ((prior - sim.systematic_rate_rad_s).cwiseAbs().maxCoeff(), 0.0);  // one function, bit for bit

  // The workflow, given the same device, names nothing and leaves the gap that the same noise
  // realization leaves on the device without effects (each noise term has its own stream).
  const auto result = discrepancy::find_missing_effects(sim.to_time_series(), candidates().list, options);
  EXPECT_THAT(named(result), ::testing::IsEmpty());
  const auto plain_sim = devices::simulate(plain, profile, sim_options);
  const auto noise_only = discrepancy::find_missing_effects(plain_sim.to_time_series(), candidates().list,
                                                            devices::discrepancy_options(plain));
  constexpr double kBlockAveraging = 0.05;  // the prior sees block means of temperature, the data average the rate
  EXPECT_LE(result.gap_final_rad_s, (1.0 + kBlockAveraging) * noise_only.gap_final_rad_s);
}

TEST(DiscrepancyWorkflow, RejectsBadOptionsAndRecordsWithoutTemperature) {
  const auto device = fmvmg(false);
  TimeSeries record(Eigen::VectorXd::LinSpaced(100, 0.0, 99.0));
  record.set_channel({role::kRate, "rad/s", "rate_dps", Eigen::VectorXd::Zero(100)});
  auto options = devices::discrepancy_options(device);
  EXPECT_THROW(discrepancy::find_missing_effects(record, candidates().list, options), DataError);
  record.set_channel({role::kTemperature, "degC", "temp_c", Eigen::VectorXd::LinSpaced(100, 0.0, 10.0)});
  options.bias_degree = 9;
  EXPECT_THROW(discrepancy::find_missing_effects(record, candidates().list, options), ConfigError);
}

// ---- building blocks -------------------------------------------------------------------------

TEST(Blocks, AverageEachTimeSpanAndDropEmptyOnesInGaps) {
  Eigen::VectorXd t(8), x(8);
  t << 0, 1, 2, 3, 20, 21, 22, 23;
  x << 1, 2, 3, 4, 10, 20, 30, 40;
  const auto b = discrepancy::make_blocks(TimeSeries(t), 2.0);
  ASSERT_EQ(b.size(), 4);
  EXPECT_THAT(b.count, ::testing::ElementsAre(2, 2, 2, 2));
  const Eigen::VectorXd m = discrepancy::block_means(b, x);
  EXPECT_THAT(std::vector<double>(m.data(), m.data() + m.size()), ::testing::ElementsAre(1.5, 3.5, 15.0, 35.0));
  EXPECT_DOUBLE_EQ(b.start_s[2], 20.0);
  EXPECT_DOUBLE_EQ(b.end_s[2], 22.0);  // two samples of dt = 1 s
  const Eigen::VectorXd at = discrepancy::interpolate(b, m, Eigen::Vector3d(-5.0, 1.5, 100.0));
  EXPECT_DOUBLE_EQ(at[0], 1.5);
  EXPECT_DOUBLE_EQ(at[2], 35.0);
}

TEST(NoiseCovariance, MatchesTheSampleCovarianceOfSimulatedBlockMeans) {
  // 400 realizations of 1 h at 1 Hz with N, B and K all on; blocks of 120 s.
  error_model::NoiseTerms noise;
  noise.arw_rad_sqrt_s = 5e-4;
  noise.bias_instability_rad_s = 1.5e-4;
  noise.rate_random_walk_rad_s_sqrt_s = 2e-6;
  const int realizations = 400, n = 3600;
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(n, 0.0, n - 1.0);
  const auto blocks = discrepancy::make_blocks(TimeSeries(t), 120.0);
  const Eigen::MatrixXd model = discrepancy::noise_covariance(blocks, noise);
  Eigen::MatrixXd sample = Eigen::MatrixXd::Zero(blocks.size(), blocks.size());
  for (int r = 0; r < realizations; ++r) {
    const Eigen::VectorXd m =
        discrepancy::block_means(blocks, error_model::rate_noise(noise, 1.0, n, 77 + static_cast<std::uint64_t>(r)));
    sample += m * m.transpose() / realizations;
  }
  // Sample (co)variances of 400 draws scatter by about sqrt(2/400) = 7 % of the variance.
  constexpr double kSamplingTolerance = 0.25;
  for (Eigen::Index i : {0, 7, 15, 29}) {
    EXPECT_NEAR(sample(i, i), model(i, i), kSamplingTolerance * model(i, i)) << "block " << i;
    if (i + 1 < blocks.size()) {
      EXPECT_NEAR(sample(i, i + 1), model(i, i + 1), kSamplingTolerance * model(i, i))
          << "blocks " << i << ", " << i + 1;
    }
  }
  EXPECT_NEAR(sample(0, 29), model(0, 29), kSamplingTolerance * model(0, 0));
}

TEST(NoiseAllanDeviation, FollowsTheIeee952ClosedForms) {
  constexpr double kClosedForm = 1e-15;  // rad/s on values of 1e-5 .. 1e-3: rounding (1e-12 relative at worst)
  error_model::NoiseTerms white, walk, flicker;
  white.arw_rad_sqrt_s = 1e-3;
  walk.rate_random_walk_rad_s_sqrt_s = 1e-5;
  flicker.bias_instability_rad_s = 1e-4;
  for (double tau : {1.0, 10.0, 100.0}) {
    EXPECT_NEAR(discrepancy::model_allan_deviation(white, tau), 1e-3 / std::sqrt(tau), kClosedForm);
    EXPECT_NEAR(discrepancy::model_allan_deviation(walk, tau), 1e-5 * std::sqrt(tau / 3.0), kClosedForm);
  }
  // Flicker floor 0.664 B within +-5 % for tau in [10 tau_min, tau_max / 3] (Gauss-Markov sum with
  // 2 poles per decade over [0.5, 5000] s; the continuous-time average rolls off below 10 tau_min).
  constexpr double kFlickerFloorTolerance = 0.05;
  for (double tau : {5.0, 100.0, 1600.0})
    EXPECT_NEAR(discrepancy::model_allan_deviation(flicker, tau), 0.664 * 1e-4, kFlickerFloorTolerance * 0.664e-4)
        << tau;
}

TEST(ResidualViews, SeparateHeatingFromCoolingAndFindTheSinusoid) {
  // rad/s, 10 % of the amplitude: the sinusoid is fitted at the nearest line (span / 12 = 599 s)
  // beside the leg step's harmonics; measured 2e-8.
  constexpr double kPeakAmplitude = 6e-6;
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(720, 0.0, 719.0 * 10.0);
  Eigen::VectorXd temp(t.size()), residual(t.size());
  for (Eigen::Index k = 0; k < t.size(); ++k) {
    temp[k] = k < 360 ? 0.02 * t[k] : 0.02 * (7190.0 - t[k]);
    residual[k] = (k < 360 ? -1e-4 : 1e-4) + 6e-5 * std::sin(2.0 * std::numbers::pi * t[k] / 600.0);
  }
  const auto blocks = discrepancy::make_blocks(TimeSeries(t), 10.0);
  const auto v = discrepancy::residual_views(blocks, temp, residual, residual, error_model::NoiseTerms{}, 6);
  constexpr double kSinusoidAverage = 1e-5;  // the sinusoid averages out over each leg within this
  EXPECT_NEAR(v.heating.mean_rad_s, -1e-4, kSinusoidAverage);
  EXPECT_NEAR(v.cooling.mean_rad_s, 1e-4, kSinusoidAverage);
  EXPECT_EQ(v.heating_by_temperature.size(), 6u);
  // The leg step is the largest line (its fundamental, 4/pi x 1e-4); the sinusoid is among the peaks.
  const auto peak =
      std::find_if(v.peaks.begin(), v.peaks.end(), [](const auto& p) { return std::abs(p.period_s - 600.0) < 12.0; });
  ASSERT_NE(peak, v.peaks.end());
  EXPECT_NEAR(peak->amplitude_rad_s, 6e-5, kPeakAmplitude);
  EXPECT_FALSE(v.allan.empty());
}

}  // namespace
}  // namespace driftlab
