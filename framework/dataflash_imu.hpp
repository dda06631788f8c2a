// From an ArduPilot DataFlash log (framework/dataflash.hpp) to the IMU record (framework/imu.hpp):
// the thin adapter between the pure parser and the record every command reads.
//
// Messages (ArduPilot's AP_InertialSensor logging; units as ArduPilot logs them, which are the
// record's internal units):
//   IMU   TimeUS (us), I (instance), GyrX GyrY GyrZ (rad/s), AccX AccY AccZ (m/s^2), T (degC): one
//         gyro and one accelerometer stream per value of I (gyro_x, gyro1_x, accel1_z, ...); both
//         share the message's time stamp.
//   IMU2, IMU3  older logs (IMU without an I column): instances 1 and 2, IMU is instance 0; the
//         oldest logs time them in TimeMS (ms).
// Not read: GYR / ACC (raw high-rate logging) and ISBH / ISBD (batch sampler): they carry no
// temperature. TCLR (the firmware's temperature-calibration learning) is listed by `driftlab log
// info`, not made a record.
//
// Device ids: the parameters INS_GYR_ID, INS_GYR2_ID, INS_GYR3_ID (gyros of instances 0, 1, 2) and
// INS_ACC_ID, INS_ACC2_ID, INS_ACC3_ID, as first logged (at boot), in decimal; 0 (or anything but a
// whole number 1 .. 2^32-1) means none; a later change is noted. Instances above 2 get none.
//
// Temperature calibration. ArduPilot corrects each IMU instance n-1 with INS_TCALn (n = 1..3) when
// INS_TCALn_ENABLE is 1 (AP_InertialSensor_tempcal.cpp, correct_sensor): per axis,
//     corrected = raw - P(clamp(T) - 35) + P(clamp(T_cal) - 35),
//     P(d) = (c1 d + c2 d^2 + c3 d^3) * 1e-6,  clamp to [INS_TCALn_TMIN, INS_TCALn_TMAX] (degC),
// ck = INS_TCALn_GYRk_X/_Y/_Z (rad/s per degC^k x 1e6) for the gyro and INS_TCALn_ACCk_* for the
// accelerometer, T the IMU temperature, T_cal = INS_GYRn_CALTEMP / INS_ACCn_CALTEMP (the temperature
// of the offset calibration; -300 when never calibrated, which the clamp makes TMIN, as in the
// firmware). A log recorded with the correction on holds corrected values; the record holds the
// raw ones, as ArduPilot's Tools/scripts/tempcal_IMU.py computes them before fitting:
//     raw = logged + P(clamp(T) - 35) - P(clamp(T_cal) - 35),
// in the sensor frame (below), with the parameters as first logged (ENABLE takes effect at boot; a
// later change of any of them is noted, not applied), and a note per instance. Like tempcal_IMU.py
// this leaves the accelerometer scale factors (INS_ACCSCAL*, within about 1e-3 of 1) and the
// firmware's low-pass filter out of the inversion. Without a temperature column, or with a
// parameter missing, the values stay as logged, corrected, and a note says so.
//
// Board orientation (AHRS_ORIENTATION). ArduPilot logs GyrX..Z / AccX..Z in the vehicle's body
// frame: AP_InertialSensor_Backend::_rotate_and_correct_gyro / _accel apply the temperature
// correction and the offsets in the sensor frame and rotate by AHRS_ORIENTATION last, and
// Write_IMU_instance (AP_InertialSensor_Logging.cpp) logs that published value. The record holds
// the sensor frame -- the frame a gyro's drift belongs to and INS_TCAL is defined in: for
// AHRS_ORIENTATION 1..43 every sample is rotated back, sensor = R^T body, as tempcal_IMU.py does,
// with a note. R (body = R sensor) is ArduPilot's enum Rotation (AP_Math/rotations.h) with the
// roll, pitch, yaw of the firmware's own test (AP_Math/tests/test_rotations.cpp, TestEulers) and
// R = Rz(yaw) Ry(pitch) Rx(roll) (Matrix3::from_euler); multiples of 90 deg are exact. Rotation 38
// is (90, 68.8, 293.3) deg as in the firmware (pymavlink's table, which tempcal_IMU.py uses, has
// (90, 68, 270) and ends at 41). Any other value -- 100 and 101 are custom rotations set by
// CUST_ROTn_* parameters -- is a DataError naming AHRS_ORIENTATION: the values cannot be put back
// into the sensor frame. The value first logged is used; a later change is noted.
//
// Repairs and errors shared with the other log readers (time base, sorting, duplicates,
// non-finite values): framework/imu_streams.hpp. Errors of this adapter (DataError naming the file):
// no IMU messages (the message names unknown types and truncation when the log had them), an IMU
// message without the columns above, an AHRS_ORIENTATION that is no fixed rotation, an instance
// value that is not an integer 0..255, INS_TCAL
// parameters whose removal makes a value non-finite or beyond kMaxMagnitude (csv.hpp); --topic
// other than "" or IMU is a ConfigError.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "framework/dataflash.hpp"
#include "framework/imu.hpp"
#include "framework/record_reader.hpp"
#include "framework/time_series.hpp"

namespace driftlab::dataflash {

// The message types imu_record reads: pass them as ReadOptions::keep_types.
const std::vector<std::string>& imu_types();

// "INS_GYR_ID", "INS_ACC2_ID", ...: the parameter holding the device id of a sensor of an instance.
std::string device_id_parameter(imu::Sensor sensor, int instance);
// Its value as first logged, when it is a device id (see above); nullopt otherwise.
std::optional<std::uint32_t> device_id(const Log& log, imu::Sensor sensor, int instance);

// INS_TCALn of one IMU instance (n = instance + 1), as first logged.
struct TemperatureCalibration {
  int instance = 0;
  double enable = 0.0;                                   // INS_TCALn_ENABLE: 0 off, 1 on, 2 learning
  double tmin = 0.0, tmax = 0.0;                         // degC
  std::array<std::array<double, 3>, 3> gyro{}, accel{};  // [order - 1][axis x y z], as logged (x 1e6)
  double gyro_cal_temp = 0.0, accel_cal_temp = 0.0;      // INS_GYRn_CALTEMP, INS_ACCn_CALTEMP (degC)
};
// The instance's set, or nullopt when the log lacks INS_TCALn_ENABLE or (with ENABLE = 1) any
// parameter the correction needs (`missing`, when given, receives the first such name).
std::optional<TemperatureCalibration> temperature_calibration(const Log& log, int instance,
                                                              std::string* missing = nullptr);
// What the firmware subtracted from `axis` (0..2) of `sensor` at IMU temperature `temperature`:
// P(clamp(T) - 35) - P(clamp(T_cal) - 35), in rad/s or m/s^2.
double firmware_correction(const TemperatureCalibration& tcal, imu::Sensor sensor, int axis, double temperature);

// The board rotation of an AHRS_ORIENTATION value (see above), or nullopt for a value that is not
// one of ArduPilot's fixed rotations 0..43.
struct BoardRotation {
  std::string name;                                         // "ROTATION_ROLL_180"
  std::array<std::array<double, 3>, 3> body_from_sensor{};  // R: body = R sensor
};
std::optional<BoardRotation> board_rotation(double ahrs_orientation);

// The IMU record of a parsed log (its imu_types kept). `selection.topic` is "" or "IMU" (anything
// else: ConfigError naming --topic); `selection.instance` and `selection.sensor` as for every log.
TimeSeries imu_record(const Log& log, const LogSelection& selection, std::vector<std::string>* notes = nullptr);

// read() with imu_types kept, then imu_record.
TimeSeries read_imu(const std::filesystem::path& path, const LogSelection& selection,
                    std::vector<std::string>* notes = nullptr);

}  // namespace driftlab::dataflash
