// filter/kalman: Kalman filter (Li et al. 2023 eqs. 10-14) with an optional RTS smoother; the
// output is the estimate of the noise-free measurement H x per sample. Models, the Allan-term
// conversion and the time convention are documented in kalman.hpp.
#include <cmath>
#include <memory>
#include <stdexcept>

#include "framework/error.hpp"
#include "framework/registry.hpp"
#include "plugins/kalman/kalman.hpp"

namespace driftlab {
namespace {

using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Side of a square matrix given as a row-major list, or -1 when the size is not a square.
Eigen::Index square_side(const std::vector<double>& values) {
  const auto n = static_cast<Eigen::Index>(std::llround(std::sqrt(static_cast<double>(values.size()))));
  return n >= 1 && static_cast<std::size_t>(n * n) == values.size() ? n : -1;
}

Eigen::MatrixXd square_matrix(const std::vector<double>& values) {
  const Eigen::Index n = square_side(values);
  return Eigen::Map<const RowMajorMatrix>(values.data(), n, n);
}

Eigen::Index model_states(const ParamValues& p) {
  const auto& model = p.text("model");
  if (model == "random_walk") return 1;
  if (model == "random_walk_gauss_markov") return 2;
  return square_side(p.reals("f_matrix"));
}

std::string symmetric_psd_problem(const ParamValue& value) {
  const auto& values = std::get<std::vector<double>>(value);
  if (square_side(values) < 0) return "needs n x n entries (row-major)";
  try {
    const Eigen::MatrixXd m = square_matrix(values);
    kalman::validate({Eigen::MatrixXd::Identity(m.rows(), m.rows()), Eigen::MatrixXd::Identity(1, m.rows()), m,
                      Eigen::MatrixXd::Identity(1, 1)});
  } catch (const std::invalid_argument&) {
    return "must be symmetric positive semi-definite";
  }
  return "";
}

class KalmanFilter final : public Filter {
 public:
  explicit KalmanFilter(const ParamValues& p)
      : model_(p.text("model")),
        from_allan_(p.text("noise") == "from_allan"),
        q_(p.real("q")),
        r_(p.real("r")),
        arw_(p.real("arw")),
        rrw_(p.real("rrw")),
        sample_rate_hz_(p.real("sample_rate_hz")),
        gm_sigma_(p.real("gm_sigma")),
        gm_tau_(p.real("gm_tau")),
        f_(square_matrix(p.reals("f_matrix"))),
        h_(Eigen::Map<const Eigen::RowVectorXd>(p.reals("h_matrix").data(),
                                                static_cast<Eigen::Index>(p.reals("h_matrix").size()))),
        q_matrix_(square_matrix(p.reals("q_matrix"))),
        smoother_(p.boolean("smoother")),
        initial_variance_(p.real("initial_variance")) {
    const auto& x0 = p.reals("initial_state");
    initial_state_ =
        x0.empty()
            ? Eigen::VectorXd(Eigen::VectorXd::Zero(model_states(p)))
            : Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(x0.data(), static_cast<Eigen::Index>(x0.size())));
  }

  Eigen::VectorXd filter(const Eigen::VectorXd& z, RunContext& ctx) override {
    const double fs = sample_rate(ctx);
    const bool needs_rate = from_allan_ || model_ == "random_walk_gauss_markov";
    if (needs_rate && !(fs > 0.0)) {
      throw DataError({"", 0, "sample_rate_hz"},
                      "filter/kalman needs the sample rate (noise: from_allan or the Gauss-Markov model): "
                      "set sample_rate_hz or provide time stamps");
    }
    const double r = from_allan_ ? kalman::measurement_variance_from_arw(arw_, fs) : r_;
    const double q = from_allan_ ? kalman::process_variance_from_rrw(rrw_, fs) : q_;
    ctx.diagnostics["model"] = model_;
    ctx.diagnostics["r_rad2_s2"] = r;
    if (model_ != "linear") ctx.diagnostics["q_rad2_s2"] = q;
    if (fs > 0.0) ctx.diagnostics["sample_rate_hz"] = fs;
    ctx.diagnostics["smoothed"] = smoother_;
    try {
      if (model_ == "random_walk") return scalar(z, {q, r}, fs, ctx);
      kalman::LinearModel model = model_ == "random_walk_gauss_markov"
                                      ? kalman::random_walk_gauss_markov_model(q, gm_sigma_, gm_tau_, 1.0 / fs, r)
                                      : kalman::LinearModel{f_, h_, q_matrix_, Eigen::MatrixXd::Constant(1, 1, r)};
      const Eigen::MatrixXd p0 = initial_variance_ * Eigen::MatrixXd::Identity(model.states(), model.states());
      const auto estimates =
          smoother_ ? kalman::smooth(z, model, initial_state_, p0) : kalman::filter(z, model, initial_state_, p0);
      if (estimates.state.rows() > 0) {
        const Eigen::VectorXd last = estimates.state.row(estimates.state.rows() - 1).transpose();
        ctx.diagnostics["final_state"] = std::vector<double>(last.data(), last.data() + last.size());
      }
      return estimates.state * model.H.transpose();
    } catch (const std::invalid_argument& e) {
      throw DataError({"", 0, "signal"}, std::string("filter/kalman: ") + e.what());
    }
  }

 private:
  Eigen::VectorXd scalar(const Eigen::VectorXd& z, const kalman::ScalarModel& model, double fs, RunContext& ctx) const {
    const double gain = kalman::steady_state_gain(model);
    ctx.diagnostics["steady_state_gain"] = gain;
    if (fs > 0.0 && !smoother_) {
      // Equivalent noise bandwidth (one-sided) of x_k = (1 - K) x_{k-1} + K z_k.
      ctx.diagnostics["steady_state_noise_bandwidth_hz"] = fs * gain / (2.0 * (2.0 - gain));
    }
    const double x0 = initial_state_[0];
    if (smoother_) return kalman::smooth(z, model, x0, initial_variance_).state;
    return kalman::filter_states(z, model, x0, initial_variance_);
  }

  double sample_rate(const RunContext& ctx) const { return sample_rate_hz_ > 0.0 ? sample_rate_hz_ : ctx.rate_hz(); }

  std::string model_;
  bool from_allan_;
  double q_, r_, arw_, rrw_, sample_rate_hz_, gm_sigma_, gm_tau_;
  Eigen::MatrixXd f_, h_, q_matrix_;
  bool smoother_;
  double initial_variance_;
  Eigen::VectorXd initial_state_;
};

}  // namespace

void register_kalman_plugins(Registry& registry) {
  registry.add(
      {.name = "filter/kalman",
       .summary = "Kalman filter (random walk, random walk + Gauss-Markov, or matrices) with optional RTS smoother",
       .reference = "Li et al. 2023 eqs. 10-14 (Joseph-form update); Rauch, Tung & Striebel 1965; "
                    "IEEE Std 952 (Allan terms N, K)",
       .params =
           ParamTable{
               {
                   param::choice("model", "random_walk", {"random_walk", "random_walk_gauss_markov", "linear"},
                                 "state model: random walk + white noise (paper); plus a first-order Gauss-Markov "
                                 "term (gm_sigma, gm_tau); or linear (f_matrix, h_matrix, q_matrix)"),
                   param::choice("noise", "given", {"given", "from_allan"},
                                 "given: use q and r; from_allan: r = arw^2 fs, q = rrw^2 / fs (fs = sample rate)"),
                   param::real("q", 1e-10, "(rad/s)^2", "random-walk increment variance per sample (noise: given)")
                       .at_least(0),
                   param::real("r", 1e-6, "(rad/s)^2", "measurement noise variance (noise: given)").greater_than(0),
                   param::real("arw", 1e-4, "rad/s/sqrt(Hz)",
                               "angle random walk N for noise: from_allan (1 deg/sqrt(h) = 2.909e-4 rad/s/sqrt(Hz))")
                       .greater_than(0),
                   param::real("rrw", 1e-7, "rad/s^2/sqrt(Hz)",
                               "rate random walk K for noise: from_allan (1 deg/h/sqrt(h) = 8.081e-8 rad/s^2/sqrt(Hz))")
                       .at_least(0),
                   param::real("sample_rate_hz", 0.0, "Hz",
                               "sample rate for from_allan and Gauss-Markov; 0 = from the time stamps")
                       .at_least(0),
                   param::real("gm_sigma", 1e-4, "rad/s", "stationary standard deviation of the Gauss-Markov term")
                       .at_least(0),
                   param::real("gm_tau", 100.0, "s", "correlation time of the Gauss-Markov term").greater_than(0),
                   param::reals("f_matrix", {1.0}, "1", "model linear: state transition F, n x n, row-major"),
                   param::reals("h_matrix", {1.0}, "1", "model linear: measurement row H, n entries"),
                   param::reals("q_matrix", {1e-10}, "(rad/s)^2",
                                "model linear: process noise covariance Q, n x n, row-major")
                       .must("symmetric positive semi-definite n x n (row-major)", symmetric_psd_problem,
                             std::vector<double>{1.0, 2.0, 3.0, 4.0}),
                   param::boolean("smoother", false, "run the Rauch-Tung-Striebel smoother (offline) after the filter"),
                   param::reals("initial_state", {}, "rad/s", "state before the first sample; empty = zeros"),
                   param::real("initial_variance", 1.0, "(rad/s)^2", "P0 = initial_variance * I").greater_than(0),
               },
               {
                   {"f_matrix has n x n entries",
                    {"f_matrix"},
                    [](const ParamValues& v) { return square_side(v.reals("f_matrix")) > 0; }},
                   {"h_matrix and q_matrix match f_matrix (n and n x n entries)",
                    {"f_matrix", "h_matrix", "q_matrix"},
                    [](const ParamValues& v) {
                      const Eigen::Index n = square_side(v.reals("f_matrix"));
                      return static_cast<Eigen::Index>(v.reals("h_matrix").size()) == n &&
                             square_side(v.reals("q_matrix")) == n;
                    }},
                   {"initial_state is empty or has one entry per state of the model",
                    {"initial_state", "model", "f_matrix"},
                    [](const ParamValues& v) {
                      const auto size = static_cast<Eigen::Index>(v.reals("initial_state").size());
                      return size == 0 || size == model_states(v);
                    }},
               }},
       .make = [](const ParamValues& p, const Registry&) { return std::make_unique<KalmanFilter>(p); }});
}

}  // namespace driftlab
