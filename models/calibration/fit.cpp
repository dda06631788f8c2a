#include "models/calibration/fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "framework/error.hpp"
#include "framework/golden_section.hpp"
#include "framework/sampling.hpp"
#include "models/calibration/evidence.hpp"
#include "models/calibration/oven_run.hpp"
#include "plugins/common/holdout.hpp"
#include "plugins/ga/ga.hpp"
#include "plugins/ga/ga_plugin.hpp"
#include "plugins/polynomial/polynomial.hpp"
#include "plugins/rbf/rbf.hpp"
#include "plugins/tuning/tuning.hpp"

namespace driftlab::calibration {
namespace {

constexpr int kScaleFactorOrder = 2;       // k_0 + k_1 dT + k_2 dT^2
constexpr double kVaryingTrueRate = 1e-3;  // rad/s: a true rate with a larger std drives a scale-factor fit
constexpr double kSaturatedBranch = 1e-6;  // of the branch state's +-1 (hysteresis_state_range)

// How the RBF network on the physical residual is tuned (add_rbf): the shared tuning loop
// (plugins/tuning search(), optimizer/ga with --ga-population, --ga-generations and --seed) on a
// blocked holdout of the bins, over these ranges.
struct RbfTuning {
  double holdout_fraction = 0.2;                                          // share of the bins held out
  std::size_t holdout_blocks = 10;                                        // contiguous held-out runs
  Bound sigma{"sigma", 0.1, 3.0, false};                                  // kernel width, in standardized input units
  Bound log10_regularization{"log10_regularization", -8.0, -1.0, false};  // ridge penalty, decades
  Bound centres{"centres", 3.0, 40.0, true};  // the upper end also at most a quarter of the training bins
  std::size_t kmeans_sample = 2000;           // rows the k-means of the centres sees at most
};
const RbfTuning kRbfTuning;

// Per-bin means of the causal features for one (lag, width) candidate.
struct Features {
  Eigen::VectorXd tm, d, s;
  Eigen::MatrixXd w_powers;  // true rate x (Tm - T0)^j, j = 0..kScaleFactorOrder (unscaled)
};

Features features(const Record& r, const Binning& b, double lag_s, double deriv_s, double width_k, double t0,
                  bool with_w) {
  Features f;
  f.tm = Eigen::VectorXd::Zero(b.bins);
  f.d = Eigen::VectorXd::Zero(b.bins);
  f.s = Eigen::VectorXd::Zero(b.bins);
  if (with_w) f.w_powers = Eigen::MatrixXd::Zero(b.bins, kScaleFactorOrder + 1);
  CausalState state(lag_s, deriv_s, width_k);
  for (Eigen::Index i = 0; i < r.time_s.size(); ++i) {
    state.step(r.time_s[i], r.temp_c[i]);
    const int k = b.bin_of[static_cast<std::size_t>(i)];
    const double tm = state.model_temp_c();
    f.tm[k] += tm;
    f.d[k] += state.temp_rate_k_s();
    f.s[k] += state.hysteresis_state();
    if (with_w) {
      double p = r.true_rate_rad_s.size() ? r.true_rate_rad_s[i] : 0.0;
      for (int j = 0; j <= kScaleFactorOrder; ++j) {
        f.w_powers(k, j) += p;
        p *= tm - t0;
      }
    }
  }
  const Eigen::Map<const Eigen::VectorXd> n(b.count.data(), b.bins);
  f.tm.array() /= n.array();
  f.d.array() /= n.array();
  f.s.array() /= n.array();
  if (with_w) f.w_powers.array().colwise() /= n.array();
  return f;
}

struct Candidate {
  double lag_s = 0.0, width_k = 0.0;
  bool rate_term = false;
  int order = 1;
  double cv = std::numeric_limits<double>::infinity();
};

// All records' bins stacked: the rows kept (heating-only mask) and where each record's rows end.
struct Stack {
  std::vector<Eigen::Index> rows;  // kept rows into the stacked bins
  std::vector<Eigen::Index> group_ends;
};

Eigen::VectorXd stacked(const std::vector<Features>& fs, Eigen::VectorXd Features::*member) {
  Eigen::Index n = 0;
  for (const auto& f : fs) n += (f.*member).size();
  Eigen::VectorXd out(n);
  Eigen::Index at = 0;
  for (const auto& f : fs) {
    out.segment(at, (f.*member).size()) = f.*member;
    at += (f.*member).size();
  }
  return out;
}

struct Design {
  Eigen::MatrixXd A;
  double scale = 1.0;  // temperature scale of the polynomial columns, K
  int order = 0;
  bool rate_term = false, hysteresis = false;
  int sf_columns = 0;
};

Design design(const std::vector<Features>& fs, const std::vector<Eigen::Index>& rows, double t0, int order,
              bool rate_term, bool hysteresis, bool with_sf) {
  const Eigen::VectorXd tm_all = stacked(fs, &Features::tm);
  const Eigen::VectorXd d_all = stacked(fs, &Features::d);
  const Eigen::VectorXd s_all = stacked(fs, &Features::s);
  const Eigen::VectorXd tm = tm_all(rows);
  Design out;
  out.order = order;
  out.rate_term = rate_term;
  out.hysteresis = hysteresis;
  out.scale = std::max({std::abs(tm.maxCoeff() - t0), std::abs(tm.minCoeff() - t0), 1.0});
  const Eigen::MatrixXd V = polynomial::scaled_powers(tm, t0, out.scale, order);
  const int extra = (rate_term ? 1 : 0) + (hysteresis ? 1 : 0) + (with_sf ? kScaleFactorOrder + 1 : 0);
  out.A.resize(static_cast<Eigen::Index>(rows.size()), order + 1 + extra);
  out.A.leftCols(order + 1) = V;
  int c = order + 1;
  if (rate_term) out.A.col(c++) = d_all(rows);
  if (hysteresis) out.A.col(c++) = s_all(rows);
  if (with_sf) {
    Eigen::Index n = 0;
    for (const auto& f : fs) n += f.w_powers.rows();
    Eigen::MatrixXd W(n, kScaleFactorOrder + 1);
    Eigen::Index at = 0;
    for (const auto& f : fs) {
      W.middleRows(at, f.w_powers.rows()) = f.w_powers;
      at += f.w_powers.rows();
    }
    for (int j = 0; j <= kScaleFactorOrder; ++j) {
      out.A.col(c++) = W(rows, Eigen::all).col(j) / std::pow(out.scale, j);
    }
    out.sf_columns = kScaleFactorOrder + 1;
  }
  return out;
}

// What the oven runs can determine (oven_run.hpp's limits): which history terms may be fitted at all.
struct Determinable {
  bool rate_and_hysteresis = false;  // span >= kMinHistorySpanK and both directions
  double max_lag_s = 0.0;            // the longest soak (0: no lag term)
  std::string why_not;               // what is missing, for the selection text
};

Determinable determinable(const std::vector<OvenRun>& runs) {
  const RunsSummary all = summarize(runs);
  const bool span = all.span_k() >= kMinHistorySpanK;
  Determinable d;
  d.rate_and_hysteresis = span && all.heating && all.cooling;
  d.max_lag_s = span ? all.longest_soak_s : 0.0;
  if (!span)
    d.why_not = "span below " + std::to_string(static_cast<int>(kMinHistorySpanK)) + " K: no history terms";
  else if (!(all.heating && all.cooling))
    d.why_not = "one direction: no dT/dt or hysteresis term";
  if (span && all.longest_soak_s < kMinSoakS)
    d.why_not += std::string(d.why_not.empty() ? "" : "; ") + "no soak: no lag term";
  return d;
}

// Significance and plausibility of a fitted candidate's history terms: each coefficient beyond
// kSignificanceSigmas standard errors, and no larger than the bias swing of the bins it explains
// (a dT/dt term over the largest |dT/dt| of the bins; a hysteresis term over its +-1 state).
constexpr double kSignificanceSigmas = 3.0;
// A richer model is kept only when it lowers the held-out error of the simpler one by this fraction.
constexpr double kTransferMargin = 0.1;

double lag1_inflation(const Eigen::VectorXd& r) {
  if (r.size() < 3) return 1.0;
  const double num = r.head(r.size() - 1).dot(r.tail(r.size() - 1));
  const double den = r.squaredNorm();
  const double rho = den > 0 ? std::clamp(num / den, 0.0, 0.99) : 0.0;
  return std::sqrt((1.0 + rho) / (1.0 - rho));
}

// Pooled RMSE of each held-out group predicted by the fit on the other groups, with the model's
// extrapolation policy applied to held-out rows whose model temperature lies outside the training
// rows' range (as the compensator will apply it): the polynomial columns are evaluated at the
// nearest edge (clamp), continued along their tangent there (linear) or as they are (evaluate).
double policy_cv_rmse(const Design& dz, const Eigen::VectorXd& tm, const Eigen::VectorXd& y,
                      const std::vector<int>& groups, double t0, Extrapolation policy) {
  const int count = *std::max_element(groups.begin(), groups.end()) + 1;
  double ss = 0.0;
  for (int k = 0; k < count; ++k) {
    std::vector<Eigen::Index> train, test;
    for (std::size_t i = 0; i < groups.size(); ++i)
      (groups[i] == k ? test : train).push_back(static_cast<Eigen::Index>(i));
    if (train.empty() || test.empty()) continue;
    polynomial::LinearFit lf;
    try {
      lf = polynomial::least_squares(dz.A(train, Eigen::all), y(train));
    } catch (const std::invalid_argument&) {
      return std::numeric_limits<double>::infinity();
    }
    const double lo = tm(train).minCoeff(), hi = tm(train).maxCoeff();
    Eigen::MatrixXd At = dz.A(test, Eigen::all);
    if (policy != Extrapolation::Evaluate) {
      for (Eigen::Index r = 0; r < At.rows(); ++r) {
        const double x = tm[test[static_cast<std::size_t>(r)]];
        if (x >= lo && x <= hi) continue;
        const double edge = std::clamp(x, lo, hi), u = (edge - t0) / dz.scale, du = (x - edge) / dz.scale;
        double power = 1.0;  // u^i at the edge
        for (int i = 0; i <= dz.order; ++i) {
          At(r, i) = power + (policy == Extrapolation::Linear && i > 0 ? i * std::pow(u, i - 1) * du : 0.0);
          power *= u;
        }
      }
    }
    ss += (y(test) - At * lf.coefficients).squaredNorm();
  }
  return std::sqrt(ss / static_cast<double>(y.size()));
}

// "" when the history terms of the fit are significant and plausible, else why not.
// Standard errors: the larger of the least-squares ones (inflated for lag-1 correlation) and the
// delete-one-group jackknife over the held-out groups (legs or time blocks).
std::string implausible(const Design& dz, const polynomial::LinearFit& lf, const Eigen::VectorXd& y,
                        const Eigen::VectorXd& d_rows, const std::vector<int>& groups) {
  const double inflate = lag1_inflation(y - dz.A * lf.coefficients);
  const Eigen::VectorXd jackknife = polynomial::jackknife_standard_errors(dz.A, y, groups);
  const double swing = y.maxCoeff() - y.minCoeff();
  Eigen::Index c = dz.order + 1;
  const auto significant = [&](Eigen::Index k) {
    return std::abs(lf.coefficients[k]) > kSignificanceSigmas * std::max(inflate * lf.standard_errors[k], jackknife[k]);
  };
  if (dz.rate_term) {
    if (!significant(c)) return "dT/dt term within 3 sigma of 0";
    if (std::abs(lf.coefficients[c]) * d_rows.cwiseAbs().maxCoeff() > swing)
      return "dT/dt term larger than the bias swing";
    ++c;
  }
  if (dz.hysteresis) {
    if (!significant(c)) return "hysteresis within 3 sigma of 0";
    if (2.0 * std::abs(lf.coefficients[c]) > swing) return "hysteresis larger than the bias swing";
  }
  return "";
}

// One calibration fit, step by step, on the records' bins stacked once (the rows kept: all, or the
// heating ones).
class Fitter {
 public:
  Fitter(const std::vector<Record>& records, const FitOptions& o) : records_(records), o_(o), t0_(o.reference_temp_c) {
    check_records();
    stack_bins();
    assess_runs();
    choose_holdout_designs();
  }

  // The best candidate of the grid (order, lag, width, dT/dt term) by held-out error, and the best
  // one without history terms.
  std::pair<Candidate, Candidate> search() {
    // Candidates whose history terms the runs cannot determine are not scored; a scored candidate
    // with history terms is kept only when they are significant and plausible (implausible()).
    lags_ = {0.0};
    widths_ = {0.0};
    std::vector<bool> rate_terms{false};
    if (physical()) {
      for (double lag : o_.lag_grid_s)
        if (lag > 0 && lag <= can_.max_lag_s) lags_.push_back(lag);
      if (can_.rate_and_hysteresis) {
        for (double w : o_.hysteresis_width_grid_k)
          if (w > 0) widths_.push_back(w);
        rate_terms.push_back(true);
      }
    }
    Candidate best, simple;
    std::size_t done = 0;
    const std::size_t total = lags_.size() * widths_.size();
    for (double lag : lags_) {
      for (double width : widths_) {
        const auto fs = features_for(lag, width);
        for (bool rate_term : rate_terms) {
          for (int p = o_.min_order; p <= o_.max_order; ++p) {
            const Design dz = design(fs, st_.rows, t0_, p, rate_term, width > 0, with_sf_);
            const double cv = cv_of(dz);
            const Candidate c{lag, width, rate_term, p, cv};
            if (lag == 0 && width == 0 && !rate_term && cv < simple.cv) simple = c;
            if (cv < best.cv && admissible(fs, dz)) best = c;
          }
        }
        o_.progress(physical() ? "calibrate: physical model search" : "calibrate: polynomial order",
                    double(++done) / total);
      }
    }
    if (!std::isfinite(best.cv))
      throw DataError({records_.front().name, 0, "rate"}, "no candidate model could be fitted");
    return {best, simple};
  }

  // The best cell's lag and width refined between their grid neighbours (golden section).
  void refine(Candidate& best) const {
    if (!physical()) return;
    const auto cv_at = [&](double lag, double width) {
      const auto fs = features_for(lag, width);
      const Design d = design(fs, st_.rows, t0_, best.order, best.rate_term, width > 0, with_sf_);
      return admissible(fs, d) ? cv_of(d) : std::numeric_limits<double>::infinity();
    };
    const auto refined = [&](const std::vector<double>& grid, double value, double upper,
                             const std::function<double(double)>& cv) {
      if (!(value > 0) || o_.refine_iterations <= 0) return value;
      std::vector<double> sorted = grid;
      std::sort(sorted.begin(), sorted.end());
      const auto at = std::find(sorted.begin(), sorted.end(), value);
      if (at == sorted.end()) return value;
      const double lo = at == sorted.begin() || *std::prev(at) <= 0 ? value / 2 : *std::prev(at);
      const double hi = std::min(upper, std::next(at) == sorted.end() ? value : *std::next(at));
      const auto m = golden_section_minimize([&](double u) { return cv(std::exp(u)); }, std::log(lo), std::log(hi),
                                             o_.refine_iterations);
      if (m.value < best.cv) {
        best.cv = m.value;
        return std::exp(m.x);
      }
      return value;
    };
    o_.progress("calibrate: refining lag and hysteresis width", 0.0);
    best.lag_s = refined(lags_, best.lag_s, can_.max_lag_s, [&](double lag) { return cv_at(lag, best.width_k); });
    best.width_k = refined(widths_, best.width_k, INFINITY, [&](double width) { return cv_at(best.lag_s, width); });
    o_.progress("calibrate: refining lag and hysteresis width", 1.0);
  }

  // Never worse than the simple model: history terms stay only when they lower the held-out error
  // by the margin, on time blocks and on what transfers (whole runs or legs). Returns why the simple
  // model was kept instead ("" when it was not).
  std::string keep_history_only_if_it_transfers(Candidate& best, const Candidate& simple) const {
    const auto has_history = [](const Candidate& c) { return c.lag_s > 0 || c.width_k > 0 || c.rate_term; };
    std::string why;
    if (has_history(best) && !(best.cv < (1.0 - kTransferMargin) * simple.cv)) {
      why = "history terms lowered the held-out error by less than " +
            std::to_string(static_cast<int>(100 * kTransferMargin)) + " % (" + std::to_string(best.cv) + " vs " +
            std::to_string(simple.cv) + "): polynomial kept";
      best = simple;
    }
    if (has_history(best) && !transfer_.empty()) {
      const auto transfer_cv = [&](const Candidate& c) {
        const auto fs = features_for(c.lag_s, c.width_k);
        return policy_cv_rmse(design(fs, st_.rows, t0_, c.order, c.rate_term, c.width_k > 0, with_sf_),
                              stacked(fs, &Features::tm)(st_.rows), y_, transfer_, t0_, o_.extrapolation);
      };
      const double rich = transfer_cv(best), plain = transfer_cv(simple);
      if (!(rich < (1.0 - kTransferMargin) * plain)) {
        why = "history terms did not transfer to held-out whole runs/legs (" + std::to_string(rich) + " vs " +
              std::to_string(plain) + "): polynomial kept";
        best = simple;
      }
    }
    return why;
  }

  // The chosen candidate's final linear fit on every kept bin, as a model with its fit summary;
  // `residual` receives the bins' residuals.
  CalibrationModel linear_model(const Candidate& best, const std::string& chosen_why, Eigen::VectorXd& residual) {
    const auto fs = features_for(best.lag_s, best.width_k);
    const Design dz = design(fs, st_.rows, t0_, best.order, best.rate_term, best.width_k > 0, with_sf_);
    polynomial::LinearFit lf;
    try {
      lf = polynomial::least_squares(dz.A, y_);
    } catch (const std::invalid_argument& e) {
      throw DataError({records_.front().name, 0, "rate"}, std::string("least-squares fit failed: ") + e.what());
    }
    residual = y_ - dz.A * lf.coefficients;
    const double inflate = lag1_inflation(residual);

    CalibrationModel m;
    m.kind = o_.kind;
    m.reference_temp_c = t0_;
    m.extrapolation = o_.extrapolation;
    tm_ = stacked(fs, &Features::tm)(st_.rows);
    d_ = stacked(fs, &Features::d)(st_.rows);
    s_ = stacked(fs, &Features::s)(st_.rows);
    m.valid_min_c = tm_.minCoeff();  // the range the fitted bins cover
    m.valid_max_c = tm_.maxCoeff();
    double si = 1.0;
    int c = 0;
    for (int i = 0; i <= best.order; ++i, ++c) {
      m.bias_rad_s.push_back(lf.coefficients[c] / si);
      m.bias_sigma_rad_s.push_back(inflate * lf.standard_errors[c] / si);
      si *= dz.scale;
    }
    m.lag_tau_s = best.lag_s;
    m.derivative_tau_s = o_.derivative_tau_s;
    if (best.rate_term) {
      m.temperature_rate_rad_s_per_k_s = lf.coefficients[c];
      m.temperature_rate_sigma = inflate * lf.standard_errors[c];
      m.temperature_rate_range_k_s = InputRange{d_.minCoeff(), d_.maxCoeff()};  // what the fitted bins cover
      ++c;
    }
    if (best.width_k > 0) {
      m.hysteresis_width_k = best.width_k;
      m.hysteresis_rad_s = lf.coefficients[c];
      m.hysteresis_sigma_rad_s = inflate * lf.standard_errors[c];
      // The state saturates at +-1 exponentially: a bin mean within kSaturatedBranch of it saw the
      // saturated branch, whose samples reach +-1 itself.
      const auto saturated = [](double edge) { return std::abs(std::abs(edge) - 1.0) <= kSaturatedBranch; };
      m.hysteresis_state_range =
          InputRange{saturated(s_.minCoeff()) ? -1.0 : s_.minCoeff(), saturated(s_.maxCoeff()) ? 1.0 : s_.maxCoeff()};
      ++c;
    }
    if (with_sf_) {
      for (int j = 0; j <= kScaleFactorOrder; ++j, ++c)
        m.scale_factor_per_k.push_back(lf.coefficients[c] / std::pow(dz.scale, j));
    }

    m.fit.bin_s = o_.bin_s;
    m.fit.holdout_blocks = o_.holdout_blocks;
    m.fit.holdout_rms_rad_s = best.cv;
    m.fit.train_rms_rad_s = lf.rms_residual;
    m.fit.heating_only = o_.heating_only;
    m.fit.scale_factor_fitted = with_sf_;
    for (const auto& r : records_) {
      m.fit.records.push_back(r.name);
      m.fit.samples += static_cast<std::size_t>(r.time_s.size());
    }
    m.fit.holdout_design = holdout_design_;
    m.fit.uncompensated_rms_rad_s = std::sqrt(y_.squaredNorm() / static_cast<double>(y_.size()));
    m.fit.selection =
        "order " + std::string(physical() ? "and history terms (lag_tau_s, dT/dt, hysteresis width) " : "") +
        "by held-out error over orders " + std::to_string(o_.min_order) + ".." + std::to_string(o_.max_order);
    if (physical() && !can_.why_not.empty()) m.fit.selection += "; " + can_.why_not;
    if (!rejected_.empty()) {
      m.fit.selection += "; candidates rejected:";
      for (const auto& r : rejected_) m.fit.selection += " " + r + (&r == &rejected_.back() ? "" : ",");
    }
    if (!chosen_why.empty()) m.fit.selection += "; " + chosen_why;
    if (physical() && !m.uses_state()) m.kind = ModelKind::Polynomial;
    return m;
  }

  // An RBF network of (model temperature, dT/dt, branch state) on the linear model's residual,
  // GA-tuned on blocked held-out bins; kept only when it lowers their error by the margin.
  void add_rbf(CalibrationModel& m, const Eigen::VectorXd& residual) const {
    if (!can_.rate_and_hysteresis) {
      m.fit.selection += "; no RBF network (its inputs dT/dt and branch state need both directions and the span)";
      return;
    }
    Eigen::MatrixXd X(y_.size(), 3);
    X.col(0) = tm_.cwiseMax(m.valid_min_c).cwiseMin(m.valid_max_c);
    X.col(1) = d_;
    X.col(2) = s_;
    tuning::Settings settings;
    settings.plugin = "calibrate: RBF tuning";
    settings.holdout_fraction = kRbfTuning.holdout_fraction;
    settings.holdout_blocks = kRbfTuning.holdout_blocks;
    settings.max_samples = 0;  // every bin
    settings.seed = o_.seed;
    const tuning::Split split = tuning::split(X, residual, settings);
    rbf::Config base;
    base.seed = o_.seed;
    base.kmeans_sample = kRbfTuning.kmeans_sample;
    const auto decode = [&](const Eigen::VectorXd& v) {
      rbf::Config cfg = base;
      cfg.sigma = v[0];
      cfg.regularization = std::pow(10.0, v[1]);
      cfg.centres = static_cast<std::size_t>(std::llround(v[2]));
      return cfg;
    };
    std::size_t evals = 0;
    const std::size_t expected = o_.ga_population * (o_.ga_generations + 1);
    const auto counted = [&] { o_.progress("calibrate: RBF tuning (GA)", std::min(1.0, double(++evals) / expected)); };
    const auto fit_and_score = [&](const tuning::Split& d, const Eigen::VectorXd& v) {
      tuning::Score score;
      try {
        score.holdout_prediction = rbf::fit(d.X_train, d.y_train, decode(v)).network.predict(d.X_holdout);
      } catch (...) {
        counted();
        throw;
      }
      counted();
      return score;
    };
    ga::Config gc;
    gc.population = o_.ga_population;
    gc.generations = o_.ga_generations;
    gc.seed = o_.seed;
    const auto optimizer = make_ga_optimizer(gc);
    RunContext ctx;
    ctx.seed = o_.seed;
    ctx.threads = 1;  // one thread: the progress counter is not thread safe, and fits are seconds
    Bound centres = kRbfTuning.centres;
    centres.upper =
        std::max(centres.lower, std::min<double>(centres.upper, static_cast<double>(split.X_train.rows()) / 4.0));
    double best_value = std::numeric_limits<double>::infinity();
    Eigen::VectorXd best;
    std::string search_notes;  // "; GA: ..." when the search ended at a bound or did not improve
    try {
      const std::vector<Bound> bounds{kRbfTuning.sigma, kRbfTuning.log10_regularization, centres};
      auto found = tuning::search(*optimizer, bounds, settings, split, fit_and_score, ctx);
      for (const auto& note : tuning::search_notes(found.result, bounds))
        search_notes += (search_notes.empty() ? "; GA tuning: " : "; ") + note;
      best_value = found.result.best_value;
      best = std::move(found.result.best);
    } catch (const DataError&) {  // no candidate gave a finite held-out error: no network
    }
    const Eigen::VectorXd& rh = split.y_holdout;
    const double no_rbf = holdout::rmse(Eigen::VectorXd::Zero(rh.size()), rh);
    if (std::isfinite(best_value) && best_value < (1.0 - kTransferMargin) * no_rbf) {
      const auto net = rbf::fit(X, residual, decode(best)).network;
      RbfTerm t;
      for (int k = 0; k < 3; ++k) {
        t.mean.push_back(net.mean()[k]);
        t.scale.push_back(net.scale()[k]);
        t.input_min.push_back(X.col(k).minCoeff());
        t.input_max.push_back(X.col(k).maxCoeff());
      }
      t.centres = net.centres();
      t.sigma = net.sigma();
      t.weights_rad_s.assign(net.weights().data(), net.weights().data() + net.weights().size());
      t.bias_rad_s = net.bias();
      m.rbf = std::move(t);
      m.kind = ModelKind::Rbf;
      m.fit.selection += "; RBF on the physical residual, GA-tuned (holdout RMSE " + std::to_string(best_value) +
                         " vs " + std::to_string(no_rbf) + " rad/s without it)" + search_notes;
    } else {
      m.fit.selection += "; no RBF network: it did not lower the held-out residual (" + std::to_string(no_rbf) +
                         " rad/s) by " + std::to_string(static_cast<int>(100 * kTransferMargin)) + " %";
    }
  }

  // Allan noise terms of the compensated calibration residual (first record), for the Kalman stage
  // and the Kalibr export.
  void add_noise_terms(CalibrationModel& m) const {
    const Record& r = records_.front();
    const auto out = compensate(m, r.time_s, r.rate_rad_s, r.temp_c);
    const Eigen::VectorXd err =
        r.true_rate_rad_s.size() ? Eigen::VectorXd(out.rate_rad_s - r.true_rate_rad_s) : out.rate_rad_s;
    // The rate while it samples: a gap in the record (a 1e9-s pause) must not lower it (issue 28).
    const double rate_hz = sampling::rate_within_segments_hz(r.time_s, sampling::facts_of(r.time_s));
    o_.progress("calibrate: Allan noise terms", 0.0);
    if (const auto n = fit_noise(err, rate_hz)) {
      m.noise = {n->arw_rad_sqrt_s, n->bias_instability_rad_s, n->rate_random_walk_rad_s_sqrt_s, rate_hz,
                 n->arw_upper,      n->bias_instability_upper, n->rate_random_walk_upper};
    }
    o_.progress("calibrate: Allan noise terms", 1.0);
  }

 private:
  bool physical() const { return o_.kind != ModelKind::Polynomial; }

  void check_records() {
    for (const auto& r : records_) {
      if (r.time_s.size() != r.rate_rad_s.size() || r.time_s.size() != r.temp_c.size()) {
        throw DataError({r.name, 0, "rate"}, "time, rate and temperature differ in length");
      }
      if (r.true_rate_rad_s.size() && r.true_rate_rad_s.size() != r.time_s.size()) {
        throw DataError({r.name, 0, "true_rate"}, "true rate differs in length");
      }
      if (r.true_rate_rad_s.size() > 1) {
        const double mean = r.true_rate_rad_s.mean();
        const double sd = std::sqrt((r.true_rate_rad_s.array() - mean).square().mean());
        if (sd > kVaryingTrueRate) with_sf_ = true;
      }
    }
  }

  // Bins, targets and the heating mask (from the dT/dt estimate without lag).
  void stack_bins() {
    std::vector<double> y_all;
    Eigen::Index offset = 0;
    for (const auto& r : records_) {
      bins_.push_back(make_bins(r.time_s, o_.bin_s));
      const Binning& b = bins_.back();
      if (static_cast<std::size_t>(b.bins) < 2 * o_.holdout_blocks) {
        throw DataError({r.name, 0, "t_s"}, "record too short: " + std::to_string(b.bins) + " bins of " +
                                                std::to_string(o_.bin_s) + " s for " +
                                                std::to_string(o_.holdout_blocks) +
                                                " held-out blocks (need at least two bins per block)");
      }
      std::vector<double> y(static_cast<std::size_t>(b.bins), 0.0);
      for (Eigen::Index i = 0; i < r.time_s.size(); ++i) {
        const double w = r.true_rate_rad_s.size() ? r.true_rate_rad_s[i] : 0.0;
        y[static_cast<std::size_t>(b.bin_of[static_cast<std::size_t>(i)])] +=
            r.rate_rad_s[i] - w;  // rate - true = sf_dev w + bias
      }
      const Features f0 = features(r, b, 0.0, o_.derivative_tau_s, 0.0, t0_, false);
      for (int k = 0; k < b.bins; ++k) {
        y_all.push_back(y[static_cast<std::size_t>(k)] / b.count[static_cast<std::size_t>(k)]);
        if (!o_.heating_only || f0.d[k] > 0) st_.rows.push_back(offset + k);
      }
      offset += b.bins;
      st_.group_ends.push_back(static_cast<Eigen::Index>(st_.rows.size()));
    }
    const Eigen::VectorXd y_stack =
        Eigen::Map<const Eigen::VectorXd>(y_all.data(), static_cast<Eigen::Index>(y_all.size()));
    y_ = y_stack(st_.rows);
    if (static_cast<std::size_t>(y_.size()) < 2 * o_.holdout_blocks * records_.size()) {
      throw DataError({records_.front().name, 0, "temperature"},
                      o_.heating_only ? "too few heating bins to fit (dT/dt > 0)" : "too few bins to fit");
    }
  }

  // What the runs determine; a run the quality gate refuses is a DataError.
  void assess_runs() {
    for (std::size_t i = 0; i < records_.size(); ++i)
      runs_.push_back(analyse_oven_run(records_[i].name, records_[i].time_s, records_[i].temp_c, o_.bin_s));
    for (const auto& f : quality_gate(runs_))
      if (f.severity == Finding::Severity::Error) throw DataError({records_.front().name, 0, "temperature"}, f.message);
    can_ = determinable(runs_);
  }

  // Two hold-out designs. Orders and history terms are searched on contiguous time blocks of each
  // record (noise inside the range the final fit covers, so scored as evaluated). History terms
  // are then kept only when they also lower the error on what transfers: whole runs when there
  // are several records, else whole legs when the record has at least two legs of every
  // direction it holds (so each fold still holds that direction), with the extrapolation policy.
  void choose_holdout_designs() {
    try {
      blocks_ = polynomial::block_labels(y_.size(), o_.holdout_blocks, st_.group_ends);
    } catch (const std::invalid_argument& e) {
      throw DataError({records_.front().name, 0, "t_s"}, e.what());
    }
    holdout_design_ = std::to_string(o_.holdout_blocks) + " contiguous time blocks per record";
    if (records_.size() >= 2) {
      for (std::size_t i = 0, at = 0; i < records_.size(); ++i)
        for (; at < static_cast<std::size_t>(st_.group_ends[i]); ++at) transfer_.push_back(static_cast<int>(i));
      holdout_design_ +=
          "; history terms also on whole runs (leave-one-run-out over " + std::to_string(records_.size()) + " records)";
      return;
    }
    int heating_legs = 0, cooling_legs = 0, legs = 0;
    for (const auto& l : runs_.front().legs) {
      heating_legs += l.direction > 0;
      cooling_legs += l.direction < 0;
      ++legs;
    }
    if (legs >= 3 && heating_legs != 1 && cooling_legs != 1) {
      std::vector<int> leg_of_bin;
      std::size_t leg = 0;
      for (const Eigen::Index first : bins_.front().first) {
        while (leg + 1 < runs_.front().legs.size() && records_.front().time_s[first] > runs_.front().legs[leg].end_s)
          ++leg;
        leg_of_bin.push_back(static_cast<int>(leg));
      }
      for (const auto row : st_.rows) transfer_.push_back(leg_of_bin[static_cast<std::size_t>(row)]);
      holdout_design_ += "; history terms also on whole legs (leave-one-leg-out over " + std::to_string(legs) +
                         " legs: " + std::to_string(heating_legs) + " heating, " + std::to_string(cooling_legs) +
                         " cooling)";
    } else {
      holdout_design_ += " (one record with fewer than two legs of a direction: whole legs cannot be held out)";
    }
  }

  std::vector<Features> features_for(double lag, double width) const {
    std::vector<Features> fs;
    for (std::size_t i = 0; i < records_.size(); ++i)
      fs.push_back(features(records_[i], bins_[i], lag, o_.derivative_tau_s, width, t0_, with_sf_));
    return fs;
  }

  double cv_of(const Design& dz) const {
    try {
      return polynomial::labelled_cv_rmse(dz.A, y_, blocks_);
    } catch (const std::invalid_argument&) {
      return std::numeric_limits<double>::infinity();
    }
  }

  // True when the candidate has no history terms or they are significant and plausible; records why not.
  bool admissible(const std::vector<Features>& fs, const Design& dz) const {
    if (!dz.rate_term && !dz.hysteresis) return true;
    try {
      const auto why =
          implausible(dz, polynomial::least_squares(dz.A, y_), y_, stacked(fs, &Features::d)(st_.rows), blocks_);
      if (!why.empty() && std::find(rejected_.begin(), rejected_.end(), why) == rejected_.end())
        rejected_.push_back(why);
      return why.empty();
    } catch (const std::invalid_argument&) {
      return false;
    }
  }

  const std::vector<Record>& records_;
  const FitOptions& o_;
  const double t0_;
  bool with_sf_ = false;
  std::vector<Binning> bins_;
  Stack st_;
  Eigen::VectorXd y_;
  std::vector<OvenRun> runs_;
  Determinable can_;
  std::vector<int> blocks_, transfer_;
  std::string holdout_design_;
  std::vector<double> lags_, widths_;
  mutable std::vector<std::string> rejected_;
  Eigen::VectorXd tm_, d_, s_;  // the final candidate's features of the kept bins
};

}  // namespace

Record slice(const Record& r, double from_s, double to_s) {
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < r.time_s.size(); ++i) {
    if (r.time_s[i] >= from_s && r.time_s[i] < to_s) rows.push_back(i);
  }
  Record out;
  out.name = r.name;
  out.time_s = r.time_s(rows);
  out.rate_rad_s = r.rate_rad_s(rows);
  out.temp_c = r.temp_c(rows);
  if (r.true_rate_rad_s.size()) out.true_rate_rad_s = r.true_rate_rad_s(rows);
  if (r.systematic_rad_s.size()) out.systematic_rad_s = r.systematic_rad_s(rows);
  return out;
}

CalibrationModel fit_calibration(const std::vector<Record>& records, const FitOptions& o) {
  if (records.empty()) throw ConfigError({"", 0, "data"}, "no calibration records");
  if (o.min_order < 0 || o.max_order < o.min_order || o.max_order > 12) {
    throw ConfigError({"", 0, "order"}, "polynomial orders need 0 <= min_order <= max_order <= 12");
  }
  if (!(o.bin_s > 0)) throw ConfigError({"", 0, "bin_s"}, "bin length must be > 0 s");
  if (!(o.derivative_tau_s > 0)) throw ConfigError({"", 0, "derivative_tau_s"}, "must be > 0 s");

  Fitter fitter(records, o);
  auto [best, simple] = fitter.search();
  fitter.refine(best);
  const std::string chosen_why = fitter.keep_history_only_if_it_transfers(best, simple);
  Eigen::VectorXd residual;
  CalibrationModel m = fitter.linear_model(best, chosen_why, residual);
  if (o.kind == ModelKind::Rbf) fitter.add_rbf(m, residual);
  try {  // the records' model must be physical (e.g. a rate that ignores a moving true rate gives sf 0)
    m.validate();
  } catch (const ConfigError& e) {
    const Diagnostic& first = e.problems().front();
    throw DataError({records.front().name, 0, first.where.field},
                    "the calibration records give a model that is not physical: " + first.message);
  }
  fitter.add_noise_terms(m);
  return m;
}

namespace {

FitOptions fixed_cubic(const FitOptions& base, bool heating_only) {
  FitOptions o = base;
  o.kind = ModelKind::Polynomial;
  o.min_order = o.max_order = 3;
  o.extrapolation = Extrapolation::Clamp;
  o.heating_only = heating_only;
  return o;
}

}  // namespace

CalibrationModel fit_px4_style(const std::vector<Record>& records, const FitOptions& base) {
  try {
    return fit_calibration(records, fixed_cubic(base, true));
  } catch (const DataError&) {
    return fit_cubic_all_bins(records, base);
  }
}

CalibrationModel fit_cubic_all_bins(const std::vector<Record>& records, const FitOptions& base) {
  return fit_calibration(records, fixed_cubic(base, false));
}

Disagreement largest_disagreement(const std::vector<Record>& records) {
  constexpr double kBinS = 60.0;
  constexpr int kOrder = 3;
  struct Curve {
    Eigen::VectorXd temp, bias, coefficients;
    double t0 = 0.0, scale = 1.0, residual_rms = 0.0, lo = 0.0, hi = 0.0;
    int order = 0;
  };
  std::vector<Curve> curves;
  for (const auto& r : records) {
    const Binning b = make_bins(r.time_s, kBinS);
    Curve c;
    c.temp = Eigen::VectorXd::Zero(b.bins);
    c.bias = Eigen::VectorXd::Zero(b.bins);
    for (Eigen::Index i = 0; i < r.time_s.size(); ++i) {
      const int k = b.bin_of[static_cast<std::size_t>(i)];
      c.temp[k] += r.temp_c[i];
      c.bias[k] += r.rate_rad_s[i] - (r.true_rate_rad_s.size() ? r.true_rate_rad_s[i] : 0.0);
    }
    const Eigen::Map<const Eigen::VectorXd> n(b.count.data(), b.bins);
    c.temp.array() /= n.array();
    c.bias.array() /= n.array();
    c.lo = c.temp.minCoeff();
    c.hi = c.temp.maxCoeff();
    c.t0 = 0.5 * (c.lo + c.hi);
    c.scale = std::max(0.5 * (c.hi - c.lo), 1e-3);
    c.order = std::clamp(static_cast<int>(b.bins) - 2, 0, kOrder);
    const Eigen::MatrixXd V = polynomial::scaled_powers(c.temp, c.t0, c.scale, c.order);
    try {
      c.coefficients = polynomial::least_squares(V, c.bias).coefficients;
    } catch (const std::invalid_argument&) {
      c.order = 0;
      c.coefficients = Eigen::VectorXd::Constant(1, c.bias.mean());
    }
    const Eigen::VectorXd fitted = polynomial::scaled_powers(c.temp, c.t0, c.scale, c.order) * c.coefficients;
    c.residual_rms = b.bins > 1 ? std::sqrt((c.bias - fitted).squaredNorm() / static_cast<double>(b.bins)) : 0.0;
    curves.push_back(std::move(c));
  }
  const auto evaluate = [](const Curve& c, const Eigen::VectorXd& t) -> Eigen::VectorXd {
    return polynomial::scaled_powers(t, c.t0, c.scale, c.order) * c.coefficients;
  };
  Disagreement worst;
  for (std::size_t a = 0; a < curves.size(); ++a) {
    for (std::size_t b = 0; b < curves.size(); ++b) {
      if (a == b) continue;
      const Curve &ca = curves[a], &cb = curves[b];
      std::vector<Eigen::Index> inside;
      for (Eigen::Index k = 0; k < cb.temp.size(); ++k)
        if (cb.temp[k] >= ca.lo && cb.temp[k] <= ca.hi) inside.push_back(k);
      double diff = 0.0;
      if (inside.size() >= 3) {
        const Eigen::VectorXd t = cb.temp(inside);
        diff = std::sqrt((evaluate(ca, t) - evaluate(cb, t)).squaredNorm() / static_cast<double>(inside.size()));
      } else {
        diff = std::abs(ca.bias.mean() - cb.bias.mean());
      }
      const double noise = std::max({ca.residual_rms, cb.residual_rms, std::numeric_limits<double>::min()});
      if (diff / noise > worst.ratio) worst = {diff / noise, diff, records[a].name, records[b].name};
    }
  }
  return worst;
}

}  // namespace driftlab::calibration
