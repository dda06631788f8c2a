#include "models/allan/noise_fit.hpp"

#include "framework/error.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

namespace driftlab::allan {
namespace {

struct Point {
  double tau;
  double variance;
  double relative_sigma;  // interval half width / variance
  double sigma;           // current weight's standard deviation
};

constexpr int kReweightings = 4;
// Relative uncertainty of the IEEE 952 model itself (variance), added in quadrature to each point's
// statistical width: real sensors' filters and correlated noise bend the short-tau curve away from
// the five terms, and points with edf ~1e6 would otherwise dictate the fit of every term.
constexpr double kModelTolerance = 0.05;

struct SubsetFit {
  Eigen::VectorXd c;           // coefficients of the subset's terms
  Eigen::MatrixXd covariance;  // unscaled (A^T W A)^-1
  double chi2 = std::numeric_limits<double>::infinity();
  bool ok = false;
};

SubsetFit solve(const std::vector<Point>& points, unsigned mask) {
  std::vector<Term> terms;
  for (std::size_t t = 0; t < kTermCount; ++t) {
    if (mask & (1u << t)) terms.push_back(static_cast<Term>(t));
  }
  const auto rows = static_cast<Eigen::Index>(points.size());
  const auto cols = static_cast<Eigen::Index>(terms.size());
  Eigen::MatrixXd a(rows, cols);
  Eigen::VectorXd b(rows);
  for (Eigen::Index i = 0; i < rows; ++i) {
    const Point& p = points[static_cast<std::size_t>(i)];
    for (Eigen::Index j = 0; j < cols; ++j) {
      a(i, j) = term_basis(terms[static_cast<std::size_t>(j)], p.tau) / p.sigma;
    }
    b(i) = p.variance / p.sigma;
  }
  const Eigen::VectorXd scale = a.colwise().norm().transpose();
  SubsetFit fit;
  if ((scale.array() <= 0.0).any()) return fit;
  const Eigen::MatrixXd scaled = a * scale.cwiseInverse().asDiagonal();
  const Eigen::MatrixXd normal = scaled.transpose() * scaled;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(normal);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return fit;
  const Eigen::MatrixXd inverse = ldlt.solve(Eigen::MatrixXd::Identity(cols, cols));
  fit.c = ldlt.solve(scaled.transpose() * b).cwiseQuotient(scale);
  fit.covariance = scale.cwiseInverse().asDiagonal() * inverse * scale.cwiseInverse().asDiagonal();
  fit.chi2 = (a * fit.c - b).squaredNorm();
  fit.ok = fit.c.allFinite() && (fit.c.array() > 0.0).all();
  return fit;
}

// Standard deviation of coefficient `term` in the fit of `best` plus that term.
double coefficient_sigma(std::span<const SubsetFit> fits, unsigned best, std::size_t term, double scale) {
  const unsigned with = best | (1u << term);
  const SubsetFit& fit = fits[with];
  if (fit.covariance.size() == 0) return 0.0;
  const auto k = static_cast<Eigen::Index>(std::popcount(with & ((1u << term) - 1u)));
  return std::sqrt(std::max(fit.covariance(k, k), 0.0) * scale);
}

}  // namespace

double term_basis(Term t, double tau) {
  switch (t) {
    case Term::Q:
      return 3.0 / (tau * tau);
    case Term::N:
      return 1.0 / tau;
    case Term::B:
      return 2.0 * std::numbers::ln2 / std::numbers::pi;
    case Term::K:
      return tau / 3.0;
    case Term::R:
      return tau * tau / 2.0;
  }
  return 0.0;
}

double NoiseFit::term_deviation(Term t, double tau) const {
  const double v = (*this)[t].value;
  return std::sqrt(v * v * term_basis(t, tau));
}

double NoiseFit::model_deviation(double tau) const {
  double variance = 0.0;
  for (std::size_t t = 0; t < kTermCount; ++t) {
    variance += terms[t].value * terms[t].value * term_basis(static_cast<Term>(t), tau);
  }
  return std::sqrt(variance);
}

NoiseFit fit_noise_terms(std::span<const Estimate> curve) {
  std::vector<Point> points;
  for (const Estimate& e : curve) {
    const double half_width = 0.5 * (e.dev_hi * e.dev_hi - e.dev_lo * e.dev_lo);
    if (e.dev > 0.0 && half_width > 0.0 && std::isfinite(half_width) && e.tau > 0.0) {
      const double variance = e.dev * e.dev;
      const double relative = std::hypot(half_width / variance, kModelTolerance);
      points.push_back({e.tau, variance, relative, relative * variance});
    }
  }
  if (points.size() < 2) {
    throw DataError(
        {}, "noise-term fit needs at least 2 points with a confidence interval, got " + std::to_string(points.size()));
  }
  constexpr unsigned kSubsets = 1u << kTermCount;
  std::vector<SubsetFit> fits(kSubsets);
  unsigned best = 0;
  for (int round = 0; round <= kReweightings; ++round) {
    if (round > 0) {
      for (Point& p : points) {
        double model = 0.0;
        std::size_t index = 0;
        for (std::size_t t = 0; t < kTermCount; ++t) {
          if (best & (1u << t)) {
            model += fits[best].c(static_cast<Eigen::Index>(index++)) * term_basis(static_cast<Term>(t), p.tau);
          }
        }
        p.sigma = p.relative_sigma * model;
      }
    }
    best = 0;
    for (unsigned mask = 1; mask < kSubsets; ++mask) {
      fits[mask] = {};
      if (static_cast<std::size_t>(std::popcount(mask)) > points.size()) continue;
      fits[mask] = solve(points, mask);
      if (fits[mask].ok && (best == 0 || fits[mask].chi2 < fits[best].chi2)) best = mask;
    }
    if (best == 0) throw DataError({}, "noise-term fit found no positive combination of terms");
  }

  NoiseFit result;
  result.points = points.size();
  result.chi2 = fits[best].chi2;
  result.dof = points.size() - static_cast<std::size_t>(std::popcount(best));
  result.scale = result.dof > 0 ? std::max(1.0, result.chi2 / static_cast<double>(result.dof)) : 1.0;
  std::size_t index = 0;
  for (std::size_t t = 0; t < kTermCount; ++t) {
    TermEstimate& term = result.terms[t];
    if (best & (1u << t)) {
      const auto k = static_cast<Eigen::Index>(index++);
      const double c = fits[best].c(k);
      const double sigma_c = std::sqrt(fits[best].covariance(k, k) * result.scale);
      term = {std::sqrt(c), sigma_c / (2.0 * std::sqrt(c)),        true,
              c > sigma_c,  std::sqrt(std::max(c - sigma_c, 0.0)), std::sqrt(c + sigma_c)};
    } else {
      const double sigma_c = coefficient_sigma(fits, best, t, result.scale);
      term = {0.0, std::sqrt(sigma_c), false, false, 0.0, std::sqrt(sigma_c)};
    }
  }
  return result;
}

}  // namespace driftlab::allan
