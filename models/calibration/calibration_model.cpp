#include "models/calibration/calibration_model.hpp"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <utility>

#include "framework/error.hpp"
#include "framework/regular_file.hpp"
#include "framework/signal.hpp"
#include "framework/units.hpp"
#include "plugins/polynomial/polynomial.hpp"

namespace driftlab::calibration {

std::string to_string(ModelKind kind) {
  switch (kind) {
    case ModelKind::Polynomial:
      return "poly";
    case ModelKind::Physical:
      return "physical";
    case ModelKind::Rbf:
      return "rbf";
  }
  return "poly";
}

std::string to_string(Extrapolation policy) {
  switch (policy) {
    case Extrapolation::Clamp:
      return "clamp";
    case Extrapolation::Linear:
      return "linear";
    case Extrapolation::Evaluate:
      return "evaluate";
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

std::string outside_inputs_text(unsigned flags) {
  std::string out;
  for (const auto& [bit, name] :
       {std::pair{kOutsideTemperature, "model temperature"}, std::pair{kOutsideTemperatureRate, "dT/dt"},
        std::pair{kOutsideBranchState, "branch state"}, std::pair{kOutsideRbfInputs, "RBF input"}})
    if (flags & bit) out += (out.empty() ? "" : ", ") + std::string(name);
  return out;
}

std::string OutsideCount::text(const std::string& what) const {
  return std::to_string(samples) + " " + what + " had a model input outside its fitted range (" +
         outside_inputs_text(inputs) + ")";
}

double CalibrationModel::polynomial_bias_rad_s(double temp_c) const {
  const double t0 = reference_temp_c;
  if (temp_c < valid_min_c || temp_c > valid_max_c) {
    const double edge = temp_c < valid_min_c ? valid_min_c : valid_max_c;
    switch (extrapolation) {
      case Extrapolation::Clamp:
        return horner(bias_rad_s, edge - t0);
      case Extrapolation::Linear:
        return horner(bias_rad_s, edge - t0) + horner_derivative(bias_rad_s, edge - t0) * (temp_c - edge);
      case Extrapolation::Evaluate:
        break;
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
  const auto finite = [](const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
  };
  const auto temperature = [](double t) { return t >= kMinTemperatureC && t <= kMaxTemperatureC; };
  const std::string temperatures =
      "[" + message_number(kMinTemperatureC) + ", " + message_number(kMaxTemperatureC) + "] degC";
  if (bias_rad_s.empty()) bad("bias.polynomial_rad_s_per_k_i", "needs at least one coefficient");
  if (bias_rad_s.size() > kMaxPolynomialTerms || scale_factor_per_k.size() > kMaxPolynomialTerms) {
    bad(bias_rad_s.size() > kMaxPolynomialTerms ? "bias.polynomial_rad_s_per_k_i" : "scale_factor.polynomial_per_k_j",
        "expected at most " + std::to_string(kMaxPolynomialTerms) + " coefficients");
  }
  if (!bias_sigma_rad_s.empty() && bias_sigma_rad_s.size() != bias_rad_s.size()) {
    bad("bias.sigma_rad_s_per_k_i", "needs one value per coefficient");
  }
  if (!(temperature(valid_min_c) && temperature(valid_max_c) && valid_min_c <= valid_max_c)) {
    bad("valid_range_c", "needs [min, max] with min <= max, both within " + temperatures);
  }
  if (!temperature(reference_temp_c)) bad("reference_temp_c", "expected a temperature within " + temperatures);
  if (!(lag_tau_s >= 0 && std::isfinite(lag_tau_s))) bad("physical.lag_tau_s", "must be finite and >= 0 s");
  if (!(derivative_tau_s > 0 && std::isfinite(derivative_tau_s)))
    bad("physical.derivative_tau_s", "must be finite and > 0 s");
  if (!(hysteresis_width_k >= 0 && std::isfinite(hysteresis_width_k)))
    bad("physical.hysteresis_width_k", "must be finite and >= 0 K");
  if (!finite(bias_rad_s)) bad("bias.polynomial_rad_s_per_k_i", "non-finite coefficient");
  if (!finite(bias_sigma_rad_s)) bad("bias.sigma_rad_s_per_k_i", "non-finite value");
  if (!finite(scale_factor_per_k)) bad("scale_factor.polynomial_per_k_j", "non-finite coefficient");
  for (const auto& [range, key] : {std::pair{&temperature_rate_range_k_s, "physical.temperature_rate_range_k_s"},
                                   std::pair{&hysteresis_state_range, "physical.hysteresis_state_range"}})
    if (*range && !(std::isfinite((*range)->min) && std::isfinite((*range)->max) && (*range)->min <= (*range)->max))
      bad(key, "needs [min, max], finite, with min <= max");
  if (!finite({temperature_rate_rad_s_per_k_s, temperature_rate_sigma, hysteresis_rad_s, hysteresis_sigma_rad_s}))
    bad("physical", "non-finite coefficient");
  if (!finite({noise.arw_rad_sqrt_s, noise.bias_instability_rad_s, noise.rate_random_walk_rad_s_sqrt_s,
               noise.sample_rate_hz}) ||
      std::min({noise.arw_rad_sqrt_s, noise.bias_instability_rad_s, noise.rate_random_walk_rad_s_sqrt_s,
                noise.sample_rate_hz}) < 0)
    bad("noise", "noise terms and sample_rate_hz must be finite and >= 0");
  if (rbf) {
    if (rbf->mean.size() != 3 || rbf->scale.size() != 3) bad("rbf.mean", "needs 3 values (and rbf.scale too)");
    if (rbf->centres.cols() != 3) bad("rbf.centres", "needs rows of 3 values");
    if (static_cast<std::size_t>(rbf->centres.rows()) > kMaxRbfCentres)
      bad("rbf.centres", "expected at most " + std::to_string(kMaxRbfCentres) + " centres");
    if (static_cast<std::size_t>(rbf->centres.rows()) != rbf->weights_rad_s.size()) {
      bad("rbf.weights_rad_s", "needs one weight per centre");
    }
    if (!(rbf->sigma >= kMinRbfSigma && rbf->sigma <= kMaxRbfSigma))
      bad("rbf.sigma", "expected a width within [" + message_number(kMinRbfSigma) + ", " +
                           message_number(kMaxRbfSigma) + "] (standardized units)");
    if (!finite(rbf->mean) ||
        !std::all_of(rbf->scale.begin(), rbf->scale.end(), [](double x) { return x > 0 && std::isfinite(x); }))
      bad("rbf.scale", "mean and scale must be finite, scale > 0");
    if (!rbf->centres.allFinite() || !finite(rbf->weights_rad_s) || !std::isfinite(rbf->bias_rad_s))
      bad("rbf.weights_rad_s", "centres, weights and bias must be finite");
    double bound = std::abs(rbf->bias_rad_s);  // |rbf(x)| <= |bias| + sum |w_k|
    for (double w : rbf->weights_rad_s) bound += std::abs(w);
    if (!std::isfinite(bound))
      bad("rbf.weights_rad_s", "the network's output overflows (|bias| + sum |w| is not finite)");
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
  if (problems.empty()) {  // the evaluation, on a grid over the range (and beyond it where the policy evaluates)
    constexpr int kGrid = 1000;
    const double margin = extrapolation == Extrapolation::Clamp ? 0.0 : kExtrapolationMarginK;
    const double lo = valid_min_c - margin, hi = valid_max_c + margin;
    for (int i = 0; i <= kGrid; ++i) {
      const double t = lo + (hi - lo) * i / kGrid;
      if (!std::isfinite(polynomial_bias_rad_s(t))) {
        bad("bias.polynomial_rad_s_per_k_i",
            "the bias is not finite at " + message_number(t) + " degC; expected a finite bias over the valid range" +
                (margin > 0 ? " and " + message_number(margin) + " K beyond it (extrapolation " +
                                  to_string(extrapolation) + ")"
                            : std::string()));
        break;
      }
    }
    for (int i = 0; i <= kGrid; ++i) {
      const double t = valid_min_c + (valid_max_c - valid_min_c) * i / kGrid;
      const double sf = scale_factor(t);
      if (!(sf >= kMinScaleFactor && sf <= kMaxScaleFactor)) {
        bad("scale_factor.polynomial_per_k_j",
            "the scale factor is " + message_number(sf) + " at " + message_number(t) + " degC; expected " +
                message_number(kMinScaleFactor) + " to " + message_number(kMaxScaleFactor) + " over the valid range");
        break;
      }
    }
  }
  if (!problems.empty()) throw ConfigError(std::move(problems));
}

// ---- JSON ------------------------------------------------------------------------------------

namespace {

// JSON key spellings of a channel's units: a gyro's in rad/s, an accelerometer's in m/s^2.
struct KeyUnits {
  std::string value;        // "rad_s" | "m_s2"
  std::string unit;         // "rad/s" | "m/s^2"
  std::string white;        // N: angle / velocity random walk
  std::string instability;  // B
  std::string random_walk;  // K: rate / acceleration random walk
};

const KeyUnits& key_units(imu::Sensor sensor) {
  static const KeyUnits gyro{"rad_s", "rad/s", "arw_rad_sqrt_s", "bias_instability_rad_s",
                             "rate_random_walk_rad_s_sqrt_s"};
  static const KeyUnits accel{"m_s2", "m/s^2", "vrw_m_s_sqrt_s", "bias_instability_m_s2",
                              "acceleration_random_walk_m_s2_sqrt_s"};
  return sensor == imu::Sensor::Gyro ? gyro : accel;
}

nlohmann::json model_body(const CalibrationModel& m, imu::Sensor sensor) {
  using nlohmann::json;
  const KeyUnits& u = key_units(sensor);
  json j;
  j["kind"] = to_string(m.kind);
  j["units"] = {{"value", u.unit},
                {"temperature", "degC"},
                {"time", "s"},
                {"bias", "bias(T) = sum_i a_i (T - reference_temp_c)^i, a_i in " + u.unit + "/K^i"},
                {"compensated", "(measured - bias) / (1 + sum_j k_j (T - reference_temp_c)^j)"}};
  j["reference_temp_c"] = m.reference_temp_c;
  j["valid_range_c"] = {m.valid_min_c, m.valid_max_c};
  j["extrapolation"] = to_string(m.extrapolation);
  j["bias"] = {{"polynomial_" + u.value + "_per_k_i", m.bias_rad_s},
               {"sigma_" + u.value + "_per_k_i", m.bias_sigma_rad_s}};
  j["physical"] = {{"lag_tau_s", m.lag_tau_s},
                   {"derivative_tau_s", m.derivative_tau_s},
                   {"temperature_rate_" + u.value + "_per_k_s", m.temperature_rate_rad_s_per_k_s},
                   {"temperature_rate_sigma", m.temperature_rate_sigma},
                   {"hysteresis_" + u.value, m.hysteresis_rad_s},
                   {"hysteresis_sigma_" + u.value, m.hysteresis_sigma_rad_s},
                   {"hysteresis_width_k", m.hysteresis_width_k}};
  if (m.temperature_rate_range_k_s)
    j["physical"]["temperature_rate_range_k_s"] = {m.temperature_rate_range_k_s->min,
                                                   m.temperature_rate_range_k_s->max};
  if (m.hysteresis_state_range)
    j["physical"]["hysteresis_state_range"] = {m.hysteresis_state_range->min, m.hysteresis_state_range->max};
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
                {"weights_" + u.value, m.rbf->weights_rad_s},
                {"bias_" + u.value, m.rbf->bias_rad_s}};
    if (!m.rbf->input_min.empty()) {
      j["rbf"]["input_min"] = m.rbf->input_min;
      j["rbf"]["input_max"] = m.rbf->input_max;
    }
  } else {
    j["rbf"] = nullptr;
  }
  j["scale_factor"] = {{"polynomial_per_k_j", m.scale_factor_per_k}};
  j["noise"] = {{u.white, m.noise.arw_rad_sqrt_s},
                {u.instability, m.noise.bias_instability_rad_s},
                {u.random_walk, m.noise.rate_random_walk_rad_s_sqrt_s},
                {"sample_rate_hz", m.noise.sample_rate_hz}};
  nlohmann::json unresolved = nlohmann::json::object();
  for (const auto& [key, upper] :
       {std::pair{u.white, m.noise.arw_upper}, std::pair{u.instability, m.noise.bias_instability_upper},
        std::pair{u.random_walk, m.noise.rate_random_walk_upper}})
    if (upper) unresolved[key] = *upper;
  if (!unresolved.empty()) j["noise"]["unresolved_upper"] = unresolved;
  j["fit"] = {{"records", m.fit.records},
              {"samples", m.fit.samples},
              {"bin_s", m.fit.bin_s},
              {"selection", m.fit.selection},
              {"holdout_blocks", m.fit.holdout_blocks},
              {"holdout_rms_" + u.value, m.fit.holdout_rms_rad_s},
              {"train_rms_" + u.value, m.fit.train_rms_rad_s},
              {"holdout_design", m.fit.holdout_design},
              {"uncompensated_rms_" + u.value, m.fit.uncompensated_rms_rad_s},
              {"heating_only", m.fit.heating_only},
              {"scale_factor_fitted", m.fit.scale_factor_fitted}};
  return j;
}

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
  // m.validate()'s problems, each naming this file and the key under `path`; validate() spells
  // the keys of a gyro ("rad_s"), `value_key` is the channel's ("m_s2" for an accelerometer).
  void validate(const CalibrationModel& m, const std::string& path, const std::string& value_key) const {
    try {
      m.validate();
    } catch (const ConfigError& e) {
      std::vector<Diagnostic> problems = e.problems();
      for (auto& d : problems) {
        std::string key = d.where.field;
        if (const auto at = key.find("rad_s"); at != std::string::npos) key.replace(at, 5, value_key);
        d.where = {file_, 0, join(path, key)};
      }
      throw ConfigError(std::move(problems));
    }
  }

 private:
  std::string file_;
};

// The JSON text of a model file; a key repeated in one object is refused (ConfigError naming the file
// and the key path), as the YAML readers refuse one: nlohmann::json would silently keep the last.
nlohmann::json parse_unique_keys(const Reader& r, const std::string& text) {
  struct Frame {
    bool object;
    std::string path;  // key path of this object or array ("channels[0].model")
    std::set<std::string> keys;
    std::string last_key;
    std::size_t next = 0;  // arrays: index of the next element
  };
  std::vector<Frame> stack;
  const auto child_path = [&]() -> std::string {
    if (stack.empty()) return "";
    Frame& top = stack.back();
    if (top.object) return Reader::join(top.path, top.last_key);
    return top.path + "[" + std::to_string(top.next++) + "]";
  };
  using Event = nlohmann::json::parse_event_t;
  return nlohmann::json::parse(text, [&](int, Event event, nlohmann::json& parsed) {
    switch (event) {
      case Event::object_start:
      case Event::array_start: {
        std::string path = child_path();
        stack.push_back({event == Event::object_start, std::move(path), {}, {}, 0});
        break;
      }
      case Event::object_end:
      case Event::array_end:
        stack.pop_back();
        break;
      case Event::key: {
        Frame& top = stack.back();
        top.last_key = parsed.get<std::string>();
        if (!top.keys.insert(top.last_key).second)
          r.fail(Reader::join(top.path, top.last_key), "the key appears twice in one object; expected each key once");
        break;
      }
      case Event::value:
        if (!stack.empty() && !stack.back().object) ++stack.back().next;
        break;
    }
    return true;
  });
}

// The model of one channel from `j` (the v1 file's top level, or a v2 channel's "model");
// `at` is the key path of `j` in messages ("" or "channels[2].model").
CalibrationModel read_model_body(const Reader& r, const nlohmann::json& j, const std::string& at, imu::Sensor sensor) {
  const KeyUnits& u = key_units(sensor);
  const auto key = [&](const std::string& k) { return Reader::join(at, k); };
  CalibrationModel m;
  const std::string kind = r.text(j, at, "kind");
  const auto parsed_kind = parse_model_kind(kind);
  if (!parsed_kind) r.fail(key("kind"), "expected poly, physical or rbf, got \"" + kind + "\"");
  m.kind = *parsed_kind;
  m.reference_temp_c = r.number(j, at, "reference_temp_c");
  const auto range = r.numbers(r.at(j, at, "valid_range_c"), key("valid_range_c"));
  if (range.size() != 2 || !(range[0] <= range[1])) r.fail(key("valid_range_c"), "expected [min, max] with min <= max");
  m.valid_min_c = range[0];
  m.valid_max_c = range[1];
  const std::string policy = r.text(j, at, "extrapolation");
  const auto parsed_policy = parse_extrapolation(policy);
  if (!parsed_policy) r.fail(key("extrapolation"), "expected clamp, linear or evaluate, got \"" + policy + "\"");
  m.extrapolation = *parsed_policy;
  const std::string bias_at = key("bias");
  const auto& bias = r.at(j, at, "bias");
  const std::string poly_key = "polynomial_" + u.value + "_per_k_i", sigma_key = "sigma_" + u.value + "_per_k_i";
  m.bias_rad_s = r.numbers(r.at(bias, bias_at, poly_key), Reader::join(bias_at, poly_key));
  if (m.bias_rad_s.empty()) r.fail(Reader::join(bias_at, poly_key), "needs at least one coefficient");
  if (const auto* s = r.optional(bias, sigma_key)) m.bias_sigma_rad_s = r.numbers(*s, Reader::join(bias_at, sigma_key));
  if (!m.bias_sigma_rad_s.empty() && m.bias_sigma_rad_s.size() != m.bias_rad_s.size()) {
    r.fail(Reader::join(bias_at, sigma_key), "needs one value per coefficient");
  }
  if (const auto* p = r.optional(j, "physical")) {
    const std::string pa = key("physical");
    m.lag_tau_s = r.number_or(*p, pa, "lag_tau_s", 0.0);
    m.derivative_tau_s = r.number_or(*p, pa, "derivative_tau_s", m.derivative_tau_s);
    m.temperature_rate_rad_s_per_k_s = r.number_or(*p, pa, "temperature_rate_" + u.value + "_per_k_s", 0.0);
    m.temperature_rate_sigma = r.number_or(*p, pa, "temperature_rate_sigma", 0.0);
    m.hysteresis_rad_s = r.number_or(*p, pa, "hysteresis_" + u.value, 0.0);
    m.hysteresis_sigma_rad_s = r.number_or(*p, pa, "hysteresis_sigma_" + u.value, 0.0);
    m.hysteresis_width_k = r.number_or(*p, pa, "hysteresis_width_k", 0.0);
    if (m.lag_tau_s < 0) r.fail(Reader::join(pa, "lag_tau_s"), "must be >= 0 s");
    if (!(m.derivative_tau_s > 0)) r.fail(Reader::join(pa, "derivative_tau_s"), "must be > 0 s");
    if (m.hysteresis_width_k < 0) r.fail(Reader::join(pa, "hysteresis_width_k"), "must be >= 0 K");
    for (const auto& [stored, name] : {std::pair{&m.temperature_rate_range_k_s, "temperature_rate_range_k_s"},
                                       std::pair{&m.hysteresis_state_range, "hysteresis_state_range"}})
      if (const auto* v = r.optional(*p, name)) {
        const auto values = r.numbers(*v, Reader::join(pa, name));
        if (values.size() != 2 || !(values[0] <= values[1]))
          r.fail(Reader::join(pa, name), "expected [min, max] with min <= max");
        *stored = InputRange{values[0], values[1]};
      }
  }
  if (const auto* b = r.optional(j, "rbf")) {
    const std::string ba = key("rbf");
    const auto bkey = [&](const std::string& k) { return Reader::join(ba, k); };
    RbfTerm t;
    t.mean = r.numbers(r.at(*b, ba, "mean"), bkey("mean"));
    t.scale = r.numbers(r.at(*b, ba, "scale"), bkey("scale"));
    if (t.mean.size() != 3) r.fail(bkey("mean"), "needs 3 values (model_temp_c, temp_rate_k_s, hysteresis_state)");
    if (t.scale.size() != 3) r.fail(bkey("scale"), "needs 3 values");
    for (double s : t.scale) {
      if (!(s > 0)) r.fail(bkey("scale"), "values must be > 0");
    }
    t.sigma = r.number(*b, ba, "sigma");
    if (!(t.sigma > 0)) r.fail(bkey("sigma"), "must be > 0");
    const auto& centres = r.at(*b, ba, "centres");
    if (!centres.is_array()) r.fail(bkey("centres"), "expected a list of [T, D, s] rows");
    t.centres.resize(static_cast<Eigen::Index>(centres.size()), 3);
    for (std::size_t k = 0; k < centres.size(); ++k) {
      const std::string ck = bkey("centres[" + std::to_string(k) + "]");
      const auto row = r.numbers(centres[k], ck);
      if (row.size() != 3) r.fail(ck, "needs 3 values");
      for (int c = 0; c < 3; ++c) t.centres(static_cast<Eigen::Index>(k), c) = row[static_cast<std::size_t>(c)];
    }
    t.weights_rad_s = r.numbers(r.at(*b, ba, "weights_" + u.value), bkey("weights_" + u.value));
    if (t.weights_rad_s.size() != centres.size()) r.fail(bkey("weights_" + u.value), "needs one weight per centre");
    t.bias_rad_s = r.number(*b, ba, "bias_" + u.value);
    if (const auto* lo = r.optional(*b, "input_min")) t.input_min = r.numbers(*lo, bkey("input_min"));
    if (const auto* hi = r.optional(*b, "input_max")) t.input_max = r.numbers(*hi, bkey("input_max"));
    m.rbf = std::move(t);
  }
  if (m.kind == ModelKind::Rbf && !m.rbf) r.fail(key("rbf"), "kind is rbf but the rbf section is missing");
  if (const auto* s = r.optional(j, "scale_factor")) {
    if (const auto* c = r.optional(*s, "polynomial_per_k_j")) {
      m.scale_factor_per_k = r.numbers(*c, key("scale_factor.polynomial_per_k_j"));
    }
  }
  if (const auto* n = r.optional(j, "noise")) {
    const std::string na = key("noise");
    m.noise.arw_rad_sqrt_s = r.number_or(*n, na, u.white, 0.0);
    m.noise.bias_instability_rad_s = r.number_or(*n, na, u.instability, 0.0);
    m.noise.rate_random_walk_rad_s_sqrt_s = r.number_or(*n, na, u.random_walk, 0.0);
    m.noise.sample_rate_hz = r.number_or(*n, na, "sample_rate_hz", 0.0);
    if (const auto* un = r.optional(*n, "unresolved_upper")) {
      const std::string ua = na + ".unresolved_upper";
      for (auto [name, upper] :
           {std::pair{u.white, &m.noise.arw_upper}, std::pair{u.instability, &m.noise.bias_instability_upper},
            std::pair{u.random_walk, &m.noise.rate_random_walk_upper}})
        if (r.optional(*un, name)) *upper = r.number_or(*un, ua, name, 0.0);
    }
  }
  if (const auto* f = r.optional(j, "fit")) {
    const std::string fa = key("fit");
    if (const auto* recs = r.optional(*f, "records"); recs && recs->is_array()) {
      for (const auto& x : *recs) {
        if (x.is_string()) m.fit.records.push_back(x.get<std::string>());
      }
    }
    m.fit.samples = r.count_or(*f, fa, "samples");
    m.fit.bin_s = r.number_or(*f, fa, "bin_s", 0.0);
    if (r.optional(*f, "selection")) m.fit.selection = r.text(*f, fa, "selection");
    if (r.optional(*f, "holdout_design")) m.fit.holdout_design = r.text(*f, fa, "holdout_design");
    m.fit.holdout_blocks = r.count_or(*f, fa, "holdout_blocks");
    m.fit.holdout_rms_rad_s = r.number_or(*f, fa, "holdout_rms_" + u.value, 0.0);
    m.fit.train_rms_rad_s = r.number_or(*f, fa, "train_rms_" + u.value, 0.0);
    m.fit.uncompensated_rms_rad_s = r.number_or(*f, fa, "uncompensated_rms_" + u.value, 0.0);
    if (const auto* h = r.optional(*f, "heating_only"); h && h->is_boolean()) m.fit.heating_only = h->get<bool>();
    if (const auto* h = r.optional(*f, "scale_factor_fitted"); h && h->is_boolean()) {
      m.fit.scale_factor_fitted = h->get<bool>();
    }
  }
  r.validate(m, at, u.value);
  return m;
}

}  // namespace

const ChannelCalibration* ImuCalibration::find(const imu::ChannelId& id) const {
  for (const auto& c : channels)
    if (c.id == id) return &c;
  return nullptr;
}

void ImuCalibration::validate() const {
  if (channels.empty()) throw ConfigError({"", 0, "channels"}, "the model has no channel");
  for (std::size_t i = 0; i < channels.size(); ++i) {
    for (std::size_t k = 0; k < i; ++k)
      if (channels[k].id == channels[i].id)
        throw ConfigError({"", 0, "channels"}, "channel " + channels[i].id.role() + " appears twice");
    try {
      channels[i].model.validate();
    } catch (const ConfigError& e) {
      std::vector<Diagnostic> problems = e.problems();
      for (auto& d : problems)
        d.where.field = "channels[" + std::to_string(i) + "] (" + channels[i].id.role() + ") model." + d.where.field;
      throw ConfigError(std::move(problems));
    }
  }
}

ImuCalibration single_axis(CalibrationModel model, char axis, std::string device) {
  ImuCalibration out;
  out.device = std::move(device);
  out.channels.push_back(
      {{imu::Sensor::Gyro, axis, 0}, "rate", "rate", "rad/s", "temperature", "", true, std::move(model)});
  return out;
}

std::string to_json_text(const ImuCalibration& imu_model) {
  using nlohmann::json;
  json j;
  j["format"] = kImuFormat;
  j["device"] = imu_model.device;
  json channels = json::array();
  for (const auto& c : imu_model.channels) {
    channels.push_back({{"sensor", imu::to_string(c.id.sensor)},
                        {"axis", std::string(1, c.id.axis)},
                        {"instance", c.id.instance},
                        {"role", c.role},
                        {"column", c.column},
                        {"unit", c.unit()},
                        {"read_unit", c.read_unit},
                        {"temperature_column", c.temperature_column},
                        {"device_id", c.device_id},
                        {"offset_observable", c.offset_observable},
                        {"model", model_body(c.model, c.id.sensor)}});
  }
  j["channels"] = std::move(channels);
  return j.dump(2) + "\n";
}

ImuCalibration read_calibration(const std::filesystem::path& path) {
  const Reader r(input_name(path));
  const std::string text = read_config_text(path, "calibration model file");
  nlohmann::json j;
  try {
    j = parse_unique_keys(r, text);
  } catch (const nlohmann::json::exception& e) {  // syntax, and numbers beyond double (out_of_range)
    r.fail("", std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object()) r.fail("", "expected a JSON object");
  const std::string format = r.text(j, "", "format");
  ImuCalibration out;
  if (r.optional(j, "device")) out.device = r.text(j, "", "device");
  if (format == kFormat) {  // a single-axis gyro of earlier versions: the record's "rate" column
    std::string axis = "z";
    if (r.optional(j, "axis")) axis = r.text(j, "", "axis");
    if (axis != "x" && axis != "y" && axis != "z") r.fail("axis", "expected x, y or z, got \"" + axis + "\"");
    return single_axis(read_model_body(r, j, "", imu::Sensor::Gyro), axis[0], out.device);
  }
  if (format != kImuFormat)
    r.fail("format", "expected \"" + std::string(kImuFormat) + "\" (or \"" + kFormat + "\"), got \"" + format + "\"");
  const auto& channels = r.at(j, "", "channels");
  if (!channels.is_array() || channels.empty()) r.fail("channels", "expected a non-empty list of channels");
  for (std::size_t i = 0; i < channels.size(); ++i) {
    const std::string at = "channels[" + std::to_string(i) + "]";
    const auto& cj = channels[i];
    ChannelCalibration c;
    const std::string sensor = r.text(cj, at, "sensor");
    if (sensor != "gyro" && sensor != "accel") r.fail(at + ".sensor", "expected gyro or accel, got \"" + sensor + "\"");
    c.id.sensor = sensor == "gyro" ? imu::Sensor::Gyro : imu::Sensor::Accel;
    const std::string axis = r.text(cj, at, "axis");
    if (axis != "x" && axis != "y" && axis != "z") r.fail(at + ".axis", "expected x, y or z, got \"" + axis + "\"");
    c.id.axis = axis[0];
    const double instance = r.number(cj, at, "instance");
    if (instance < 0 || instance > 99 || instance != std::floor(instance))
      r.fail(at + ".instance", "expected a whole number from 0 to 99");
    c.id.instance = static_cast<int>(instance);
    c.role = r.text(cj, at, "role");
    if (c.role != c.id.role() && !(c.role == "rate" && c.id.sensor == imu::Sensor::Gyro && c.id.instance == 0))
      r.fail(at + ".role",
             "expected \"" + c.id.role() + "\" (or \"rate\" for a single-axis gyro), got \"" + c.role + "\"");
    c.column = r.text(cj, at, "column");
    if (c.column.empty()) r.fail(at + ".column", "must not be empty");
    c.read_unit = r.text(cj, at, "read_unit");
    const auto unit = find_unit(c.read_unit);
    const Quantity want = c.id.sensor == imu::Sensor::Gyro ? Quantity::AngularRate : Quantity::Acceleration;
    if (!unit || unit->quantity != want)
      r.fail(at + ".read_unit", "expected " + std::string(sensor == "gyro" ? "an angular-rate" : "an acceleration") +
                                    " unit, got \"" + c.read_unit + "\"");
    c.temperature_column = r.text(cj, at, "temperature_column");
    if (r.optional(cj, "device_id")) c.device_id = r.text(cj, at, "device_id");
    if (const auto* o = r.optional(cj, "offset_observable")) {
      if (!o->is_boolean()) r.fail(at + ".offset_observable", "expected true or false");
      c.offset_observable = o->get<bool>();
    }
    c.model = read_model_body(r, r.at(cj, at, "model"), at + ".model", c.id.sensor);
    if (out.find(c.id)) r.fail(at, "channel " + c.id.role() + " appears twice");
    out.channels.push_back(std::move(c));
  }
  return out;
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

double CausalCompensator::rbf_value(double tc) {
  const RbfTerm& r = *model_.rbf;
  const auto input = [&](std::size_t k, double x) {
    if (!r.input_min.empty() && (x < r.input_min[k] || x > r.input_max[k])) {
      outside_ |= kOutsideRbfInputs;
      x = std::clamp(x, r.input_min[k], r.input_max[k]);
    }
    return (x - r.mean[k]) / r.scale[k];
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
  outside_ = tm < model_.valid_min_c || tm > model_.valid_max_c ? kOutsideTemperature : 0;
  double b = model_.polynomial_bias_rad_s(tm);
  if (stateful_) {
    const auto limited = [&](double x, const std::optional<InputRange>& range, unsigned bit) {
      if (!range || range->contains(x)) return x;
      outside_ |= bit;
      return std::clamp(x, range->min, range->max);
    };
    b += model_.temperature_rate_rad_s_per_k_s *
             limited(state_.temp_rate_k_s(), model_.temperature_rate_range_k_s, kOutsideTemperatureRate) +
         model_.hysteresis_rad_s *
             limited(state_.hysteresis_state(), model_.hysteresis_state_range, kOutsideBranchState);
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
  out.outside.resize(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    out.rate_rad_s[i] = c.step(time_s[i], rate_rad_s[i], temp_c[i]);
    out.bias_rad_s[i] = c.last_bias_rad_s();
    out.outside[static_cast<std::size_t>(i)] = static_cast<unsigned char>(c.last_outside());
  }
  return out;
}

}  // namespace driftlab::calibration
