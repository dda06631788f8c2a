#include "devices/discrepancy_options.hpp"

#include <algorithm>
#include <memory>

#include "devices/systematic_rate.hpp"

namespace driftlab::devices {

discrepancy::Options discrepancy_options(const DeviceDefinition& device) {
  require_single_axis(device);
  discrepancy::Options o;
  o.reference_temp_c = device.error_model.reference_temp_c;
  auto model = std::make_shared<const DeviceModel>(device.physics);
  o.prior = [model, config = device.error_model](const Eigen::VectorXd& time_s, const Eigen::VectorXd& temp_c,
                                                 const Eigen::VectorXd& true_rate) {
    return systematic_rate(*model, config, time_s, temp_c, true_rate).rate_rad_s;
  };
  o.noise = device.error_model.noise;
  o.sensor_time_constant_s = device.thermal.sensor_time_constant_s;
  o.drive_frequency_at_reference_hz = device.physics.drive.frequency_hz;
  o.drive_frequency_slope_hz_per_k = device.physics.drive.frequency_hz * device.physics.drive.frequency_tc_per_k;
  o.bias_degree = std::max(1, static_cast<int>(device.error_model.bias_polynomial_rad_s.size()) - 1);
  return o;
}

}  // namespace driftlab::devices
