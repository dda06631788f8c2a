#include "framework/imu_streams.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "framework/csv.hpp"
#include "framework/error.hpp"

namespace driftlab::imu {
namespace {

constexpr char kAxes[3] = {'x', 'y', 'z'};
constexpr std::int64_t kExactTicks = std::int64_t{1} << 53;  // converted to double without rounding

double seconds(std::int64_t ticks, std::int64_t ticks_per_second) {
  if (ticks > -kExactTicks && ticks < kExactTicks)
    return static_cast<double>(ticks) / static_cast<double>(ticks_per_second);
  return static_cast<double>(ticks / ticks_per_second) +
         static_cast<double>(ticks % ticks_per_second) / static_cast<double>(ticks_per_second);
}

// Values at the times `base` (all within the span of `time`), linear between samples.
Eigen::VectorXd resample(const std::vector<std::int64_t>& time, const std::vector<double>& values,
                         const std::vector<std::int64_t>& base) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(base.size()));
  std::size_t j = 0;
  for (std::size_t i = 0; i < base.size(); ++i) {
    const std::int64_t t = base[i];
    while (j + 1 < time.size() && time[j + 1] <= t) ++j;
    double v = values[j];
    if (time[j] != t && j + 1 < time.size())
      v += (values[j + 1] - values[j]) * static_cast<double>(t - time[j]) / static_cast<double>(time[j + 1] - time[j]);
    out[static_cast<Eigen::Index>(i)] = v;
  }
  return out;
}

bool selects_any_axis(const Selection& sel, Sensor sensor, int instance) {
  return std::any_of(std::begin(kAxes), std::end(kAxes), [&](char axis) {
    return sel.selects({sensor, axis, instance});
  });
}

void require_samples(const std::string& file, const std::string& source, const std::string& label, std::size_t n) {
  if (n < 2)
    throw DataError({file, 0, source}, label + " has " + std::to_string(n) + " samples; a record needs at least 2");
}

void require_instance(const std::string& file, const std::string& source, int instance) {
  if (instance < 0 || instance > kMaxInstance)
    throw DataError({file, 0, source},
                    "instance " + std::to_string(instance) + " is beyond the IMU role names (0 to 99)");
}

}  // namespace

std::vector<std::size_t> repaired_order(const std::vector<std::int64_t>& time, const std::string& label,
                                        std::vector<std::string>* notes) {
  std::size_t out_of_order = 0;
  for (std::size_t i = 1; i < time.size(); ++i) out_of_order += time[i] < time[i - 1];
  std::vector<std::size_t> order(time.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  if (out_of_order > 0)
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return time[a] < time[b]; });
  std::vector<std::size_t> kept;
  kept.reserve(order.size());
  for (const auto i : order)
    if (kept.empty() || time[kept.back()] != time[i]) kept.push_back(i);
  const std::size_t duplicates = order.size() - kept.size();
  if (notes && out_of_order > 0)
    notes->push_back(label + ": " + std::to_string(out_of_order) +
                     " samples earlier than the one before; sorted by time");
  if (notes && duplicates > 0)
    notes->push_back(label + ": " + std::to_string(duplicates) +
                     " repeated time stamps; the first sample of each kept");
  return kept;
}

bool usable_value(double v) { return std::isfinite(v) && std::abs(v) <= kMaxMagnitude; }

std::string unusable_value(double v) { return std::isfinite(v) ? "value beyond 1e100" : "non-finite value"; }

void check_temperature(std::vector<double>& values, const std::string& file, const std::string& field,
                       const std::string& label, std::vector<std::string>* notes) {
  const auto missing =
      static_cast<std::size_t>(std::count_if(values.begin(), values.end(), [](double v) { return !usable_value(v); }));
  if (missing == 0) return;
  if (missing < values.size())
    throw DataError({file, 0, field}, std::to_string(missing) + " of " + std::to_string(values.size()) +
                                          " temperatures are not finite (" + label + ")");
  if (notes) notes->push_back(label + ": temperature is NaN throughout; no temperature channel for it");
  values.clear();
}

std::int64_t time_stamp_us(const std::string& file, const std::string& source, double us) {
  constexpr double kMaxTimeUs = 9007199254740992.0;
  if (!(us >= 0.0 && us <= kMaxTimeUs))
    throw DataError({file, 0, source}, "time stamp " + std::to_string(us) + " us is outside 0 to 2^53 us");
  return static_cast<std::int64_t>(us);
}

void repair_order(SampleOrder& order, const std::string& label, std::vector<std::string>* notes) {
  SampleOrder repaired;
  for (const auto i : repaired_order(order.time_us, label, notes)) {
    repaired.time_us.push_back(order.time_us[i]);
    repaired.message.push_back(order.message[i]);
  }
  order = std::move(repaired);
}

std::vector<double> pick(const std::string& file, const SensorStream& s, const std::vector<double>& values,
                         const SampleOrder& order, const std::string& field) {
  std::vector<double> out(order.message.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i] = values[order.message[i]];
    if (!usable_value(out[i]))
      throw DataError(
          {file, 0, s.source + "." + field},
          unusable_value(out[i]) + " at time stamp " + std::to_string(order.time_us[i]) + " us (" + s.label + ")");
  }
  return out;
}

std::vector<double> pick_temperature(const std::string& file, const SensorStream& s, const std::vector<double>& values,
                                     const SampleOrder& order, std::vector<std::string>* notes) {
  std::vector<double> out;
  out.reserve(order.message.size());
  for (const auto i : order.message) out.push_back(values[i]);
  check_temperature(out, file, s.source + ".temperature", s.label, notes);
  return out;
}

TimeSeries assemble(std::vector<SensorStream> sensors, std::vector<TemperatureStream> temperatures,
                    const LogSelection& selection, std::int64_t ticks_per_second, const std::string& file,
                    std::vector<std::string>* notes) {
  const Selection sel = selection.sensor.empty() ? Selection{} : parse_selection(selection.sensor, "--sensor");
  std::vector<SensorStream> streams;
  std::string have;
  for (auto& s : sensors) {
    have += (have.empty() ? "" : ", ") + s.label;
    if (selection.instance >= 0 && s.instance != selection.instance) continue;
    if (!selects_any_axis(sel, s.sensor, s.instance)) continue;
    require_instance(file, s.source, s.instance);
    require_samples(file, s.source, s.label, s.time.size());
    streams.push_back(std::move(s));
  }
  if (streams.empty())
    throw DataError({file, 0, selection.instance >= 0 ? "--instance" : "--sensor"},
                    "the selection (instance " +
                        (selection.instance >= 0 ? std::to_string(selection.instance) : std::string("any")) +
                        ", sensor '" + (selection.sensor.empty() ? std::string("all") : selection.sensor) +
                        "') matches no stream of the log (it has: " + (have.empty() ? std::string("none") : have) +
                        ")");
  // Gyros first, then accelerometers; by instance within each.
  std::stable_sort(streams.begin(), streams.end(), [](const SensorStream& a, const SensorStream& b) {
    return std::pair(a.sensor != Sensor::Gyro, a.instance) < std::pair(b.sensor != Sensor::Gyro, b.instance);
  });

  // Per instance: the temperature a sensor stream carries, else a separate stream of the instance.
  std::vector<const SensorStream*> carried(kMaxInstance + 1, nullptr);
  std::vector<const TemperatureStream*> separate(kMaxInstance + 1, nullptr);
  for (const auto& s : streams)
    if (!s.temperature.empty() && !carried[static_cast<std::size_t>(s.instance)])
      carried[static_cast<std::size_t>(s.instance)] = &s;
  for (const auto& s : streams) {
    const auto instance = static_cast<std::size_t>(s.instance);
    if (carried[instance] || separate[instance]) continue;
    for (const auto& t : temperatures)
      if (t.instance == s.instance) {
        require_samples(file, t.source, t.label, t.time.size());
        separate[instance] = &t;
        break;
      }
  }

  std::int64_t from = streams.front().time.front(), to = streams.front().time.back();
  auto cover = [&](const std::vector<std::int64_t>& time) {
    from = std::max(from, time.front());
    to = std::min(to, time.back());
  };
  for (const auto& s : streams) cover(s.time);
  for (const auto* t : separate)
    if (t) cover(t->time);
  const SensorStream& base = streams.front();
  std::vector<std::int64_t> base_time;
  for (const auto t : base.time)
    if (t >= from && t <= to) base_time.push_back(t);
  if (base_time.size() < 2)
    throw DataError(
        {file, 0, base.source},
        "the selected streams overlap in time at fewer than 2 samples of the time base (" + base.label + ")");
  const std::size_t others = streams.size() - 1 +
                             static_cast<std::size_t>(std::count_if(separate.begin(), separate.end(),
                                                                    [](const auto* t) { return t != nullptr; }));
  if (notes && others > 0) {
    notes->push_back("time base: " + base.label + "; " + std::to_string(others) +
                     " other streams linearly interpolated onto it");
    if (base_time.size() < base.time.size())
      notes->push_back(std::to_string(base.time.size() - base_time.size()) +
                       " samples of the time base outside the span " + "every selected stream covers were dropped");
  }

  Eigen::VectorXd time(static_cast<Eigen::Index>(base_time.size()));
  for (std::size_t i = 0; i < base_time.size(); ++i)
    time[static_cast<Eigen::Index>(i)] = seconds(base_time[i], ticks_per_second);
  TimeSeries record(std::move(time));
  std::vector<bool> has_temperature(kMaxInstance + 1, false), has_device(kMaxInstance + 1, false);
  for (const auto& s : streams) {
    for (int a = 0; a < 3; ++a) {
      const ChannelId id{s.sensor, kAxes[a], s.instance};
      if (!sel.selects(id)) continue;
      const std::string unit = internal_unit(s.sensor);
      record.set_channel({id.role(), unit, s.source, resample(s.time, s.axes[a], base_time), unit});
    }
    const auto instance = static_cast<std::size_t>(s.instance);
    if (!has_temperature[instance]) {
      has_temperature[instance] = true;
      if (const auto* c = carried[instance])
        record.set_channel(
            {temperature_role(s.instance), "degC", c->source, resample(c->time, c->temperature, base_time), "degC"});
      else if (const auto* t = separate[instance])
        record.set_channel(
            {temperature_role(s.instance), "degC", t->source, resample(t->time, t->values, base_time), "degC"});
    }
    if (!s.device_id.empty() && !has_device[instance]) {
      has_device[instance] = true;
      record.set_device_id(s.instance, s.device_id);
    }
  }
  return record;
}

}  // namespace driftlab::imu
