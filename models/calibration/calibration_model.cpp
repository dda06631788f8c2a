#include "models/calibration/calibration_model.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "framework/atomic_file.hpp"
#include "framework/error.hpp"
#include "framework/signal.hpp"
#include "plugins/polynomial/polynomial.hpp"

namespace driftlab::calibration {

std::string to_string(ModelKind kind) {
  switch (kind) {
    case ModelKind::Polynomial: return "poly";
    case ModelKind::Physical: return "physical";
    case ModelKind::Rbf: return "rbf";
  }
  return "poly";
}

std::string to_string(Extrapolation policy) {
  switch (policy) {
    case Extrapolation::Clamp: return "clamp";
    case Extrapolation::Linear: return "linear";
    case Extrapolation::Evaluate: return "evaluate";
  }
  return "clamp";
}

std::optional<ModelKind> parse_model_kind(const std::string& text) {
  for (const auto k : {ModelKind::Polynomial, ModelKind::Physical, ModelKind::Rbf}) {
    if (to_string(k) == text) return k;
  }
  return std::nullopt;
}

std::optional<Extrapolation> parse_extrapolation(const std::string& text) {
  for (const auto e : {Extrapolation::Clamp, Extrapolation::Linear, Extrapolation::Evaluate}) {
    if (to_string(e) == text) return e;
  }
  return std::nullopt;
}

namespace {

double horner(const std::vector<double>& a, double u) { return polynomial::evaluate(a, 0.0, u); }

double horner_derivative(const std::vector<double>& a, double u) {
  double v = 0.0;
  for (std::size_t i = a.size(); i-- > 1;) v = v * u + static_cast<double>(i) * a[i];
  return v;
}

}  // namespace

double CalibrationModel::polynomial_bias_rad_s(double temp_c) const {
  const double t0 = reference_temp_c;
  if (temp_c < valid_min_c || temp_c > valid_max_c) {
    const double edge = temp_c < valid_min_c ? valid_min_c : valid_max_c;
    switch (extrapolation) {
      case Extrapolation::Clamp: return horner(bias_rad_s, edge - t0);
      case Extrapolation::Linear:
        return horner(bias_rad_s, edge - t0) + horner_derivative(bias_rad_s, edge - t0) * (temp_c - edge);
      case Extrapolation::Evaluate: break;
    }
  }
  return horner(bias_rad_s, temp_c - t0);
}

double CalibrationModel::scale_factor(double temp_c) const {
  if (scale_factor_per_k.empty()) return 1.0;
  const double tc = std::clamp(temp_c, valid_min_c, valid_max_c);
  return 1.0 + horner(scale_factor_per_k, tc - reference_temp_c);
}

void CalibrationModel::validate() const {
  std::vector<Diagnostic> problems;
  const auto bad = [&](const std::string& key, const std::string& message) {
    problems.push_back({{"", 0, key}, message});
  };
  if (bias_rad_s.empty()) bad("bias.polynomial_rad_s_per_k_i", "needs at least one coefficient");
  if (!bias_sigma_rad_s.empty() && bias_sigma_rad_s.size() != bias_rad_s.size()) {
    bad("bias.sigma_rad_s_per_k_i", "needs one value per coefficient");
  }
  if (!(std::isfinite(valid_min_c) && std::isfinite(valid_max_c) && valid_min_c <= valid_max_c)) {
    bad("valid_range_c", "needs [min, max] with min <= max");
  }
  if (!(lag_tau_s >= 0)) bad("physical.lag_tau_s", "must be >= 0 s");
  if (!(derivative_tau_s > 0)) bad("physical.derivative_tau_s", "must be > 0 s");
  if (!(hysteresis_width_k >= 0)) bad("physical.hysteresis_width_k", "must be >= 0 K");
  for (double c : bias_rad_s) {
    if (!std::isfinite(c)) bad("bias.polynomial_rad_s_per_k_i", "non-finite coefficient");
  }
  if (rbf) {
    if (rbf->mean.size() != 3 || rbf->scale.size() != 3) bad("rbf.mean", "needs 3 values (and rbf.scale too)");
    if (rbf->centres.cols() != 3) bad("rbf.centres", "needs rows of 3 values");
    if (static_cast<std::size_t>(rbf->centres.rows()) != rbf->weights_rad_s.size()) {
      bad("rbf.weights_rad_s", "needs one weight per centre");
    }
    if (!(rbf->sigma > 0)) bad("rbf.sigma", "must be > 0");
    if (!rbf->input_min.empty() || !rbf->input_max.empty()) {
      if (rbf->input_min.size() != 3 || rbf->input_max.size() != 3) {
        bad("rbf.input_min", "needs 3 values (and rbf.input_max too), or neither");
      } else {
        for (int k = 0; k < 3; ++k) {
          if (!(rbf->input_min[static_cast<std::size_t>(k)] <= rbf->input_max[static_cast<std::size_t>(k)]))
            bad("rbf.input_max", "each value must be >= the matching rbf.input_min");
        }
      }
    }
  }
  if (!problems.empty()) throw ConfigError(std::move(problems));
}

// ---- JSON ------------------------------------------------------------------------------------

std::string to_json_text(const CalibrationModel& m) {
  using nlohmann::json;
  json j;
  j["format"] = kFormat;
  j["kind"] = to_string(m.kind);
  j["device"] = m.device;
  j["axis"] = m.axis;
  j["units"] = {{"rate", "rad/s"}, {"temperature", "degC"}, {"time", "s"},
                {"bias", "bias(T) = sum_i a_i (T - reference_temp_c)^i, a_i in rad/s/K^i"},
                {"compensated", "(measured - bias) / (1 + sum_j k_j (T - reference_temp_c)^j)"}};
  j["reference_temp_c"] = m.reference_temp_c;
  j["valid_range_c"] = {m.valid_min_c, m.valid_max_c};
  j["extrapolation"] = to_string(m.extrapolation);
  j["bias"] = {{"polynomial_rad_s_per_k_i", m.bias_rad_s}, {"sigma_rad_s_per_k_i", m.bias_sigma_rad_s}};
  j["physical"] = {{"lag_tau_s", m.lag_tau_s},
                   {"derivative_tau_s", m.derivative_tau_s},
                   {"temperature_rate_rad_s_per_k_s", m.temperature_rate_rad_s_per_k_s},
                   {"temperature_rate_sigma", m.temperature_rate_sigma},
                   {"hysteresis_rad_s", m.hysteresis_rad_s},
                   {"hysteresis_sigma_rad_s", m.hysteresis_sigma_rad_s},
                   {"hysteresis_width_k", m.hysteresis_width_k}};
  if (m.rbf) {
    json centres = json::array();
    for (Eigen::Index k = 0; k < m.rbf->centres.rows(); ++k) {
      centres.push_back({m.rbf->centres(k, 0), m.rbf->centres(k, 1), m.rbf->centres(k, 2)});
    }
    j["rbf"] = {{"inputs", {"model_temp_c", "temp_rate_k_s", "hysteresis_state"}},
                {"mean", m.rbf->mean},
                {"scale", m.rbf->scale},
                {"sigma", m.rbf->sigma},
                {"centres", centres},
                {"weights_rad_s", m.rbf->weights_rad_s},
                {"bias_rad_s", m.rbf->bias_rad_s}};
    if (!m.rbf->input_min.empty()) {
      j["rbf"]["input_min"] = m.rbf->input_min;
      j["rbf"]["input_max"] = m.rbf->input_max;
    }
  } else {
    j["rbf"] = nullptr;
  }
  j["scale_factor"] = {{"polynomial_per_k_j", m.scale_factor_per_k}};
  j["noise"] = {{"arw_rad_sqrt_s", m.noise.arw_rad_sqrt_s},
                {"bias_instability_rad_s", m.noise.bias_instability_rad_s},
                {"rate_random_walk_rad_s_sqrt_s", m.noise.rate_random_walk_rad_s_sqrt_s},
                {"sample_rate_hz", m.noise.sample_rate_hz}};
  j["fit"] = {{"records", m.fit.records},
              {"samples", m.fit.samples},
              {"bin_s", m.fit.bin_s},
              {"selection", m.fit.selection},
              {"holdout_blocks", m.fit.holdout_blocks},
              {"holdout_rms_rad_s", m.fit.holdout_rms_rad_s},
              {"train_rms_rad_s", m.fit.train_rms_rad_s},
              {"heating_only", m.fit.heating_only},
              {"scale_factor_fitted", m.fit.scale_factor_fitted}};
  return j.dump(2) + "\n";
}

void write_calibration_model(const CalibrationModel& model, const std::filesystem::path& json) {
  model.validate();
  write_file_atomically(json, to_json_text(model));
}

namespace {

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& message) const {
    throw ConfigError({file_, 0, key}, message);
  }

  const nlohmann::json& at(const nlohmann::json& parent, const std::string& path, const std::string& key) const {
    if (!parent.is_object() || !parent.contains(key)) fail(join(path, key), "missing key");
    return parent.at(key);
  }
  const nlohmann::json* optional(const nlohmann::json& parent, const std::string& key) const {
    if (!parent.is_object() || !parent.contains(key) || parent.at(key).is_null()) return nullptr;
    return &parent.at(key);
  }
  double number(const nlohmann::json& v, const std::string& key) const {
    if (!v.is_number()) fail(key, "expected a number, got " + std::string(v.type_name()));
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(key, "not a finite number");
    return x;
  }
  double number(const nlohmann::json& parent, const std::string& path, const std::string& key) const {
    return number(at(parent, path, key), join(path, key));
  }
  double number_or(const nlohmann::json& parent, const std::string& path, const std::string& key, double def) const {
    const auto* v = optional(parent, key);
    return v ? number(*v, join(path, key)) : def;
  }
  // A whole, non-negative number that fits std::size_t (sample and block counts).
  std::size_t count_or(const nlohmann::json& parent, const std::string& path, const std::string& key) const {
    const double x = number_or(parent, path, key, 0.0);
    if (x < 0 || x != std::floor(x) || x >= 9007199254740992.0) {
      fail(join(path, key), "expected a whole number of at least 0 and below 2^53");
    }
    return static_cast<std::size_t>(x);
  }
  std::vector<double> numbers(const nlohmann::json& v, const std::string& key) const {
    if (!v.is_array()) fail(key, "expected a list of numbers, got " + std::string(v.type_name()));
    std::vector<double> out;
    for (std::size_t i = 0; i < v.size(); ++i) out.push_back(number(v[i], key + "[" + std::to_string(i) + "]"));
    return out;
  }
  std::string text(const nlohmann::json& parent, const std::string& path, const std::string& key) const {
    const auto& v = at(parent, path, key);
    if (!v.is_string()) fail(join(path, key), "expected a string, got " + std::string(v.type_name()));
    return v.get<std::string>();
  }
  static std::string join(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
  }

 private:
  std::string file_;
};

}  // namespace

CalibrationModel read_calibration_model(const std::filesystem::path& path) {
  const Reader r(path.string());
  std::ifstream in(path, std::ios::binary);
  if (!in) r.fail("", "cannot open the calibration model file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(buffer.str());
  } catch (const nlohmann::json::exception& e) {  // syntax, and numbers beyond double (out_of_range)
    r.fail("", std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object()) r.fail("", "expected a JSON object");
  const std::string format = r.text(j, "", "format");
  if (format != kFormat) r.fail("format", "expected \"" + std::string(kFormat) + "\", got \"" + format + "\"");

  CalibrationModel m;
  const std::string kind = r.text(j, "", "kind");
  const auto parsed_kind = parse_model_kind(kind);
  if (!parsed_kind) r.fail("kind", "expected poly, physical or rbf, got \"" + kind + "\"");
  m.kind = *parsed_kind;
  if (r.optional(j, "device")) m.device = r.text(j, "", "device");
  if (r.optional(j, "axis")) m.axis = r.text(j, "", "axis");
  if (m.axis != "x" && m.axis != "y" && m.axis != "z") r.fail("axis", "expected x, y or z, got \"" + m.axis + "\"");
  m.reference_temp_c = r.number(j, "", "reference_temp_c");
  const auto range = r.numbers(r.at(j, "", "valid_range_c"), "valid_range_c");
  if (range.size() != 2 || !(range[0] <= range[1])) r.fail("valid_range_c", "expected [min, max] with min <= max");
  m.valid_min_c = range[0];
  m.valid_max_c = range[1];
  const std::string policy = r.text(j, "", "extrapolation");
  const auto parsed_policy = parse_extrapolation(policy);
  if (!parsed_policy) r.fail("extrapolation", "expected clamp, linear or evaluate, got \"" + policy + "\"");
  m.extrapolation = *parsed_policy;
  const auto& bias = r.at(j, "", "bias");
  m.bias_rad_s = r.numbers(r.at(bias, "bias", "polynomial_rad_s_per_k_i"), "bias.polynomial_rad_s_per_k_i");
  if (m.bias_rad_s.empty()) r.fail("bias.polynomial_rad_s_per_k_i", "needs at least one coefficient");
  if (const auto* s = r.optional(bias, "sigma_rad_s_per_k_i")) m.bias_sigma_rad_s = r.numbers(*s, "bias.sigma_rad_s_per_k_i");
  if (!m.bias_sigma_rad_s.empty() && m.bias_sigma_rad_s.size() != m.bias_rad_s.size()) {
    r.fail("bias.sigma_rad_s_per_k_i", "needs one value per coefficient");
  }
  if (const auto* p = r.optional(j, "physical")) {
    m.lag_tau_s = r.number_or(*p, "physical", "lag_tau_s", 0.0);
    m.derivative_tau_s = r.number_or(*p, "physical", "derivative_tau_s", m.derivative_tau_s);
    m.temperature_rate_rad_s_per_k_s = r.number_or(*p, "physical", "temperature_rate_rad_s_per_k_s", 0.0);
    m.temperature_rate_sigma = r.number_or(*p, "physical", "temperature_rate_sigma", 0.0);
    m.hysteresis_rad_s = r.number_or(*p, "physical", "hysteresis_rad_s", 0.0);
    m.hysteresis_sigma_rad_s = r.number_or(*p, "physical", "hysteresis_sigma_rad_s", 0.0);
    m.hysteresis_width_k = r.number_or(*p, "physical", "hysteresis_width_k", 0.0);
    if (m.lag_tau_s < 0) r.fail("physical.lag_tau_s", "must be >= 0 s");
    if (!(m.derivative_tau_s > 0)) r.fail("physical.derivative_tau_s", "must be > 0 s");
    if (m.hysteresis_width_k < 0) r.fail("physical.hysteresis_width_k", "must be >= 0 K");
  }
  if (const auto* b = r.optional(j, "rbf")) {
    RbfTerm t;
    t.mean = r.numbers(r.at(*b, "rbf", "mean"), "rbf.mean");
    t.scale = r.numbers(r.at(*b, "rbf", "scale"), "rbf.scale");
    if (t.mean.size() != 3) r.fail("rbf.mean", "needs 3 values (model_temp_c, temp_rate_k_s, hysteresis_state)");
    if (t.scale.size() != 3) r.fail("rbf.scale", "needs 3 values");
    for (double s : t.scale) {
      if (!(s > 0)) r.fail("rbf.scale", "values must be > 0");
    }
    t.sigma = r.number(*b, "rbf", "sigma");
    if (!(t.sigma > 0)) r.fail("rbf.sigma", "must be > 0");
    const auto& centres = r.at(*b, "rbf", "centres");
    if (!centres.is_array()) r.fail("rbf.centres", "expected a list of [T, D, s] rows");
    t.centres.resize(static_cast<Eigen::Index>(centres.size()), 3);
    for (std::size_t k = 0; k < centres.size(); ++k) {
      const std::string key = "rbf.centres[" + std::to_string(k) + "]";
      const auto row = r.numbers(centres[k], key);
      if (row.size() != 3) r.fail(key, "needs 3 values");
      for (int c = 0; c < 3; ++c) t.centres(static_cast<Eigen::Index>(k), c) = row[static_cast<std::size_t>(c)];
    }
    t.weights_rad_s = r.numbers(r.at(*b, "rbf", "weights_rad_s"), "rbf.weights_rad_s");
    if (t.weights_rad_s.size() != centres.size()) r.fail("rbf.weights_rad_s", "needs one weight per centre");
    t.bias_rad_s = r.number(*b, "rbf", "bias_rad_s");
    if (const auto* lo = r.optional(*b, "input_min")) t.input_min = r.numbers(*lo, "rbf.input_min");
    if (const auto* hi = r.optional(*b, "input_max")) t.input_max = r.numbers(*hi, "rbf.input_max");
    m.rbf = std::move(t);
  }
  if (m.kind == ModelKind::Rbf && !m.rbf) r.fail("rbf", "kind is rbf but the rbf section is missing");
  if (const auto* s = r.optional(j, "scale_factor")) {
    if (const auto* c = r.optional(*s, "polynomial_per_k_j")) {
      m.scale_factor_per_k = r.numbers(*c, "scale_factor.polynomial_per_k_j");
    }
  }
  if (const auto* n = r.optional(j, "noise")) {
    m.noise.arw_rad_sqrt_s = r.number_or(*n, "noise", "arw_rad_sqrt_s", 0.0);
    m.noise.bias_instability_rad_s = r.number_or(*n, "noise", "bias_instability_rad_s", 0.0);
    m.noise.rate_random_walk_rad_s_sqrt_s = r.number_or(*n, "noise", "rate_random_walk_rad_s_sqrt_s", 0.0);
    m.noise.sample_rate_hz = r.number_or(*n, "noise", "sample_rate_hz", 0.0);
  }
  if (const auto* f = r.optional(j, "fit")) {
    if (const auto* recs = r.optional(*f, "records"); recs && recs->is_array()) {
      for (const auto& x : *recs) {
        if (x.is_string()) m.fit.records.push_back(x.get<std::string>());
      }
    }
    m.fit.samples = r.count_or(*f, "fit", "samples");
    m.fit.bin_s = r.number_or(*f, "fit", "bin_s", 0.0);
    if (r.optional(*f, "selection")) m.fit.selection = r.text(*f, "fit", "selection");
    m.fit.holdout_blocks = r.count_or(*f, "fit", "holdout_blocks");
    m.fit.holdout_rms_rad_s = r.number_or(*f, "fit", "holdout_rms_rad_s", 0.0);
    m.fit.train_rms_rad_s = r.number_or(*f, "fit", "train_rms_rad_s", 0.0);
    if (const auto* h = r.optional(*f, "heating_only"); h && h->is_boolean()) m.fit.heating_only = h->get<bool>();
    if (const auto* h = r.optional(*f, "scale_factor_fitted"); h && h->is_boolean()) {
      m.fit.scale_factor_fitted = h->get<bool>();
    }
  }
  return m;
}

// ---- causal evaluation -----------------------------------------------------------------------

CausalState::CausalState(double lag_tau_s, double derivative_tau_s, double hysteresis_width_k)
    : lag_tau_(lag_tau_s), deriv_tau_(derivative_tau_s), width_(hysteresis_width_k) {}

void CausalState::step(double t_s, double temp_c) {
  if (!std::isfinite(t_s) || !std::isfinite(temp_c)) {
    throw DataError({"", 0, "temperature"}, "non-finite time or temperature at t = " + std::to_string(t_s) + " s");
  }
  if (!started_) {
    started_ = true;
    t_prev_ = t_s;
    x_prev_ = tm_ = y1_ = y2_ = temp_c;
    rate_ = s_ = 0.0;
    return;
  }
  const double dt = t_s - t_prev_;
  if (!(dt > 0)) {
    throw DataError({"", 0, "time"}, "time stamps must increase (t = " + std::to_string(t_s) + " s after " +
                                         std::to_string(t_prev_) + " s)");
  }
  if (dt != dt_cached_) {
    dt_cached_ = dt;
    a_lag_ = lag_tau_ > 0 ? std::exp(-dt / lag_tau_) : 0.0;
    a_der_ = std::exp(-dt / deriv_tau_);
  }
  tm_ = lag_tau_ > 0 ? signal::lag_step(tm_, x_prev_, temp_c, dt, lag_tau_, a_lag_) : temp_c;
  const double y1_prev = y1_;
  const double y1 = signal::lag_step(y1_, x_prev_, temp_c, dt, deriv_tau_, a_der_);
  y2_ = signal::lag_step(y2_, y1_prev, y1, dt, deriv_tau_, a_der_);
  y1_ = y1;
  rate_ = (y1_ - y2_) / deriv_tau_;
  if (width_ > 0) s_ = signal::hysteresis_step(s_, y1_ - y1_prev, width_);
  t_prev_ = t_s;
  x_prev_ = temp_c;
}

CausalCompensator::CausalCompensator(const CalibrationModel& model)
    : model_(model),
      state_(model.lag_tau_s, model.derivative_tau_s, model.hysteresis_width_k),
      stateful_(model.uses_state()) {
  model_.validate();
}

double CausalCompensator::rbf_value(double tc) const {
  const RbfTerm& r = *model_.rbf;
  const auto input = [&](std::size_t k, double x) {
    return ((r.input_min.empty() ? x : std::clamp(x, r.input_min[k], r.input_max[k])) - r.mean[k]) / r.scale[k];
  };
  const double u0 = input(0, tc);
  const double u1 = input(1, state_.temp_rate_k_s());
  const double u2 = input(2, state_.hysteresis_state());
  const double g = -0.5 / (r.sigma * r.sigma);
  double y = r.bias_rad_s;
  for (Eigen::Index k = 0; k < r.centres.rows(); ++k) {
    const double d0 = u0 - r.centres(k, 0), d1 = u1 - r.centres(k, 1), d2 = u2 - r.centres(k, 2);
    y += r.weights_rad_s[static_cast<std::size_t>(k)] * std::exp(g * (d0 * d0 + d1 * d1 + d2 * d2));
  }
  return y;
}

double CausalCompensator::step(double t_s, double rate_rad_s, double temp_c) {
  if (!std::isfinite(rate_rad_s)) {
    throw DataError({"", 0, "rate"}, "non-finite rate at t = " + std::to_string(t_s) + " s");
  }
  double tm = temp_c;
  if (stateful_) {
    state_.step(t_s, temp_c);
    tm = state_.model_temp_c();
  } else {
    if (!std::isfinite(temp_c) || !std::isfinite(t_s)) {
      throw DataError({"", 0, "temperature"}, "non-finite time or temperature at t = " + std::to_string(t_s) + " s");
    }
    if (started_ && !(t_s > t_prev_)) {
      throw DataError({"", 0, "time"}, "time stamps must increase (t = " + std::to_string(t_s) + " s after " +
                                           std::to_string(t_prev_) + " s)");
    }
    started_ = true;
    t_prev_ = t_s;
  }
  extrapolated_ = tm < model_.valid_min_c || tm > model_.valid_max_c;
  double b = model_.polynomial_bias_rad_s(tm);
  if (stateful_) {
    b += model_.temperature_rate_rad_s_per_k_s * state_.temp_rate_k_s() +
         model_.hysteresis_rad_s * state_.hysteresis_state();
    if (model_.rbf) b += rbf_value(std::clamp(tm, model_.valid_min_c, model_.valid_max_c));
  }
  bias_ = b;
  const double out = rate_rad_s - b;
  return model_.scale_factor_per_k.empty() ? out : out / model_.scale_factor(tm);
}

Compensated compensate(const CalibrationModel& model, const Eigen::VectorXd& time_s, const Eigen::VectorXd& rate_rad_s,
                       const Eigen::VectorXd& temp_c) {
  if (time_s.size() != rate_rad_s.size() || time_s.size() != temp_c.size()) {
    throw DataError({"", 0, "rate"}, "time, rate and temperature differ in length");
  }
  CausalCompensator c(model);
  Compensated out;
  const Eigen::Index n = time_s.size();
  out.rate_rad_s.resize(n);
  out.bias_rad_s.resize(n);
  out.extrapolated.resize(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    out.rate_rad_s[i] = c.step(time_s[i], rate_rad_s[i], temp_c[i]);
    out.bias_rad_s[i] = c.last_bias_rad_s();
    out.extrapolated[static_cast<std::size_t>(i)] = c.last_extrapolated() ? 1 : 0;
  }
  return out;
}

}  // namespace driftlab::calibration
