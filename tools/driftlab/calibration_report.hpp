// The `driftlab calibrate --report DIR` evidence: the competing models fitted on the same
// calibration data, scored on held-out records (report.json + report.html), for a test engineer:
//   - the quality gate's findings and which model was chosen, and why;
//   - per held-out record a table of every method (residual drift, B, N, extrapolated share) and the
//     residual drift of each on every leg of that record (legs as the quality gate finds them:
//     models/calibration/oven_run.hpp);
//   - figures: bias against temperature (60-s block means of measured - true rate; calibration and
//     held-out records, heating and cooling in distinct colours) with each model's correction on
//     the held-out record; |residual| against temperature and against time (log axes: the models
//     differ by decades); the Allan deviation of every method's residual with 68.3 % intervals.
// Units: deg/h throughout (the report scores gyro channels).
#pragma once

#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "framework/output_set.hpp"
#include "models/allan/confidence.hpp"
#include "models/calibration/calibration_model.hpp"
#include "models/calibration/fit.hpp"
#include "models/calibration/oven_run.hpp"
#include "tools/driftlab/cli.hpp"

namespace driftlab::cli {

struct CompetingModel {
  std::string name;                                    // "PX4-style poly", "poly", "physical", "rbf"
  std::string description;                             // how it was fitted
  std::optional<calibration::CalibrationModel> model;  // empty: no compensation
};

// An externally computed output for a record (e.g. the offline paper pipeline), same length.
struct ExternalOutput {
  std::string name, description;
  std::string bandwidth;  // what the method does to the output bandwidth
  std::size_t record = 0;
  Eigen::VectorXd rate_rad_s;
};

struct ReportInput {
  std::string command;                           // the command line, for the report
  std::vector<calibration::Record> calibration;  // what was fitted
  std::vector<CompetingModel> models;
  std::vector<calibration::Record> evaluations;  // held-out records
  std::vector<ExternalOutput> external;
  std::string truth_note;                  // what "truth" is for these records
  std::vector<calibration::Finding> gate;  // the oven-run quality gate on the calibration records
  std::string chosen;                      // the model written, and why (its selection)
  std::vector<std::string> notes;          // e.g. a baseline that could not be fitted
};

// One method's scores on one held-out record, in deg/h.
struct MethodScore {
  std::string name, description, bandwidth;
  double drift_dph = 0, b_dph = NAN, n_dph_rthz = NAN, extrapolated = 0;  // extrapolated: share of samples
  bool b_resolved = false;  // b_dph is B; otherwise only the bound B < b_dph (models/allan/analysis.hpp)
  double b_within_tau_s = 0;
  std::vector<double> block_mean_dph;  // per 60-s block: mean of output - truth
  std::vector<double> block_bias_dph;  // per block: mean of the correction applied (models only)
  std::vector<double> leg_drift_dph;   // per leg: residual drift over the leg (NaN: shorter than a block)
  std::vector<allan::Estimate> allan;  // OADEV of output - truth, rad/s (evenly sampled records)
};

// Every method's scores on one held-out record.
struct HeldOutScores {
  std::string record;
  std::vector<MethodScore> methods;                 // the models in input order, then the external outputs
  std::optional<double> intrinsic_floor_drift_dph;  // measured - systematic, when the record has it
};

// Scores every model on every held-out record and stages `files` (report.json, report.html; planned
// with plan_report_files, cli.hpp) in `outputs` (figures need gnuplot; without it the HTML says so);
// the caller commits. Returns the scores per held-out record.
std::vector<HeldOutScores> write_calibration_report(const ReportInput& input, const ReportFiles& files,
                                                    OutputSet& outputs);

}  // namespace driftlab::cli
