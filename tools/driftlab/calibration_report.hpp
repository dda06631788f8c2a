// The `driftlab calibrate --report DIR` evidence: the competing models fitted on the same
// calibration data, scored on held-out records (report.json + report.html), for a test engineer:
//   - the quality gate's findings and which model was chosen, and why;
//   - per held-out record a table of every method (residual drift, B, N, extrapolated share) and the
//     residual drift of each on every leg of that record (legs as the quality gate finds them:
//     models/calibration/oven_run.hpp);
//   - figures: bias against temperature (60-s block means of measured - true rate; calibration and
//     held-out records, heating and cooling in distinct colours) with each model's correction on
//     the held-out record; |residual| against temperature and against time (log axes: the models
//     differ by decades); the Allan deviation of every method's residual with 68.3 % intervals and
//     the reading guides (plot.hpp allan_guides) of the model with the least residual drift;
//   - with ReportInput::gmwm, a GMWM composite noise model (models/allan/gmwm.hpp) fitted to the
//     same OADEV curve of every residual, beside B and N (report.json methods[].gmwm as
//     `driftlab allan --gmwm` writes it: noise_report.hpp; a table of its parameters).
// Units: deg/h throughout (the report scores gyro channels) except the GMWM parameters, which are in
// the IEEE 952 gyro units of noise_report.hpp (N in deg/sqrt(h) = deg/h/sqrt(Hz) / 60).
#pragma once

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "framework/output_set.hpp"
#include "models/allan/analysis.hpp"
#include "models/allan/gmwm.hpp"
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

// The GMWM fit of every residual (`calibrate --gmwm MODEL --gmwm-bootstrap R --seed S`).
struct GmwmRequest {
  std::vector<allan::gmwm::Process> model;  // empty: no GMWM fit
  std::size_t bootstrap = 50;               // replicates of the parametric bootstrap; 0: asymptotic intervals
  std::uint64_t seed = 1;                   // of the bootstrap's simulated records
  unsigned threads = 1;
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
  GmwmRequest gmwm;
};

// One method's scores on one held-out record, in deg/h.
struct MethodScore {
  std::string name, description, bandwidth;
  double drift_dph = 0, b_dph = NAN, n_dph_rthz = NAN, extrapolated = 0;  // extrapolated: share of samples
  bool b_resolved = false;  // b_dph is B; otherwise only the bound B < b_dph (models/allan/analysis.hpp)
  double b_within_tau_s = 0;
  std::vector<double> block_mean_dph;    // per 60-s block: mean of output - truth
  std::vector<double> block_bias_dph;    // per block: mean of the correction applied (models only)
  std::vector<double> leg_drift_dph;     // per leg: residual drift over the leg (NaN: shorter than a block)
  std::optional<allan::Analysis> allan;  // OADEV of output - truth and its B, N, rad/s (evenly sampled records)
  std::optional<allan::gmwm::Fit> gmwm;  // GmwmRequest::model fitted to that OADEV, SI
  std::string gmwm_failure;              // why a requested GMWM fit is missing (no curve, too few points)
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
