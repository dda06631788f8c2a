// `driftlab devices list` and `driftlab devices describe FILE`.
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "devices/device_file.hpp"
#include "devices/device_model.hpp"
#include "framework/imu.hpp"
#include "framework/units.hpp"
#include "tools/driftlab/cli.hpp"
#include "tools/driftlab/data_dirs.hpp"

namespace driftlab::cli {
namespace {

std::string in_unit(double internal, const std::string& unit) {
  const auto u = find_unit(unit);
  std::ostringstream out;
  out << (u ? from_internal(internal, *u) : internal);
  return out.str();
}

void describe_channels(const devices::DeviceDefinition& d, std::ostream& out) {
  out << "channels:\n";
  for (const auto& c : d.channels) {
    const auto unit = find_unit(c.unit);
    const double scale = unit ? unit->scale : 1.0;
    out << "  " << std::left << std::setw(12) << c.name << " role " << std::setw(16) << c.role << " unit "
        << std::setw(6) << c.unit;
    if (std::isfinite(c.range_min))
      out << "  range [" << in_unit(c.range_min, c.unit) << ", " << in_unit(c.range_max, c.unit) << "]";
    if (c.resolution > 0) out << "  resolution " << c.resolution / scale;
    if (c.noise > 0) out << "  noise " << c.noise / scale;
    if (c.scale_factor_mv_per_dps > 0) out << "  scale factor " << c.scale_factor_mv_per_dps << " mV/(deg/s)";
    out << "\n";
  }
}

void describe_identity(const devices::DeviceDefinition& d, std::ostream& out) {
  out << d.name << " - " << d.title << "\n  file: " << d.source << "\n";
  if (!d.manufacturer.empty()) out << "  manufacturer: " << d.manufacturer << "\n";
  if (!d.reference.empty()) out << "  reference: " << d.reference << "\n";
  if (!d.notes.empty()) out << "  notes: " << d.notes << "\n";
}

// One IMU axis in the device file's units: gyro deg/s and deg/h, accelerometer mg and ug.
void describe_imu_axis(const imu::ChannelId& id, const devices::ImuAxis& axis, std::ostream& out) {
  const bool gyro = id.sensor == imu::Sensor::Gyro;
  const double bias_unit = gyro ? kRadPerDeg : 1e-3 * kStandardGravity;
  const double noise_unit = gyro ? kRadPerSecPerDph : 1e-6 * kStandardGravity;
  out << "  " << std::left << std::setw(9) << id.role() << std::right << "bias (" << (gyro ? "deg/s" : "mg")
      << " per K^i):";
  for (double c : axis.bias_polynomial) out << " " << c / bias_unit;
  out << "  scale factor (ppm per K^i, i >= 1):";
  for (double c : axis.scale_factor_polynomial) out << " " << c * 1e6;
  if (axis.scale_factor_polynomial.empty()) out << " none";
  out << "  lag " << axis.lag_s << " s\n           N " << axis.noise.arw_rad_sqrt_s / noise_unit
      << (gyro ? " deg/h/sqrt(Hz)  B " : " ug/sqrt(Hz)  B ") << axis.noise.bias_instability_rad_s / noise_unit
      << (gyro ? " deg/h  K " : " ug  K ") << axis.noise.rate_random_walk_rad_s_sqrt_s / noise_unit * 60.0
      << (gyro ? " deg/h/sqrt(h)\n" : " ug/sqrt(h)\n");
}

void describe_imu(const devices::DeviceDefinition& d, std::ostream& out) {
  const devices::ImuDefinition& imu = *d.imu;
  describe_identity(d, out);
  out << std::setprecision(6) << "whole IMU: " << imu.instances.size() << " instance(s), T0 = " << imu.reference_temp_c
      << " degC, up [" << imu.up[0] << ", " << imu.up[1] << ", " << imu.up[2] << "] in the IMU's axes, gravity "
      << imu.gravity_mps2 << " m/s^2\n";
  for (std::size_t i = 0; i < imu.instances.size(); ++i) {
    const auto& instance = imu.instances[i];
    out << "instance " << i;
    if (instance.device_id) out << " (device id " << static_cast<std::uint64_t>(*instance.device_id) << ")";
    out << ": die lags chamber " << instance.die_time_constant_s << " s, sensor lags die "
        << instance.sensor_time_constant_s << " s, temperature noise " << instance.temperature_noise_c
        << " degC, resolution " << instance.temperature_resolution_c << " degC\n";
    for (const auto sensor : {imu::Sensor::Gyro, imu::Sensor::Accel})
      for (std::size_t a = 0; a < 3; ++a)
        describe_imu_axis({sensor, "xyz"[a], static_cast<int>(i)},
                          (sensor == imu::Sensor::Gyro ? instance.gyro : instance.accel).axes[a], out);
    out << "  bias versus axis temperature:\n   T_degC   gyro_x_dps  gyro_y_dps  gyro_z_dps   accel_x_mg  "
           "accel_y_mg  accel_z_mg\n"
        << std::fixed << std::right;
    for (double t : {-40.0, -30.0, -15.0, 0.0, 25.0, 45.0, 60.0, 85.0}) {
      const double x = t - imu.reference_temp_c;
      out << std::setprecision(2) << std::setw(9) << t << std::setprecision(4);
      for (const auto& axis : instance.gyro.axes)
        out << std::setw(12) << error_model::polynomial(axis.bias_polynomial, x) / kRadPerDeg;
      out << " ";
      for (const auto& axis : instance.accel.axes)
        out << std::setw(12) << error_model::polynomial(axis.bias_polynomial, x) / (1e-3 * kStandardGravity);
      out << "\n";
    }
    out << std::defaultfloat << std::setprecision(6);
  }
}

void describe(const devices::DeviceDefinition& d, std::ostream& out) {
  if (d.imu) {
    describe_imu(d, out);
    return;
  }
  const devices::DeviceModel model(d.physics);
  const auto& p = d.physics;
  const auto& s = p.structure;
  describe_identity(d, out);
  out << std::setprecision(6);
  out << "structure: E " << s.youngs_modulus_pa / 1e9 << " GPa (TCE " << s.youngs_modulus_tc_per_k * 1e6
      << " ppm/K), nu " << s.poisson_ratio << ", rho " << s.density_kg_m3 << " kg/m^3, " << s.length_m * 1e6 << " x "
      << s.width_m * 1e6 << " x " << s.thickness_m * 1e6 << " um\n"
      << "  proof mass " << model.proof_mass_kg() * 1e6 << " mg (" << s.proof_mass_area_fraction * 100
      << " % of the footprint), " << s.beams_per_mode << " beams of width " << s.beam_width_m * 1e6 << " um per mode\n";
  out << "modes at T0 = " << p.reference_temp_c << " degC:\n";
  for (const auto* mode : {&p.drive, &p.sense}) {
    out << "  " << (mode == &p.drive ? "drive" : "sense") << "  f " << mode->frequency_hz << " Hz  Q "
        << mode->quality_factor << "  k " << model.stiffness_n_per_m(*mode) << " N/m  implied beam length "
        << model.implied_beam_length_m(*mode) * 1e6 << " um  df/f " << mode->frequency_tc_per_k * 1e6
        << " ppm/K  Q exponent " << mode->quality_factor_exponent << "\n";
  }
  out << "  split " << model.split_hz(p.reference_temp_c) << " Hz, drive amplitude "
      << p.electronics.drive_amplitude_m * 1e6 << " um, drive force " << model.drive_force_n(p.reference_temp_c) * 1e6
      << " uN\n  quadrature " << p.electronics.quadrature_rad_s / kRadPerDeg << " deg/s ("
      << p.electronics.quadrature_tc_per_k * 1e6 << " ppm/K), demodulation phase error "
      << p.electronics.demodulation_phase_error_rad * 1e3 << " mrad\n";
  out << "thermal: die lags chamber " << d.thermal.die_time_constant_s << " s, sensor lags die "
      << d.thermal.sensor_time_constant_s << " s\n";
  describe_channels(d, out);
  const auto& n = d.error_model.noise;
  out << "error model:\n  N " << n.arw_rad_sqrt_s / kRadPerSecPerDph << " deg/h/sqrt(Hz)  B "
      << n.bias_instability_rad_s / kRadPerSecPerDph << " deg/h  K "
      << n.rate_random_walk_rad_s_sqrt_s / kRadPerSecPerDph * 60.0 << " deg/h/sqrt(h)\n";
  const auto components = error_model::flicker_components(n);
  if (!components.empty())
    out << "  B as " << components.size() << " Gauss-Markov processes, tau " << components.front().tau_s << " .. "
        << components.back().tau_s << " s, sigma " << components.front().sigma_rad_s / kRadPerSecPerDph
        << " deg/h each\n";
  for (const auto& g : n.gauss_markov)
    out << "  Gauss-Markov sigma " << g.sigma_rad_s / kRadPerSecPerDph << " deg/h, tau " << g.tau_s << " s\n";
  out << "  bias polynomial (deg/h per K^i):";
  for (double c : d.error_model.bias_polynomial_rad_s) out << " " << c / kRadPerSecPerDph;
  out << "\n  scale-factor polynomial (ppm per K^i, i >= 1):";
  for (double c : d.error_model.scale_factor_polynomial) out << " " << c * 1e6;
  out << "\neffects:";
  const auto effects = devices::describe_effects(d.error_model.effects);
  if (effects.empty()) out << " none";
  for (const auto& e : effects) out << " " << e;
  out << "\n\nversus die temperature (scale factor and bias include the empirical polynomials):\n"
      << "   T_degC   drive_Hz    sense_Hz  split_Hz   Q_sense  gain_nm/dps  demod_mrad   sf_ppm  bias_dph\n";
  out << std::right;
  for (double t : {-40.0, -30.0, -15.0, 0.0, 25.0, 45.0, 60.0, 85.0}) {
    const auto response = model.response(t);
    const double sf = response.scale_factor * error_model::empirical_scale_factor(d.error_model, t);
    const double bias = error_model::systematic_rate(d.error_model, response, t, 0.0);
    out << std::fixed << std::setprecision(2) << std::setw(9) << t << std::setw(11) << model.drive_frequency_hz(t)
        << std::setw(12) << model.sense_frequency_hz(t) << std::setw(10) << model.split_hz(t) << std::setw(10)
        << std::setprecision(0) << model.quality_factor(d.physics.sense, t) << std::setprecision(4) << std::setw(13)
        << model.sense_response(t).amplitude_m_per_rad_s * 1e9 * kRadPerDeg << std::setw(12) << std::setprecision(3)
        << model.demodulation_phase_error_rad(t) * 1e3 << std::setw(9) << std::setprecision(0) << (sf - 1.0) * 1e6
        << std::setw(10) << std::setprecision(1) << bias / kRadPerSecPerDph << "\n";
  }
  out << std::defaultfloat;
}

}  // namespace

void add_devices_command(CLI::App& app, CommandEnv&) {
  auto* devices = app.add_subcommand("devices", "list and describe device definitions (devices/*.yaml)");
  devices->require_subcommand(1);
  struct Options {
    std::string devices_dir, file;
  };
  auto options = std::make_shared<Options>();
  devices->add_option("--devices-dir", options->devices_dir,
                      "directory of device files (default $DRIFTLAB_DEVICES_DIR, else an installed driftlab's "
                      "share/driftlab/devices, else the source tree's devices/)");

  devices->fallthrough();  // --devices-dir may also follow `list` or `describe`
  auto* list = devices->add_subcommand("list", "list the device files with their name and title");
  list->callback([options] {
    const auto dir = resolve_devices_dir(options->devices_dir);
    for (const auto& file : devices::list_device_files(dir)) {
      std::cout << std::left << std::setw(24) << file.filename().string() << " ";
      try {
        const auto d = devices::load_device_file(file);
        std::cout << std::setw(14) << d.name << d.title << "\n";
      } catch (const ConfigError& e) {
        std::cout << "INVALID: " << e.problems().front().to_string() << "\n";
      }
    }
  });

  auto* describe_cmd = devices->add_subcommand("describe", "validate a device file and show its model");
  describe_cmd->add_option("file", options->file, "device file, or the name of one in the devices directory")
      ->required();
  describe_cmd->callback([options] {
    describe(devices::load_device_file(resolve_device_file(options->file, options->devices_dir)), std::cout);
  });
}

}  // namespace driftlab::cli
