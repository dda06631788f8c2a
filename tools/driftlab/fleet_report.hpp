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
// unit, naming channel, figure, value and fleet median. For the bias figures (FigureDef::floored:
// a0, hysteresis) the scale is at least the channel's fleet-median held-out residual: a difference
// within the accuracy the models claim is not unusual. Without that floor a figure that is 0 in
// most units (a hysteresis term kept only where significant) flagged every unit with a small one
// (measured: 4 of 16 normal simulated units, 7 to 15 deg/h against held-out residuals of 10 to 17).
//
// Spec limits: a manifest column "<channels>.<figure key>_max" (channels as --channels: gyro,
// gyro1, gyro_x, accel; the key's unit must be the channels' sensor's) bounds |figure| of every
// selected channel; an empty cell sets no limit for that unit. A unit is within spec when it passed
// and meets every limit; yield = units within spec / units.
#pragma once

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

inline constexpr double kOutlierZ = 3.5;  // Iglewicz & Hoaglin's cut for the modified z-score

struct FigureDef {
  const char* name;
  const char* gyro_suffix;
  const char* accel_suffix;
  const char* doc;
  bool floored;  // outlier scale at least the channel's median held-out residual (same unit)
};
inline constexpr FigureDef kFigures[] = {
    {"a0", "dph", "mg", "bias at T0", true},
    {"a1", "dph_per_k", "mg_per_k", "slope of the bias at T0", false},
    {"hysteresis", "dph", "mg", "heating/cooling branch coefficient", true},
    {"N", "dph_rthz", "mg_rthz", "white-noise density of the compensated residual", false},
    {"holdout", "dph", "mg", "held-out residual", false},
};
std::string figure_key(const FigureDef& figure, imu::Sensor sensor);  // "holdout_dph"

// The figures of one fitted channel, by key.
std::map<std::string, double> channel_figures(const calibration::ChannelCalibration& channel);

struct SpecLimit {
  std::string column;  // the manifest header, "gyro.holdout_dph_max"
  imu::Selection channels;
  std::string figure_key;
  double max = 0.0;
};
// Parses a manifest header "<channels>.<figure key>_max"; ConfigError naming `where` otherwise.
SpecLimit parse_spec_column(const std::string& header, const Location& where);

struct UnitSummary {
  std::string unit;
  std::string status;  // "passed", "failed"
  int exit_class = 0;  // of a failed unit: 1 failure, 2 configuration, 3 bad data
  std::string reason;
  std::map<std::string, std::map<std::string, double>> figures;  // channel role -> key -> value
  std::vector<SpecLimit> limits;  // this unit's (non-empty cells)
};
// A unit's summary from its status.json (the format cmd_fleet writes); ConfigError naming the file
// when it is not one.
UnitSummary read_unit_summary(const std::filesystem::path& status_json);

struct Outlier {
  std::string unit, channel, figure_key;
  double value = 0.0, median = 0.0, z = 0.0;
  std::string text;  // "gyro_x hysteresis_dph 151.2; fleet median 3.1 (robust z 14.2)"
};
std::vector<Outlier> find_outliers(const std::vector<UnitSummary>& units);

// The limits a passed unit does not meet, in words; empty when within spec.
std::vector<std::string> spec_violations(const UnitSummary& unit);

// Writes OUT/report.json, OUT/units.csv and OUT/report.html into `files` (planned there).
void write_fleet_report(const std::vector<UnitSummary>& units, const std::vector<Outlier>& outliers,
                        const std::filesystem::path& out, const std::string& command, OutputSet& files);

}  // namespace driftlab::cli
