// Device definitions as data: devices/*.yaml (format driftlab-device/1). Adding a gyro means adding
// a file. Loading validates everything and throws one driftlab::ConfigError listing every problem
// with file, line and key path. Units are in the key names (converted to SI on load):
//
//   format: driftlab-device/1                         required
//   identity: {name, title, manufacturer, reference, notes}          name required
//   reference_temp_c: 25                              calibration temperature T0, degC
//   structure:                                        the die (see device_model.hpp for assumptions)
//     youngs_modulus_gpa, poisson_ratio (0..0.5), density_kg_m3, length_um, width_um, thickness_um,
//     proof_mass_area_fraction (0..1]                 required
//     youngs_modulus_tc_ppm_per_k: -60                TCE
//     suspension: {beams_per_mode: 16, beam_width_um: 5}
//   modes:
//     drive: / sense:  frequency_hz, quality_factor   required
//       frequency_tc_ppm_per_k (default TCE/2), frequency_tc2_ppb_per_k2 (0), quality_factor_exponent (1)
//   electronics: drive_amplitude_um (required), quadrature_dps, quadrature_tc_ppm_per_k,
//                demodulation_phase_error_mrad
//   thermal: die_time_constant_s, sensor_time_constant_s          (first-order lags, default 0)
//   channels: - {name, role, unit, range: [min, max], resolution, noise, scale_factor_mv_per_dps}
//     roles: rate (angular-rate unit, required), temperature (temperature unit, required),
//            drive_frequency (frequency unit); resolution and noise in the channel's unit
//   error_model:
//     bias_polynomial: {unit: deg/h, coefficients: [c0, c1, c2, ...]}   c_i per K^i around T0
//     scale_factor_polynomial_ppm: [ppm/K, ppm/K^2, ...]
//     noise: {arw_dph_rthz (N, deg/h/sqrt(Hz)), bias_instability_dph (B, deg/h),
//             rate_random_walk_dph_rth (K, deg/h/sqrt(h)), flicker_correlation_times_s: [min, max],
//             flicker_poles_per_decade}
//   effects: {NAME: {key: value, ...}, ...}           optional; framework/effect_catalogue.hpp
//
// Cross-checks: the implied suspension-beam length (device_model.hpp) must fit within the die; the
// rate range must contain 0; channel roles unique.
//
// A whole IMU (imu_definition.hpp for the model) has, besides format, identity and
// reference_temp_c, only an `imu:` section instead of structure ... effects:
//   imu:
//     up_direction: [0, 0, 1]       'up' in the IMU's axes on the rate table (normalized; default z up)
//     gravity_mps2: 9.80665         local gravity (default standard gravity)
//     instances:                    1 to 10 IMUs on one board
//       - device_id: 2490378        optional whole number in [0, 2^32): written as column device_id{i}
//         thermal: {die_time_constant_s, sensor_time_constant_s}          (default 0)
//         temperature_sensor: {noise_c, resolution_c}                     (default 0)
//         gyro:
//           noise: {arw_dph_rthz, bias_instability_dph, rate_random_walk_dph_rth,
//                   flicker_correlation_times_s, flicker_poles_per_decade}   the axes' default
//           x: {bias_polynomial_dps: [c0, c1, ...] (required, deg/s per K^i around T0),
//               scale_factor_polynomial_ppm: [ppm/K, ...], lag_s, noise: {...} (replaces the default)}
//           y: ..., z: ...          all three required
//         accel:
//           noise: {vrw_ug_rthz (N, ug/sqrt(Hz)), bias_instability_ug (B, ug),
//                   acceleration_random_walk_ug_rth (K, ug/sqrt(h)), flicker_...}
//           x: {bias_polynomial_mg: [c0, c1, ...] (required, mg per K^i), scale_factor_polynomial_ppm,
//               lag_s, noise}
//           y: ..., z: ...
#pragma once

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "devices/device_model.hpp"
#include "devices/imu_definition.hpp"
#include "framework/error.hpp"
#include "models/error_model/error_model.hpp"

namespace driftlab::devices {

inline constexpr const char* kDeviceFormat = "driftlab-device/1";

struct ChannelSpec {
  std::string name;
  std::string role;                                             // rate | temperature | drive_frequency
  std::string unit;                                             // as written in the file (e.g. "deg/s")
  double range_min = -std::numeric_limits<double>::infinity();  // internal units
  double range_max = std::numeric_limits<double>::infinity();
  double resolution = 0.0;               // LSB, internal units; 0 = not quantized
  double noise = 0.0;                    // white noise std per sample, internal units (temperature, frequency)
  double scale_factor_mv_per_dps = 0.0;  // rate channel: analogue scale factor, informative
};

struct Thermal {
  double die_time_constant_s = 0.0;     // die lags the chamber
  double sensor_time_constant_s = 0.0;  // case temperature sensor lags the die
};

struct DeviceDefinition {
  std::string source;  // file it was loaded from
  std::string name, title, manufacturer, reference, notes;
  PhysicsConfig physics;
  Thermal thermal;
  std::vector<ChannelSpec> channels;
  error_model::Config error_model;  // reference temperature, polynomials, noise, effects
  // A whole IMU: set when the file has an `imu:` section; physics, thermal, channels and the
  // error model's polynomials, noise and effects are then unused (the single-axis simulator refuses it).
  std::optional<ImuDefinition> imu;

  const ChannelSpec* find_channel(const std::string& role) const;  // nullptr when absent
};

// Throws ConfigError (the file, key "imu") when `d` is a whole IMU: for the users of the
// single-axis physics, channels and error model (the single-axis simulator, the discrepancy prior).
void require_single_axis(const DeviceDefinition& d);

DeviceDefinition load_device_file(const std::filesystem::path& path);
// `file` names the source in messages.
DeviceDefinition parse_device(const std::string& yaml_text, const std::string& file);

// Sorted *.yaml files of a directory. Throws ConfigError when it is not a directory.
std::vector<std::filesystem::path> list_device_files(const std::filesystem::path& dir);
// A device argument: a file path, or the name of a file in `dir` ("fmvmg" or "fmvmg.yaml"); the
// argument as given when neither exists (reading it then names it in the error). The one rule of
// the command line (tools/driftlab/devices_dir.hpp) and the Python module.
std::filesystem::path find_device_file(const std::string& argument, const std::filesystem::path& dir);

// ---- effects: the `effects:` section and `--effect`, both from framework/effect_catalogue.hpp ----
// Reads an `effects:` mapping into `effects` (added or replaced), reporting problems.
void parse_effects(const YAML::Node& node, const std::string& file, const std::string& path,
                   error_model::Effects& effects, std::vector<Diagnostic>& problems);
// Command-line form "NAME:key=value,key=value" (values are YAML, so lists like [100, 1] work).
// Throws ConfigError (field "--effect").
void apply_effect_option(const std::string& text, error_model::Effects& effects);
// Names of the switched-on effects with their parameters in file units, e.g. "thermal_lag{tau_s=400}".
std::vector<std::string> describe_effects(const error_model::Effects& effects);

}  // namespace driftlab::devices
