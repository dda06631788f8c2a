// Small plugins that exist only in the framework tests, so that registry, parameter and pipeline
// behaviour is tested independently of the real algorithms.
#pragma once

#include <Eigen/Dense>

#include "framework/error.hpp"
#include "framework/registry.hpp"

namespace driftlab::testing_plugins {

// filter/test_gain: y = gain * z + offset (+ a seeded constant when `jitter` is true).
class Gain final : public Filter {
 public:
  explicit Gain(const ParamValues& p)
      : gain_(p.real("gain")), offset_(p.real("offset")), jitter_(p.boolean("jitter")), seed_(p.integer("seed")) {}
  Eigen::VectorXd filter(const Eigen::VectorXd& z, RunContext& ctx) override {
    ctx.diagnostics["gain"] = gain_;
    const double extra = jitter_ ? 1e-3 * static_cast<double>(seed_ % 1000) : 0.0;
    return (gain_ * z.array() + offset_ + extra).matrix();
  }

 private:
  double gain_, offset_;
  bool jitter_;
  std::int64_t seed_;
};

// optimizer/test_grid: evaluates the midpoint of the bounds (enough to test nesting).
class Midpoint final : public Optimizer {
 public:
  explicit Midpoint(const ParamValues&) {}
  OptimizationResult minimize(const Objective& f, const std::vector<Bound>& bounds, RunContext&) override {
    OptimizationResult r;
    r.best.resize(static_cast<Eigen::Index>(bounds.size()));
    for (std::size_t i = 0; i < bounds.size(); ++i)
      r.best[static_cast<Eigen::Index>(i)] = 0.5 * (bounds[i].lower + bounds[i].upper);
    r.best_value = f(r.best);
    r.evaluations = 1;
    return r;
  }
};

// regressor/test_linear: least-squares y = X b + c; holds a nested optimizer parameter.
class Linear final : public Regressor {
 public:
  explicit Linear(const ParamValues&) {}
  void fit(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, RunContext&) override {
    Eigen::MatrixXd A(X.rows(), X.cols() + 1);
    A << X, Eigen::VectorXd::Ones(X.rows());
    coef_ = A.colPivHouseholderQr().solve(y);
  }
  Eigen::VectorXd predict(const Eigen::MatrixXd& X) const override {
    if (coef_.size() == 0) throw NotFittedError("regressor/test_linear: predict before fit");
    return X * coef_.head(X.cols()) + Eigen::VectorXd::Constant(X.rows(), coef_[X.cols()]);
  }

 private:
  Eigen::VectorXd coef_;
};

// decomposition/test_halves: imf1 = x - trend, residue = straight line through the end points.
class Halves final : public Decomposer {
 public:
  explicit Halves(const ParamValues&) {}
  Decomposition decompose(const Eigen::VectorXd& x, RunContext&) override {
    Decomposition d;
    d.residue = Eigen::VectorXd::LinSpaced(x.size(), x[0], x[x.size() - 1]);
    d.imfs = x - d.residue;
    return d;
  }
};

// classifier/test_all_drift: every IMF is drift.
class AllDrift final : public Classifier {
 public:
  explicit AllDrift(const ParamValues&) {}
  Classification classify(const Eigen::MatrixXd& imfs, RunContext&) override {
    Classification c;
    for (Eigen::Index k = 0; k < imfs.cols(); ++k) {
      c.groups.push_back(ImfGroup::Drift);
      c.scores.push_back(0.0);
      c.reasons.push_back("test rule");
    }
    return c;
  }
};

inline void register_test_plugins(Registry& r) {
  r.add({.name = "filter/test_gain",
         .summary = "gain and offset",
         .reference = "",
         .params = ParamTable{{param::real("gain", 1.0, "1", "multiplier").greater_than(0).at_most(100),
                               param::real("offset", 0.0, "rad/s", "added after the gain"),
                               param::boolean("jitter", false, "add 1e-3 * (seed mod 1000)"), param::seed()}},
         .make = [](const ParamValues& p, const Registry&) { return std::make_unique<Gain>(p); }});
  r.add({.name = "optimizer/test_midpoint",
         .summary = "midpoint of the bounds",
         .reference = "",
         .params = ParamTable{{param::integer("evaluations", 1, "1", "budget").at_least(1).at_most(10)}},
         .make = [](const ParamValues& p, const Registry&) { return std::make_unique<Midpoint>(p); }});
  ParamTable linear{{param::nested("optimizer", "optimizer", "optimizer/test_midpoint", "tunes nothing"),
                     param::integer("min_terms", 1, "1", "lower"), param::integer("max_terms", 3, "1", "upper"),
                     param::choice("method", "qr", {"qr", "normal"}, "solver")}};
  linear.rules.push_back({"min_terms <= max_terms", {"min_terms", "max_terms"}, [](const ParamValues& v) {
                            return v.integer("min_terms") <= v.integer("max_terms");
                          }});
  r.add({.name = "regressor/test_linear",
         .summary = "least squares",
         .reference = "",
         .params = linear,
         .make = [](const ParamValues& p, const Registry&) { return std::make_unique<Linear>(p); }});
  r.add({.name = "decomposition/test_halves",
         .summary = "detrend by the end points",
         .reference = "",
         .params = {},
         .make = [](const ParamValues& p, const Registry&) { return std::make_unique<Halves>(p); }});
  r.add({.name = "classifier/test_all_drift",
         .summary = "everything is drift",
         .reference = "",
         .params = {},
         .make = [](const ParamValues& p, const Registry&) { return std::make_unique<AllDrift>(p); }});
}

}  // namespace driftlab::testing_plugins
