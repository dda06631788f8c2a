#include "plugins/emd/emd.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "plugins/builtins.hpp"
#include "framework/error.hpp"
#include "framework/params_io.hpp"
#include "framework/registry.hpp"
#include "tests/plugins/progress_check.hpp"

namespace driftlab {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kSampleRateHz = 1000.0;
// Sums of at most ~20 components of magnitude <= 10 reproduce x to a few ulps of 10.
constexpr double kRoundingTolerance = 1e-12;

Eigen::VectorXd tone(Eigen::Index n, double frequency_hz, double phase = 0.0, double amplitude = 1.0,
                     bool cosine = false) {
  Eigen::VectorXd x(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double angle = 2.0 * kPi * frequency_hz * static_cast<double>(i) / kSampleRateHz + phase;
    x[i] = amplitude * (cosine ? std::cos(angle) : std::sin(angle));
  }
  return x;
}

Eigen::VectorXd white_noise(Eigen::Index n, unsigned seed, double sd = 1.0) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, sd);
  Eigen::VectorXd x(n);
  for (Eigen::Index i = 0; i < n; ++i) x[i] = normal(rng);
  return x;
}

// Noise + two tones + a trend: many IMFs, every code path of sifting.
Eigen::VectorXd busy_signal(Eigen::Index n, unsigned seed) {
  Eigen::VectorXd trend(n);
  for (Eigen::Index i = 0; i < n; ++i) trend[i] = 2.0 * static_cast<double>(i) / static_cast<double>(n);
  return white_noise(n, seed, 0.5) + tone(n, 7.0, 0.3) + tone(n, 0.9, 1.1, 2.0) + trend;
}

double max_abs_in(const Eigen::VectorXd& v, Eigen::Index from, Eigen::Index to) {
  return v.segment(from, to - from).cwiseAbs().maxCoeff();
}

double reconstruction_error(const Eigen::VectorXd& x, const emd::Result& r) {
  return (x - r.imfs.rowwise().sum() - r.residue).cwiseAbs().maxCoeff();
}

emd::EnsembleConfig small_ensemble(std::uint64_t seed, unsigned threads) {
  emd::EnsembleConfig c;
  c.ensemble_size = 12;
  c.noise_strength = 0.2;
  c.seed = seed;
  c.threads = threads;
  return c;
}

// ---- A naive reference sift: extrema by definition, Rilling's boundary_conditions literally,
// not-a-knot spline by a dense solve, evaluation by the textbook segment formula. -----------------

struct Knots {
  std::vector<double> t, y;
};

// Not-a-knot cubic spline through the knots, evaluated at 0..n-1 (general sparse LU on the M system).
Eigen::VectorXd naive_spline(const Knots& k, Eigen::Index n) {
  const auto m = static_cast<Eigen::Index>(k.t.size());
  Eigen::VectorXd second(m);
  if (m == 2) {
    second.setZero();
  } else if (m == 3) {
    const double d0 = (k.y[1] - k.y[0]) / (k.t[1] - k.t[0]), d1 = (k.y[2] - k.y[1]) / (k.t[2] - k.t[1]);
    second.setConstant(2.0 * (d1 - d0) / (k.t[2] - k.t[0]));
  } else {
    std::vector<Eigen::Triplet<double>> a;
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(m);
    auto h = [&](Eigen::Index i) { return k.t[i + 1] - k.t[i]; };
    // Third derivative continuous at the second and the next-to-last knot.
    a.emplace_back(0, 0, -1.0 / h(0));
    a.emplace_back(0, 1, 1.0 / h(0) + 1.0 / h(1));
    a.emplace_back(0, 2, -1.0 / h(1));
    a.emplace_back(m - 1, m - 3, -1.0 / h(m - 3));
    a.emplace_back(m - 1, m - 2, 1.0 / h(m - 3) + 1.0 / h(m - 2));
    a.emplace_back(m - 1, m - 1, -1.0 / h(m - 2));
    for (Eigen::Index i = 1; i + 1 < m; ++i) {
      a.emplace_back(i, i - 1, h(i - 1));
      a.emplace_back(i, i, 2.0 * (h(i - 1) + h(i)));
      a.emplace_back(i, i + 1, h(i));
      rhs[i] = 6.0 * ((k.y[i + 1] - k.y[i]) / h(i) - (k.y[i] - k.y[i - 1]) / h(i - 1));
    }
    Eigen::SparseMatrix<double> matrix(m, m);
    matrix.setFromTriplets(a.begin(), a.end());
    Eigen::SparseLU<Eigen::SparseMatrix<double>> lu(matrix);
    second = lu.solve(rhs);
  }
  Eigen::VectorXd out(n);
  for (Eigen::Index s = 0; s < n; ++s) {
    const double t = static_cast<double>(s);
    const auto upper = std::upper_bound(k.t.begin(), k.t.end(), t);
    const auto j = std::clamp<Eigen::Index>(upper - k.t.begin() - 1, 0, m - 2);
    const double h = k.t[j + 1] - k.t[j], a = k.t[j + 1] - t, b = t - k.t[j];
    out[s] = second[j] * a * a * a / (6.0 * h) + second[j + 1] * b * b * b / (6.0 * h) +
             (k.y[j] / h - second[j] * h / 6.0) * a + (k.y[j + 1] / h - second[j + 1] * h / 6.0) * b;
  }
  return out;
}

std::vector<Eigen::Index> slice_reversed(const std::vector<Eigen::Index>& v, Eigen::Index from, Eigen::Index to) {
  std::vector<Eigen::Index> out;
  for (Eigen::Index i = std::min<Eigen::Index>(to, static_cast<Eigen::Index>(v.size())) - 1;
       i >= std::max<Eigen::Index>(from, 0); --i)
    out.push_back(v[static_cast<std::size_t>(i)]);
  return out;
}

// Rilling, Flandrin & Goncalves, emd.m `boundary_conditions` with nbsym = 2, 0-based. An empty
// reflected list counts as not reaching past the end (MATLAB would fail on it).
void rilling_mirror(const Eigen::VectorXd& x, const std::vector<Eigen::Index>& imax,
                    const std::vector<Eigen::Index>& imin, Knots& upper, Knots& lower) {
  constexpr Eigen::Index nbsym = 2;
  const Eigen::Index n = x.size(), last = n - 1;
  const auto nmax = static_cast<Eigen::Index>(imax.size()), nmin = static_cast<Eigen::Index>(imin.size());
  std::vector<Eigen::Index> lmax, lmin, rmax, rmin;
  Eigen::Index lsym = 0, rsym = last;
  if (imax.front() < imin.front()) {
    if (x[0] > x[imin.front()]) {
      lmax = slice_reversed(imax, 1, nbsym + 1);
      lmin = slice_reversed(imin, 0, nbsym);
      lsym = imax.front();
    } else {
      lmax = slice_reversed(imax, 0, nbsym);
      lmin = slice_reversed(imin, 0, nbsym - 1);
      lmin.push_back(0);
    }
  } else {
    if (x[0] < x[imax.front()]) {
      lmax = slice_reversed(imax, 0, nbsym);
      lmin = slice_reversed(imin, 1, nbsym + 1);
      lsym = imin.front();
    } else {
      lmax = slice_reversed(imax, 0, nbsym - 1);
      lmax.push_back(0);
      lmin = slice_reversed(imin, 0, nbsym);
    }
  }
  if (imax.back() < imin.back()) {
    if (x[last] < x[imax.back()]) {
      rmax = slice_reversed(imax, nmax - nbsym, nmax);
      rmin = slice_reversed(imin, nmin - nbsym - 1, nmin - 1);
      rsym = imin.back();
    } else {
      rmax = slice_reversed(imax, nmax - nbsym + 1, nmax);
      rmax.insert(rmax.begin(), last);
      rmin = slice_reversed(imin, nmin - nbsym, nmin);
    }
  } else {
    if (x[last] > x[imin.back()]) {
      rmax = slice_reversed(imax, nmax - nbsym - 1, nmax - 1);
      rmin = slice_reversed(imin, nmin - nbsym, nmin);
      rsym = imax.back();
    } else {
      rmax = slice_reversed(imax, nmax - nbsym, nmax);
      rmin = slice_reversed(imin, nmin - nbsym + 1, nmin);
      rmin.insert(rmin.begin(), last);
    }
  }
  auto reflect = [](Eigen::Index axis, const std::vector<Eigen::Index>& idx) {
    std::vector<double> t;
    for (auto i : idx) t.push_back(2.0 * static_cast<double>(axis) - static_cast<double>(i));
    return t;
  };
  auto tlmax = reflect(lsym, lmax), tlmin = reflect(lsym, lmin);
  if (tlmax.empty() || tlmin.empty() || tlmax.front() > 0.0 || tlmin.front() > 0.0) {
    if (lsym == imax.front())
      lmax = slice_reversed(imax, 0, nbsym);
    else
      lmin = slice_reversed(imin, 0, nbsym);
    lsym = 0;
    tlmax = reflect(lsym, lmax);
    tlmin = reflect(lsym, lmin);
  }
  auto trmax = reflect(rsym, rmax), trmin = reflect(rsym, rmin);
  const auto end = static_cast<double>(last);
  if (trmax.empty() || trmin.empty() || trmax.back() < end || trmin.back() < end) {
    if (rsym == imax.back())
      rmax = slice_reversed(imax, nmax - nbsym, nmax);
    else
      rmin = slice_reversed(imin, nmin - nbsym, nmin);
    rsym = last;
    trmax = reflect(rsym, rmax);
    trmin = reflect(rsym, rmin);
  }
  auto assemble = [&](const std::vector<double>& tl, const std::vector<Eigen::Index>& il,
                      const std::vector<Eigen::Index>& inner, const std::vector<double>& tr,
                      const std::vector<Eigen::Index>& ir, Knots& k) {
    for (std::size_t q = 0; q < tl.size(); ++q) k.t.push_back(tl[q]), k.y.push_back(x[il[q]]);
    for (auto i : inner) k.t.push_back(static_cast<double>(i)), k.y.push_back(x[i]);
    for (std::size_t q = 0; q < tr.size(); ++q) k.t.push_back(tr[q]), k.y.push_back(x[ir[q]]);
  };
  assemble(tlmax, lmax, imax, trmax, rmax, upper);
  assemble(tlmin, lmin, imin, trmin, rmin, lower);
}

// Wu & Huang 2009 / libeemd end points: line through the two nearest extrema, not inside the signal.
void linear_ends(const Eigen::VectorXd& x, const std::vector<Eigen::Index>& idx, bool upper, Knots& k) {
  const Eigen::Index last = x.size() - 1;
  auto end_value = [&](Eigen::Index a, Eigen::Index b, Eigen::Index end) {
    double v = x[a];
    if (a != b) v = x[a] + (x[b] - x[a]) * static_cast<double>(end - a) / static_cast<double>(b - a);
    return upper ? std::max(v, x[end]) : std::min(v, x[end]);
  };
  const Eigen::Index m = static_cast<Eigen::Index>(idx.size());
  k.t.push_back(0.0);
  k.y.push_back(end_value(idx[0], idx[std::min<Eigen::Index>(1, m - 1)], 0));
  for (auto i : idx) k.t.push_back(static_cast<double>(i)), k.y.push_back(x[i]);
  k.t.push_back(static_cast<double>(last));
  k.y.push_back(end_value(idx[static_cast<std::size_t>(m - 1)],
                          idx[static_cast<std::size_t>(std::max<Eigen::Index>(m - 2, 0))], last));
}

// Extrema by definition: a run of equal samples x[a..b] (often a single sample), 1 <= a, b + 2 <= n,
// higher (lower) than both its neighbours is one maximum (minimum), at (a + b) / 2.
void naive_extrema(const Eigen::VectorXd& x, std::vector<Eigen::Index>& imax, std::vector<Eigen::Index>& imin) {
  for (Eigen::Index a = 1; a + 1 < x.size();) {
    Eigen::Index b = a;
    while (b + 2 < x.size() && x[b + 1] == x[a]) ++b;
    if (x[a] > x[a - 1] && x[a] > x[b + 1]) imax.push_back((a + b) / 2);
    if (x[a] < x[a - 1] && x[a] < x[b + 1]) imin.push_back((a + b) / 2);
    a = b + 1;
  }
}

Eigen::VectorXd naive_one_sift(const Eigen::VectorXd& x, emd::EndPolicy policy) {
  std::vector<Eigen::Index> imax, imin;
  naive_extrema(x, imax, imin);
  Knots upper, lower;
  if (policy == emd::EndPolicy::Mirror) {
    rilling_mirror(x, imax, imin, upper, lower);
  } else {
    linear_ends(x, imax, true, upper);
    linear_ends(x, imin, false, lower);
  }
  return x - 0.5 * (naive_spline(upper, x.size()) + naive_spline(lower, x.size()));
}

emd::EmdConfig one_sift(emd::EndPolicy policy) {
  emd::EmdConfig c;
  c.sift.stop_rule = emd::StopRule::FixedSifts;
  c.sift.fixed_sifts = 1;
  c.sift.end_policy = policy;
  c.max_imfs = 1;
  return c;
}

// ---- EMD ---------------------------------------------------------------------------------------

TEST(Emd, OneSiftMatchesANaiveDenseSplineReferenceForBothEndPolicies) {
  // The dense LU solve and the O(n) recurrence differ only by rounding; envelopes are O(1).
  constexpr double kSiftTolerance = 1e-9;
  for (unsigned seed = 1; seed <= 12; ++seed) {
    // Alternate white noise (dense extrema) with a few slow random tones (sparse extrema, every
    // mirror branch hit across seeds).
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> uniform(0.0, 2.0 * kPi);
    const Eigen::Index n = 400 + 37 * seed;
    Eigen::VectorXd x = white_noise(n, seed);
    if (seed % 2 == 0)
      x = tone(n, 11.0, uniform(rng)) + tone(n, 23.0, uniform(rng), 0.7) + tone(n, 3.0, uniform(rng), 1.5);
    for (auto policy : {emd::EndPolicy::Mirror, emd::EndPolicy::Linear}) {
      const auto r = emd::emd(x, one_sift(policy));
      ASSERT_EQ(r.imfs.cols(), 1);
      EXPECT_LT((r.imfs.col(0) - naive_one_sift(x, policy)).cwiseAbs().maxCoeff(), kSiftTolerance)
          << "seed " << seed << (policy == emd::EndPolicy::Mirror ? " mirror" : " linear");
    }
  }
}

TEST(Emd, OneSiftMatchesTheNaiveReferenceForEnvelopesOfFewKnots) {
  // Envelopes of 2 to ~12 knots, the upper and lower ones of different sizes: the spline fit's
  // small systems, the rows its vector lanes leave to one spline alone, and the meeting of the
  // forward and backward sweeps next to the ends.
  constexpr double kSiftTolerance = 1e-9;
  constexpr Eigen::Index n = 300;
  int sifted = 0;
  for (int half_periods = 2; half_periods <= 11; ++half_periods) {
    for (int p = 0; p < 6; ++p) {
      const double frequency_hz = 0.5 * half_periods * kSampleRateHz / static_cast<double>(n);
      Eigen::VectorXd x = tone(n, frequency_hz, 0.5 * p) + tone(n, 2.7 * frequency_hz, 1.3 * p, 0.3);
      for (auto policy : {emd::EndPolicy::Mirror, emd::EndPolicy::Linear}) {
        const auto r = emd::emd(x, one_sift(policy));
        if (r.imfs.cols() == 0) continue;  // too few extrema to sift
        ++sifted;
        EXPECT_LT((r.imfs.col(0) - naive_one_sift(x, policy)).cwiseAbs().maxCoeff(), kSiftTolerance)
            << half_periods << " half periods, phase step " << p;
      }
    }
  }
  EXPECT_GT(sifted, 100);
}

// Signals longer than the sifter's 2048-sample blocks, at extrema densities that take each of its
// paths: white noise (dense), an 83 Hz tone (12 samples a period) with a little noise (mid), slow
// tones (sparse), quantized noise (flat runs: equal neighbours in the first extrema search), and
// noise with quiet stretches (dense on average, with envelope pieces of ~50 samples).
std::vector<Eigen::VectorXd> multi_block_signals() {
  constexpr Eigen::Index n = 5000;
  const Eigen::VectorXd noise = white_noise(n, 21);
  Eigen::VectorXd gaps = noise;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (i % 300 >= 250) gaps[i] = 0.01 * static_cast<double>(i % 300 - 250);
  }
  return {noise, tone(n, 83.0, 0.4) + 0.05 * white_noise(n, 22), tone(n, 9.0, 0.2) + tone(n, 2.0, 1.0, 0.5),
          (2.0 * noise).array().round().matrix(), gaps};
}

// Extrema by definition and sign-bit changes between neighbours.
struct NaiveCounts {
  Eigen::Index maxima = 0, minima = 0, zero_crossings = 0;
};

NaiveCounts naive_counts(const Eigen::VectorXd& h) {
  std::vector<Eigen::Index> imax, imin;
  naive_extrema(h, imax, imin);
  NaiveCounts c{static_cast<Eigen::Index>(imax.size()), static_cast<Eigen::Index>(imin.size()), 0};
  for (Eigen::Index i = 1; i < h.size(); ++i) c.zero_crossings += std::signbit(h[i]) != std::signbit(h[i - 1]);
  return c;
}

TEST(Emd, RepeatedSiftsAcrossBlocksMatchTheNaiveReference) {
  // Each sift starts from the extrema the previous one found block by block, so this checks the
  // block scans too. Tolerance as above, times the few sifts.
  constexpr double kSiftTolerance = 1e-8;
  constexpr int kSifts = 3;
  for (const Eigen::VectorXd& x : multi_block_signals()) {
    emd::EmdConfig c = one_sift(emd::EndPolicy::Mirror);
    c.sift.fixed_sifts = kSifts;
    const auto r = emd::emd(x, c);
    Eigen::VectorXd h = x;
    for (int k = 0; k < kSifts; ++k) h = naive_one_sift(h, emd::EndPolicy::Mirror);
    ASSERT_EQ(r.imfs.cols(), 1);
    EXPECT_LT((r.imfs.col(0) - h).cwiseAbs().maxCoeff(), kSiftTolerance) << naive_counts(x).maxima << " maxima";
  }
}

TEST(Emd, SNumberRuleStopsAfterTheSiftsThatTheNaiveCountsGive) {
  // The S-number rule reads the extrema and zero crossings the block scans count.
  constexpr int kSNumber = 4, kMaxSifts = 50;
  for (const Eigen::VectorXd& x : multi_block_signals()) {
    emd::EmdConfig c;
    c.max_imfs = 1;
    const auto r = emd::emd(x, c);
    Eigen::VectorXd h = x;
    int sifts = 0, s_run = 0;
    while (sifts < kMaxSifts && s_run < kSNumber) {
      h = naive_one_sift(h, emd::EndPolicy::Mirror);
      ++sifts;
      const NaiveCounts n = naive_counts(h);
      if (n.maxima < 1 || n.minima < 1 || n.maxima + n.minima < 3) break;
      s_run = std::abs(n.maxima + n.minima - n.zero_crossings) <= 1 ? s_run + 1 : 0;
    }
    ASSERT_EQ(r.sifts.size(), 1u);
    EXPECT_EQ(r.sifts[0], sifts) << naive_counts(x).maxima << " maxima";
  }
}

TEST(Emd, ReconstructsTheInputToRounding) {
  for (auto policy : {emd::EndPolicy::Mirror, emd::EndPolicy::Linear}) {
    for (auto rule : {emd::StopRule::SNumber, emd::StopRule::CauchySd, emd::StopRule::FixedSifts}) {
      emd::EmdConfig c;
      c.sift.end_policy = policy;
      c.sift.stop_rule = rule;
      const Eigen::VectorXd x = busy_signal(3000, 7);
      const auto r = emd::emd(x, c);
      EXPECT_GE(r.imfs.cols(), 5);
      EXPECT_LT(reconstruction_error(x, r), kRoundingTolerance);
    }
  }
}

TEST(Emd, RecoversTwoWellSeparatedTonesAsTheFirstTwoImfs) {
  // 20 Hz and 0.5 Hz at 1 kHz, generic phases. Away from the first and last second (the 0.5 Hz
  // envelopes are extrapolated there) the tones come back to 1e-4 of their unit amplitude (the
  // spline envelopes of a sampled sine are exact to ~1e-5).
  constexpr double kToneTolerance = 1e-4;
  const Eigen::Index n = 10000, edge = 1000;
  for (double phase : {0.0, 0.7, 1.9, 3.0}) {
    const Eigen::VectorXd fast = tone(n, 20.0, 1.3 * phase), slow = tone(n, 0.5, phase);
    emd::EmdConfig c;
    c.sift.end_policy = emd::EndPolicy::Linear;
    const auto r = emd::emd(fast + slow, c);
    ASSERT_GE(r.imfs.cols(), 2);
    EXPECT_LT(max_abs_in(r.imfs.col(0) - fast, edge, n - edge), kToneTolerance) << "phase " << phase;
    EXPECT_LT(max_abs_in(r.imfs.col(1) - slow, edge, n - edge), kToneTolerance) << "phase " << phase;
  }
}

TEST(Emd, MirrorEndsRecoverTonesEverywhereWhenTheSignalIsSymmetricAboutItsEnds) {
  // cos(2 pi 20 t) + cos(2 pi 0.5 t) on [0, 10] s is even about both end samples, so the mirrored
  // extrema continue it exactly and even the end samples come out right; the leftover IMFs are
  // spline-interpolation error (~1e-6).
  constexpr double kToneTolerance = 1e-5;
  const Eigen::Index n = 10001;
  const Eigen::VectorXd fast = tone(n, 20.0, 0.0, 1.0, true), slow = tone(n, 0.5, 0.0, 1.0, true);
  const auto r = emd::emd(fast + slow, {});
  ASSERT_GE(r.imfs.cols(), 2);
  EXPECT_LT((r.imfs.col(0) - fast).cwiseAbs().maxCoeff(), kToneTolerance);
  EXPECT_LT((r.imfs.col(1) - slow).cwiseAbs().maxCoeff(), kToneTolerance);
}

TEST(Emd, MirrorEndsRecoverTheFastToneAwayFromTheEdgesForAnyPhase) {
  // Mirroring also reflects the slow tone's slope at a generic end, which perturbs the envelopes
  // near the ends (the later IMFs inherit it: a known property of mirror extension); the first
  // IMF is unaffected in the interior.
  constexpr double kToneTolerance = 1e-4;
  const Eigen::Index n = 10000, edge = 1000;
  for (double phase : {0.0, 0.7, 1.9, 3.0}) {
    const Eigen::VectorXd fast = tone(n, 20.0, 1.3 * phase), slow = tone(n, 0.5, phase);
    const auto r = emd::emd(fast + slow, {});
    EXPECT_LT(max_abs_in(r.imfs.col(0) - fast, edge, n - edge), kToneTolerance) << "phase " << phase;
  }
}

TEST(Emd, ReportsASmallOrthogonalityIndexForWellSeparatedTones) {
  // Huang 1998 reports IO of order 1e-3..1e-2 for good decompositions; the two pure tones give
  // ~1e-5 with linear ends (no end distortion) and ~1e-2 with mirrored ends.
  constexpr double kOrthogonalTolerance = 1e-3;
  constexpr double kMirrorOrthogonalTolerance = 5e-2;
  const Eigen::Index n = 10000;
  const Eigen::VectorXd x = tone(n, 20.0, 0.4) + tone(n, 0.5, 1.0);
  emd::EmdConfig linear;
  linear.sift.end_policy = emd::EndPolicy::Linear;
  const auto r = emd::emd(x, linear);
  EXPECT_LT(std::abs(emd::orthogonality_index(x, r.imfs, r.residue)), kOrthogonalTolerance);
  const auto m = emd::emd(x, {});
  EXPECT_LT(std::abs(emd::orthogonality_index(x, m.imfs, m.residue)), kMirrorOrthogonalTolerance);
}

TEST(Emd, OrthogonalityIndexIsTheCrossEnergyOverTheSignalEnergy) {
  // Huang 1998 eq. 6.5 (time sums first) computed the long way on two IMFs and a residue.
  constexpr double kIdentityTolerance = 1e-12;
  const Eigen::Index n = 500;
  Eigen::MatrixXd imfs(n, 2);
  imfs.col(0) = tone(n, 40.0);
  imfs.col(1) = tone(n, 9.0, 0.5) + 0.1 * tone(n, 40.0);
  const Eigen::VectorXd residue = Eigen::VectorXd::Constant(n, 0.3);
  const Eigen::VectorXd x = imfs.rowwise().sum() + residue;
  double cross = 0.0;
  const std::vector<Eigen::VectorXd> c = {imfs.col(0), imfs.col(1), residue};
  for (std::size_t j = 0; j < c.size(); ++j)
    for (std::size_t k = 0; k < c.size(); ++k)
      if (j != k) cross += c[j].dot(c[k]);
  EXPECT_NEAR(emd::orthogonality_index(x, imfs, residue), cross / x.squaredNorm(), kIdentityTolerance);
}

TEST(Emd, PutsALinearTrendIntoTheResidue) {
  // 5 Hz tone on a ramp: one IMF (the tone) and the ramp as residue. Linear ends continue a ramp
  // exactly; mirrored ends bend it near the ends only.
  constexpr double kExactTolerance = 1e-9;
  constexpr double kMirrorInteriorTolerance = 1e-3;
  const Eigen::Index n = 10000, edge = 1000;
  Eigen::VectorXd trend(n);
  for (Eigen::Index i = 0; i < n; ++i) trend[i] = 0.3 * static_cast<double>(i) / kSampleRateHz - 1.0;
  const Eigen::VectorXd x = trend + tone(n, 5.0, 0.2);
  emd::EmdConfig linear;
  linear.sift.end_policy = emd::EndPolicy::Linear;
  const auto r = emd::emd(x, linear);
  EXPECT_EQ(r.imfs.cols(), 1);
  EXPECT_LT((r.residue - trend).cwiseAbs().maxCoeff(), kExactTolerance);
  const auto m = emd::emd(x, {});
  EXPECT_LT(max_abs_in(m.residue - trend, edge, n - edge), kMirrorInteriorTolerance);
}

TEST(Emd, LeavesAMonotonicSignalWhole) {
  Eigen::VectorXd x(300);
  for (Eigen::Index i = 0; i < x.size(); ++i) x[i] = std::exp(0.01 * static_cast<double>(i));
  const auto r = emd::emd(x, {});
  EXPECT_EQ(r.imfs.cols(), 0);
  EXPECT_EQ(r.residue, x);
  const auto e = emd::emd(Eigen::VectorXd(), {});
  EXPECT_EQ(e.imfs.cols(), 0);
  EXPECT_EQ(e.residue.size(), 0);
}

TEST(Emd, TreatsFlatPeaksOfQuantizedDataAsSingleExtrema) {
  // A sine quantized to 9 levels has flat peaks and troughs dozens of samples wide. Counted once
  // each (at their middle) they keep the envelopes on the sine, which comes back as one IMF;
  // strict-inequality extrema would miss every flat peak.
  constexpr double kMinimumCorrelation = 0.99;
  const Eigen::Index n = 4000, edge = 500;
  const Eigen::VectorXd sine = tone(n, 2.0, 0.3, 4.0);
  const Eigen::VectorXd x = sine.array().round().matrix();
  const auto r = emd::emd(x, {});
  EXPECT_LT(reconstruction_error(x, r), kRoundingTolerance);
  Eigen::Index strongest = 0;
  r.imfs.colwise().squaredNorm().maxCoeff(&strongest);
  const Eigen::VectorXd imf = r.imfs.col(strongest).segment(edge, n - 2 * edge);
  const Eigen::VectorXd truth = sine.segment(edge, n - 2 * edge);
  EXPECT_GT(imf.dot(truth) / (imf.norm() * truth.norm()), kMinimumCorrelation);
}

TEST(Emd, FixedSiftsRuleSiftsExactlyThatManyTimesPerImf) {
  emd::EmdConfig c;
  c.sift.stop_rule = emd::StopRule::FixedSifts;
  c.sift.fixed_sifts = 7;
  const auto r = emd::emd(busy_signal(2000, 3), c);
  ASSERT_FALSE(r.sifts.empty());
  for (long s : r.sifts) EXPECT_LE(s, 7);
  EXPECT_GE(std::count(r.sifts.begin(), r.sifts.end(), 7L), static_cast<long>(r.sifts.size()) - 1)
      << "only the last IMF may run out of extrema before 7 sifts";
}

TEST(Emd, EveryRuleRespectsTheSiftCapAndSNumberNeedsAtLeastSSifts) {
  const Eigen::VectorXd x = busy_signal(2000, 5);
  emd::EmdConfig capped;
  capped.sift.max_sifts = 3;
  for (auto rule : {emd::StopRule::SNumber, emd::StopRule::CauchySd, emd::StopRule::FixedSifts}) {
    capped.sift.stop_rule = rule;
    for (long s : emd::emd(x, capped).sifts) EXPECT_LE(s, 3);
  }
  emd::EmdConfig s_number;
  s_number.sift.s_number = 6;
  const auto r = emd::emd(x, s_number);
  for (std::size_t k = 0; k + 1 < r.sifts.size(); ++k) EXPECT_GE(r.sifts[k], 6) << "IMF " << k + 1;
}

TEST(Emd, ATighterCauchyThresholdSiftsMore) {
  const Eigen::VectorXd x = busy_signal(2000, 9);
  emd::EmdConfig loose, tight;
  loose.sift.stop_rule = tight.sift.stop_rule = emd::StopRule::CauchySd;
  loose.sift.sd_threshold = 0.3;
  tight.sift.sd_threshold = 0.001;
  const auto first_imf_sifts = [&](const emd::EmdConfig& c) { return emd::emd(x, c).sifts.front(); };
  EXPECT_GT(first_imf_sifts(tight), first_imf_sifts(loose));
}

TEST(Emd, StopsAtMaxImfsWithTheRestInTheResidue) {
  const Eigen::VectorXd x = busy_signal(3000, 11);
  emd::EmdConfig c;
  c.max_imfs = 2;
  const auto r = emd::emd(x, c);
  EXPECT_EQ(r.imfs.cols(), 2);
  EXPECT_LT(reconstruction_error(x, r), kRoundingTolerance);
  const auto full = emd::emd(x, {});
  EXPECT_GT(full.imfs.cols(), 2);
  EXPECT_EQ(full.imfs.leftCols(2), r.imfs) << "the first IMFs do not depend on the cap";
}

TEST(Emd, RejectsBadConfigurationsAndNonFiniteSamples) {
  const Eigen::VectorXd x = busy_signal(200, 1);
  auto with = [](auto change) {
    emd::EmdConfig c;
    change(c);
    return c;
  };
  EXPECT_THROW(emd::emd(x, with([](auto& c) { c.sift.s_number = 0; })), std::invalid_argument);
  EXPECT_THROW(emd::emd(x, with([](auto& c) { c.sift.sd_threshold = 0.0; })), std::invalid_argument);
  EXPECT_THROW(emd::emd(x, with([](auto& c) { c.sift.sd_threshold = std::nan(""); })), std::invalid_argument);
  EXPECT_THROW(emd::emd(x, with([](auto& c) { c.sift.fixed_sifts = 0; })), std::invalid_argument);
  EXPECT_THROW(emd::emd(x, with([](auto& c) { c.sift.max_sifts = 0; })), std::invalid_argument);
  EXPECT_THROW(emd::emd(x, with([](auto& c) { c.max_imfs = -1; })), std::invalid_argument);
  Eigen::VectorXd bad = x;
  bad[17] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(emd::emd(bad, {}), std::domain_error);
  auto ensemble = [](auto change) {
    emd::EnsembleConfig c;
    change(c);
    return c;
  };
  EXPECT_THROW(emd::eemd(x, ensemble([](auto& c) { c.ensemble_size = 0; })), std::invalid_argument);
  EXPECT_THROW(emd::eemd(x, ensemble([](auto& c) { c.noise_strength = -0.1; })), std::invalid_argument);
  EXPECT_THROW(emd::eemd(x, ensemble([](auto& c) { c.threads = 0; })), std::invalid_argument);
  EXPECT_THROW(emd::ceemdan(x, {.ensemble = ensemble([](auto& c) { c.max_imfs = -2; })}), std::invalid_argument);
  EXPECT_THROW(emd::ceemdan(bad, {}), std::domain_error);
}

// ---- EEMD / CEEMDAN ----------------------------------------------------------------------------

TEST(Eemd, ReconstructsTheInputToRoundingWithTheResidueSetToXMinusTheImfs) {
  const Eigen::VectorXd x = busy_signal(2000, 2);
  const auto r = emd::eemd(x, small_ensemble(5, 2));
  EXPECT_GE(r.imfs.cols(), 5);
  EXPECT_LT(reconstruction_error(x, r), kRoundingTolerance);
}

TEST(Eemd, GivesTheSameBitsForOneTwoAndThreeThreadsAndOtherBitsForAnotherSeed) {
  const Eigen::VectorXd x = busy_signal(1500, 4);
  const auto one = emd::eemd(x, small_ensemble(42, 1));
  for (unsigned threads : {2u, 3u}) {
    const auto r = emd::eemd(x, small_ensemble(42, threads));
    EXPECT_EQ(r.imfs, one.imfs) << threads << " threads";
    EXPECT_EQ(r.residue, one.residue) << threads << " threads";
    EXPECT_EQ(r.sifts, one.sifts) << threads << " threads";
  }
  const auto other = emd::eemd(x, small_ensemble(43, 2));
  EXPECT_FALSE(other.imfs.cols() == one.imfs.cols() && other.imfs == one.imfs);
}

TEST(Eemd, WithoutNoiseEqualsEmd) {
  // Every member is the plain signal, so the ensemble mean is EMD up to the rounding of the mean.
  constexpr double kMeanOfEqualTermsTolerance = 1e-12;
  const Eigen::VectorXd x = busy_signal(1500, 6);
  auto c = small_ensemble(1, 2);
  c.noise_strength = 0.0;
  const auto e = emd::eemd(x, c);
  const auto plain = emd::emd(x, {});
  ASSERT_EQ(e.imfs.cols(), plain.imfs.cols());
  EXPECT_LT((e.imfs - plain.imfs).cwiseAbs().maxCoeff(), kMeanOfEqualTermsTolerance);
}

TEST(Eemd, AlignsImfCountsToMaxImfsWhenGiven) {
  const Eigen::VectorXd x = busy_signal(1500, 8);
  auto c = small_ensemble(3, 1);
  c.max_imfs = 4;
  const auto r = emd::eemd(x, c);
  EXPECT_EQ(r.imfs.cols(), 4);
  EXPECT_LT(reconstruction_error(x, r), kRoundingTolerance);
}

// Progress (emd::Progress): fractions in [0, 1), increasing (testing_progress::checked_fractions),
// reported on the calling thread, and the decomposition bit-identical with or without a listener.
using testing_progress::checked_fractions;

TEST(EmdProgress, EmdReportsEachImfAndGivesTheSameBits) {
  const Eigen::VectorXd x = busy_signal(1500, 21);
  std::vector<double> fractions;
  const auto r = emd::emd(x, {.progress = [&](double f) { fractions.push_back(f); }});
  const auto plain = emd::emd(x, {});
  EXPECT_EQ(r.imfs, plain.imfs);
  EXPECT_EQ(r.residue, plain.residue);
  const int cap = static_cast<int>(std::floor(std::log2(1500.0)));
  // One report after each IMF but the last of the cap (the caller ends the task).
  EXPECT_EQ(static_cast<long>(checked_fractions(fractions).size()), std::min<long>(r.imfs.cols(), cap - 1));
  EXPECT_DOUBLE_EQ(fractions.front(), 1.0 / cap);
}

TEST(EmdProgress, EemdReportsEachBatchOfMembersAndGivesTheSameBits) {
  const Eigen::VectorXd x = busy_signal(1500, 22);
  auto c = small_ensemble(5, 2);  // 2 threads: batches of 2 members
  const auto plain = emd::eemd(x, c);
  std::vector<double> fractions;
  c.progress = [&](double f) { fractions.push_back(f); };
  const auto r = emd::eemd(x, c);
  EXPECT_EQ(r.imfs, plain.imfs);
  const int batches = (c.ensemble_size + 1) / 2;
  EXPECT_EQ(static_cast<int>(checked_fractions(fractions).size()), batches - 1);
}

TEST(EmdProgress, CeemdanReportsEveryBatchOfMembersOfEveryStageAndGivesTheSameBits) {
  const Eigen::VectorXd x = busy_signal(1500, 23);
  auto c = small_ensemble(6, 1);  // 1 thread: one member per batch
  const auto plain = emd::ceemdan(x, {.ensemble = c});
  std::vector<double> fractions;
  c.progress = [&](double f) { fractions.push_back(f); };
  const auto r = emd::ceemdan(x, {.ensemble = c});
  EXPECT_EQ(r.imfs, plain.imfs);
  EXPECT_EQ(r.residue, plain.residue);
  // Every member of every stage, but not the last report of a decomposition that fills its cap.
  EXPECT_GE(checked_fractions(fractions).size(), static_cast<std::size_t>(c.ensemble_size * r.imfs.cols() - 1));
}

class CeemdanVariants : public ::testing::TestWithParam<emd::CeemdanVariant> {};

TEST_P(CeemdanVariants, ReconstructsTheInputToRounding) {
  const Eigen::VectorXd x = busy_signal(2000, 12);
  const auto r = emd::ceemdan(x, {.ensemble = small_ensemble(9, 2), .variant = GetParam()});
  EXPECT_GE(r.imfs.cols(), 5);
  EXPECT_LT(reconstruction_error(x, r), kRoundingTolerance);
}

TEST_P(CeemdanVariants, GivesTheSameBitsForOneTwoAndThreeThreadsAndOtherBitsForAnotherSeed) {
  const Eigen::VectorXd x = busy_signal(1500, 13);
  const auto one = emd::ceemdan(x, {.ensemble = small_ensemble(77, 1), .variant = GetParam()});
  for (unsigned threads : {2u, 3u}) {
    const auto r = emd::ceemdan(x, {.ensemble = small_ensemble(77, threads), .variant = GetParam()});
    EXPECT_EQ(r.imfs, one.imfs) << threads << " threads";
    EXPECT_EQ(r.residue, one.residue) << threads << " threads";
  }
  const auto other = emd::ceemdan(x, {.ensemble = small_ensemble(78, 3), .variant = GetParam()});
  EXPECT_FALSE(other.imfs.cols() == one.imfs.cols() && other.imfs == one.imfs);
}

TEST_P(CeemdanVariants, WithoutNoiseEqualsEmd) {
  // With eps0 = 0 every member's first mode of r_k is EMD's next IMF (both variants).
  constexpr double kMeanOfEqualTermsTolerance = 1e-12;
  const Eigen::VectorXd x = busy_signal(1500, 14);
  auto c = small_ensemble(1, 2);
  c.noise_strength = 0.0;
  const auto r = emd::ceemdan(x, {.ensemble = c, .variant = GetParam()});
  const auto plain = emd::emd(x, {});
  ASSERT_EQ(r.imfs.cols(), plain.imfs.cols());
  EXPECT_LT((r.imfs - plain.imfs).cwiseAbs().maxCoeff(), kMeanOfEqualTermsTolerance);
}

INSTANTIATE_TEST_SUITE_P(Emd, CeemdanVariants,
                         ::testing::Values(emd::CeemdanVariant::Torres2011, emd::CeemdanVariant::Colominas2014),
                         [](const auto& variant) {
                           return variant.param == emd::CeemdanVariant::Torres2011 ? "Torres2011" : "Colominas2014";
                         });

// ---- plugins -----------------------------------------------------------------------------------

TEST(EmdPlugins, DecomposeThroughTheRegistryAndReportSiftsAndOrthogonality) {
  Registry registry;
  register_builtin_plugins(registry);
  const Eigen::VectorXd x = busy_signal(1500, 15);
  for (const char* name : {"decomposition/emd", "decomposition/eemd", "decomposition/ceemdan"}) {
    const auto params =
        params_from_assignments(registry, name,
                                std::string(name) == "decomposition/emd" ? std::vector<std::string>{}
                                                                         : std::vector<std::string>{"ensemble_size=4"});
    auto decomposer = registry.create_as<Decomposer>({name, params});
    RunContext ctx;
    ctx.threads = 2;
    const auto d = decomposer->decompose(x, ctx);
    EXPECT_LT((x - d.imfs.rowwise().sum() - d.residue).cwiseAbs().maxCoeff(), kRoundingTolerance) << name;
    EXPECT_EQ(ctx.diagnostics["sifts_per_imf"].size(), static_cast<std::size_t>(d.imfs.cols())) << name;
    EXPECT_TRUE(ctx.diagnostics.contains("orthogonality_index")) << name;
  }
}

TEST(EmdPlugins, RejectFixedSiftsAboveTheSiftCapNamingBothParameters) {
  Registry registry;
  register_builtin_plugins(registry);
  try {
    params_from_assignments(registry, "decomposition/emd", {"stop_rule=fixed_sifts", "fixed_sifts=60", "max_sifts=50"});
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("fixed_sifts"), std::string::npos) << message;
    EXPECT_NE(message.find("max_sifts"), std::string::npos) << message;
  }
  EXPECT_NO_THROW(params_from_assignments(registry, "decomposition/emd", {"fixed_sifts=60", "max_sifts=50"}))
      << "the rule only applies to stop_rule fixed_sifts";
}

TEST(EmdPlugins, ReportANonFiniteSampleAsADataError) {
  Registry registry;
  register_builtin_plugins(registry);
  auto decomposer =
      registry.create_as<Decomposer>({"decomposition/emd", params_from_assignments(registry, "decomposition/emd", {})});
  Eigen::VectorXd x = busy_signal(100, 1);
  x[3] = std::nan("");
  RunContext ctx;
  EXPECT_THROW(decomposer->decompose(x, ctx), DataError);
}

// Rows of a numeric CSV with a header line, the first `skip` columns left out.
std::vector<std::vector<double>> read_numeric_csv(const std::string& path, std::size_t skip) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::stringstream fields(line);
    std::vector<double> row;
    for (std::string field; std::getline(fields, field, ',');) row.push_back(std::stod(field));
    rows.emplace_back(row.begin() + static_cast<std::ptrdiff_t>(skip), row.end());
  }
  return rows;
}

TEST(Emd, TheSteadySNumberRuleWithLinearEndsGivesLibeemdsImfs) {
  // tests/data/emd/README.md: libeemd 1.4.1's EMD (S_number 4, 50 sifts) of a 1000-sample record.
  const std::string dir = std::string(DRIFTLAB_TEST_DATA) + "/emd/";
  const auto record = read_numeric_csv(dir + "gyro_N1000.csv", 1);
  const auto libeemd = read_numeric_csv(dir + "emd_libeemd_N1000_imfs.csv", 1);
  ASSERT_EQ(record.size(), 1000u);
  ASSERT_EQ(libeemd.size(), 1000u);
  Eigen::VectorXd x(1000);
  for (Eigen::Index i = 0; i < x.size(); ++i) x[i] = record[static_cast<std::size_t>(i)][0];
  const auto column = [&](std::size_t k) {
    Eigen::VectorXd c(x.size());
    for (Eigen::Index i = 0; i < x.size(); ++i) c[i] = libeemd[static_cast<std::size_t>(i)][k];
    return c;
  };
  const std::size_t residual = libeemd.front().size() - 1;
  constexpr double kPrinted = 1e-9;  // relative; the reference is printed with 11 significant digits

  emd::EmdConfig steady;
  steady.sift.stop_rule = emd::StopRule::SNumberSteady;
  steady.sift.end_policy = emd::EndPolicy::Linear;
  const auto r = emd::emd(x, steady);
  ASSERT_GE(r.imfs.cols(), 6);
  for (Eigen::Index k = 0; k < r.imfs.cols(); ++k) {
    const Eigen::VectorXd theirs = column(static_cast<std::size_t>(k));
    EXPECT_LT((r.imfs.col(k) - theirs).cwiseAbs().maxCoeff(), kPrinted * theirs.cwiseAbs().maxCoeff()) << "IMF " << k;
  }
  // libeemd sifts on while it has rows left (here once more, a residue with one minimum and no
  // maximum); driftlab stops there (a single bump is the trend): its residue is libeemd's last rows.
  Eigen::VectorXd rest = Eigen::VectorXd::Zero(x.size());
  for (auto k = static_cast<std::size_t>(r.imfs.cols()); k <= residual; ++k) rest += column(k);
  EXPECT_LT((r.residue - rest).cwiseAbs().maxCoeff(), kPrinted * rest.cwiseAbs().maxCoeff());

  // Huang 2003's rule (the default) stops earlier on the same record: the IMFs differ.
  emd::EmdConfig plain = steady;
  plain.sift.stop_rule = emd::StopRule::SNumber;
  const auto p = emd::emd(x, plain);
  EXPECT_GT((p.imfs.col(0) - column(0)).cwiseAbs().maxCoeff(), 1e-3 * column(0).cwiseAbs().maxCoeff());
}

}  // namespace
}  // namespace driftlab
