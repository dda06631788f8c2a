// regressor/polynomial: adapter of plugins/polynomial/polynomial.hpp. One input feature x; the
// order is fixed (`order` > 0) or chosen between min_order and max_order on held-out contiguous
// time blocks. ctx.diagnostics gets the chosen order, the held-out RMSE per order and the
// coefficients with their standard errors.
#include <memory>
#include <optional>
#include <stdexcept>

#include "framework/error.hpp"
#include "framework/registry.hpp"
#include "plugins/polynomial/polynomial.hpp"

namespace driftlab {
namespace {

class PolynomialPlugin final : public Regressor {
 public:
  explicit PolynomialPlugin(const ParamValues& p)
      : config_{.min_order = static_cast<int>(p.integer("order") > 0 ? p.integer("order") : p.integer("min_order")),
                .max_order = static_cast<int>(p.integer("order") > 0 ? p.integer("order") : p.integer("max_order")),
                .blocks = static_cast<std::size_t>(p.integer("holdout_blocks")),
                .x0 = p.real("center")} {}

  void fit(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, RunContext& ctx) override {
    fit_.reset();
    if (X.cols() != 1) {
      throw DataError({"", 0, "features"},
                      "regressor/polynomial: needs exactly one input feature, got " + std::to_string(X.cols()));
    }
    try {
      fit_ = polynomial::fit(X.col(0), y, config_);
    } catch (const std::invalid_argument& e) {
      throw DataError({"", 0, "features"}, std::string("regressor/polynomial: ") + e.what());
    }
    ctx.diagnostics["order"] = fit_->order;
    ctx.diagnostics["holdout_rmse_by_order"] = fit_->cv_rmse;
    ctx.diagnostics["coefficients"] = fit_->coefficients;
    ctx.diagnostics["standard_errors"] = fit_->standard_errors;
  }

  Eigen::VectorXd predict(const Eigen::MatrixXd& X) const override {
    if (!fit_) throw NotFittedError("regressor/polynomial: predict called before fit");
    if (X.cols() != 1) {
      throw DataError({"", 0, "features"},
                      "regressor/polynomial: needs exactly one input feature, got " + std::to_string(X.cols()));
    }
    Eigen::VectorXd out(X.rows());
    for (Eigen::Index i = 0; i < X.rows(); ++i) out[i] = polynomial::evaluate(fit_->coefficients, fit_->x0, X(i, 0));
    return out;
  }

 private:
  polynomial::Config config_;
  std::optional<polynomial::Fit> fit_;
};

}  // namespace

void register_polynomial_plugins(Registry& registry) {
  registry.add(
      {.name = "regressor/polynomial",
       .summary = "polynomial in (x - center), order chosen on held-out contiguous time blocks",
       .reference = "PX4 / ArduPilot thermal calibration (third-order fit)",
       .params =
           ParamTable{
               {param::integer("order", 0, "1", "fixed polynomial order; 0 = choose between min_order and max_order")
                    .at_least(0)
                    .at_most(12),
                param::integer("min_order", 1, "1", "lowest order scored when choosing").at_least(0).at_most(12),
                param::integer("max_order", 5, "1", "highest order scored when choosing").at_least(0).at_most(12),
                param::integer("holdout_blocks", 8, "1", "contiguous held-out time blocks for the order choice")
                    .at_least(2),
                param::real("center", 25.0, "unit of x", "expansion point x0 (e.g. the reference temperature, degC)")},
               {{"min_order <= max_order",
                 {"min_order", "max_order"},
                 [](const ParamValues& p) { return p.integer("min_order") <= p.integer("max_order"); }}}},
       .make = [](const ParamValues& p, const Registry&) { return std::make_unique<PolynomialPlugin>(p); }});
}

}  // namespace driftlab
