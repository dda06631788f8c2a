#include "models/discrepancy/workflow.hpp"

#include "framework/error.hpp"
#include "models/allan/analysis.hpp"
#include "models/allan/gmwm.hpp"

namespace driftlab::discrepancy::detail {

void Workflow::set_noise(Result& result) {
  if (options_.noise) {
    noise_ = *options_.noise;
  } else {
    if (!evenly_sampled_)
      throw DataError({"", 0, "rate"}, "the record has gaps: give the device's noise terms (--device) to test effects");
    // The noise terms come from the part of the residual that no candidate reaches: the model
    // plus every applicable candidate at its best parameters (ordinary least squares on the
    // blocks), so that a lag, a hysteresis, a dT/dt term, a warm-up or a periodic term is not
    // counted as noise (it would inflate K and B and hide itself).
    whitener_ = Eigen::MatrixXd::Identity(blocks_.size(), blocks_.size());
    const State ordinary = fitted({});
    std::vector<Term> reach;
    bool mover = false;
    for (const auto& score : score_all(ordinary)) {
      if (!score.applicable || !(score.delta_chi2 > 0.0)) continue;
      const std::size_t c = candidate_index(score.effect);
      if (candidates_[c].effect->moves_model_temperature()) {
        if (mover) continue;
        mover = true;
      }
      reach.push_back({c, score.theta});
    }
    const State reached = fitted(std::move(reach));
    Eigen::VectorXd residual = record_.channel(role::kRate).values - full_model(reached);
    // ... and what the views that live in temperature take (a step at one temperature, a
    // branch offset, dT/dt terms); the views in time are left out: they would take the random
    // walk itself.
    const Thermal block = thermal(reached.design.moved);
    const Thermal full = thermal(moved_record(smooth_record_, reached.terms));
    const auto step = temperature_step(reached, block, full.temp).step;
    const Eigen::VectorXd full_step =
        step ? step_column(full.temp, step->level_c) : Eigen::VectorXd(Eigen::VectorXd::Zero(full.temp.size()));
    const auto columns = [&](const Thermal& th, const Eigen::VectorXd& step_values) {
      Eigen::MatrixXd m(th.temp.size(), 6);
      m << step_values, branch_columns(th), rate_columns(th);
      return m;
    };
    const Eigen::MatrixXd block_columns = columns(block, block_means(blocks_, full_step));
    residual -= columns(full, full_step) * least_squares(block_columns, y_ - block_model(reached)).beta;
    noise_ = estimated_noise(residual);
    result.noise_estimated = true;
  }
  result.noise = noise_;
  Eigen::MatrixXd c = noise_covariance(blocks_, noise_);
  const double jitter = 1e-12 * c.diagonal().mean();
  if (!(jitter > 0.0)) throw DataError({"", 0, "noise"}, "the noise terms are all zero: the test needs a noise model");
  c.diagonal().array() += jitter;
  Eigen::LLT<Eigen::MatrixXd> llt(c);
  if (llt.info() != Eigen::Success) throw DataError({"", 0, "noise"}, "the noise covariance is not positive definite");
  whitener_ = llt.matrixL();
  covariance_trace_ = c.trace();
}

error_model::NoiseTerms Workflow::estimated_noise(const Eigen::VectorXd& residual) const {
  const double rate_hz = record_.sample_rate_hz();
  const auto analysis = allan::analyze_rate(residual, rate_hz, {.fit_terms = options_.noise_gmwm.empty()});
  error_model::NoiseTerms n;
  if (!options_.noise_gmwm.empty()) {
    const auto model = allan::gmwm::parse_model(options_.noise_gmwm, "noise_gmwm");
    const auto fit = allan::gmwm::fit(analysis.curve, rate_hz, model);
    for (const auto& c : fit.components) {
      const auto& p = c.parameters;
      switch (c.process) {
        case allan::gmwm::Process::WhiteNoise:
          n.arw_rad_sqrt_s = p[0].value;
          break;
        case allan::gmwm::Process::RandomWalk:
          n.rate_random_walk_rad_s_sqrt_s = p[0].value;
          break;
        case allan::gmwm::Process::GaussMarkov:
          n.gauss_markov.push_back({p[1].value, p[0].value});
          break;
        default:
          break;  // refused by validate_options
      }
    }
  } else {
    if (!analysis.fit)
      throw DataError({"", 0, "rate"}, "the residual's Allan curve has too few points for noise terms");
    const auto& fit = *analysis.fit;
    n.arw_rad_sqrt_s = fit[allan::Term::N].value;
    n.bias_instability_rad_s = fit[allan::Term::B].value;
    n.rate_random_walk_rad_s_sqrt_s = fit[allan::Term::K].value;
  }
  n.flicker_tau_min_s = std::max(n.flicker_tau_min_s, 1.0 / rate_hz);
  n.flicker_tau_max_s = std::max(n.flicker_tau_max_s, blocks_.duration_s());
  return n;
}

double Workflow::noise_floor(const Design& d) const {
  const Eigen::MatrixXd w = whiten(d.columns);
  const Eigen::MatrixXd information = w.transpose() * w;
  const Eigen::MatrixXd gram = d.columns.transpose() * d.columns;
  const double leaked = information.completeOrthogonalDecomposition().pseudoInverse().cwiseProduct(gram).sum();
  return std::sqrt(std::max(0.0, covariance_trace_ - leaked) / static_cast<double>(blocks_.size()));
}

}  // namespace driftlab::discrepancy::detail
