#include "devices/imu_simulator.hpp"

#include <cmath>

#include "framework/seeded_random.hpp"
#include "framework/signal.hpp"

namespace driftlab::devices {
namespace {

// Noise sources of one instance: 0..2 gyro x..z, 3..5 accel x..z, 6 temperature.
constexpr int kSourcesPerInstance = 7;
constexpr int kTemperatureSource = 6;
constexpr std::uint64_t kImuStreamBase = 0x494D550000000000ULL;  // "IMU": apart from simulator.cpp's streams

std::uint64_t source_seed(std::uint64_t seed, std::size_t instance, int source) {
  return splitmix64(splitmix64(seed) ^
                    splitmix64(kImuStreamBase + instance * kSourcesPerInstance + static_cast<std::uint64_t>(source)));
}

ImuAxisRecord simulate_axis(const ImuAxis& axis, double reference_temp_c, const Eigen::VectorXd& time_s,
                            const Eigen::VectorXd& die_temp_c, Eigen::VectorXd truth, double fs, std::uint64_t seed) {
  const Eigen::VectorXd temp = signal::first_order_lag(time_s, die_temp_c, axis.lag_s);
  ImuAxisRecord r;
  r.systematic.resize(time_s.size());
  for (Eigen::Index k = 0; k < time_s.size(); ++k) {
    const double x = temp[k] - reference_temp_c;
    const double scale = 1.0 + x * error_model::polynomial(axis.scale_factor_polynomial, x);
    r.systematic[k] = scale * truth[k] + error_model::polynomial(axis.bias_polynomial, x);
  }
  r.measured = r.systematic + error_model::rate_noise(axis.noise, fs, time_s.size(), seed);
  r.truth = std::move(truth);
  return r;
}

}  // namespace

ImuSimulationRecord simulate_imu(const ImuDefinition& imu, const SimulationProfile& profile,
                                 const SimulationOptions& options) {
  const double fs = options.sample_rate_hz;
  ImuSimulationRecord r;
  r.time_s = sample_times(profile, options);
  const Eigen::Index n = r.time_s.size();
  r.chamber_temp_c = profile.chamber_c.sample(r.time_s);
  const Eigen::VectorXd table_rate = profile.true_rate.sample(r.time_s);
  Eigen::MatrixXd up(n, 3);  // the direction pointing up at each sample, in the IMU's axes
  for (Eigen::Index k = 0; k < n; ++k)
    up.row(k) = (profile.orientation ? profile.orientation->up_at(r.time_s[k]) : imu.up).transpose();

  for (std::size_t i = 0; i < imu.instances.size(); ++i) {
    const ImuInstance& spec = imu.instances[i];
    ImuInstanceRecord out;
    out.device_id = spec.device_id;
    out.die_temp_c = signal::first_order_lag(r.time_s, r.chamber_temp_c, spec.die_time_constant_s);
    for (int a = 0; a < 3; ++a) {
      out.gyro[a] = simulate_axis(spec.gyro.axes[a], imu.reference_temp_c, r.time_s, out.die_temp_c,
                                  table_rate.cwiseProduct(up.col(a)), fs, source_seed(options.seed, i, a));
      out.accel[a] = simulate_axis(spec.accel.axes[a], imu.reference_temp_c, r.time_s, out.die_temp_c,
                                   imu.gravity_mps2 * up.col(a), fs, source_seed(options.seed, i, 3 + a));
    }
    out.temp_c = signal::first_order_lag(r.time_s, out.die_temp_c, spec.sensor_time_constant_s);
    error_model::NormalStream noise(source_seed(options.seed, i, kTemperatureSource), 0);
    for (double& t : out.temp_c) {
      if (spec.temperature_noise_c > 0.0) t += spec.temperature_noise_c * noise.next();
      if (spec.temperature_resolution_c > 0.0)
        t = std::round(t / spec.temperature_resolution_c) * spec.temperature_resolution_c;
    }
    r.instances.push_back(std::move(out));
  }
  return r;
}

}  // namespace driftlab::devices
