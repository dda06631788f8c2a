#include "models/allan/gmwm.hpp"

#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <unsupported/Eigen/NonLinearOptimization>
#include <unsupported/Eigen/NumericalDiff>

#include "framework/error.hpp"
#include "framework/parallel.hpp"
#include "framework/seeded_random.hpp"
#include "models/allan/analysis.hpp"
#include "models/error_model/error_model.hpp"

namespace driftlab::allan::gmwm {
namespace {

constexpr int kReweightings = 3;
constexpr int kMaxFunctionEvaluations = 400;
constexpr double kResolvedLogSigma = 0.5;
constexpr double kLongestTimeFactor = 10.0;  // gm correlation times up to this x the longest tau
constexpr double kStartScale = 1e-2;
constexpr std::uint64_t kBootstrapStream = 0x474D574D00000000ULL;  // "GMWM"

struct Point {
  double m = 0.0, variance = 0.0, edf = 0.0;
};

int parameter_count(Process p) { return p == Process::GaussMarkov ? 2 : 1; }

int parameter_count(const std::vector<Process>& model) {
  int n = 0;
  for (const Process p : model) n += parameter_count(p);
  return n;
}

// The model's parameters in SI from the log vector u (log N^2 ...; gm: log sigma^2, log T).
std::vector<double> si_parameters(Process p, const double* u) {
  if (p == Process::GaussMarkov) return {std::exp(0.5 * u[0]), std::exp(u[1])};
  return {std::exp(0.5 * u[0])};
}

double model_variance(const std::vector<Process>& model, const Eigen::VectorXd& u, double m, double dt) {
  double sum = 0.0;
  int at = 0;
  for (const Process p : model) {
    const auto values = si_parameters(p, u.data() + at);
    sum += process_variance(p, values, m, dt);
    at += parameter_count(p);
  }
  return sum;
}

// Weighted residuals sqrt(w_j) (a_j - A_j(u)) with w_j = edf_j / (2 W_j^2), W_j the weighting
// variance (the data's at first, then the model's).
struct Residuals {
  using Scalar = double;
  enum { InputsAtCompileTime = Eigen::Dynamic, ValuesAtCompileTime = Eigen::Dynamic };
  using InputType = Eigen::VectorXd;
  using ValueType = Eigen::VectorXd;
  using JacobianType = Eigen::MatrixXd;

  const std::vector<Point>* points = nullptr;
  const std::vector<Process>* model = nullptr;
  std::vector<double> weighting;
  double dt = 1.0, log_t_min = 0.0, log_t_max = 0.0;

  int inputs() const { return parameter_count(*model); }
  int values() const { return static_cast<int>(points->size()); }

  int operator()(const Eigen::VectorXd& u, Eigen::VectorXd& r) const {
    Eigen::VectorXd bounded = bound(u);
    for (std::size_t j = 0; j < points->size(); ++j) {
      const Point& p = (*points)[j];
      const double a = model_variance(*model, bounded, p.m, dt);
      r[static_cast<Eigen::Index>(j)] = std::sqrt(p.edf / 2.0) * (p.variance - a) / weighting[j];
    }
    return 0;
  }

  // Gauss-Markov times limited to [dt, kLongestTimeFactor x longest tau]; the coefficients free.
  Eigen::VectorXd bound(Eigen::VectorXd u) const {
    int at = 0;
    for (const Process p : *model) {
      if (p == Process::GaussMarkov) u[at + 1] = std::clamp(u[at + 1], log_t_min, log_t_max);
      at += parameter_count(p);
    }
    return u;
  }
};

double objective(const Residuals& f, const Eigen::VectorXd& u) {
  Eigen::VectorXd r(f.values());
  f(u, r);
  return r.squaredNorm();
}

Eigen::VectorXd minimize(const Residuals& f, Eigen::VectorXd u) {
  Eigen::NumericalDiff<Residuals, Eigen::Central> diff(f);
  Eigen::LevenbergMarquardt<Eigen::NumericalDiff<Residuals, Eigen::Central>> lm(diff);
  lm.parameters.maxfev = kMaxFunctionEvaluations;
  lm.minimize(u);
  return f.bound(u);
}

// The starting points: each term's asymptote read off the curve; then each scaled down in turn.
std::vector<Eigen::VectorXd> starts(const std::vector<Process>& model, const std::vector<Point>& points, double dt) {
  const Point& first = points.front();
  const Point& last = points.back();
  const double tau1 = first.m * dt, tau_n = last.m * dt;
  std::vector<double> gm_times;
  int gms = 0;
  for (const Process p : model) gms += p == Process::GaussMarkov;
  for (int i = 0; i < gms; ++i)  // spread over the curve's taus in log space
    gm_times.push_back(tau1 * std::pow(tau_n / tau1, (i + 1.0) / (gms + 1.0)));
  Eigen::VectorXd base(parameter_count(model));
  int at = 0, gm = 0;
  for (const Process p : model) {
    switch (p) {
      case Process::WhiteNoise:
        base[at] = std::log(first.variance * tau1);
        break;
      case Process::Quantization:
        base[at] = std::log(first.variance * tau1 * tau1 / 3.0);
        break;
      case Process::RandomWalk:
        base[at] = std::log(3.0 * last.variance / tau_n);
        break;
      case Process::Drift:
        base[at] = std::log(2.0 * last.variance / (tau_n * tau_n));
        break;
      case Process::GaussMarkov: {
        const double t = gm_times[static_cast<std::size_t>(gm++)];
        // The Allan variance of a Gauss-Markov process peaks near tau = 1.9 T at about 0.2 sigma^2.
        const Point* near = &points.front();
        for (const Point& q : points)
          if (std::abs(std::log(q.m * dt / (1.9 * t))) < std::abs(std::log(near->m * dt / (1.9 * t)))) near = &q;
        base[at] = std::log(near->variance / 0.2);
        base[at + 1] = std::log(t);
        break;
      }
    }
    at += parameter_count(p);
  }
  std::vector<Eigen::VectorXd> out{base};
  at = 0;
  for (const Process p : model) {
    Eigen::VectorXd lower = base;
    lower[at] += std::log(kStartScale);
    out.push_back(lower);
    if (p == Process::GaussMarkov) {
      for (const double f : {0.25, 4.0}) {
        Eigen::VectorXd shifted = base;
        shifted[at + 1] += std::log(f);
        out.push_back(shifted);
      }
    }
    at += parameter_count(p);
  }
  return out;
}

}  // namespace

std::string to_string(Process p) {
  switch (p) {
    case Process::WhiteNoise:
      return "wn";
    case Process::Quantization:
      return "qn";
    case Process::RandomWalk:
      return "rw";
    case Process::Drift:
      return "dr";
    case Process::GaussMarkov:
      return "gm";
  }
  return "?";
}

std::vector<Process> parse_model(const std::string& text, const std::string& field) {
  const std::string expected =
      "expected processes joined by '+', from wn (white noise), qn (quantization), "
      "rw (rate random walk), dr (rate ramp), gm (Gauss-Markov, may repeat), e.g. wn+rw+gm";
  std::vector<Process> model;
  std::size_t from = 0;
  while (from <= text.size()) {
    const std::size_t plus = std::min(text.find('+', from), text.size());
    const std::string name = text.substr(from, plus - from);
    Process p{};
    bool known = false;
    for (const Process q :
         {Process::WhiteNoise, Process::Quantization, Process::RandomWalk, Process::Drift, Process::GaussMarkov})
      if (to_string(q) == name) {
        p = q;
        known = true;
      }
    if (!known) throw ConfigError({"", 0, field}, "unknown process '" + name + "' in '" + text + "'; " + expected);
    if (p != Process::GaussMarkov && std::find(model.begin(), model.end(), p) != model.end())
      throw ConfigError({"", 0, field}, "process '" + name + "' given twice in '" + text + "' (only gm may repeat)");
    model.push_back(p);
    from = plus + 1;
  }
  return model;
}

std::string to_string(const std::vector<Process>& model) {
  std::string s;
  for (const Process p : model) s += (s.empty() ? "" : "+") + to_string(p);
  return s;
}

double process_variance(Process p, std::span<const double> v, double m, double dt) {
  const double tau = m * dt;
  switch (p) {
    case Process::WhiteNoise:
      return v[0] * v[0] / tau;
    case Process::Quantization:
      return 3.0 * v[0] * v[0] / (tau * tau);
    case Process::RandomWalk:
      return v[0] * v[0] * (2.0 * tau * tau + dt * dt) / (6.0 * tau);
    case Process::Drift:
      return v[0] * v[0] * tau * tau / 2.0;
    case Process::GaussMarkov: {
      const double s2 = v[0] * v[0], phi = std::exp(-dt / v[1]);
      const double one = 1.0 - phi, phi_m = std::pow(phi, m);
      const double block = s2 * (m * (1.0 + phi) / one - 2.0 * phi * (1.0 - phi_m) / (one * one));
      const double adjacent = s2 * phi * (1.0 - phi_m) * (1.0 - phi_m) / (one * one);
      return (block - adjacent) / (m * m);
    }
  }
  return 0.0;
}

double Fit::model_variance(double tau_s) const {
  const double dt = 1.0 / sample_rate_hz;
  double sum = 0.0;
  for (const auto& c : components) {
    std::vector<double> v;
    for (const auto& p : c.parameters) v.push_back(p.value);
    sum += process_variance(c.process, v, tau_s / dt, dt);
  }
  return sum;
}

Fit fit(std::span<const Estimate> curve, double sample_rate_hz, const std::vector<Process>& model) {
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz))
    throw ConfigError({"", 0, "fs"}, "GMWM needs a positive sample rate");
  if (model.empty()) throw ConfigError({"", 0, "gmwm"}, "GMWM needs a model (e.g. wn+rw+gm)");
  const double dt = 1.0 / sample_rate_hz;
  std::vector<Point> points;
  for (const auto& e : curve)
    if (e.dev > 0.0 && e.edf > 0.0 && std::isfinite(e.dev) && std::isfinite(e.edf))
      points.push_back({e.tau / dt, e.dev * e.dev, e.edf});
  const int n = parameter_count(model);
  if (static_cast<int>(points.size()) < n + 1)
    throw DataError({"", 0, "gmwm"}, "GMWM model " + to_string(model) + " has " + std::to_string(n) +
                                         " parameters and the Allan curve only " + std::to_string(points.size()) +
                                         " usable points; a longer record or a smaller model is needed");

  Residuals f;
  f.points = &points;
  f.model = &model;
  f.dt = dt;
  f.log_t_min = std::log(dt);
  f.log_t_max = std::log(kLongestTimeFactor * points.back().m * dt);
  for (const Point& p : points) f.weighting.push_back(p.variance);

  Eigen::VectorXd best;
  double best_objective = std::numeric_limits<double>::infinity();
  for (const auto& start : starts(model, points, dt)) {
    Residuals g = f;
    Eigen::VectorXd u = start;
    for (int k = 0; k <= kReweightings; ++k) {
      u = minimize(g, u);
      for (std::size_t j = 0; j < points.size(); ++j) g.weighting[j] = model_variance(model, u, points[j].m, dt);
    }
    const double value = objective(g, u);
    if (std::isfinite(value) && value < best_objective) {
      best_objective = value;
      best = u;
      f.weighting = g.weighting;
    }
  }
  if (best.size() == 0)
    throw DataError({"", 0, "gmwm"}, "GMWM model " + to_string(model) + " could not be fitted to the Allan curve");

  Fit out;
  out.sample_rate_hz = sample_rate_hz;
  out.points = points.size();
  out.dof = points.size() - static_cast<std::size_t>(n);
  out.chi2 = best_objective;
  out.scale = std::max(1.0, out.reduced_chi2());

  Eigen::NumericalDiff<Residuals, Eigen::Central> diff(f);
  Eigen::MatrixXd jacobian(f.values(), n);
  diff.df(best, jacobian);
  const Eigen::MatrixXd information = jacobian.transpose() * jacobian;
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(information);
  const Eigen::MatrixXd covariance = lu.isInvertible()
                                         ? Eigen::MatrixXd(lu.inverse() * out.scale)
                                         : Eigen::MatrixXd::Constant(n, n, std::numeric_limits<double>::infinity());
  // A component is visible when its Allan variance exceeds the one-sigma half width of some point's
  // variance (A sqrt(2 / edf)); an invisible one, or a Gauss-Markov time at its bound, is not resolved.
  const auto visible = [&](const std::vector<double>& values, Process p) {
    for (const Point& q : points)
      if (process_variance(p, values, q.m, dt) > q.variance * std::sqrt(2.0 / q.edf)) return true;
    return false;
  };
  // The factor by which a component's variance can grow before it becomes visible.
  const auto visibility_margin = [&](const std::vector<double>& values, Process p) {
    double margin = std::numeric_limits<double>::infinity();
    for (const Point& q : points)
      margin = std::min(margin, q.variance * std::sqrt(2.0 / q.edf) / process_variance(p, values, q.m, dt));
    return std::max(margin, 1.0);
  };
  int at = 0;
  for (const Process p : model) {
    Component c{p, {}};
    const auto values = si_parameters(p, best.data() + at);
    const bool at_bound =
        p == Process::GaussMarkov && (best[at + 1] <= f.log_t_min + 1e-9 || best[at + 1] >= f.log_t_max - 1e-9);
    c.observable = visible(values, p) && !at_bound;
    for (int k = 0; k < parameter_count(p); ++k) {
      // value = exp(u / 2) for the coefficients (log of a square), exp(u) for T.
      const double per_log = p == Process::GaussMarkov && k == 1 ? 1.0 : 0.5;
      const double sigma_log = per_log * std::sqrt(std::max(covariance(at + k, at + k), 0.0));
      Parameter q;
      switch (p) {
        case Process::WhiteNoise:
          q.name = "N", q.unit = "rad/sqrt(s)";
          break;
        case Process::Quantization:
          q.name = "Q", q.unit = "rad";
          break;
        case Process::RandomWalk:
          q.name = "K", q.unit = "rad/s/sqrt(s)";
          break;
        case Process::Drift:
          q.name = "R", q.unit = "rad/s^2";
          break;
        case Process::GaussMarkov:
          q.name = k == 0 ? "sigma" : "T", q.unit = k == 0 ? "rad/s" : "s";
          break;
      }
      q.value = values[static_cast<std::size_t>(k)];
      q.low = q.value * std::exp(-sigma_log);
      q.high = q.value * std::exp(sigma_log);
      q.resolved = c.observable && std::isfinite(sigma_log) && sigma_log < kResolvedLogSigma;
      if (!std::isfinite(sigma_log)) q.low = 0.0;
      if (!c.observable) {  // the bound is the level at which the component would become visible
        q.low = 0.0;
        q.high = k == 0 ? q.value * std::sqrt(visibility_margin(values, p)) : std::numeric_limits<double>::infinity();
      }
      c.parameters.push_back(q);
    }
    out.components.push_back(std::move(c));
    at += parameter_count(p);
  }
  // Gauss-Markov components by increasing correlation time, in the model's gm slots (a sum does not
  // name its terms' order).
  std::vector<std::size_t> slots;
  std::vector<Component> gms;
  for (std::size_t i = 0; i < out.components.size(); ++i)
    if (out.components[i].process == Process::GaussMarkov) {
      slots.push_back(i);
      gms.push_back(out.components[i]);
    }
  std::stable_sort(gms.begin(), gms.end(), [](const Component& a, const Component& b) {
    return a.parameters[1].value < b.parameters[1].value;
  });
  for (std::size_t k = 0; k < slots.size(); ++k) out.components[slots[k]] = gms[k];
  return out;
}

Eigen::VectorXd simulate(const std::vector<Component>& components, double fs, Eigen::Index samples,
                         std::uint64_t seed) {
  const double dt = 1.0 / fs;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(samples);
  for (std::size_t c = 0; c < components.size(); ++c) {
    const auto& p = components[c].parameters;
    error_model::NormalStream e(seed, c);
    switch (components[c].process) {
      case Process::WhiteNoise:
        for (Eigen::Index k = 0; k < samples; ++k) x[k] += p[0].value / std::sqrt(dt) * e.next();
        break;
      case Process::Quantization: {
        double previous = p[0].value * e.next();
        for (Eigen::Index k = 0; k < samples; ++k) {
          const double theta = p[0].value * e.next();
          x[k] += (theta - previous) / dt;
          previous = theta;
        }
        break;
      }
      case Process::RandomWalk: {
        double walk = 0.0;
        for (Eigen::Index k = 0; k < samples; ++k) {
          walk += p[0].value * std::sqrt(dt) * e.next();
          x[k] += walk;
        }
        break;
      }
      case Process::Drift:
        for (Eigen::Index k = 0; k < samples; ++k) x[k] += p[0].value * static_cast<double>(k) * dt;
        break;
      case Process::GaussMarkov: {
        const double phi = std::exp(-dt / p[1].value), innovation = p[0].value * std::sqrt(1.0 - phi * phi);
        double g = p[0].value * e.next();
        for (Eigen::Index k = 0; k < samples; ++k) {
          g = phi * g + innovation * e.next();
          x[k] += g;
        }
        break;
      }
    }
  }
  return x;
}

Fit bootstrap(const Fit& estimate, Eigen::Index samples, std::size_t replicates, std::uint64_t seed, unsigned threads) {
  if (replicates < 2) throw ConfigError({"", 0, "gmwm bootstrap"}, "the bootstrap needs at least 2 replicates");
  std::vector<Process> model;
  for (const auto& c : estimate.components) model.push_back(c.process);
  std::vector<std::optional<Fit>> fits(replicates);
  parallel_for(replicates, threads, [&](std::size_t r) {
    const Eigen::VectorXd x = simulate(estimate.components, estimate.sample_rate_hz, samples,
                                       splitmix64(seed ^ splitmix64(kBootstrapStream + r)));
    try {
      fits[r] =
          fit(analyze_rate(x, estimate.sample_rate_hz, {.fit_terms = false}).curve, estimate.sample_rate_hz, model);
    } catch (const Error&) {
      fits[r].reset();
    }
  });
  Fit out = estimate;
  std::size_t kept = 0;
  for (const auto& f : fits) kept += f.has_value();
  out.intervals = "bootstrap, " + std::to_string(kept) + " of " + std::to_string(replicates) + " replicates";
  for (std::size_t c = 0; c < out.components.size(); ++c)
    for (std::size_t k = 0; out.components[c].observable && k < out.components[c].parameters.size(); ++k) {
      double sum = 0.0, sum2 = 0.0;
      for (const auto& f : fits) {
        if (!f) continue;
        const double v = std::log(f->components[c].parameters[k].value);
        sum += v;
        sum2 += v * v;
      }
      Parameter& q = out.components[c].parameters[k];
      const double n = static_cast<double>(kept);
      const double s = kept > 1 ? std::sqrt(std::max(0.0, (sum2 - sum * sum / n) / (n - 1.0)))
                                : std::numeric_limits<double>::infinity();
      q.low = std::isfinite(s) ? q.value * std::exp(-s) : 0.0;
      q.high = q.value * std::exp(s);
      q.resolved = out.components[c].observable && std::isfinite(s) && s < kResolvedLogSigma;
    }
  return out;
}

}  // namespace driftlab::allan::gmwm
