// Plugin interfaces. A plugin is a thin adapter around a pure numerical kernel: it receives its
// validated parameters once (at construction, through the registry), and data only through method
// arguments. Kinds and their shapes, scikit-learn style:
//
//   decomposition  Decomposer::decompose(x)            -> IMFs + residue
//   classifier     Classifier::classify(imfs)          -> one group per IMF: noise | mixed | drift
//   regressor      Regressor::fit(X, y); predict(X)    (predict before fit throws NotFittedError)
//   optimizer      Optimizer::minimize(objective, bounds)
//   filter         Filter::filter(z)                    (batch; kernels offer streaming step())
//   effect         Effect::evaluate(record, theta)     -> basis columns (+ moved model temperature)
//
// Every plugin can also run as a pipeline step: run() maps named input signals to named output
// signals. The kind base classes implement run() from the kind's methods, so adapters only
// implement the kind's methods. Port names per kind are listed by ports_of_kind().
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "framework/sampling.hpp"
#include "framework/time_series.hpp"

namespace driftlab {

inline constexpr int kPluginInterfaceVersion = 1;

// The plugin kinds, in display order.
const std::vector<std::string>& plugin_kinds();

// One or more columns sharing a unit, sampled at the record's time stamps.
struct Signal {
  Eigen::MatrixXd columns;          // samples x columns
  std::vector<std::string> labels;  // one per column
  std::string unit;                 // internal unit, e.g. "rad/s"

  static Signal single(Eigen::VectorXd values, std::string label, std::string unit);
  Eigen::VectorXd sum() const { return columns.rowwise().sum(); }
};

using SignalMap = std::map<std::string, Signal>;

// What a step sees besides its data. Library code reports through this, never by printing.
struct RunContext {
  std::uint64_t seed = 1;  // used when a plugin has no seed parameter
  unsigned threads = 1;    // worker threads; results never depend on it
  Eigen::VectorXd time_s;  // the record's time stamps
  // The record's mean sample rate, Hz (sampling::mean_rate_hz of time_s), set once by run_pipeline.
  // 0 means "not given": a context built outside a pipeline (python, tests) may leave it, and
  // rate_hz() then derives it from time_s with the same function. Plugins read rate_hz().
  double sample_rate_hz = 0.0;
  // The sample rate a plugin uses: sample_rate_hz when > 0, else sampling::mean_rate_hz(time_s)
  // (0 for fewer than 2 time stamps or a zero span: no rate known).
  double rate_hz() const { return sample_rate_hz > 0.0 ? sample_rate_hz : sampling::mean_rate_hz(time_s); }
  std::function<void(double fraction)> progress = [](double) {};
  nlohmann::json diagnostics = nlohmann::json::object();  // per-step report entries
};

struct PortSpec {
  std::string name;
  bool required = true;
  bool many = false;  // accepts a list of references whose columns are concatenated
  std::string doc;
};

struct KindPorts {
  std::vector<PortSpec> inputs;
  std::vector<std::string> outputs;
};
// Throws ConfigError for an unknown kind.
const KindPorts& ports_of_kind(const std::string& kind);

class Plugin {
 public:
  virtual ~Plugin() = default;
  virtual SignalMap run(const SignalMap& inputs, RunContext& ctx) = 0;
};

// ---- decomposition --------------------------------------------------------------------------
struct Decomposition {
  Eigen::MatrixXd imfs;     // samples x K, highest frequency first
  Eigen::VectorXd residue;  // x = imfs.rowwise().sum() + residue
};

class Decomposer : public Plugin {
 public:
  virtual Decomposition decompose(const Eigen::VectorXd& x, RunContext& ctx) = 0;
  SignalMap run(const SignalMap& inputs, RunContext& ctx) final;
};

// ---- classifier -----------------------------------------------------------------------------
enum class ImfGroup { Noise, Mixed, Drift };
std::string to_string(ImfGroup group);

struct Classification {
  std::vector<ImfGroup> groups;      // one per IMF column
  std::vector<double> scores;        // the statistic the rule used (e.g. sample entropy), per IMF
  std::vector<std::string> reasons;  // one logged decision per IMF
};

// Every group in the order reports list them (the classifier's output ports).
inline constexpr ImfGroup kImfGroups[] = {ImfGroup::Noise, ImfGroup::Mixed, ImfGroup::Drift};

// One IMF's decision as a classifier step reports it (its diagnostics' "imfs" list: imf, group,
// score, reason). imf_decisions() reads that list back from a step's diagnostics (empty when it
// has none), imf_decisions_json() writes it.
struct ImfDecision {
  std::size_t imf = 0;  // 1-based
  ImfGroup group = ImfGroup::Mixed;
  double score = 0.0;
  std::string reason;
};
nlohmann::json imf_decisions_json(const std::vector<ImfDecision>& decisions);
std::vector<ImfDecision> imf_decisions(const nlohmann::json& diagnostics);

class Classifier : public Plugin {
 public:
  virtual Classification classify(const Eigen::MatrixXd& imfs, RunContext& ctx) = 0;
  SignalMap run(const SignalMap& inputs, RunContext& ctx) final;
};

// ---- regressor ------------------------------------------------------------------------------
class Regressor : public Plugin {
 public:
  // X: samples x features, y: samples. Replaces any learned state.
  virtual void fit(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, RunContext& ctx) = 0;
  // Throws NotFittedError before fit().
  virtual Eigen::VectorXd predict(const Eigen::MatrixXd& X) const = 0;
  SignalMap run(const SignalMap& inputs, RunContext& ctx) final;
};

// ---- optimizer ------------------------------------------------------------------------------
struct Bound {
  std::string name;
  double lower = 0.0, upper = 1.0;
  bool integer = false;
};

struct OptimizationResult {
  Eigen::VectorXd best;
  double best_value = 0.0;
  std::vector<double> history;  // best objective value per generation / iteration
  std::int64_t evaluations = 0;
  // Several objectives (minimize_objectives): the non-dominated points found, one row each, and
  // the objective vector of `best` (the point the optimizer chose from that set by its documented
  // rule; best_value is its first objective). Empty for single-objective runs.
  Eigen::MatrixXd pareto_x;  // points x dimension
  Eigen::MatrixXd pareto_f;  // points x objectives
  Eigen::VectorXd best_values;
};

// Objective to minimize. Must be safe to call from several threads at once.
using Objective = std::function<double(const Eigen::VectorXd&)>;
// Several objectives to minimize at once: returns one value per objective.
using VectorObjective = std::function<Eigen::VectorXd(const Eigen::VectorXd&)>;

class Optimizer : public Plugin {
 public:
  virtual OptimizationResult minimize(const Objective& f, const std::vector<Bound>& bounds, RunContext& ctx) = 0;
  // Largest number of objectives minimize_objectives() accepts (1 unless overridden).
  virtual std::size_t max_objectives() const { return 1; }
  // The objective evaluations one minimize() makes at most (optimizer/ga: population x
  // (generations + 1)), for the cost estimate before a tuning run (plugins/tuning, issue 28);
  // 0 (the default) when the optimizer does not state it.
  virtual double evaluation_budget() const { return 0.0; }
  // Minimizes `objectives` criteria at once. The default handles objectives == 1 through
  // minimize() and throws ConfigError for more; multi-objective optimizers override it.
  virtual OptimizationResult minimize_objectives(const VectorObjective& f, std::size_t objectives,
                                                 const std::vector<Bound>& bounds, RunContext& ctx);
  SignalMap run(const SignalMap& inputs, RunContext& ctx) final;  // throws: nested use only
};

// ---- filter ---------------------------------------------------------------------------------
class Filter : public Plugin {
 public:
  virtual Eigen::VectorXd filter(const Eigen::VectorXd& z, RunContext& ctx) = 0;
  // Unit of the output for an input in input_unit (a denoiser keeps it; a slope adds "/s").
  virtual std::string output_unit(const std::string& input_unit) const { return input_unit; }
  SignalMap run(const SignalMap& inputs, RunContext& ctx) final;
};

// ---- effect ---------------------------------------------------------------------------------
// A candidate physical term for the discrepancy workflow (models/discrepancy/discrepancy.hpp). For
// nonlinear parameters theta (time constants, widths, periods; searched by the workflow) an effect
// contributes
//
//   rate += sum_j c_j basis_j(record; theta)          (c fitted jointly with the model by least squares)
//
// and may move the temperature that the model's bias(T) and scale factor follow (a thermal lag:
// the model is then evaluated at model_temperature_c instead of the sensor's temperature).
struct EffectParameter {
  std::string name;                 // e.g. "tau_s"
  std::string unit;                 // e.g. "s"
  double lower = 0.0, upper = 0.0;  // search interval, 0 < lower < upper
  // Log: grid uniform in log(value). Period: grid uniform in 1/value, clamped by the workflow to
  // the periods the (block-averaged) record resolves.
  enum class Scale { Log, Period } scale = Scale::Log;
};

struct EffectContext {
  double reference_temp_c = 25.0;  // T0 of the device model, degC
  double start_time_s = 0.0;       // first time stamp of the record (power-on for warm-up terms)
  // Drive-mode frequency f(T) ~ f_ref + slope (T - T0) from the device file; slope 0 = unknown.
  double drive_frequency_at_reference_hz = 0.0;
  double drive_frequency_slope_hz_per_k = 0.0;
};

struct EffectTerm {
  Eigen::MatrixXd basis;                // samples x coefficients, rad/s per unit coefficient
  Eigen::VectorXd model_temperature_c;  // empty, or the temperature the model's bias(T) follows
};

// One reported parameter, in the unit a device file's `effects:` section uses for it.
struct EffectValue {
  std::string key;             // e.g. "tau_s", "coefficients_ppm"
  std::string unit;            // e.g. "s"
  std::vector<double> values;  // one value, or several for a list key
};

class Effect : public Plugin {
 public:
  // Channel roles it reads besides time (role::kTemperature, role::kTrueRate, ...). The workflow
  // leaves an effect out when the record lacks one of them.
  virtual std::vector<std::string> required_roles() const = 0;
  virtual std::vector<EffectParameter> nonlinear_parameters() const = 0;
  // One name per basis column (its linear coefficient), e.g. {"height_rad_s"}; may be empty.
  virtual std::vector<std::string> coefficient_names() const = 0;
  // True when evaluate() sets model_temperature_c (at most one such effect is in a model).
  virtual bool moves_model_temperature() const { return false; }
  // theta has one value per nonlinear_parameters(). Pure function of its arguments. Throws
  // DataError when a required channel is missing.
  virtual EffectTerm evaluate(const TimeSeries& record, const EffectContext& context,
                              const Eigen::VectorXd& theta) const = 0;
  // The fitted term as reported (device-file keys and units where the simulator has the effect).
  virtual std::vector<EffectValue> describe(const TimeSeries& record, const EffectContext& context,
                                            const Eigen::VectorXd& theta,
                                            const Eigen::VectorXd& coefficients) const = 0;
  SignalMap run(const SignalMap& inputs, RunContext& ctx) final;  // throws: effects run in the workflow
};

}  // namespace driftlab
