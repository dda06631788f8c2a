// The fleet report of `driftlab fleet` (issue 24): built from the units' status files alone
// (OUT/units/<id>/status.json), so units finished by an earlier run and units run now give the same
// report, and written as OUT/report.json, OUT/units.csv and OUT/report.html.
//
// Figures of one channel (kFigures), in display units: deg/h for a gyro, mg for an accelerometer.
// Their keys carry the unit: "<figure>_<suffix>", e.g. holdout_dph, a1_mg_per_k.
//   a0          bias at T0, the polynomial's constant term          dph        | mg
//   a1          slope of the bias at T0                             dph_per_k  | mg_per_k
//   hysteresis  heating/cooling branch coefficient (0: not kept)    dph        | mg
//   N           white-noise density of the compensated residual     dph_rthz   | mg_rthz
//   holdout     held-out residual of the model (calibrate's fit.holdout_rms, 10-s bins)  dph | mg
//
// Outliers, per channel and figure over the units that passed: the modified z-score
// z = 0.6745 (x - median) / MAD (Iglewicz & Hoaglin 1993); when MAD = 0,
// z = (x - median) / (1.2533 mean|x - median|); none when that is 0 too. |z| > kOutlierZ flags the
// unit, naming channel, figure, value and fleet median. The scale is at least FigureDef::
// holdout_floor times the channel's fleet-median held-out residual. For the bias figures (a0,
// hysteresis; floor 1) a difference within the accuracy the models claim is not unusual: without
// that floor a figure that is 0 in most units (a hysteresis term kept only where significant)
// flagged every unit with a small one (measured: 4 of 16 normal simulated units, 7 to 15 deg/h
// against held-out residuals of 10 to 17). For the held-out residual itself (floor 0.5: flagged
// above 2.75 times the fleet median) an RMS over a few held-out blocks of a record with random-walk
// noise has a heavy right tail: without the floor 10 of 192 normal units of a simulated fleet were
// flagged (1.4 to 2.0 times the median, robust z 3.6 to 6.8); the planted faults that show in it
// reach 2.6 to 5.4 times.
//
// Robust distance over the whole model (in find_outliers): for a passed unit, D^2 = sum of z^2
// over every (channel, figure) of it that has a scale, z the robust z-score above (same median,
// scale and floors). For independent normal figures D^2 ~ chi-square with p = the figures summed.
// They are not (N and holdout move together, floors shrink z, robust scales from a few hundred
// units are noisy: measured median D^2 of 95 for p = 30 in a 12-unit fleet), so D^2 is first made
// consistent as in MCD reweighting (Rousseeuw & Van Driessen 1999): D^2 chi2_p(0.5) / median of
// the fleet's D^2. The unit is flagged when that exceeds the chi-square quantile
// kDistanceQuantile(p): a per-unit false alarm of 0.1 % if the consistent D^2 were chi-square,
// about 0.2 expected false flags in 200 units. A flag names the kDistanceDrivers figures that
// contribute most; it finds a unit unusual in several figures none of which crosses kOutlierZ alone.
//
// Quantisation (quantisation_check, on each channel's raw record): q = the smallest step between
// the record's distinct values (steps below kQuantisationTolerance of the value range are taken as
// rounding); share = the fraction of samples within kQuantisationTolerance q of a multiple of q;
// sigma = the per-sample noise 1.4826 MAD(successive differences) / sqrt(2). The channel is
// quantised when share >= kQuantisedShare and q >= sigma: its output, hence its residual after
// any bias correction, sits on multiples of one LSB that the noise does not dither (a bias stuck at
// a multiple of one LSB). A fine LSB under the noise (every normal unit at its device resolution)
// is not a finding; a constant output has no step (a dead axis shows in N instead).
//
// Families (find_families): each passed unit's gyro bias-vs-temperature curves (the fitted bias
// polynomial of every gyro channel evaluated at kFamilyGridC, display units, concatenated) are
// clustered by k-medoids (PAM: BUILD then SWAP, Kaufman & Rousseeuw 1990; Euclidean distance,
// deterministic: ties go to the first unit in manifest order) for k = 2..kMaxFamilies; the k of the
// largest mean silhouette is kept when that silhouette is >= kFamilySilhouette (Kaufman &
// Rousseeuw's "reasonable structure", 0.51) and its smallest family holds at least kMinFamilyShare
// of the units (and 2): a lone faulty unit is an outlier, not a family. Otherwise one family.
//
// Spec limits: a manifest column "<channels>.<figure key>_max" (channels as --channels: gyro,
// gyro1, gyro_x, accel; the key's unit must be the channels' sensor's) bounds |figure| of every
// selected channel; an empty cell sets no limit for that unit. A unit is within spec when it passed
// and meets every limit; yield = units within spec / units.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "framework/error.hpp"
#include "framework/imu.hpp"
#include "framework/output_set.hpp"
#include "models/calibration/calibration_model.hpp"

namespace driftlab::cli {

inline constexpr double kOutlierZ = 3.5;            // Iglewicz & Hoaglin's cut for the modified z-score
inline constexpr double kDistanceQuantile = 0.999;  // chi-square quantile of the whole-model distance
inline constexpr std::size_t kDistanceDrivers = 3;  // figures named in a distance flag
inline constexpr double kQuantisationTolerance = 1e-6;
inline constexpr double kQuantisedShare = 0.99;
inline constexpr double kFamilyGridC[] = {-30, -20, -10, 0, 10, 20, 30, 40, 50, 60};  // degC (the oven's span)
inline constexpr std::size_t kMaxFamilies = 6;
inline constexpr double kFamilySilhouette = 0.51;
inline constexpr double kMinFamilyShare = 0.05;

struct FigureDef {
  const char* name;
  const char* gyro_suffix;
  const char* accel_suffix;
  const char* doc;
  double holdout_floor;  // outlier scale at least this times the channel's median held-out residual
};
inline constexpr FigureDef kFigures[] = {
    {"a0", "dph", "mg", "bias at T0", 1.0},
    {"a1", "dph_per_k", "mg_per_k", "slope of the bias at T0", 0.0},
    {"hysteresis", "dph", "mg", "heating/cooling branch coefficient", 1.0},
    {"N", "dph_rthz", "mg_rthz", "white-noise density of the compensated residual", 0.0},
    {"holdout", "dph", "mg", "held-out residual", 0.5},
};
std::string figure_key(const FigureDef& figure, imu::Sensor sensor);  // "holdout_dph"

// The figures of one fitted channel, by key.
std::map<std::string, double> channel_figures(const calibration::ChannelCalibration& channel);

struct Quantisation {
  double lsb = 0.0;           // q, the record's unit (0: no step, a constant output)
  double share = 0.0;         // of samples on multiples of q
  double sample_sigma = 0.0;  // per-sample noise, the record's unit
  bool quantised = false;
};
Quantisation quantisation_check(const Eigen::VectorXd& x);

// The fitted bias of a channel at kFamilyGridC, display units.
std::vector<double> bias_curve(const calibration::ChannelCalibration& channel);

struct SpecLimit {
  std::string column;  // the manifest header, "gyro.holdout_dph_max"
  imu::Selection channels;
  std::string figure_key;
  double max = 0.0;
};
// Parses a manifest header "<channels>.<figure key>_max"; ConfigError naming `where` otherwise.
SpecLimit parse_spec_column(const std::string& header, const Location& where);

// status.json of one unit (OUT/units/<id>/status.json, format kUnitStatusFormat): the one
// definition of its keys. cmd_fleet writes it; a resumed run (its input_hash) and the fleet report
// (unit_summary) read it back.
inline constexpr const char* kUnitStatusFormat = "driftlab-fleet-unit/2";
struct GateFinding {  // one finding of the calibration quality gate
  std::string severity, code, message;
};
struct DiscrepancyCheck {  // `driftlab discrepancy` on a gyro channel's first record
  struct Named {
    std::string effect;
    double delta_bic = 0.0;
  };
  std::vector<Named> named;
  bool unexplained = false;
  double gap_initial_dph = 0.0, gap_final_dph = 0.0;
  std::string text;  // "gyro_x: ... named, delta BIC ..."
};
struct UnitStatus {
  std::string unit;
  std::string input_hash;         // of the unit's inputs and options
  std::vector<std::string> data;  // its records
  std::string status = "failed";  // "passed", "failed"
  int exit_class = 0;             // of a failed unit: 1, 2 or 3
  std::string reason;             // of a failed unit
  std::vector<GateFinding> quality_gate;
  std::map<std::string, std::map<std::string, double>> figures;  // channel role -> key -> value
  std::map<std::string, Quantisation> quantisation;              // channel role -> check, display units
  std::map<std::string, std::vector<double>> bias_curves;        // channel role -> bias_curve
  std::map<std::string, DiscrepancyCheck> discrepancy;           // gyro channel role -> check (--discrepancy)
  std::vector<std::string> export_notes;
};
nlohmann::json to_json(const UnitStatus& status);
// Throws nlohmann::json::exception when `j` is not a unit status.
UnitStatus unit_status_from_json(const nlohmann::json& j);
// ConfigError naming the file when it is not a unit status file.
UnitStatus read_unit_status(const std::filesystem::path& status_json);

struct UnitSummary {
  std::string unit;
  std::string status;  // "passed", "failed"
  int exit_class = 0;  // of a failed unit: 1 failure, 2 configuration, 3 bad data
  std::string reason;
  std::map<std::string, std::map<std::string, double>> figures;  // channel role -> key -> value
  std::vector<SpecLimit> limits;                                 // this unit's (non-empty cells)
  std::map<std::string, Quantisation> quantisation;              // channel role -> check, display units
  std::map<std::string, std::vector<double>> bias_curves;        // channel role -> bias_curve
  std::vector<std::string> discrepancy;  // per gyro channel checked (--discrepancy): "gyro_x: ... named, delta BIC ..."
};
// What the report needs of a unit's status (limits: none, they come from the manifest).
UnitSummary unit_summary(const UnitStatus& status);
// A unit's summary from its status.json (read_unit_status); ConfigError naming the file when it is
// not one.
UnitSummary read_unit_summary(const std::filesystem::path& status_json);

// A finding about one unit. rule "robust_z": channel, figure_key, value, fleet median, z;
// "distance": channel "model", figure_key "distance", value the consistent D^2, median chi2_p(0.5)
// (the fleet's median after the correction), z = D^2 / threshold; "quantisation": figure_key "quantisation_<suffix>",
// value the LSB, median the fleet's LSB of that channel, z = LSB / per-sample noise (infinite, null in report.json,
// when the output does not move between samples at all).
struct Outlier {
  std::string unit, channel, figure_key;
  double value = 0.0, median = 0.0, z = 0.0;
  std::string text;  // "gyro_x hysteresis_dph 151.2; fleet median 3.1 (robust z 14.2)"
  std::string rule = "robust_z";
};
// Every finding, by unit (manifest order kept within a unit): robust z per figure, the whole-model
// distance, quantisation.
std::vector<Outlier> find_outliers(const std::vector<UnitSummary>& units);

struct Families {
  std::size_t k = 1;
  double silhouette = 0.0;                    // of the k kept (0 for one family)
  std::vector<double> silhouette_by_k;        // k = 2.. (empty: fewer than 4 units)
  std::map<std::string, std::size_t> family;  // unit -> 0-based family (medoid order)
  std::vector<std::string> medoids;           // the unit of each family
  std::vector<std::string> channels;          // the curves' channels, in order
};
Families find_families(const std::vector<UnitSummary>& units);

// The limits a passed unit does not meet, in words; empty when within spec.
std::vector<std::string> spec_violations(const UnitSummary& unit);

// Writes OUT/report.json, OUT/units.csv and OUT/report.html into `files` (planned there).
void write_fleet_report(const std::vector<UnitSummary>& units, const std::vector<Outlier>& outliers,
                        const Families& families, const std::filesystem::path& out, const std::string& command,
                        OutputSet& files);

}  // namespace driftlab::cli
