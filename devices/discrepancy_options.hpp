// What the discrepancy workflow (models/discrepancy/discrepancy.hpp) takes from a device file:
// T0; the device's systematic rate as the workflow's fixed prior (systematic_rate.hpp, the
// simulator's own function, so the prior is what `driftlab simulate` produces without noise; the
// workflow turns the case sensor's reading into the die's with sensor_time_constant_s); the noise
// terms; the sensor's lag behind the die; the drive-frequency line f0 (1 + a1 (T - T0)) for the
// drive-frequency thermometer; and the correction polynomial's degree (the file's bias polynomial
// degree, at least 1). Effects already listed in the device file are part of the prior (fixed, not
// refitted).
#pragma once

#include "devices/device_file.hpp"
#include "models/discrepancy/discrepancy.hpp"

namespace driftlab::devices {

// Throws ConfigError for a whole-IMU device (require_single_axis).
discrepancy::Options discrepancy_options(const DeviceDefinition& device);

}  // namespace driftlab::devices
