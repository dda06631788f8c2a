// Whole-IMU records from CSV: header styles people log, units, instances, and the errors for a
// role given twice or a column claimed twice (framework/imu.hpp, framework/csv.hpp).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/imu.hpp"
#include "framework/units.hpp"

namespace driftlab {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

constexpr double kConversionTolerance = 1e-12;  // one or two double roundings

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(ImuNames, RolesRoundTrip) {
  for (const auto sensor : {imu::Sensor::Gyro, imu::Sensor::Accel})
    for (const char axis : {'x', 'y', 'z'})
      for (const int instance : {0, 1, 2}) {
        const imu::ChannelId id{sensor, axis, instance};
        const auto back = imu::parse_role(id.role());
        ASSERT_TRUE(back.has_value()) << id.role();
        EXPECT_EQ(*back, id);
        EXPECT_EQ(imu::parse_role(imu::truth_role(id), "true_"), id);
      }
  EXPECT_FALSE(imu::parse_role("rate"));
  EXPECT_FALSE(imu::parse_role("gyro0_x"));  // instance 0 has no digit
  EXPECT_EQ(imu::parse_temperature_role("temperature2"), 2);
}

TEST(ImuNames, RecognisesCommonHeaderStyles) {
  struct Case {
    const char* header;
    const char* role;
    const char* unit;
  };
  const Case cases[] = {
      {"gyro_x", "gyro_x", "rad/s"},     {"gx", "gyro_x", "rad/s"},           {"GyrX", "gyro_x", "rad/s"},
      {"GyrZ_1", "gyro1_z", "rad/s"},    {"gyro1_y", "gyro1_y", "rad/s"},     {"gyro_x_dps", "gyro_x", "deg/s"},
      {"gyro_z_mdps", "gyro_z", "mdps"}, {"gyr_y_rad_s", "gyro_y", "rad/s"},  {"accel_z", "accel_z", "m/s^2"},
      {"acc_x", "accel_x", "m/s^2"},     {"AccY", "accel_y", "m/s^2"},        {"ax", "accel_x", "m/s^2"},
      {"accel_z_g", "accel_z", "g"},     {"acc_2_x_mg", "accel2_x", "mg"},    {"accel_x_mps2", "accel_x", "m/s^2"},
      {"temp", "temperature", "degC"},   {"temp_c", "temperature", "degC"},   {"T", "temperature", "degC"},
      {"temp1", "temperature1", "degC"}, {"imu2_temp_k", "temperature2", "K"}};
  for (const auto& c : cases) {
    const auto m = imu::recognize_imu_column(c.header);
    ASSERT_TRUE(m.has_value()) << c.header;
    EXPECT_EQ(m->role, c.role) << c.header;
    EXPECT_EQ(m->unit, c.unit) << c.header;
  }
  for (const char* other : {"t", "rate_dps", "max", "gyro_x1_2", "g", "axis", "gyro1_x_2"})
    EXPECT_FALSE(imu::recognize_imu_column(other).has_value()) << other;
}

TEST(ImuNames, SelectionBySensorInstanceAndChannel) {
  const auto gyro = imu::parse_selection("gyro", "--channels");
  EXPECT_TRUE(gyro.selects({imu::Sensor::Gyro, 'x', 1}));
  EXPECT_FALSE(gyro.selects({imu::Sensor::Accel, 'x', 0}));
  const auto some = imu::parse_selection("gyro_x,accel1_z", "--channels");
  EXPECT_TRUE(some.selects({imu::Sensor::Gyro, 'x', 0}));
  EXPECT_FALSE(some.selects({imu::Sensor::Gyro, 'x', 1}));
  EXPECT_TRUE(some.selects({imu::Sensor::Accel, 'z', 1}));
  EXPECT_THAT(error_of([] { imu::parse_selection("gyro,magnetometer", "--channels"); }),
              AllOf(HasSubstr("--channels"), HasSubstr("magnetometer")));
}

TEST(ImuCsv, ReadsAThreeAxisOvenRecordWithoutAMapping) {
  const std::string text =
      "time_us,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,temp\n"
      "1000000,0.01,0.02,0.03,0.1,0.2,9.8,25.5\n"
      "1010000,0.011,0.021,0.031,0.11,0.21,9.81,25.6\n"
      "1020000,0.012,0.022,0.032,0.12,0.22,9.82,25.7\n";
  CsvReadOptions options;
  options.required_roles = {};
  const auto r = parse_csv(text, "imu.csv", options);
  ASSERT_EQ(r.size(), 3);
  EXPECT_NEAR(r.time()[1], 1.01, kConversionTolerance);
  EXPECT_NEAR(r.channel("gyro_y").values[2], 0.022, kConversionTolerance);
  EXPECT_EQ(r.channel("gyro_y").source, "gyro_y");
  EXPECT_EQ(r.channel("accel_z").unit, "m/s^2");
  EXPECT_EQ(r.channel("accel_z").read_unit, "m/s^2");
  EXPECT_NEAR(r.channel("temperature").values[0], 25.5, kConversionTolerance);
  EXPECT_EQ(r.channels().size(), 7u);
}

TEST(ImuCsv, ConvertsTheUnitsPeopleLogIn) {
  const std::string text =
      "time_ms,gx,ax,temp_k\n"
      "0,1000,1000,300\n"
      "10,2000,-500,301\n";
  CsvReadOptions options;
  options.required_roles = {};
  options.columns = {parse_column_mapping("time=time_ms:ms"), parse_column_mapping("gyro_x=gx:lsb*0.061:mdps"),
                     parse_column_mapping("accel_x=ax:mg"), parse_column_mapping("temperature=temp_k:K")};
  const auto r = parse_csv(text, "raw.csv", options);
  EXPECT_NEAR(r.time()[1], 0.01, kConversionTolerance);
  EXPECT_NEAR(r.channel("gyro_x").values[0], 1000 * 0.061e-3 * kRadPerDeg, kConversionTolerance);
  EXPECT_EQ(r.channel("gyro_x").read_unit, "0.061*mdeg/s");
  EXPECT_NEAR(r.channel("accel_x").values[1], -0.5 * kStandardGravity, kConversionTolerance);
  EXPECT_NEAR(r.channel("temperature").values[1], 301 - 273.15, kConversionTolerance);
}

TEST(ImuCsv, ARoleGivenTwiceIsAnErrorNamingBothColumns) {
  const std::string text = "t_s,gyro_x,gx,temp\n0,1,1,20\n1,1,1,20\n";
  CsvReadOptions options;
  options.required_roles = {};
  EXPECT_THAT(error_of([&] { parse_csv(text, "two.csv", options); }),
              AllOf(HasSubstr("two.csv"), HasSubstr("gyro_x"), HasSubstr("'gx'"), HasSubstr("two columns")));
  options.columns = {parse_column_mapping("rate=gyro_x:rad/s"), parse_column_mapping("rate=gx:rad/s")};
  EXPECT_THAT(error_of([&] { parse_csv(text, "two.csv", options); }),
              AllOf(HasSubstr("'gyro_x'"), HasSubstr("'gx'"), HasSubstr("rate")));
  options.columns = {parse_column_mapping("gyro_x=gx:rad/s"), parse_column_mapping("gyro_y=gx:rad/s")};
  EXPECT_THAT(error_of([&] { parse_csv(text, "two.csv", options); }),
              AllOf(HasSubstr("'gx'"), HasSubstr("gyro_x"), HasSubstr("gyro_y")));
}

TEST(ImuCsv, AUnitOfTheWrongDimensionIsRefused) {
  EXPECT_THAT(error_of([] { parse_column_mapping("accel_x=ax:deg/s"); }),
              AllOf(HasSubstr("deg/s"), HasSubstr("acceleration")));
  EXPECT_THAT(error_of([] { parse_column_mapping("gyro_x=gx:lsb*-1:mdps"); }), HasSubstr("unknown unit"));
}

}  // namespace
}  // namespace driftlab
