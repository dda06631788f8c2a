// MRPT rawlogs in the reader registry (framework/record_reader.hpp): recognised here by content,
// read by the module libdriftlab_rawlog.so (tools/mrpt/rawlog_record.cpp), which links MRPT and is
// loaded from the framework library's directory the first time a rawlog is read -- MRPT's ~180
// shared libraries load for that command only, and the framework never links MRPT (DESIGN.md
// section 2 and 8). A build without MRPT refuses a rawlog with a message naming what is missing.
//
// Recognition (sniff): the file's first bytes, read through zlib (gzip'ed or plain, as
// CFileGZInputStream reads them), are an MRPT archive's first object header: one byte 0x80 | n
// (n = 1..127; the older header: n as a little-endian uint32) and then n characters of a class
// name, the name of a rawlog's top-level object:
// CObservation..., CSensoryFrame or CActionCollection, with or without MRPT 2's namespace
// ("mrpt::obs::CObservationIMU"). Nothing else a driftlab reader takes starts so.
//
// The record (read_imu): the CObservationIMU observations of one sensor label, read by
// tools/mrpt/rawlog_io.hpp (import_rawlog: every object checked, MRPT's deserializer run first in a
// memory-limited child process, errors naming the object index) -- one label is one IMU instance, 0:
//   IMU_WX, IMU_WY, IMU_WZ        gyro_x, gyro_y, gyro_z (rad/s)
//   IMU_X_ACC, IMU_Y_ACC, IMU_Z_ACC  accel_x, accel_y, accel_z (m/s^2)
//   IMU_TEMPERATURE               temperature (degC)
// each only when the observations carry it (a rawlog written by `driftlab mrpt export` of a
// single-axis CSV has IMU_WZ and IMU_TEMPERATURE: the record has gyro_z and temperature). Time: s
// since the label's first observation (MRPT's 100-ns ticks / 1e7, as `driftlab mrpt import`).
// Odometry actions are not part of the IMU record (`driftlab nav --rawlog` reads them).
// LogSelection: topic = the sensor label ("" = the only label; several labels without one is a
// ConfigError listing them), instance -1 or 0, sensor as for every log.
// Errors: DataError naming the file (and the object index) for a malformed, truncated or empty
// rawlog, one without IMU observations, time stamps that do not increase, a non-finite value or one
// beyond kMaxMagnitude (csv.hpp), a temperature NaN only in part; ConfigError for an unknown label or
// instance.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "framework/record_reader.hpp"
#include "framework/time_series.hpp"

namespace driftlab::rawlog {

// Whether the file's content starts like a rawlog (see above). False for a file that cannot be read.
bool sniff(const std::filesystem::path& path);

// The IMU record of a rawlog (see above).
TimeSeries read_imu(const std::filesystem::path& path, const LogSelection& selection,
                    std::vector<std::string>* notes = nullptr);

// What `driftlab log info` lists of a rawlog.
struct Info {
  std::string format;  // "observations-only", "actions/sensory-frame" or "mixed"
  std::size_t objects = 0, imu_observations = 0, odometry_actions = 0, sensory_frames = 0;
  struct Sensor {
    std::string label;
    std::size_t samples = 0;
    double start_unix_s = 0.0, duration_s = 0.0;  // first observation (Unix time, s) and span, s
    std::vector<std::string> fields;              // MRPT's names of the fields it carries ("IMU_WZ")
    bool has_temperature = false;
    double temperature_min_c = 0.0, temperature_max_c = 0.0;
  };
  std::vector<Sensor> sensors;  // one per IMU sensor label, in label order
};
Info info(const std::filesystem::path& path);

}  // namespace driftlab::rawlog
