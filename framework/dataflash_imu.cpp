#include "framework/dataflash_imu.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <map>
#include <numbers>
#include <utility>

#include "framework/csv.hpp"
#include "framework/error.hpp"
#include "framework/imu_streams.hpp"

namespace driftlab::dataflash {
namespace {

constexpr double kReferenceTemperature = 35.0;  // degC, TEMP_REFERENCE of AP_InertialSensor_tempcal.cpp
constexpr double kCoefficientScale = 1e-6;      // INV_SCALE_FACTOR: parameters are stored x 1e6
constexpr int kParameterInstances = 3;          // INS_GYR_ID..INS_GYR3_ID, INS_TCAL1..3
constexpr char kAxisNames[3] = {'X', 'Y', 'Z'};

[[noreturn]] void fail(const Log& log, const std::string& field, const std::string& message) {
  throw DataError({log.file, 0, field}, message);
}

// Names whose value changes after it was first logged, for a note.
std::vector<std::string> changed(const Log& log, const std::vector<std::string>& names) {
  std::vector<std::string> out;
  for (const auto& name : names) {
    const auto first = log.parameter(name);
    if (!first) continue;
    for (const auto& p : log.parameters)
      if (p.name == name && p.value != *first) {
        out.push_back(name);
        break;
      }
  }
  return out;
}

std::vector<std::string> tcal_names(int instance) {
  const std::string n = std::to_string(instance + 1), prefix = "INS_TCAL" + n + "_";
  std::vector<std::string> out{prefix + "ENABLE", prefix + "TMIN", prefix + "TMAX", "INS_GYR" + n + "_CALTEMP",
                               "INS_ACC" + n + "_CALTEMP"};
  for (const char* sensor : {"GYR", "ACC"})
    for (int order = 1; order <= 3; ++order)
      for (const char axis : kAxisNames) out.push_back(prefix + sensor + std::to_string(order) + "_" + axis);
  return out;
}

double polynomial(const std::array<std::array<double, 3>, 3>& c, int axis, double d) {
  return (c[0][axis] + (c[1][axis] + c[2][axis] * d) * d) * d * kCoefficientScale;
}

const std::vector<double>& field(const Log& log, const MessageType& t, const std::string& name) {
  if (!t.has_column(name))
    fail(log, t.name + "." + name,
         "message type '" + t.name + "' has no column '" + name +
             "' (an IMU message has TimeUS, "
             "GyrX..Z, AccX..Z and T)");
  return t.column(name);
}

// What a log without IMU messages had instead, for the error.
std::string no_imu_detail(const Log& log) {
  std::string out;
  if (!log.unknown_types.empty()) {
    const auto first =
        std::min_element(log.unknown_types.begin(), log.unknown_types.end(),
                         [](const auto& a, const auto& b) { return a.second.first_offset < b.second.first_offset; });
    out += "; " + std::to_string(log.unknown_types.size()) + " message type(s) without an FMT, the first (" +
           std::to_string(first->first) + ") at byte " + std::to_string(first->second.first_offset) +
           ": did the log lose its FMT messages?";
  }
  if (log.truncated_bytes > 0)
    out += "; the file ends within a message (" + std::to_string(log.truncated_bytes) + " bytes)";
  return out;
}

// Messages of one instance: the type and the indices of its messages.
struct Instance {
  const MessageType* type = nullptr;
  std::string label, source;
  std::vector<std::size_t> messages;
};

std::map<int, Instance> instances(const Log& log) {
  std::map<int, Instance> out;
  const MessageType* imu = log.find("IMU");
  if (imu && imu->has_column("I")) {
    const auto& ids = imu->column("I");
    for (std::size_t i = 0; i < ids.size(); ++i) {
      const double id = ids[i];
      if (!(id >= 0 && id <= 255 && id == std::floor(id)))
        fail(log, "IMU.I",
             "instance " + std::to_string(id) + " of IMU message " + std::to_string(i) + " is not an integer 0..255");
      out[static_cast<int>(id)].messages.push_back(i);
    }
    for (auto& [id, in] : out) {
      in.type = imu;
      in.label = "IMU I=" + std::to_string(id);
      in.source = "IMU[" + std::to_string(id) + "]";
    }
    return out;
  }
  const char* names[] = {"IMU", "IMU2", "IMU3"};
  for (int id = 0; id < 3; ++id) {
    const MessageType* t = log.find(names[id]);
    if (!t || t->count == 0) continue;
    Instance& in = out[id];
    in.type = t;
    in.label = in.source = names[id];
    in.messages.resize(t->count);
    for (std::size_t i = 0; i < in.messages.size(); ++i) in.messages[i] = i;
  }
  return out;
}

struct Euler {
  const char* name;
  double roll, pitch, yaw;  // deg
};
// ArduPilot's enum Rotation 0..43, the angles of AP_Math/tests/test_rotations.cpp.
constexpr Euler kRotations[] = {
    {"ROTATION_NONE", 0, 0, 0},
    {"ROTATION_YAW_45", 0, 0, 45},
    {"ROTATION_YAW_90", 0, 0, 90},
    {"ROTATION_YAW_135", 0, 0, 135},
    {"ROTATION_YAW_180", 0, 0, 180},
    {"ROTATION_YAW_225", 0, 0, 225},
    {"ROTATION_YAW_270", 0, 0, 270},
    {"ROTATION_YAW_315", 0, 0, 315},
    {"ROTATION_ROLL_180", 180, 0, 0},
    {"ROTATION_ROLL_180_YAW_45", 180, 0, 45},
    {"ROTATION_ROLL_180_YAW_90", 180, 0, 90},
    {"ROTATION_ROLL_180_YAW_135", 180, 0, 135},
    {"ROTATION_PITCH_180", 0, 180, 0},
    {"ROTATION_ROLL_180_YAW_225", 180, 0, 225},
    {"ROTATION_ROLL_180_YAW_270", 180, 0, 270},
    {"ROTATION_ROLL_180_YAW_315", 180, 0, 315},
    {"ROTATION_ROLL_90", 90, 0, 0},
    {"ROTATION_ROLL_90_YAW_45", 90, 0, 45},
    {"ROTATION_ROLL_90_YAW_90", 90, 0, 90},
    {"ROTATION_ROLL_90_YAW_135", 90, 0, 135},
    {"ROTATION_ROLL_270", 270, 0, 0},
    {"ROTATION_ROLL_270_YAW_45", 270, 0, 45},
    {"ROTATION_ROLL_270_YAW_90", 270, 0, 90},
    {"ROTATION_ROLL_270_YAW_135", 270, 0, 135},
    {"ROTATION_PITCH_90", 0, 90, 0},
    {"ROTATION_PITCH_270", 0, 270, 0},
    {"ROTATION_PITCH_180_YAW_90", 0, 180, 90},
    {"ROTATION_PITCH_180_YAW_270", 0, 180, 270},
    {"ROTATION_ROLL_90_PITCH_90", 90, 90, 0},
    {"ROTATION_ROLL_180_PITCH_90", 180, 90, 0},
    {"ROTATION_ROLL_270_PITCH_90", 270, 90, 0},
    {"ROTATION_ROLL_90_PITCH_180", 90, 180, 0},
    {"ROTATION_ROLL_270_PITCH_180", 270, 180, 0},
    {"ROTATION_ROLL_90_PITCH_270", 90, 270, 0},
    {"ROTATION_ROLL_180_PITCH_270", 180, 270, 0},
    {"ROTATION_ROLL_270_PITCH_270", 270, 270, 0},
    {"ROTATION_ROLL_90_PITCH_180_YAW_90", 90, 180, 90},
    {"ROTATION_ROLL_90_YAW_270", 90, 0, 270},
    {"ROTATION_ROLL_90_PITCH_68_YAW_293", 90, 68.8, 293.3},
    {"ROTATION_PITCH_315", 0, 315, 0},
    {"ROTATION_ROLL_90_PITCH_315", 90, 315, 0},
    {"ROTATION_PITCH_7", 0, 7, 0},
    {"ROTATION_ROLL_45", 45, 0, 0},
    {"ROTATION_ROLL_315", 315, 0, 0},
};

// cos and sin of an angle in degrees, exact at multiples of 90.
std::pair<double, double> cos_sin(double deg) {
  if (deg == std::floor(deg / 90.0) * 90.0) {
    switch (static_cast<int>(deg / 90.0) % 4) {
      case 0:
        return {1.0, 0.0};
      case 1:
        return {0.0, 1.0};
      case 2:
        return {-1.0, 0.0};
      default:
        return {0.0, -1.0};
    }
  }
  const double rad = deg * std::numbers::pi / 180.0;
  return {std::cos(rad), std::sin(rad)};
}

std::string orientation_text(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

// The logged body-frame axes of `s` rotated back into the sensor frame: sensor = R^T body.
void to_sensor_frame(imu::SensorStream& s, const BoardRotation& r) {
  const auto& m = r.body_from_sensor;
  for (std::size_t i = 0; i < s.axes[0].size(); ++i) {
    const double b[3] = {s.axes[0][i], s.axes[1][i], s.axes[2][i]};
    for (int a = 0; a < 3; ++a) s.axes[a][i] = m[0][a] * b[0] + m[1][a] * b[1] + m[2][a] * b[2];
  }
}

// The board rotation of the log, when it has one other than none; DataError for a value that is
// no fixed rotation.
std::optional<BoardRotation> log_board_rotation(const Log& log, std::vector<std::string>* notes) {
  const auto value = log.parameter("AHRS_ORIENTATION");
  if (!value || *value == 0.0) return std::nullopt;
  const auto rotation = board_rotation(*value);
  if (!rotation)
    fail(log, "AHRS_ORIENTATION",
         "AHRS_ORIENTATION is " + orientation_text(*value) +
             ": ArduPilot logs the IMU values in the body frame, rotated by it, and only its fixed rotations 0..43 "
             "can be turned back into the sensor frame (100 and 101 are custom rotations set by CUST_ROTn_* "
             "parameters, which this reader does not apply)");
  if (notes) {
    std::string text = "AHRS_ORIENTATION " + orientation_text(*value) + " (" + rotation->name +
                       "): the IMU values are logged in the body frame; the record holds them rotated back into the "
                       "sensor frame, as ArduPilot's tempcal_IMU.py does";
    if (!changed(log, {"AHRS_ORIENTATION"}).empty())
      text += "; AHRS_ORIENTATION changes within the log: the first value is used";
    notes->push_back(text);
  }
  return rotation;
}

void set_device_id(const Log& log, imu::SensorStream& s, std::vector<std::string>* notes) {
  const auto id = device_id(log, s.sensor, s.instance);
  if (!id) return;
  s.device_id = std::to_string(*id);
  const std::string name = device_id_parameter(s.sensor, s.instance);
  if (notes && !changed(log, {name}).empty())
    notes->push_back(name + " changes within the log; the first value (" + s.device_id + ") is the record's");
}

// Removes the firmware's INS_TCAL correction from the gyro and accel streams of one instance.
void remove_tcal(const Log& log, int instance, const std::string& label, imu::SensorStream& gyro,
                 imu::SensorStream& accel, std::vector<std::string>* notes) {
  if (instance >= kParameterInstances) return;
  const std::string n = std::to_string(instance + 1);
  const auto enable = log.parameter("INS_TCAL" + n + "_ENABLE");
  if (!enable || *enable != 1.0) return;
  const std::string what =
      label + ": recorded with INS_TCAL" + n + "_ENABLE=1 (the firmware's temperature correction on)";
  auto note = [&](const std::string& text) {
    if (notes) notes->push_back(what + "; " + text);
  };
  std::string missing;
  const auto tcal = temperature_calibration(log, instance, &missing);
  if (!tcal)
    return note("the correction is not removed: parameter " + missing + " is not in the log; values as logged");
  if (gyro.temperature.empty())
    return note("the correction is not removed: the IMU messages carry no temperature; values as logged");
  for (imu::SensorStream* s : {&gyro, &accel})
    for (int a = 0; a < 3; ++a)
      for (std::size_t i = 0; i < s->axes[a].size(); ++i) {
        double& v = s->axes[a][i];
        v += firmware_correction(*tcal, s->sensor, a, gyro.temperature[i]);
        if (!std::isfinite(v) || std::abs(v) > kMaxMagnitude)
          fail(log, "INS_TCAL" + n,
               label + ": removing the firmware's temperature correction gives " +
                   (std::isfinite(v) ? "a value beyond 1e100" : "a non-finite value") + " at time stamp " +
                   std::to_string(s->time[i]) + " us: are the INS_TCAL" + n + " parameters corrupt?");
      }
  char range[96];
  std::snprintf(range, sizeof range, "TMIN %g, TMAX %g degC", tcal->tmin, tcal->tmax);
  std::string text =
      std::string("removed (") + range + "), as ArduPilot's tempcal_IMU.py does; gyro and accel are the raw values";
  if (const auto later = changed(log, tcal_names(instance)); !later.empty())
    text += "; " + later.front() + (later.size() > 1 ? " and others change" : " changes") +
            " within the log: the values at boot are used";
  note(text);
}

}  // namespace

const std::vector<std::string>& imu_types() {
  static const std::vector<std::string> types{"IMU", "IMU2", "IMU3"};
  return types;
}

std::string device_id_parameter(imu::Sensor sensor, int instance) {
  return std::string(sensor == imu::Sensor::Gyro ? "INS_GYR" : "INS_ACC") +
         (instance == 0 ? "" : std::to_string(instance + 1)) + "_ID";
}

std::optional<std::uint32_t> device_id(const Log& log, imu::Sensor sensor, int instance) {
  if (instance < 0 || instance >= kParameterInstances) return std::nullopt;
  const auto id = log.parameter(device_id_parameter(sensor, instance));
  constexpr double kMaxId = 4294967295.0;
  if (!id || !(*id >= 1 && *id <= kMaxId) || *id != std::floor(*id)) return std::nullopt;
  return static_cast<std::uint32_t>(*id);
}

std::optional<TemperatureCalibration> temperature_calibration(const Log& log, int instance, std::string* missing) {
  const std::string n = std::to_string(instance + 1), prefix = "INS_TCAL" + n + "_";
  std::string first_missing;
  auto get = [&](const std::string& name) {
    const auto v = log.parameter(name);
    if (!v && first_missing.empty()) first_missing = name;
    return v.value_or(0.0);
  };
  TemperatureCalibration t;
  t.instance = instance;
  t.enable = get(prefix + "ENABLE");
  if (first_missing.empty() && t.enable == 1.0) {
    t.tmin = get(prefix + "TMIN");
    t.tmax = get(prefix + "TMAX");
    t.gyro_cal_temp = get("INS_GYR" + n + "_CALTEMP");
    t.accel_cal_temp = get("INS_ACC" + n + "_CALTEMP");
    for (int order = 0; order < 3; ++order)
      for (int a = 0; a < 3; ++a) {
        const std::string suffix = std::to_string(order + 1) + "_" + kAxisNames[a];
        t.gyro[order][a] = get(prefix + "GYR" + suffix);
        t.accel[order][a] = get(prefix + "ACC" + suffix);
      }
  }
  if (!first_missing.empty()) {
    if (missing) *missing = first_missing;
    return std::nullopt;
  }
  return t;
}

double firmware_correction(const TemperatureCalibration& tcal, imu::Sensor sensor, int axis, double temperature) {
  const bool gyro = sensor == imu::Sensor::Gyro;
  const auto& c = gyro ? tcal.gyro : tcal.accel;
  const double cal_temp = gyro ? tcal.gyro_cal_temp : tcal.accel_cal_temp;
  // std::clamp needs tmin <= tmax; the firmware's constrain_float returns tmin when they are crossed.
  auto clamp = [&](double t) { return std::max(tcal.tmin, std::min(t, tcal.tmax)); };
  return polynomial(c, axis, clamp(temperature) - kReferenceTemperature) -
         polynomial(c, axis, clamp(cal_temp) - kReferenceTemperature);
}

std::optional<BoardRotation> board_rotation(double ahrs_orientation) {
  if (!(ahrs_orientation >= 0 && ahrs_orientation < static_cast<double>(std::size(kRotations))) ||
      ahrs_orientation != std::floor(ahrs_orientation))
    return std::nullopt;
  const Euler& e = kRotations[static_cast<std::size_t>(ahrs_orientation)];
  const auto [cr, sr] = cos_sin(e.roll);
  const auto [cp, sp] = cos_sin(e.pitch);
  const auto [cy, sy] = cos_sin(e.yaw);
  BoardRotation r;
  r.name = e.name;
  r.body_from_sensor = {{{cp * cy, sr * sp * cy - cr * sy, cr * sp * cy + sr * sy},
                         {cp * sy, sr * sp * sy + cr * cy, cr * sp * sy - sr * cy},
                         {-sp, sr * cp, cr * cp}}};
  return r;
}

TimeSeries imu_record(const Log& log, const LogSelection& selection, std::vector<std::string>* notes) {
  if (!selection.topic.empty() && selection.topic != "IMU")
    throw ConfigError({"", 0, "--topic"}, "'" + selection.topic +
                                              "': a DataFlash log's IMU is read from its IMU messages "
                                              "(--topic IMU, or leave --topic out)");
  const auto by_instance = instances(log);
  if (by_instance.empty())
    fail(log, "IMU",
         "no IMU messages in the log (" + std::to_string(log.messages) + " messages of " +
             std::to_string(log.types.size()) + " types read)" + no_imu_detail(log));

  const auto rotation = log_board_rotation(log, notes);
  std::vector<imu::SensorStream> all;
  for (const auto& [id, in] : by_instance) {
    const MessageType& t = *in.type;
    if (!t.timed) fail(log, t.name + ".TimeUS", "message type '" + t.name + "' has no TimeUS column");
    imu::SampleOrder order;
    for (const auto i : in.messages) {
      order.time_us.push_back(imu::time_stamp_us(log.file, in.source, static_cast<double>(t.time_us[i])));
      order.message.push_back(i);
    }
    imu::repair_order(order, in.label, notes);
    imu::SensorStream gyro{imu::Sensor::Gyro, id, in.label, in.source, order.time_us, {}, {}, {}};
    if (t.has_column("T")) gyro.temperature = imu::pick_temperature(log.file, gyro, t.column("T"), order, notes);
    imu::SensorStream accel = gyro;
    accel.sensor = imu::Sensor::Accel;
    gyro.label += " gyro";
    accel.label += " accel";
    for (int a = 0; a < 3; ++a) {
      const std::string g = std::string("Gyr") + kAxisNames[a], acc = std::string("Acc") + kAxisNames[a];
      gyro.axes[a] = imu::pick(log.file, gyro, field(log, t, g), order, g);
      accel.axes[a] = imu::pick(log.file, accel, field(log, t, acc), order, acc);
    }
    if (!t.has_column("T") && notes) notes->push_back(in.label + ": no temperature column T; no temperature channel");
    if (rotation) {
      to_sensor_frame(gyro, *rotation);
      to_sensor_frame(accel, *rotation);
    }
    remove_tcal(log, id, in.label, gyro, accel, notes);
    set_device_id(log, gyro, notes);
    set_device_id(log, accel, notes);
    all.push_back(std::move(gyro));
    all.push_back(std::move(accel));
  }
  return imu::assemble(std::move(all), {}, selection, imu::kMicrosecondsPerSecond, log.file, notes);
}

TimeSeries read_imu(const std::filesystem::path& path, const LogSelection& selection, std::vector<std::string>* notes) {
  ReadOptions options;
  options.keep_types = imu_types();
  return imu_record(read(path, options), selection, notes);
}

}  // namespace driftlab::dataflash
