// What an oven run holds, read from its temperature before anything is fitted: the legs (heating
// and cooling ramps between reversals), the soaks (plateaus), the span, the ramp rates, the
// dropouts, and the quality gate's findings on them. `driftlab calibrate` prints the findings,
// stores them in report.json and the HTML report, and the fit (fit.hpp) uses the legs to hold out
// whole legs and the directions and soaks to decide which history terms the run can determine.
//
// Legs: the temperature is averaged over bins of bin_s seconds and cut at its reversals, found as
// a zig-zag with a reversal threshold of max(kReversalMinK, kReversalFraction x span): a reversal is
// a move back from the running extreme by more than the threshold, so sensor noise and overshoot
// at a plateau do not cut a leg. A leg's direction is +1 (heating) or -1 (cooling) when it moves
// by more than the threshold, else 0 (a run that never leaves its start level).
// Soaks: maximal stretches of bins whose temperature stays within kSoakBandK (max - min), at least
// kMinSoakS long.
//
// The gate's limits, each with its reason (one home: the fit's plausibility rules use them too):
//   kMinFitSpanK        0.05 K   error below: no temperature dependence can be fitted (a MEMS
//                                temperature sensor resolves ~0.003-0.06 K)
//   kMinHistorySpanK    10 K     warning below: lag, dT/dt and hysteresis terms are not fitted (a
//                                term that moves the bias by a few deg/h per K cannot be told
//                                from the polynomial over a few K)
//   both directions              warning when one is missing: dT/dt and hysteresis terms are not
//                                fitted (fitted on one direction they are a constant offset there
//                                and a wrong correction in the other)
//   kMinSoakS           60 s     a thermal lag is only determined against a soak at least as long
//                                as the lag; without one, no lag term (warning)
//   kMaxRampKPerMin     5 K/min  warning above: the die lags the sensor's reading (datasheet
//                                ramp rates for thermal calibration are 0.5-3 K/min)
//   kMinLegS            300 s    warning below: a ramp this short holds few independent bins
//   dropouts                     warning: steps longer than sampling::kGapFactor x the median step
//                                (a note for regular bursts, which are a recording scheme)
// --strict (driftlab calibrate) turns every warning into an error.
// Units: time s, temperature degC, rates K/min.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace driftlab::calibration {

inline constexpr double kReversalMinK = 0.5;
inline constexpr double kReversalFraction = 0.1;
inline constexpr double kSoakBandK = 0.5;
inline constexpr double kMinSoakS = 60.0;
inline constexpr double kMinFitSpanK = 0.05;
inline constexpr double kMinHistorySpanK = 10.0;
inline constexpr double kMaxRampKPerMin = 5.0;
inline constexpr double kMinLegS = 300.0;

// The time blocks of bin_s seconds (sampling::time_blocks) with a bin index per sample: the rows
// every calibration fit and this analysis average over.
struct Binning {
  std::vector<int> bin_of;          // per sample: its bin
  std::vector<double> count;        // per bin: samples
  std::vector<Eigen::Index> first;  // per bin: its first sample
  int bins = 0;
};
Binning make_bins(const Eigen::VectorXd& time_s, double bin_s);

struct Leg {
  double start_s = 0.0, end_s = 0.0;  // time of its first and last bin
  double from_c = 0.0, to_c = 0.0;    // bin-mean temperature at its ends
  int direction = 0;                  // +1 heating, -1 cooling, 0 level
  double ramp_k_per_min() const { return end_s > start_s ? 60.0 * (to_c - from_c) / (end_s - start_s) : 0.0; }
  std::string name() const { return direction > 0 ? "heating" : direction < 0 ? "cooling" : "level"; }
};

struct Soak {
  double start_s = 0.0, end_s = 0.0, level_c = 0.0;
};

struct Finding {
  enum class Severity { Note, Warning, Error };
  Severity severity = Severity::Warning;
  std::string code;     // short name: "span", "one_direction", "no_soak", "fast_ramp", "short_leg", "dropouts"
  std::string message;  // with the numbers
};
std::string to_string(Finding::Severity severity);  // "note", "warning", "error"

struct OvenRun {
  std::string record;
  std::vector<Leg> legs;
  std::vector<Soak> soaks;
  double min_c = 0.0, max_c = 0.0;
  double longest_soak_s = 0.0;
  int gaps = 0;
  bool regular_bursts = false;
  bool heating() const;  // a heating leg is present
  bool cooling() const;
  double span_k() const { return max_c - min_c; }
};

// What several runs fitted together hold (directions and soaks may come from any run).
struct RunsSummary {
  double min_c = 0.0, max_c = 0.0, longest_soak_s = 0.0;
  bool heating = false, cooling = false;
  double span_k() const { return max_c - min_c; }
};
RunsSummary summarize(const std::vector<OvenRun>& runs);  // runs must not be empty

// Throws DataError (naming the record) when time and temperature differ in length or hold fewer
// than 2 samples.
OvenRun analyse_oven_run(const std::string& record, const Eigen::VectorXd& time_s, const Eigen::VectorXd& temp_c,
                         double bin_s);

// The gate over the runs a model is fitted on together (directions and soaks may come from any run).
std::vector<Finding> quality_gate(const std::vector<OvenRun>& runs);

}  // namespace driftlab::calibration
