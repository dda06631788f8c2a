#include "models/calibration/oven_run.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "framework/error.hpp"
#include "framework/sampling.hpp"

namespace driftlab::calibration {
namespace {

std::string fixed(double v, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", digits, v);
  return text;
}

}  // namespace

std::string to_string(Finding::Severity severity) {
  switch (severity) {
    case Finding::Severity::Note:
      return "note";
    case Finding::Severity::Warning:
      return "warning";
    case Finding::Severity::Error:
      return "error";
  }
  return "warning";
}

Binning make_bins(const Eigen::VectorXd& time_s, double bin_s) {
  Binning b;
  b.bin_of.resize(static_cast<std::size_t>(time_s.size()));
  for (const auto& block : sampling::time_blocks(time_s, bin_s)) {
    b.count.push_back(static_cast<double>(block.samples));
    b.first.push_back(block.first);
    std::fill_n(b.bin_of.begin() + block.first, block.samples, b.bins++);
  }
  return b;
}

RunsSummary summarize(const std::vector<OvenRun>& runs) {
  RunsSummary out{runs.front().min_c, runs.front().max_c, 0.0, false, false};
  for (const auto& r : runs) {
    out.min_c = std::min(out.min_c, r.min_c);
    out.max_c = std::max(out.max_c, r.max_c);
    out.longest_soak_s = std::max(out.longest_soak_s, r.longest_soak_s);
    out.heating = out.heating || r.heating();
    out.cooling = out.cooling || r.cooling();
  }
  return out;
}

bool OvenRun::heating() const {
  return std::any_of(legs.begin(), legs.end(), [](const Leg& l) { return l.direction > 0; });
}
bool OvenRun::cooling() const {
  return std::any_of(legs.begin(), legs.end(), [](const Leg& l) { return l.direction < 0; });
}

OvenRun analyse_oven_run(const std::string& record, const Eigen::VectorXd& time_s, const Eigen::VectorXd& temp_c,
                         double bin_s) {
  if (time_s.size() != temp_c.size() || time_s.size() < 2)
    throw DataError({record, 0, "temperature"}, "an oven run needs at least 2 samples of time and temperature");
  OvenRun run;
  run.record = record;
  // Bin means of the temperature.
  const Binning b = make_bins(time_s, bin_s);
  std::vector<double> t, temp(static_cast<std::size_t>(b.bins), 0.0);
  for (Eigen::Index i = 0; i < time_s.size(); ++i)
    temp[static_cast<std::size_t>(b.bin_of[static_cast<std::size_t>(i)])] += temp_c[i];
  for (int k = 0; k < b.bins; ++k) {
    temp[static_cast<std::size_t>(k)] /= b.count[static_cast<std::size_t>(k)];
    t.push_back(time_s[b.first[static_cast<std::size_t>(k)]]);
  }
  run.min_c = *std::min_element(temp.begin(), temp.end());
  run.max_c = *std::max_element(temp.begin(), temp.end());
  const double threshold = std::max(kReversalMinK, kReversalFraction * run.span_k());

  // Zig-zag: turning points at the running extreme once the temperature moves back past the threshold.
  std::vector<std::size_t> turns{0};
  int direction = 0;
  std::size_t extreme = 0;
  for (std::size_t k = 1; k < temp.size(); ++k) {
    if (direction == 0) {
      if (std::abs(temp[k] - temp[0]) > threshold) direction = temp[k] > temp[0] ? 1 : -1;
      if (direction != 0) extreme = k;
      continue;
    }
    if ((temp[k] - temp[extreme]) * direction > 0) {
      extreme = k;
    } else if ((temp[extreme] - temp[k]) * direction > threshold) {
      turns.push_back(extreme);
      direction = -direction;
      extreme = k;
    }
  }
  if (turns.back() != temp.size() - 1) turns.push_back(temp.size() - 1);
  for (std::size_t i = 0; i + 1 < turns.size(); ++i) {
    Leg leg{t[turns[i]], t[turns[i + 1]], temp[turns[i]], temp[turns[i + 1]], 0};
    if (std::abs(leg.to_c - leg.from_c) > threshold) leg.direction = leg.to_c > leg.from_c ? 1 : -1;
    run.legs.push_back(leg);
  }
  if (run.legs.empty()) run.legs.push_back({t.front(), t.back(), temp.front(), temp.back(), 0});

  // Soaks: greedy maximal stretches within the band.
  for (std::size_t i = 0; i < temp.size();) {
    double lo = temp[i], hi = temp[i], sum = 0;
    std::size_t j = i;
    while (j < temp.size() && std::max(hi, temp[j]) - std::min(lo, temp[j]) <= kSoakBandK) {
      lo = std::min(lo, temp[j]);
      hi = std::max(hi, temp[j]);
      sum += temp[j];
      ++j;
    }
    const double length = t[j - 1] - t[i] + bin_s;
    if (length >= kMinSoakS) {
      run.soaks.push_back({t[i], t[j - 1] + bin_s, sum / static_cast<double>(j - i)});
      run.longest_soak_s = std::max(run.longest_soak_s, length);
    }
    i = j;
  }
  const auto facts = sampling::facts_of(time_s);
  run.gaps = facts.gaps;
  run.regular_bursts = facts.regular_bursts();
  return run;
}

std::vector<Finding> quality_gate(const std::vector<OvenRun>& runs) {
  using S = Finding::Severity;
  std::vector<Finding> out;
  if (runs.empty()) return out;
  const RunsSummary all = summarize(runs);
  const double lo = all.min_c, hi = all.max_c, span = all.span_k(), longest_soak = all.longest_soak_s;
  const bool heating = all.heating, cooling = all.cooling;
  if (span < kMinFitSpanK) {
    out.push_back({S::Error, "span",
                   "temperature span " + fixed(span, 3) + " K (" + fixed(lo, 2) + " .. " + fixed(hi, 2) +
                       " degC) is below " + fixed(kMinFitSpanK, 2) + " K: nothing to fit"});
    return out;
  }
  if (span < kMinHistorySpanK)
    out.push_back({S::Warning, "span",
                   "temperature span " + fixed(span, 2) + " K (" + fixed(lo, 2) + " .. " + fixed(hi, 2) +
                       " degC) is below " + fixed(kMinHistorySpanK, 0) +
                       " K: no lag, dT/dt or hysteresis term is fitted"});
  if (!heating || !cooling)
    out.push_back({S::Warning, "one_direction",
                   std::string(heating   ? "heating only"
                               : cooling ? "cooling only"
                                         : "no heating or cooling leg") +
                       ": no dT/dt or hysteresis term is fitted (they need both directions)"});
  if (longest_soak < kMinSoakS)
    out.push_back({S::Warning, "no_soak",
                   "no soak (temperature within " + fixed(kSoakBandK, 1) + " K for " + fixed(kMinSoakS, 0) +
                       " s or more): no thermal lag term is fitted"});
  for (const auto& r : runs) {
    for (const auto& leg : r.legs) {
      if (leg.direction == 0) continue;
      const double ramp = std::abs(leg.ramp_k_per_min());
      const std::string where = r.record + ", " + leg.name() + " leg " + fixed(leg.start_s, 0) + " .. " +
                                fixed(leg.end_s, 0) + " s (" + fixed(leg.from_c, 1) + " -> " + fixed(leg.to_c, 1) +
                                " degC)";
      if (ramp > kMaxRampKPerMin)
        out.push_back({S::Warning, "fast_ramp",
                       where + ": mean ramp " + fixed(ramp, 1) + " K/min above " + fixed(kMaxRampKPerMin, 0) +
                           " K/min (the die lags the reading)"});
      if (leg.end_s - leg.start_s < kMinLegS)
        out.push_back(
            {S::Warning, "short_leg",
             where + ": " + fixed(leg.end_s - leg.start_s, 0) + " s, shorter than " + fixed(kMinLegS, 0) + " s"});
    }
    if (r.gaps > 0)
      out.push_back({r.regular_bursts ? S::Note : S::Warning, "dropouts",
                     r.record + ": " + std::to_string(r.gaps) + " gap" + (r.gaps == 1 ? "" : "s") +
                         (r.regular_bursts ? " (regular bursts: a recording scheme)" : " (dropouts)")});
  }
  return out;
}

}  // namespace driftlab::calibration
