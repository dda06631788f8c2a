#include "models/discrepancy/workflow.hpp"

#include <cstdio>
#include <limits>

#include "framework/golden_section.hpp"
#include "framework/signal.hpp"
#include "framework/units.hpp"

namespace driftlab::discrepancy::detail {

Eigen::MatrixXd Workflow::bin_columns(const Eigen::VectorXd& key, bool equal_counts, std::vector<double>& edges) {
  const Eigen::Index n = key.size();
  std::vector<double> sorted(key.data(), key.data() + n);
  std::sort(sorted.begin(), sorted.end());
  edges.clear();
  for (int b = 0; b <= kViewBins; ++b) {
    const double f = static_cast<double>(b) / kViewBins;
    edges.push_back(equal_counts ? sorted[std::min<std::size_t>(static_cast<std::size_t>(f * static_cast<double>(n)),
                                                                static_cast<std::size_t>(n - 1))]
                                 : sorted.front() + f * (sorted.back() - sorted.front()));
  }
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n, kViewBins);
  for (Eigen::Index k = 0; k < n; ++k) {
    const auto b = std::upper_bound(edges.begin() + 1, edges.end() - 1, key[k]) - (edges.begin() + 1);
    m(k, b) = 1.0;
  }
  return m;
}

Workflow::Thermal Workflow::thermal(const TimeSeries& rec) const {
  Thermal th;
  th.temp = rec.channel(role::kTemperature).values;
  th.x = th.temp.array() - options_.reference_temp_c;
  th.rate = signal::time_derivative(rec.time(), th.temp);
  const double soak = 1e-3 * th.rate.cwiseAbs().maxCoeff();  // below this the chamber holds
  th.branch = th.rate.array().unaryExpr([&](double r) { return r > soak ? 1.0 : r < -soak ? -1.0 : 0.0; });
  return th;
}

Eigen::MatrixXd Workflow::branch_columns(const Thermal& th) {
  Eigen::MatrixXd m(th.temp.size(), 2);
  m.col(0) = th.branch.matrix();
  m.col(1) = (th.branch * th.x).matrix();
  return m;
}

Eigen::MatrixXd Workflow::rate_columns(const Thermal& th) {
  Eigen::MatrixXd m(th.temp.size(), 3);
  m.col(0) = th.rate;
  m.col(1) = (th.rate.array() * th.x).matrix();
  m.col(2) = (th.rate.array() * th.x.square()).matrix();
  return m;
}

Eigen::VectorXd Workflow::step_column(const Eigen::VectorXd& temp_c, double level_c) {
  return (temp_c.array() > level_c).cast<double>().matrix();
}

Eigen::VectorXd Workflow::block_step_column(const Eigen::VectorXd& full_temp_c, double level_c) const {
  return block_means(blocks_, step_column(full_temp_c, level_c));
}

Eigen::VectorXd Workflow::full_model_temperature(const State& s) const {
  return moved_record(smooth_record_, s.terms).channel(role::kTemperature).values;
}

StructureTest Workflow::temperature_step(const State& state, const Thermal& th,
                                         const Eigen::VectorXd& full_temp_c) const {
  std::vector<double> sorted(th.temp.data(), th.temp.data() + th.temp.size());
  std::sort(sorted.begin(), sorted.end());
  std::vector<double> levels;
  for (int l = 0; l < kStepLevels; ++l) {
    const double f = kStepTail + (1.0 - 2.0 * kStepTail) * l / (kStepLevels - 1);
    levels.push_back(sorted[static_cast<std::size_t>(f * static_cast<double>(sorted.size() - 1))]);
  }
  const auto chi2_at = [&](double level) { return added_columns_chi2(state, block_step_column(full_temp_c, level)); };
  std::size_t best = 0;
  double best_chi2 = std::numeric_limits<double>::infinity();
  for (std::size_t l = 0; l < levels.size(); ++l) {
    const auto a = chi2_at(levels[l]);
    if (a.kept > 0 && a.chi2 < best_chi2) best_chi2 = a.chi2, best = l;
  }
  StructureTest view{"temperature", 0.0, -std::numeric_limits<double>::infinity(), 0, 0.0, "", std::nullopt};
  if (!std::isfinite(best_chi2)) return view;
  // The level between the neighbouring grid levels (golden section, as for the candidates).
  double level = levels[best];
  const double lo = levels[best == 0 ? 0 : best - 1], hi = levels[std::min(best + 1, levels.size() - 1)];
  if (const auto refined =
          golden_section_minimize([&](double l) { return chi2_at(l).chi2; }, lo, hi, options_.golden_iterations);
      refined.value < best_chi2)
    level = refined.x;
  const auto a = chi2_at(level);
  view.parameters = static_cast<int>(a.kept) + 1;
  view.delta_chi2 = state.fit.chi2 - a.chi2;
  view.delta_bic =
      view.delta_chi2 / chi2_scale(state) - view.parameters * std::log(static_cast<double>(blocks_.size()));
  view.size_rad_s = rms(a.component);
  // The step's size from the joint fit with the model (the view's component is only the part
  // the model cannot take: a polynomial absorbs much of a step).
  Design joint = state.design;
  joint.columns.conservativeResize(Eigen::NoChange, joint.columns.cols() + 1);
  joint.columns.rightCols(1) = block_step_column(full_temp_c, level);
  const Fit f = fit(joint);
  view.step = StructureTest::TemperatureStep{level, f.beta[f.beta.size() - 1]};
  char text[160];
  std::snprintf(text, sizeof text, "a step of %+.3g deg/h where the temperature crosses %.3g degC",
                view.step->size_rad_s * kDphPerRadPerSec, level);
  view.where = text;
  return view;
}

Unexplained Workflow::structure_tests(const State& state) const {
  const TimeSeries& rec = state.design.moved;
  const Thermal th = thermal(rec);
  const Eigen::VectorXd& temp = th.temp;
  constexpr double kDph = kDphPerRadPerSec;  // the texts are in deg/h
  const double scale = chi2_scale(state);
  const double log_blocks = std::log(static_cast<double>(blocks_.size()));
  Unexplained u;
  auto add = [&](const std::string& view, const Eigen::MatrixXd& columns,
                 const std::function<std::string(const Eigen::VectorXd&)>& where) {
    const auto a = added_columns_chi2(state, columns);
    StructureTest t{
        view, state.fit.chi2 - a.chi2, -std::numeric_limits<double>::infinity(), static_cast<int>(a.kept), 0.0, ""};
    if (a.kept > 0) {
      t.delta_bic = t.delta_chi2 / scale - static_cast<double>(a.kept) * log_blocks;
      t.size_rad_s = rms(a.component);
      t.where = where(a.component);
    }
    u.views.push_back(std::move(t));
  };
  auto largest_bin = [&](const Eigen::VectorXd& key, const std::vector<double>& edges, const Eigen::VectorXd& c,
                         const std::string& unit) {
    int best = 0;
    double best_value = 0.0;
    for (int b = 0; b < kViewBins; ++b) {
      double sum = 0.0;
      int count = 0;
      for (Eigen::Index k = 0; k < key.size(); ++k)
        if (key[k] >= edges[b] && (key[k] < edges[b + 1] || b == kViewBins - 1)) sum += c[k], ++count;
      const double mean = count ? sum / count : 0.0;
      if (std::abs(mean) > std::abs(best_value)) best_value = mean, best = b;
    }
    char text[160];
    std::snprintf(text, sizeof text, "largest at %.4g .. %.4g %s (%+.3g deg/h)", edges[best], edges[best + 1],
                  unit.c_str(), best_value * kDph);
    return std::string(text);
  };
  std::vector<double> temp_edges, time_edges;
  const Eigen::MatrixXd temp_bins = bin_columns(temp, true, temp_edges);
  add("temperature", temp_bins, [&](const Eigen::VectorXd& c) { return largest_bin(temp, temp_edges, c, "degC"); });
  if (auto step = temperature_step(state, th, full_model_temperature(state)); step.delta_bic > u.views.back().delta_bic)
    u.views.back() = std::move(step);
  add("heating_vs_cooling", branch_columns(th), [&](const Eigen::VectorXd& c) {
    double heating = 0.0, cooling = 0.0;
    int nh = 0, nc = 0;
    for (Eigen::Index k = 0; k < c.size(); ++k) {
      if (th.branch[k] > 0) heating += c[k], ++nh;
      if (th.branch[k] < 0) cooling += c[k], ++nc;
    }
    char text[160];
    std::snprintf(text, sizeof text, "heating %+.3g deg/h, cooling %+.3g deg/h on average",
                  nh ? heating / nh * kDph : 0.0, nc ? cooling / nc * kDph : 0.0);
    return std::string(text);
  });
  add("temperature_rate", rate_columns(th), [&](const Eigen::VectorXd& c) {
    const Eigen::Index k = [&] {
      Eigen::Index i;
      c.cwiseAbs().maxCoeff(&i);
      return i;
    }();
    char text[160];
    std::snprintf(text, sizeof text,
                  "follows dT/dt with a temperature-dependent factor; largest %+.3g deg/h at %.3g degC, "
                  "%.3g degC/min",
                  c[k] * kDph, temp[k], th.rate[k] * 60.0);
    return std::string(text);
  });
  add("time", bin_columns(rec.time(), false, time_edges),
      [&](const Eigen::VectorXd& c) { return largest_bin(rec.time(), time_edges, c, "s"); });
  std::stable_sort(u.views.begin(), u.views.end(),
                   [](const StructureTest& a, const StructureTest& b) { return a.delta_bic > b.delta_bic; });
  u.found = u.views.front().delta_bic > options_.significance;
  return u;
}

}  // namespace driftlab::discrepancy::detail
