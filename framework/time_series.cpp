#include "framework/time_series.hpp"

#include "framework/error.hpp"
#include "framework/sampling.hpp"

namespace driftlab {

TimeSeries::TimeSeries(Eigen::VectorXd time_s, double gap_factor)
    : time_(std::move(time_s)), facts_(sampling::facts_of(time_, gap_factor)) {}

void TimeSeries::set_gap_factor(double gap_factor) {
  if (gap_factor != facts_.gap_factor) facts_ = sampling::facts_of(time_, gap_factor);
}

void TimeSeries::set_channel(Channel channel) {
  if (channel.values.size() != time_.size())
    throw DataError({channel.source, 0, channel.role}, "channel has " + std::to_string(channel.values.size()) +
                                                           " samples, time has " + std::to_string(time_.size()));
  for (auto& c : channels_)
    if (c.role == channel.role) {
      c = std::move(channel);
      return;
    }
  channels_.push_back(std::move(channel));
}

bool TimeSeries::has(const std::string& role) const {
  for (const auto& c : channels_)
    if (c.role == role) return true;
  return false;
}

const Channel& TimeSeries::channel(const std::string& role) const {
  for (const auto& c : channels_)
    if (c.role == role) return c;
  std::string roles;
  for (const auto& c : channels_) roles += (roles.empty() ? "" : ", ") + c.role;
  throw DataError({"", 0, role},
                  "no channel with this role (the record has: " + (roles.empty() ? std::string("none") : roles) + ")");
}

}  // namespace driftlab

namespace driftlab {

const std::string& TimeSeries::device_id(int instance) const {
  static const std::string none;
  return instance >= 0 && static_cast<std::size_t>(instance) < device_ids_.size() ? device_ids_[instance] : none;
}

void TimeSeries::set_device_id(int instance, std::string id) {
  if (instance < 0) return;
  if (static_cast<std::size_t>(instance) >= device_ids_.size()) device_ids_.resize(instance + 1);
  device_ids_[instance] = std::move(id);
}

}  // namespace driftlab
