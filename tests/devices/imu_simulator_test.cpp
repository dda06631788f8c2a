#include "devices/imu_simulator.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "devices/device_file.hpp"
#include "framework/units.hpp"
#include "models/allan/confidence.hpp"
#include "tests/devices/simulation_fixtures.hpp"

namespace driftlab::devices {
namespace {

const std::string kImu3 = std::string(DRIFTLAB_SOURCE_DIR) + "/devices/imu3.yaml";

ImuDefinition imu3() { return *load_device_file(kImu3).imu; }

using testing::options;
using testing::static_at;

const ImuAxisRecord& axis_of(const ImuInstanceRecord& r, bool gyro, std::size_t a) {
  return gyro ? r.gyro[a] : r.accel[a];
}
const ImuAxis& axis_of(const ImuInstance& spec, bool gyro, std::size_t a) {
  return gyro ? spec.gyro.axes[a] : spec.accel.axes[a];
}

TEST(ImuSimulator, WritesEveryAxisOfEveryInstance) {
  const auto record = simulate_imu(imu3(), default_oven_profile(), options(1.0, 600.0, 1));
  ASSERT_EQ(record.instances.size(), 2u);
  for (const auto& instance : record.instances) {
    EXPECT_EQ(instance.temp_c.size(), 600);
    for (bool gyro : {true, false})
      for (std::size_t a = 0; a < 3; ++a) {
        EXPECT_EQ(axis_of(instance, gyro, a).measured.size(), 600);
        EXPECT_EQ(axis_of(instance, gyro, a).truth.size(), 600);
        EXPECT_EQ(axis_of(instance, gyro, a).systematic.size(), 600);
      }
  }
}

TEST(ImuSimulator, MeasuredMinusSystematicHasTheStatedNoiseOnEveryAxis) {
  // Allan deviation of the noise at tau = 1 s: N^2/tau from the white part, plus at most
  // (0.664 B)^2 + K^2 tau/3 (error_model.hpp; the flicker floor rolls off below 2 tau_min = 1 s, so
  // B adds somewhat less than its floor here). The interval must reach into [N, that bound].
  // Twelve channels are checked, so the interval is a wide one: at 68 % about four would miss.
  constexpr double kConfidence = 0.99;
  constexpr double kFs = 10.0;
  const ImuDefinition imu = imu3();
  const auto record = simulate_imu(imu, static_at(25.0), options(kFs, kSecondsPerHour, 11));
  const std::vector<std::size_t> one_second{static_cast<std::size_t>(kFs)};
  for (std::size_t i = 0; i < imu.instances.size(); ++i)
    for (bool gyro : {true, false})
      for (std::size_t a = 0; a < 3; ++a) {
        const auto& r = axis_of(record.instances[i], gyro, a);
        const auto& n = axis_of(imu.instances[i], gyro, a).noise;
        const Eigen::VectorXd noise = r.measured - r.systematic;
        const auto estimate = allan::estimate(allan::Kind::Oadev, allan::angle_from_rate(noise, 1.0 / kFs), 1.0 / kFs,
                                              allan::InputType::Rate, one_second, kConfidence)
                                  .front();
        const double white = n.arw_rad_sqrt_s;
        const double with_floors = std::sqrt(white * white + std::pow(0.664 * n.bias_instability_rad_s, 2) +
                                             n.rate_random_walk_rad_s_sqrt_s * n.rate_random_walk_rad_s_sqrt_s / 3.0);
        EXPECT_GE(estimate.dev_hi, white) << "instance " << i << (gyro ? " gyro " : " accel ") << "xyz"[a];
        EXPECT_LE(estimate.dev_lo, with_floors) << "instance " << i << (gyro ? " gyro " : " accel ") << "xyz"[a];
      }
}

TEST(ImuSimulator, SystematicIsTheAxisModelAppliedToTheTruth) {
  // A chamber held at 45 degC: every lag starts in equilibrium, so each axis sits at 45 degC.
  constexpr double kTemp = 45.0;
  constexpr double kRoundOff = 1e-12;  // relative: one polynomial evaluation in double
  const ImuDefinition imu = imu3();
  const auto record = simulate_imu(imu, static_at(kTemp), options(1.0, 60.0, 1));
  const double x = kTemp - imu.reference_temp_c;
  for (std::size_t i = 0; i < imu.instances.size(); ++i)
    for (bool gyro : {true, false})
      for (std::size_t a = 0; a < 3; ++a) {
        const auto& spec = axis_of(imu.instances[i], gyro, a);
        const auto& r = axis_of(record.instances[i], gyro, a);
        const double scale = 1.0 + x * error_model::polynomial(spec.scale_factor_polynomial, x);
        const double expected = scale * r.truth[30] + error_model::polynomial(spec.bias_polynomial, x);
        EXPECT_NEAR(r.systematic[30], expected, kRoundOff * std::abs(expected));
      }
}

TEST(ImuSimulator, AccelerometerTruthIsGravityAlongTheUpDirection) {
  const auto record = simulate_imu(imu3(), static_at(25.0), options(1.0, 10.0, 1));
  for (const auto& instance : record.instances) {
    EXPECT_EQ(instance.accel[0].truth, Eigen::VectorXd::Zero(10));
    EXPECT_EQ(instance.accel[1].truth, Eigen::VectorXd::Zero(10));
    EXPECT_EQ(instance.accel[2].truth, Eigen::VectorXd::Constant(10, kStandardGravity));
  }

  ImuDefinition tilted = imu3();
  tilted.up = Eigen::Vector3d(1.0, 0.0, 1.0).normalized();
  const auto t = simulate_imu(tilted, static_at(25.0), options(1.0, 10.0, 1));
  constexpr double kRoundOff = 1e-15;  // m/s^2
  EXPECT_NEAR(t.instances[0].accel[0].truth[5], kStandardGravity / std::sqrt(2.0), kRoundOff);
  EXPECT_EQ(t.instances[0].accel[1].truth[5], 0.0);
  EXPECT_NEAR(t.instances[0].accel[2].truth[5], kStandardGravity / std::sqrt(2.0), kRoundOff);
}

TEST(ImuSimulator, RateTableTurnsAboutTheUpDirection) {
  SimulationProfile profile = static_at(25.0);
  profile.true_rate = Profile(0.0).hold(10.0).ramp_to(50.0 * kRadPerDeg, 0.0).hold(10.0);
  const auto record = simulate_imu(imu3(), profile, options(1.0, 20.0, 1));
  const auto& gyro = record.instances[1].gyro;
  EXPECT_EQ(gyro[0].truth[15], 0.0);
  EXPECT_EQ(gyro[1].truth[15], 0.0);
  EXPECT_DOUBLE_EQ(gyro[2].truth[15], 50.0 * kRadPerDeg);
  EXPECT_EQ(gyro[2].truth[5], 0.0);
}

TEST(ImuSimulator, AnOrientationScheduleCyclesTheUpDirectionThroughGravityAndTheTableRate) {
  // The normalised up direction (0, 0.6, 0.8) times g or the table rate: rounding, about an ulp
  // (ulp(0.6 g) = 8.9e-16).
  constexpr double kNormalised = 1e-15;
  SimulationProfile profile = parse_profile(
      "format: driftlab-profile/1\n"
      "rate: {start_dps: 30}\n"
      "orientation: {dwell_s: 2, up_directions: [[0, 0, 1], [-1, 0, 0], [0, 3, 4]]}\n",
      "six.yaml");
  profile.chamber_c = Profile(25.0).hold(20.0);
  const auto record = simulate_imu(imu3(), profile, options(1.0, 8.0, 1));
  const double g = kStandardGravity, w = 30.0 * kRadPerDeg;
  const auto& accel = record.instances[0].accel;
  const auto& gyro = record.instances[1].gyro;
  // t = 0, 1: z up; 2, 3: x down; 4, 5: (0, 0.6, 0.8) up; 6, 7: z up again.
  EXPECT_EQ(accel[2].truth[1], g);
  EXPECT_EQ(accel[0].truth[1], 0.0);
  EXPECT_EQ(accel[0].truth[2], -g);
  EXPECT_EQ(gyro[0].truth[3], -w);
  EXPECT_EQ(gyro[2].truth[3], 0.0);
  EXPECT_NEAR(accel[1].truth[4], 0.6 * g, kNormalised);
  EXPECT_NEAR(gyro[2].truth[5], 0.8 * w, kNormalised);
  EXPECT_EQ(accel[2].truth[6], g);
}

TEST(ImuSimulator, ABadOrientationScheduleIsRefusedWithItsLineAndTheSingleAxisSimulatorRefusesOne) {
  const auto problems_of = [](const std::string& orientation) {
    try {
      parse_profile("format: driftlab-profile/1\norientation: " + orientation + "\n", "p.yaml");
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_THAT(problems_of("{dwell_s: 0, up_directions: [[0, 0, 1]]}"), ::testing::HasSubstr("dwell_s"));
  EXPECT_THAT(problems_of("{dwell_s: 5, up_directions: [[0, 0, 0]]}"),
              ::testing::AllOf(::testing::HasSubstr("p.yaml:2"), ::testing::HasSubstr("up_directions[0]"),
                               ::testing::HasSubstr("not all zero")));
  EXPECT_THAT(problems_of("{dwell_s: 5, up_directions: [[0, 1]]}"), ::testing::HasSubstr("[x, y, z]"));
  EXPECT_THAT(problems_of("{dwell_s: 5, up_directions: []}"), ::testing::HasSubstr("up_directions"));
  EXPECT_THAT(problems_of("{dwell_s: 5}"), ::testing::HasSubstr("up_directions"));
  EXPECT_THAT(problems_of("{dwell_s: 5, up_directions: [[0, 0, 1]], spin: 1}"), ::testing::HasSubstr("spin"));

  SimulationProfile profile =
      parse_profile("format: driftlab-profile/1\norientation: {dwell_s: 5, up_directions: [[0, 0, 1]]}\n", "p.yaml");
  EXPECT_THROW(simulate(load_device_file(std::string(DRIFTLAB_SOURCE_DIR) + "/devices/fmvmg.yaml"), profile,
                        options(1.0, 10.0, 1)),
               ConfigError);
}

TEST(ImuSimulator, InstancesHaveTheirOwnTemperaturesBiasesAndNoise) {
  const auto record = simulate_imu(imu3(), default_oven_profile(), options(1.0, kSecondsPerHour, 3));
  const auto& a = record.instances[0];
  const auto& b = record.instances[1];
  // During the ramp the slower die (420 s against 240 s) stays further behind the chamber.
  constexpr Eigen::Index kOnTheRamp = 3000;
  EXPECT_GT(a.die_temp_c[kOnTheRamp], b.die_temp_c[kOnTheRamp] + 1.0);
  EXPECT_GT(std::abs(a.temp_c[kOnTheRamp] - b.temp_c[kOnTheRamp]), 1.0);
  EXPECT_NE(a.gyro[0].systematic, b.gyro[0].systematic);
  // Independent noise: the sample correlation of the two instances' gyro x noise steps (first
  // differences: the white part, free of the slow flicker and random walk) has a standard deviation
  // of about sqrt(1.5 / n) = 0.02 for n = 3600 (differencing makes each an MA(1) series).
  constexpr double kMaxCorrelation = 0.08;  // 4 standard deviations
  const Eigen::VectorXd na = a.gyro[0].measured - a.gyro[0].systematic;
  const Eigen::VectorXd nb = b.gyro[0].measured - b.gyro[0].systematic;
  const Eigen::Index n = na.size();
  const Eigen::VectorXd da = na.tail(n - 1) - na.head(n - 1), db = nb.tail(n - 1) - nb.head(n - 1);
  const Eigen::VectorXd ca = da.array() - da.mean(), cb = db.array() - db.mean();
  EXPECT_LT(std::abs(ca.dot(cb) / (ca.norm() * cb.norm())), kMaxCorrelation);
}

TEST(ImuSimulator, SameSeedSameRecordAnotherSeedOtherNoiseOnly) {
  const ImuDefinition imu = imu3();
  const auto a = simulate_imu(imu, default_oven_profile(), options(2.0, 1200.0, 7));
  const auto b = simulate_imu(imu, default_oven_profile(), options(2.0, 1200.0, 7));
  const auto c = simulate_imu(imu, default_oven_profile(), options(2.0, 1200.0, 8));
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(a.instances[i].temp_c, b.instances[i].temp_c);
    for (bool gyro : {true, false})
      for (std::size_t k = 0; k < 3; ++k) {
        EXPECT_EQ(axis_of(a.instances[i], gyro, k).measured, axis_of(b.instances[i], gyro, k).measured);
        EXPECT_EQ(axis_of(a.instances[i], gyro, k).systematic, axis_of(c.instances[i], gyro, k).systematic);
        EXPECT_NE(axis_of(a.instances[i], gyro, k).measured, axis_of(c.instances[i], gyro, k).measured);
      }
  }
}

TEST(ImuSimulator, EachNoiseStreamIsIndependentOfWhatElseTheFileDescribes) {
  const ImuDefinition full = imu3();
  ImuDefinition reduced = full;
  reduced.instances.pop_back();                                         // no second instance
  reduced.instances[0].gyro.axes[0].noise = error_model::NoiseTerms{};  // a quiet gyro x
  const auto a = simulate_imu(full, default_oven_profile(), options(2.0, 600.0, 5));
  const auto b = simulate_imu(reduced, default_oven_profile(), options(2.0, 600.0, 5));
  ASSERT_EQ(b.instances.size(), 1u);
  EXPECT_EQ(a.instances[0].gyro[1].measured, b.instances[0].gyro[1].measured);
  EXPECT_EQ(a.instances[0].accel[2].measured, b.instances[0].accel[2].measured);
  EXPECT_EQ(a.instances[0].temp_c, b.instances[0].temp_c);
  EXPECT_EQ(b.instances[0].gyro[0].measured, b.instances[0].gyro[0].systematic);
}

TEST(ImuSimulator, TheSingleAxisSimulatorRefusesAWholeImuNamingTheFile) {
  try {
    simulate(load_device_file(kImu3), static_at(25.0), options(1.0, 10.0, 1));
    FAIL() << "a whole IMU was simulated as a single axis";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.problems().front().where.file, kImu3);
    EXPECT_EQ(e.problems().front().where.field, "imu");
    EXPECT_THAT(e.what(), ::testing::HasSubstr("whole IMU"));
  }
}

}  // namespace
}  // namespace driftlab::devices
