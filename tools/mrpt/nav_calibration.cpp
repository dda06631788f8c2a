#include "tools/mrpt/nav_calibration.hpp"

#include <sstream>

#include "devices/simulator.hpp"
#include "models/calibration/fit.hpp"

namespace driftlab::mrpt_bridge {

calibration::CalibrationModel calibrate_on_oven_run(const devices::DeviceDefinition& device,
                                                    const OvenCalibration& options) {
  devices::SimulationOptions oven;
  oven.sample_rate_hz = options.sample_rate_hz;
  oven.seed = options.seed;
  const auto profile = devices::default_oven_profile();
  const auto run = devices::simulate(device, profile, oven);
  calibration::Record record;
  std::ostringstream name;
  name << "simulated oven run of " << device.name << " (" << profile.source << "; " << options.sample_rate_hz
       << " Hz, seed " << options.seed << ")";
  record.name = name.str();
  record.time_s = run.time_s;
  record.rate_rad_s = run.rate_rad_s;
  record.temp_c = run.temp_c;
  record.true_rate_rad_s = run.true_rate_rad_s;
  calibration::FitOptions fit;
  fit.kind = options.kind;
  fit.reference_temp_c = device.error_model.reference_temp_c;
  fit.seed = options.seed;
  if (options.progress) fit.progress = options.progress;
  return calibration::fit_calibration({record}, fit);
}

Eigen::VectorXd compensate_drive(const calibration::CalibrationModel& model, const DriveRecord& drive,
                                 calibration::OutsideCount* outside_count) {
  calibration::CausalCompensator compensator(model);
  const auto& g = drive.gyro;
  Eigen::VectorXd out(g.time_s.size());
  calibration::OutsideCount count;
  for (Eigen::Index k = 0; k < g.time_s.size(); ++k) {
    out[k] = compensator.step(g.time_s[k], g.rate_rad_s[k], g.temp_c[k]);
    count.add(compensator.last_outside());
  }
  if (outside_count) *outside_count = count;
  return out;
}

}  // namespace driftlab::mrpt_bridge
