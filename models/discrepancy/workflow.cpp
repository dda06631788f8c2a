#include "models/discrepancy/workflow.hpp"

#include <string>

#include "framework/error.hpp"
#include "framework/sampling.hpp"
#include "framework/signal.hpp"
#include "models/allan/gmwm.hpp"

namespace driftlab::discrepancy::detail {
namespace {

constexpr double kTargetBlocks = 400.0;

}  // namespace

Workflow::Workflow(const TimeSeries& record, const std::vector<Candidate>& candidates, const Options& options)
    : record_(record), candidates_(candidates), options_(options) {
  validate_options();
  const Eigen::VectorXd& t = record.time();
  if (t.size() < 2) throw DataError({"", 0, "rate"}, "the record has fewer than 2 samples");
  record.channel(role::kRate);
  record.channel(role::kTemperature);
  const double duration = t[t.size() - 1] - t[0];
  block_s_ = options.block_s > 0.0 ? options.block_s
                                   : std::max(record.sampling_facts().median_step_s, duration / kTargetBlocks);
  blocks_ = make_blocks(record, block_s_);
  evenly_sampled_ = record.sampling_facts().evenly_sampled();
  free_scale_factor_ = !options.prior && record.has(role::kTrueRate) &&
                       record.channel(role::kTrueRate).values.cwiseAbs().maxCoeff() > 0.0;
  const Eigen::Index parameters = model_columns();
  if (blocks_.size() < 3 * parameters)
    throw DataError({"", 0, "rate"}, "the record has " + std::to_string(blocks_.size()) +
                                         " blocks; the model needs at least " + std::to_string(3 * parameters));
  context_ = {options.reference_temp_c, t[0], options.drive_frequency_at_reference_hz,
              options.drive_frequency_slope_hz_per_k};
  y_ = block_means(blocks_, record.channel(role::kRate).values);
  block_record_ = TimeSeries(blocks_.time_s);
  smooth_record_ = TimeSeries(t);
  for (const char* role : {role::kTemperature, role::kTrueRate, role::kDriveFrequency}) {
    if (!record.has(role)) continue;
    const Channel& c = record.channel(role);
    Eigen::VectorXd means = block_means(blocks_, c.values);
    if (std::string(role) == role::kTemperature)
      means += options.sensor_time_constant_s * signal::time_derivative(blocks_.time_s, means);
    block_record_.set_channel({c.role, c.unit, c.source, means});
    smooth_record_.set_channel(
        {c.role, c.unit, c.source, std::string(role) == role::kTrueRate ? c.values : interpolate(blocks_, means, t)});
  }
}

Result Workflow::run() {
  Result result;
  result.block_s = block_s_;
  result.blocks = blocks_.size();
  set_noise(result);
  State state = fitted({});
  result.chi2_initial = state.fit.chi2;
  result.gap_initial_rad_s = gap(state);
  result.noise_floor_rad_s = noise_floor(state.design);
  result.bias_coefficients_initial = bias_coefficients(state);
  result.model_initial_rad_s = full_model(state);
  result.initial_views = views(state, result.model_initial_rad_s);

  while (static_cast<int>(result.steps.size()) < options_.max_effects) {
    auto scores = score_all(state);
    result.unexplained = structure_tests(state);
    const double best_view = result.unexplained.views.front().delta_bic;
    const bool candidate_passes =
        !scores.empty() && scores.front().applicable && scores.front().delta_bic > options_.significance;
    if (!candidate_passes || scores.front().delta_bic < best_view - options_.significance) {
      result.final_scores = std::move(scores);
      break;
    }
    Step step;
    step.effect = scores.front().effect;
    step.delta_chi2 = scores.front().delta_chi2;
    step.delta_bic = scores.front().delta_bic;
    step.chi2_scale = chi2_scale(state);
    step.gap_before_rad_s = gap(state);
    const std::size_t chosen = candidate_index(step.effect);
    std::vector<Term> terms = state.terms;
    terms.push_back({chosen, scores.front().theta});
    state = refined(std::move(terms));
    step.gap_after_rad_s = gap(state);
    step.scores = std::move(scores);
    result.steps.push_back(std::move(step));
  }

  result.unexplained = structure_tests(state);
  const Eigen::MatrixXd covariance = parameter_covariance(state);
  for (std::size_t i = 0; i < result.steps.size(); ++i) result.steps[i].parameters = describe(state, i, covariance);
  result.chi2_final = state.fit.chi2;
  result.gap_final_rad_s = gap(state);
  result.bias_coefficients_final = bias_coefficients(state);
  result.model_final_rad_s = full_model(state);
  result.final_views = views(state, result.model_final_rad_s);
  return result;
}

void Workflow::validate_options() const {
  std::vector<Diagnostic> problems;
  if (options_.bias_degree < 0 || options_.bias_degree > 6)
    problems.push_back({{"", 0, "bias_degree"}, "must be in [0, 6]"});
  if (options_.block_s < 0.0) problems.push_back({{"", 0, "block_s"}, "must be >= 0 (0 = automatic)"});
  if (!(options_.significance >= 0.0)) problems.push_back({{"", 0, "significance"}, "must be >= 0"});
  if (options_.max_effects < 0) problems.push_back({{"", 0, "max_effects"}, "must be >= 0"});
  if (options_.grid_points_per_decade < 1) problems.push_back({{"", 0, "grid_points_per_decade"}, "must be >= 1"});
  if (options_.golden_iterations < 0) problems.push_back({{"", 0, "golden_iterations"}, "must be >= 0"});
  if (!(options_.sensor_time_constant_s >= 0.0))
    problems.push_back({{"", 0, "sensor_time_constant_s"}, "must be >= 0"});
  for (const auto& c : candidates_)
    if (!c.effect) problems.push_back({{"", 0, c.name}, "candidate without an effect"});
  if (!options_.noise_gmwm.empty()) {
    try {
      for (const auto p : allan::gmwm::parse_model(options_.noise_gmwm, "noise_gmwm"))
        if (p != allan::gmwm::Process::WhiteNoise && p != allan::gmwm::Process::RandomWalk &&
            p != allan::gmwm::Process::GaussMarkov)
          problems.push_back({{"", 0, "noise_gmwm"},
                              "'" + allan::gmwm::to_string(p) +
                                  "' is not a noise term of the discrepancy model (use wn, rw and gm terms)"});
    } catch (const ConfigError& e) {
      problems.insert(problems.end(), e.problems().begin(), e.problems().end());
    }
  }
  if (!problems.empty()) throw ConfigError(std::move(problems));
}

Views Workflow::views(const State& s, const Eigen::VectorXd& full_model_rad_s) const {
  const Eigen::VectorXd full_residual =
      evenly_sampled_ ? Eigen::VectorXd(record_.channel(role::kRate).values - full_model_rad_s) : Eigen::VectorXd();
  return residual_views(blocks_, block_record_.channel(role::kTemperature).values, y_ - block_model(s), full_residual,
                        noise_);
}

}  // namespace driftlab::discrepancy::detail

namespace driftlab::discrepancy {

Result find_missing_effects(const TimeSeries& record, const std::vector<Candidate>& candidates,
                            const Options& options) {
  return detail::Workflow(record, candidates, options).run();
}

}  // namespace driftlab::discrepancy
