// allan(): the Allan-family deviation of a rate on a tau grid with chi-square intervals and edf
// (models/allan/deviation.hpp, confidence.hpp, tau_grid.hpp), plus the readings of
// models/allan/analysis.hpp (B as the flat floor, N from the -1/2 line at 1 s, the least-squares
// IEEE 952 terms) -- the composition `driftlab allan` makes, so the numbers are the same.
#include <pybind11/stl.h>

#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "framework/error.hpp"
#include "framework/units.hpp"
#include "models/allan/analysis.hpp"
#include "models/allan/tau_grid.hpp"
#include "python/src/bindings.hpp"
#include "python/src/convert.hpp"

namespace driftlab::python {
namespace {

struct BiasInstability {
  allan::FloorReading reading;
};

struct NoiseTerm {
  allan::TermEstimate estimate;
};

struct NoiseTerms {
  allan::NoiseFit fit;
  NoiseTerm term(allan::Term t) const { return {fit[t]}; }
};

struct AllanResult {
  std::string kind;
  py::array taus_s, dev_rad_s, dev_lo_rad_s, dev_hi_rad_s, edf, n, m, alpha;
  double confidence = 0.0, sample_rate_hz = 0.0;
  std::size_t samples = 0;
  std::optional<BiasInstability> bias_instability;
  std::optional<double> arw_rad_sqrt_s;
  std::optional<NoiseTerms> noise_terms;
  std::string note;
};

template <class T, class Member>
py::array column(const std::vector<allan::Estimate>& curve, Member member) {
  py::array_t<T> out(static_cast<py::ssize_t>(curve.size()));
  auto view = out.template mutable_unchecked<1>();
  for (std::size_t i = 0; i < curve.size(); ++i) view(static_cast<py::ssize_t>(i)) = static_cast<T>(curve[i].*member);
  return out;
}

using Taus = std::variant<std::string, std::vector<double>>;

AllanResult allan_deviation(const InputArray& x, double fs_hz, const std::string& kind_name, const Taus& taus,
                            double confidence, const std::string& input, const std::string& unit) {
  const auto kind = allan::parse_kind(kind_name);
  if (!kind)
    throw ConfigError({"", 0, "kind"}, "unknown kind '" + kind_name + "' (oadev, adev, mdev, hdev, ohdev, totdev)");
  if (input != "rate" && input != "angle")
    throw ConfigError({"", 0, "input"}, "'" + input + "': expected rate or angle");
  if (!(fs_hz > 0.0) || !std::isfinite(fs_hz)) throw ConfigError({"", 0, "fs_hz"}, "must be a finite rate > 0 Hz");
  const auto u = find_unit(unit);
  if (!u || u->quantity != Quantity::AngularRate)
    throw ConfigError({"", 0, "unit"}, "'" + unit + "' is not an angular-rate unit (rad/s, deg/s, deg/h, ...)");
  const allan::TauGrid grid =
      std::holds_alternative<std::string>(taus)
          ? allan::parse_tau_grid(std::get<std::string>(taus))
          : allan::TauGrid{.kind = allan::GridKind::Explicit, .taus_s = std::get<std::vector<double>>(taus)};
  const auto samples = vector_view(x, "x");
  const auto input_type = input == "rate" ? allan::InputType::Rate : allan::InputType::Angle;
  const double tau0 = 1.0 / fs_hz;

  AllanResult r{.kind = kind_name,
                .confidence = confidence,
                .sample_rate_hz = fs_hz,
                .samples = static_cast<std::size_t>(samples.size())};
  std::vector<allan::Estimate> curve;
  std::optional<allan::Analysis> analysis;
  {
    py::gil_scoped_release release;
    // SI at the boundary; in rad/s the caller's samples are integrated in place of a copy.
    const bool si = u->scale == 1.0 && u->offset == 0.0;
    Eigen::VectorXd angle;
    if (input_type == allan::InputType::Rate)
      angle = si ? allan::angle_from_rate(Eigen::Ref<const Eigen::VectorXd>(samples), tau0)
                 : allan::angle_from_rate(Eigen::VectorXd(samples.array() * u->scale + u->offset), tau0);
    else
      angle = samples.array() * u->scale + u->offset;
    const auto factors = allan::averaging_factors(grid, *kind, static_cast<std::size_t>(angle.size()), tau0);
    curve = allan::estimate(*kind, angle, tau0, input_type, factors, confidence);
    try {
      analysis = allan::analyze_angle(angle, tau0, {.confidence = confidence});
    } catch (const DataError& e) {
      r.note = std::string("no readings: ") + e.what();
    }
  }
  r.taus_s = column<double>(curve, &allan::Estimate::tau);
  r.dev_rad_s = column<double>(curve, &allan::Estimate::dev);
  r.dev_lo_rad_s = column<double>(curve, &allan::Estimate::dev_lo);
  r.dev_hi_rad_s = column<double>(curve, &allan::Estimate::dev_hi);
  r.edf = column<double>(curve, &allan::Estimate::edf);
  r.n = column<std::int64_t>(curve, &allan::Estimate::terms);
  r.m = column<std::int64_t>(curve, &allan::Estimate::m);
  r.alpha = column<std::int64_t>(curve, &allan::Estimate::alpha);
  if (analysis) {
    r.bias_instability = BiasInstability{analysis->bias_instability};
    r.arw_rad_sqrt_s = analysis->arw_rad_sqrt_s;
    if (analysis->fit)
      r.noise_terms = NoiseTerms{*analysis->fit};
    else
      r.note = "no noise-term fit: too few Allan points";
  }
  return r;
}

}  // namespace

void bind_allan(py::module_& m) {
  m.attr("DEG_H_PER_RAD_S") = kDphPerRadPerSec;

  py::class_<BiasInstability>(m, "BiasInstability",
                              "B read as the flat floor of the OADEV: min sigma(tau) / sqrt(2 ln 2 / pi) "
                              "(IEEE 952 Annex C), with the chi-square interval of that point scaled the same way; "
                              "a B only where resolved (the deviation has a floor there), otherwise B < high_rad_s")
      .def_property_readonly(
          "resolved", [](const BiasInstability& b) { return b.reading.resolved; },
          "True where the minimum is a floor (rising or flat neighbours within the intervals)")
      .def_property_readonly(
          "longest_tau_s", [](const BiasInstability& b) { return b.reading.longest_tau_s; },
          "an unresolved B is bounded within tau <= this")
      .def_property_readonly(
          "value_rad_s", [](const BiasInstability& b) { return b.reading.value; },
          "min sigma / 0.664: B when resolved, otherwise only what the bound comes from")
      .def_property_readonly("low_rad_s", [](const BiasInstability& b) { return b.reading.low; })
      .def_property_readonly("high_rad_s", [](const BiasInstability& b) { return b.reading.high; })
      .def_property_readonly(
          "tau_s", [](const BiasInstability& b) { return b.reading.tau_s; }, "tau of the minimum")
      .def("__repr__", [](const BiasInstability& b) {
        return "<driftlab.BiasInstability " + std::to_string(b.reading.value) + " rad/s at tau " +
               std::to_string(b.reading.tau_s) + " s>";
      });

  py::class_<NoiseTerm>(m, "NoiseTerm", "One fitted IEEE 952 term: value and 1-sigma in the unit its name states")
      .def_property_readonly("value", [](const NoiseTerm& t) { return t.estimate.value; })
      .def_property_readonly(
          "sigma", [](const NoiseTerm& t) { return t.estimate.sigma; },
          "1-sigma; for a term set to 0 the level it could have at one sigma")
      .def_property_readonly(
          "fitted", [](const NoiseTerm& t) { return t.estimate.fitted; },
          "False when the constrained fit set the term to 0")
      .def_property_readonly(
          "resolved", [](const NoiseTerm& t) { return t.estimate.resolved; },
          "fitted and its square more than one sigma above 0; otherwise only value < high")
      .def_property_readonly(
          "low", [](const NoiseTerm& t) { return t.estimate.low; }, "one-sigma interval, low end")
      .def_property_readonly(
          "high", [](const NoiseTerm& t) { return t.estimate.high; },
          "one-sigma interval, high end: the bound of an unresolved term")
      .def("__repr__", [](const NoiseTerm& t) {
        return t.estimate.resolved ? "<driftlab.NoiseTerm " + std::to_string(t.estimate.value) + " +- " +
                                         std::to_string(t.estimate.sigma) + ">"
                                   : "<driftlab.NoiseTerm < " + std::to_string(t.estimate.high) + " (not resolved)>";
      });

  py::class_<NoiseTerms>(m, "NoiseTerms",
                         "Least-squares fit of sigma^2 = 3Q^2/tau^2 + N^2/tau + (2 ln2/pi) B^2 + K^2 tau/3 + "
                         "R^2 tau^2/2 to the OADEV curve (IEEE 952 eq. C.2; models/allan/noise_fit.hpp)")
      .def_property_readonly(
          "Q_rad", [](const NoiseTerms& f) { return f.term(allan::Term::Q); }, "quantization")
      .def_property_readonly(
          "N_rad_sqrt_s", [](const NoiseTerms& f) { return f.term(allan::Term::N); },
          "angle random walk, rad/sqrt(s) = rad/s/sqrt(Hz)")
      .def_property_readonly(
          "B_rad_s", [](const NoiseTerms& f) { return f.term(allan::Term::B); }, "bias instability")
      .def_property_readonly(
          "K_rad_s_sqrt_s", [](const NoiseTerms& f) { return f.term(allan::Term::K); },
          "rate random walk, rad/s/sqrt(s) = rad/s^2/sqrt(Hz)")
      .def_property_readonly(
          "R_rad_s2", [](const NoiseTerms& f) { return f.term(allan::Term::R); }, "rate ramp")
      .def_property_readonly("chi2", [](const NoiseTerms& f) { return f.fit.chi2; })
      .def_property_readonly("points", [](const NoiseTerms& f) { return f.fit.points; })
      .def_property_readonly("dof", [](const NoiseTerms& f) { return f.fit.dof; })
      .def(
          "model_dev_rad_s", [](const NoiseTerms& f, double tau_s) { return f.fit.model_deviation(tau_s); },
          py::arg("tau_s"), "Allan deviation of the fitted model at tau_s, rad/s");

  py::class_<AllanResult>(m, "Allan", "Allan-family deviation on a tau grid, with intervals, edf and readings")
      .def_readonly("kind", &AllanResult::kind)
      .def_readonly("taus_s", &AllanResult::taus_s, "averaging times tau = m / fs, s")
      .def_readonly("dev_rad_s", &AllanResult::dev_rad_s, "deviation at each tau, rad/s")
      .def_readonly("dev_lo_rad_s", &AllanResult::dev_lo_rad_s, "lower chi-square bound at `confidence`, rad/s")
      .def_readonly("dev_hi_rad_s", &AllanResult::dev_hi_rad_s, "upper chi-square bound at `confidence`, rad/s")
      .def_readonly("edf", &AllanResult::edf, "equivalent degrees of freedom (Greenhall & Riley 2003; TOTDEV: SP1065)")
      .def_readonly("n", &AllanResult::n, "number of terms summed at each tau")
      .def_readonly("m", &AllanResult::m, "averaging factor at each tau")
      .def_readonly("alpha", &AllanResult::alpha,
                    "identified power-law noise type (rate PSD ~ f^alpha: 0 white rate, -1 flicker, -2 random walk)")
      .def_readonly("confidence", &AllanResult::confidence)
      .def_readonly("sample_rate_hz", &AllanResult::sample_rate_hz)
      .def_readonly("samples", &AllanResult::samples)
      .def_readonly("bias_instability", &AllanResult::bias_instability,
                    "B as the flat floor of the OADEV (BiasInstability), None when the record is too short")
      .def_readonly("arw_rad_sqrt_s", &AllanResult::arw_rad_sqrt_s,
                    "N read from the -1/2 slope line at tau = 1 s, rad/sqrt(s); None when the record is too short")
      .def_readonly("noise_terms", &AllanResult::noise_terms, "the fitted IEEE 952 terms (NoiseTerms), or None")
      .def_readonly("note", &AllanResult::note, "why a reading is None; empty otherwise")
      .def("__repr__", [](const AllanResult& r) {
        return "<driftlab.Allan " + r.kind + ": " + std::to_string(r.taus_s.shape(0)) + " taus, " +
               std::to_string(r.samples) + " samples at " + std::to_string(r.sample_rate_hz) + " Hz>";
      });

  m.def("allan", &allan_deviation, py::arg("x"), py::arg("fs_hz"), py::arg("kind") = "oadev",
        py::arg("taus") = "octave", py::arg("confidence") = allan::kDefaultConfidence, py::arg("input") = "rate",
        py::arg("unit") = "rad/s",
        R"(Allan-family deviation of a gyro rate (NIST SP 1065; IEEE 952 Annex C), as `driftlab allan`.

x: 1-D samples at fs_hz (Hz), an angular rate in `unit` (converted to rad/s; 'deg/s', 'deg/h', ...),
  or with input='angle' its integrated angle (unit: the matching rate unit, 'rad/s' for rad).
kind: 'oadev', 'adev', 'mdev', 'hdev', 'ohdev' or 'totdev'.
taus: 'octave', 'decade', 'dense', 'dense:P' (P per decade), or a sequence of taus in s.
confidence: of the chi-square intervals (0.683: Stable32's 1 sigma).
Returns Allan: taus_s, dev_rad_s, dev_lo_rad_s, dev_hi_rad_s, edf, n (terms), m, alpha, and the
readings bias_instability (B, flat floor / 0.664), arw_rad_sqrt_s (N at 1 s) and noise_terms
(the Q/N/B/K/R fit), all from the OADEV whatever `kind`. deg/h = rad/s * driftlab.DEG_H_PER_RAD_S.)");
}

}  // namespace driftlab::python
