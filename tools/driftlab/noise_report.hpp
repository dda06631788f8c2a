// The noise models of a rate record as the commands report them: the units of the IEEE 952 terms and
// of a GMWM composite model (models/allan/gmwm.hpp), its summary JSON and its text, shared by
// `driftlab allan --gmwm` and `driftlab calibrate --report DIR --gmwm`.
// Units: a channel in rad/s is an angular rate, shown in the IEEE 952 gyro units (N in deg/sqrt(h),
// K in deg/h/sqrt(h), a Gauss-Markov sigma in deg/h, T in s); any other channel keeps its own unit u
// (N in u*sqrt(s), ...).
#pragma once

#include <cstdint>
#include <ostream>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "models/allan/confidence.hpp"
#include "models/allan/gmwm.hpp"
#include "models/allan/noise_fit.hpp"

namespace driftlab::cli {

// The unit of an IEEE 952 term of a channel that is not an angular rate, built from its unit u.
std::string generic_unit(allan::Term term, const std::string& u);

// A GMWM parameter's display unit and the factor from its SI value (above).
std::pair<std::string, double> gmwm_unit(const allan::gmwm::Parameter& p, bool angular, const std::string& u);

// The fit as JSON: model, method, intervals, chi2/dof and per component its parameters, each
// {"name", "unit", "resolved", "value", "interval"} or, unresolved, "value": null and the bound
// "upper" (null for a component below what the curve resolves).
nlohmann::json gmwm_json(const allan::gmwm::Fit& fit, bool angular, const std::string& u);

// A parameter's value in its display unit (factor from gmwm_unit), without the unit:
// "1.658 [1.64, 1.68]" (resolved), "< 0.3" (not resolved), "not determined" (a component below what
// the curve resolves, no bound).
std::string gmwm_value_text(const allan::gmwm::Component& c, const allan::gmwm::Parameter& p, double factor);

// The fit in words: a head line (model, intervals, chi2/dof) and one line per parameter with why an
// unresolved one is not, each line starting with `indent`.
void print_gmwm(std::ostream& out, const allan::gmwm::Fit& fit, bool angular, const std::string& u,
                const std::string& indent = "");

// `model` fitted to the OADEV curve of a contiguous rate record of `samples` samples at
// sample_rate_hz, with the parametric bootstrap's intervals (`replicates` records seeded from
// `seed`, on `threads` threads) or, for replicates = 0, the asymptotic ones. Throws as
// allan::gmwm::fit does.
allan::gmwm::Fit fit_gmwm(std::span<const allan::Estimate> curve, double sample_rate_hz,
                          const std::vector<allan::gmwm::Process>& model, std::size_t samples, std::size_t replicates,
                          std::uint64_t seed, unsigned threads);

// Adds --gmwm-bootstrap, the one definition `allan` and `calibrate` share: the replicates of the
// parametric bootstrap, 0 (the asymptotic intervals) or 2 to 10000 (one replicate gives no
// interval); anything else is a usage error, exit 2.
void add_gmwm_bootstrap_option(CLI::App* command, std::size_t& replicates);

}  // namespace driftlab::cli
