#include "devices/systematic_rate.hpp"

#include "framework/signal.hpp"

namespace driftlab::devices {

SystematicRate systematic_rate(const DeviceModel& model, const error_model::Config& config,
                               const Eigen::VectorXd& time_s, const Eigen::VectorXd& die_temp_c,
                               const Eigen::VectorXd& true_rate_rad_s) {
  const error_model::Effects& effects = config.effects;
  SystematicRate s;
  s.resonator_temp_c =
      effects.thermal_lag ? signal::first_order_lag(time_s, die_temp_c, effects.thermal_lag->tau_s) : die_temp_c;
  s.rate_rad_s = error_model::additive_effects(effects, time_s, s.resonator_temp_c);
  s.drive_frequency_hz.resize(time_s.size());
  for (Eigen::Index k = 0; k < time_s.size(); ++k) {
    const double temp = s.resonator_temp_c[k];
    error_model::DeviceResponse response = model.response(temp);
    response.scale_factor *= error_model::effect_scale_factor(effects, config.reference_temp_c, temp);
    s.rate_rad_s[k] += error_model::systematic_rate(config, response, temp, true_rate_rad_s[k]);
    s.drive_frequency_hz[k] = response.drive_frequency_hz;
  }
  return s;
}

}  // namespace driftlab::devices
