#include "framework/sampling.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "framework/signal.hpp"

namespace driftlab::sampling {

double mean_rate_hz(const Eigen::VectorXd& time_s) {
  const Eigen::Index n = time_s.size();
  if (n < 2) return 0.0;
  const double span = time_s[n - 1] - time_s[0];
  return span > 0.0 ? static_cast<double>(n - 1) / span : 0.0;
}

Facts facts_of(const Eigen::VectorXd& time_s, double gap_factor) {
  Facts f;
  f.samples = time_s.size();
  f.gap_factor = gap_factor;
  f.mean_rate_hz = mean_rate_hz(time_s);
  if (time_s.size() > 0) f.segments.push_back({0, time_s.size()});
  if (time_s.size() < 2) return f;
  f.median_step_s = signal::median_step(time_s);
  if (time_s.size() < 3) return f;
  const double limit = gap_factor * f.median_step_s;
  std::vector<double> starts{time_s[0]};
  for (Eigen::Index k = 0; k + 1 < time_s.size(); ++k) {
    if (time_s[k + 1] - time_s[k] <= limit) continue;
    if (f.gaps++ == 0) {
      f.first_gap_time_s = time_s[k];
      f.first_gap_index = k;
      f.first_gap_s = time_s[k + 1] - time_s[k];
    }
    starts.push_back(time_s[k + 1]);
    f.segments.back().samples = k + 1 - f.segments.back().first;
    f.segments.push_back({k + 1, time_s.size() - (k + 1)});
  }
  for (std::size_t i = 1; i < starts.size(); ++i) {
    const double period = starts[i] - starts[i - 1];
    f.shortest_period_s = i == 1 ? period : std::min(f.shortest_period_s, period);
    f.longest_period_s = std::max(f.longest_period_s, period);
  }
  return f;
}

std::vector<TimeBlock> time_blocks(const Eigen::VectorXd& time_s, double block_s) {
  if (!(block_s > 0.0)) throw std::invalid_argument("block length must be positive");
  std::vector<TimeBlock> blocks;
  const Eigen::Index n = time_s.size();
  const auto number_of = [&](Eigen::Index i) {
    return static_cast<long>(std::floor((time_s[i] - time_s[0]) / block_s + kBlockBoundaryTolerance));
  };
  for (Eigen::Index first = 0, end = 0; first < n; first = end) {
    const long k = number_of(first);
    while (end < n && number_of(end) == k) ++end;
    blocks.push_back({first, end - first, k});
  }
  return blocks;
}

double rate_within_segments_hz(const Eigen::VectorXd& time_s, const Facts& facts) {
  double span = 0.0, steps = 0.0;
  for (const auto& s : facts.segments) {
    if (s.samples < 2) continue;
    span += time_s[s.first + s.samples - 1] - time_s[s.first];
    steps += static_cast<double>(s.samples - 1);
  }
  return span > 0.0 ? steps / span : 0.0;
}

std::string describe(const Facts& facts, const Eigen::VectorXd& time_s) {
  const double fs = rate_within_segments_hz(time_s, facts);
  switch (facts.layout()) {
    case Layout::Even:
      return "evenly sampled at " + message_number(fs) + " Hz";
    case Layout::RegularBursts: {
      Eigen::Index fewest = facts.segments.front().samples, most = fewest;
      for (const auto& s : facts.segments) {
        fewest = std::min(fewest, s.samples);
        most = std::max(most, s.samples);
      }
      const std::string count =
          fewest == most ? std::to_string(fewest) : std::to_string(fewest) + " .. " + std::to_string(most);
      return std::to_string(facts.segments.size()) + " regular bursts of " + count + " samples at " +
             message_number(fs) + " Hz, one every " + message_number(facts.shortest_period_s) + " .. " +
             message_number(facts.longest_period_s) + " s";
    }
    case Layout::Irregular:
      break;
  }
  if (facts.gaps == 1) return "irregular: one gap, no regular bursts";
  return "irregular: " + std::to_string(facts.gaps) + " gaps, not at a regular period (" +
         message_number(facts.shortest_period_s) + " .. " + message_number(facts.longest_period_s) +
         " s from one segment's start to the next)";
}

namespace {

// The message of both errors below: `analysis` `takes`, the record's gaps, the first one, the
// layout, the ways out and `hint`.
DataError sampling_error(const Facts& facts, const Eigen::VectorXd& time_s, const std::string& file,
                         std::string_view analysis, std::string_view takes, std::string_view hint) {
  std::string message = std::string(analysis) + " " + std::string(takes) + ", and this record has " +
                        std::to_string(facts.gaps) + " gap(s) (steps longer than " + message_number(facts.gap_factor) +
                        " x the median step of " + message_number(facts.median_step_s) +
                        " s, see --max-gap): the first of " + message_number(facts.first_gap_s) +
                        " s after t = " + message_number(facts.first_gap_time_s) + " s (sample " +
                        std::to_string(facts.first_gap_index + 1) + "). The record is " + describe(facts, time_s) +
                        ". Resample it onto an even grid with a stated method (e.g. linear interpolation) and give " +
                        "that file, split it at its gaps, or analyse the segments one by one";
  if (!hint.empty()) message += " (" + std::string(hint) + ")";
  return DataError({file, 0, "time"}, message + ".");
}

}  // namespace

DataError uneven_sampling_error(const Facts& facts, const Eigen::VectorXd& time_s, const std::string& file,
                                std::string_view analysis, std::string_view hint) {
  return sampling_error(facts, time_s, file, analysis, "assumes even sampling", hint);
}

DataError irregular_sampling_error(const Facts& facts, const Eigen::VectorXd& time_s, const std::string& file,
                                   std::string_view analysis, std::string_view hint) {
  return sampling_error(facts, time_s, file, analysis,
                        "takes an evenly sampled record or regular bursts, not gaps that are not regular bursts", hint);
}

}  // namespace driftlab::sampling
