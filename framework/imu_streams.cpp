#include "framework/imu_streams.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "framework/csv.hpp"
#include "framework/error.hpp"

namespace driftlab::imu {
namespace {

constexpr double kMicrosecondsPerSecond = 1e6;  // divided by: 22311243 us -> 22.311243 s exactly rounded
constexpr int kMaxInstance = 99;                  // imu role names: gyro1_x .. gyro99_x
constexpr char kAxes[3] = {'x', 'y', 'z'};

[[noreturn]] void fail(const std::string& file, const std::string& field, const std::string& message) {
  throw DataError({file, 0, field}, message);
}

// Values of `s` at the times `base` (all within s's span), linear between its samples.
Eigen::VectorXd resample(const std::vector<std::int64_t>& time_us, const std::vector<double>& values,
                         const std::vector<std::int64_t>& base) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(base.size()));
  std::size_t j = 0;
  for (std::size_t i = 0; i < base.size(); ++i) {
    const std::int64_t t = base[i];
    while (j + 1 < time_us.size() && time_us[j + 1] <= t) ++j;
    double v = values[j];
    if (time_us[j] != t && j + 1 < time_us.size())
      v += (values[j + 1] - values[j]) * static_cast<double>(t - time_us[j]) / static_cast<double>(time_us[j + 1] - time_us[j]);
    out[static_cast<Eigen::Index>(i)] = v;
  }
  return out;
}

bool selects_any_axis(const Selection& sel, Sensor sensor, int instance) {
  return std::any_of(std::begin(kAxes), std::end(kAxes), [&](char axis) { return sel.selects({sensor, axis, instance}); });
}

}  // namespace

std::int64_t time_stamp(const std::string& file, const std::string& source, double us) {
  constexpr double kMaxTimeUs = 9007199254740992.0;
  if (!(us >= 0.0 && us <= kMaxTimeUs))
    fail(file, source, "time stamp " + std::to_string(us) + " us is outside 0 to 2^53 us");
  return static_cast<std::int64_t>(us);
}

void repair_order(SampleOrder& raw, const std::string& label, std::vector<std::string>* notes) {
  std::size_t out_of_order = 0;
  for (std::size_t i = 1; i < raw.time_us.size(); ++i) out_of_order += raw.time_us[i] < raw.time_us[i - 1];
  std::vector<std::size_t> order(raw.time_us.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  if (out_of_order > 0)
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return raw.time_us[a] < raw.time_us[b]; });
  SampleOrder repaired;
  std::size_t duplicates = 0;
  for (const auto i : order) {
    if (!repaired.time_us.empty() && repaired.time_us.back() == raw.time_us[i]) {
      ++duplicates;
      continue;
    }
    repaired.time_us.push_back(raw.time_us[i]);
    repaired.message.push_back(raw.message[i]);
  }
  if (notes && out_of_order > 0)
    notes->push_back(label + ": " + std::to_string(out_of_order) + " samples earlier than the one before; sorted by time");
  if (notes && duplicates > 0)
    notes->push_back(label + ": " + std::to_string(duplicates) + " repeated time stamps; the first sample of each kept");
  raw = std::move(repaired);
}

std::vector<double> pick(const std::string& file, const Stream& s, const std::vector<double>& values, const SampleOrder& raw,
                         const std::string& field) {
  std::vector<double> out(raw.message.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i] = values[raw.message[i]];
    if (!std::isfinite(out[i]) || std::abs(out[i]) > kMaxMagnitude)
      fail(file, s.source + "." + field,
           (std::isfinite(out[i]) ? "value beyond 1e100" : "non-finite value") + std::string(" at time stamp ") +
               std::to_string(raw.time_us[i]) + " us (" + s.label + ")");
  }
  return out;
}

std::vector<double> temperature(const std::string& file, const Stream& s, const std::vector<double>& values, const SampleOrder& raw,
                                std::vector<std::string>* notes) {
  std::vector<double> out(raw.message.size());
  std::size_t missing = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i] = values[raw.message[i]];
    missing += !std::isfinite(out[i]) || std::abs(out[i]) > kMaxMagnitude;
  }
  if (missing == out.size()) {
    if (notes) notes->push_back(s.label + ": temperature is NaN throughout; no temperature channel for it");
    return {};
  }
  if (missing > 0)
    fail(file, s.source + ".temperature",
         std::to_string(missing) + " of " + std::to_string(out.size()) + " temperatures are not finite (" + s.label + ")");
  return out;
}

TimeSeries assemble(const std::string& file, std::vector<Stream> all, const LogSelection& selection,
                    std::vector<std::string>* notes) {
  const Selection sel = selection.sensor.empty() ? Selection{} : parse_selection(selection.sensor, "--sensor");
  std::vector<Stream> streams;
  for (auto& s : all) {
    if (selection.instance >= 0 && s.instance != selection.instance) continue;
    if (!selects_any_axis(sel, s.sensor, s.instance)) continue;
    if (s.instance > kMaxInstance)
      fail(file, s.source, "instance " + std::to_string(s.instance) + " is beyond the IMU role names (0 to 99)");
    if (s.time_us.size() < 2)
      fail(file, s.source, s.label + " has " + std::to_string(s.time_us.size()) + " samples; a record needs at least 2");
    streams.push_back(std::move(s));
  }
  if (streams.empty()) {
    std::string have;
    for (const auto& s : all) have += (have.empty() ? "" : ", ") + s.label;
    fail(file, selection.instance >= 0 ? "--instance" : "--sensor",
         "the selection (instance " + (selection.instance >= 0 ? std::to_string(selection.instance) : std::string("any")) +
             ", sensor '" + (selection.sensor.empty() ? std::string("all") : selection.sensor) +
             "') matches no stream of the log (it has: " + (have.empty() ? std::string("none") : have) + ")");
  }
  // Gyros first, then accelerometers; by instance within each.
  std::stable_sort(streams.begin(), streams.end(), [](const Stream& a, const Stream& b) {
    return std::pair(a.sensor != Sensor::Gyro, a.instance) < std::pair(b.sensor != Sensor::Gyro, b.instance);
  });

  std::int64_t from = streams.front().time_us.front(), to = streams.front().time_us.back();
  for (const auto& s : streams) {
    from = std::max(from, s.time_us.front());
    to = std::min(to, s.time_us.back());
  }
  const Stream& base = streams.front();
  std::vector<std::int64_t> base_time;
  for (const auto t : base.time_us)
    if (t >= from && t <= to) base_time.push_back(t);
  if (base_time.size() < 2)
    fail(file, base.source, "the selected streams overlap in time at fewer than 2 samples of the time base (" + base.label + ")");
  if (notes && streams.size() > 1) {
    notes->push_back("time base: " + base.label + "; " + std::to_string(streams.size() - 1) +
                     " other streams linearly interpolated onto it");
    if (base_time.size() < base.time_us.size())
      notes->push_back(std::to_string(base.time_us.size() - base_time.size()) + " samples of the time base outside the span " +
                       "every selected stream covers were dropped");
  }

  Eigen::VectorXd time(static_cast<Eigen::Index>(base_time.size()));
  for (std::size_t i = 0; i < base_time.size(); ++i)
    time[static_cast<Eigen::Index>(i)] = static_cast<double>(base_time[i]) / kMicrosecondsPerSecond;
  TimeSeries record(std::move(time));
  std::vector<bool> has_temperature(kMaxInstance + 1, false), has_device(kMaxInstance + 1, false);
  for (const auto& s : streams) {
    for (int a = 0; a < 3; ++a) {
      const ChannelId id{s.sensor, kAxes[a], s.instance};
      if (!sel.selects(id)) continue;
      const std::string unit = internal_unit(s.sensor);
      record.set_channel({id.role(), unit, s.source, resample(s.time_us, s.axes[a], base_time), unit});
    }
    const auto instance = static_cast<std::size_t>(s.instance);
    if (!s.temperature.empty() && !has_temperature[instance]) {
      has_temperature[instance] = true;
      record.set_channel({temperature_role(s.instance), "degC", s.source, resample(s.time_us, s.temperature, base_time), "degC"});
    }
    if (!s.device_id.empty() && !has_device[instance]) {
      has_device[instance] = true;
      record.set_device_id(s.instance, s.device_id);
    }
  }
  return record;
}

}  // namespace driftlab::imu
