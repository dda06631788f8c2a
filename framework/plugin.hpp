// Plugin interfaces. A plugin is a thin adapter around a pure numerical kernel: it receives its
// validated parameters once (at construction, through the registry), and data only through method
// arguments. Kinds and their shapes, scikit-learn style:
//
//   decomposition  Decomposer::decompose(x)            -> IMFs + residue
//   classifier     Classifier::classify(imfs)          -> one group per IMF: noise | mixed | drift
//   regressor      Regressor::fit(X, y); predict(X)    (predict before fit throws NotFittedError)
//   optimizer      Optimizer::minimize(objective, bounds)
//   filter         Filter::filter(z)                    (batch; kernels offer streaming step())
//   effect         Effect (discrepancy workflow; see models/discrepancy)
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
  std::uint64_t seed = 1;                       // used when a plugin has no seed parameter
  unsigned threads = 1;                         // worker threads; results never depend on it
  Eigen::VectorXd time_s;                       // the record's time stamps
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
  std::vector<ImfGroup> groups;  // one per IMF column
  std::vector<double> scores;    // the statistic the rule used (e.g. sample entropy), per IMF
  std::vector<std::string> reasons;  // one logged decision per IMF
};

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
};

// Objective to minimize. Must be safe to call from several threads at once.
using Objective = std::function<double(const Eigen::VectorXd&)>;

class Optimizer : public Plugin {
 public:
  virtual OptimizationResult minimize(const Objective& f, const std::vector<Bound>& bounds,
                                      RunContext& ctx) = 0;
  SignalMap run(const SignalMap& inputs, RunContext& ctx) final;  // throws: nested use only
};

// ---- filter ---------------------------------------------------------------------------------
class Filter : public Plugin {
 public:
  virtual Eigen::VectorXd filter(const Eigen::VectorXd& z, RunContext& ctx) = 0;
  SignalMap run(const SignalMap& inputs, RunContext& ctx) final;
};

}  // namespace driftlab
