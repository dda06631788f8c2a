// Calibration for `driftlab nav` (issue 14): when no model is given, nav calibrates one with the
// calibration library (models/calibration, issue 13) on a simulated oven run of the same device,
// with a seed different from the drive's; and it compensates the drive's yaw rate sample by sample
// with the causal compensator, as firmware would.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>

#include "devices/device_file.hpp"
#include "models/calibration/calibration_model.hpp"
#include "tools/mrpt/nav_scenario.hpp"

namespace driftlab::mrpt_bridge {

struct OvenCalibration {
  calibration::ModelKind kind = calibration::ModelKind::Polynomial;
  double sample_rate_hz = 10.0;  // of the simulated oven run
  std::uint64_t seed = 1001;     // oven-run noise and fit seed (the scenario's calibration_seed)
  std::function<void(const std::string&, double)> progress;  // optional
};
// The device in the default oven profile (-30 -> +60 -> -30 degC, 4.5 h, static), fitted by
// calibration::fit_calibration. Describes itself in model.fit.records.
calibration::CalibrationModel calibrate_on_oven_run(const devices::DeviceDefinition& device,
                                                    const OvenCalibration& options);

// The drive's measured yaw rate through calibration::CausalCompensator (rad/s, one per sample).
// `outside_count` (optional) receives the samples with a model input outside its fitted range.
Eigen::VectorXd compensate_drive(const calibration::CalibrationModel& model, const DriveRecord& drive,
                                 calibration::OutsideCount* outside_count = nullptr);

}  // namespace driftlab::mrpt_bridge
