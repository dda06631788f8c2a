// Empirical mode decomposition and its noise-assisted ensembles, as pure numerical kernels.
//
//   emd      Huang et al. 1998, "The empirical mode decomposition and the Hilbert spectrum for
//            nonlinear and non-stationary time series analysis", Proc. R. Soc. Lond. A 454, §5.
//   eemd     Wu & Huang 2009, "Ensemble empirical mode decomposition: a noise-assisted data
//            analysis method", Adv. Adapt. Data Anal. 1(1), §3 (steps 1-4).
//   ceemdan  Torres, Colominas, Schlotthauer & Flandrin 2011, "A complete ensemble empirical mode
//            decomposition with adaptive noise", ICASSP 2011, §3 (steps 1-6); and the improved
//            variant of Colominas, Schlotthauer & Torres 2014, "Improved complete ensemble EMD: a
//            suitable tool for biomedical signal processing", Biomed. Signal Process. Control 14,
//            §3 (steps 1-6).
//
// Sifting (Huang 1998 §5, eqs. 5.1-5.5). One sift of a candidate h:
//   1. local extrema of h: interior samples only (the two end samples are never extrema); a flat
//      run of equal samples that is a peak or a trough counts once, at its middle sample;
//   2. upper envelope u = cubic spline through the maxima, lower envelope l through the minima,
//      both extended past the ends by the end-effect policy below;
//   3. h <- h - (u + l) / 2.
// Splines use the NOT-A-KNOT end condition (third derivative continuous across the second and the
// next-to-last knot, as MATLAB's spline, scipy's CubicSpline and libeemd), solved as a tridiagonal
// system on the knots only (Thomas algorithm, diagonally dominant, no pivoting, eliminated from
// both ends towards the middle: the twisted factorization). With 3 knots the
// envelope is the parabola through them, with 2 knots the line.
// Knots sit at integer sample positions; the envelopes are evaluated on the sample grid, so the
// sampling rate plays no part in the decomposition.
//
// End effects (EndPolicy):
//   Mirror (default)  Rilling, Flandrin & Gonçalvès 2003, "On empirical mode decomposition and its
//                     algorithms" (the `boundary_conditions` rule of their emd.m, nbsym = 2): the
//                     two extrema of each kind nearest to an end are reflected about the extremum
//                     nearest to that end; but when the end sample lies beyond the nearest
//                     extremum of the other kind (below the nearest minimum, say, when a maximum
//                     is nearest), they are reflected about the end sample, which then also
//                     serves as a knot of that other envelope; and when a reflection would not
//                     reach past the end, both kinds are reflected about the end sample.
//                     Mirroring also reflects the local trend: where the signal still rises or
//                     falls steeply at an end, the envelopes bend there and the error can spread
//                     into the slower IMFs (see the tests); Linear suits strongly trending ends.
//   Linear            Wu & Huang 2009 §3 / libeemd: one extra knot per envelope at each end sample,
//                     its value extrapolated along the line through the two nearest extrema of that
//                     kind (held flat with only one), but never inside the signal: the upper knot is
//                     at least, the lower knot at most, the end sample's value.
//
// Stopping rules for sifting one IMF (StopRule); every rule also stops at `max_sifts`, and sifting
// stops early when the candidate has too few extrema to build envelopes:
//   SNumber     Huang, Wu, Long et al. 2003 ("A confidence limit for the empirical mode
//               decomposition and Hilbert spectral analysis", Proc. R. Soc. A 459, §4): stop after
//               `s_number` consecutive sifts in which the numbers of extrema and of zero crossings
//               differ by at most one. Default S = 4 with max_sifts = 50, libeemd's defaults.
//   SNumberSteady   libeemd's form of the S-number rule (libeemd 1.4, Luukko et al. 2016): the
//               S consecutive sifts must also each change the numbers of maxima, minima and zero
//               crossings by at most one in total from the sift before. With EndPolicy::Linear (its
//               end treatment) the IMFs equal libeemd's (tests/plugins/emd_test.cpp, to the 1e-11 of
//               its printed reference); it sifts more than SNumber (N = 1000: 73 sifts against 57).
//               SNumber stays the default: the paper's method cites Huang 2003, whose rule it is.
//   CauchySd    Huang 1998 eq. 5.5 in the aggregated form used by MATLAB's emd
//               ("SiftRelativeTolerance"): SD = sum_t (h_{k-1} - h_k)^2 / sum_t h_{k-1}^2; stop when
//               SD < sd_threshold (Huang suggests 0.2-0.3). The per-sample ratio of eq. 5.5 blows up
//               where h_{k-1} crosses zero; the aggregate does not.
//   FixedSifts  exactly `fixed_sifts` sifts per IMF (Wu & Huang 2009 use 10 for EEMD).
// A zero crossing is a change of sign bit between neighbouring samples.
//
// Decomposition stops when the residue has fewer than 3 extrema, or no maximum or no minimum (it is
// monotonic or a single bump: the trend), or when `max_imfs` IMFs were extracted. max_imfs = 0 means
// the automatic cap floor(log2 N) (EMD is a dyadic filter bank on noise, Wu & Huang 2004, so a
// record of N samples holds about log2 N modes); it only guards termination.
//
// Reconstruction: for all three methods the residue is x minus the IMFs, accumulated in extraction
// order, so x = sum_k imf_k + residue holds to rounding (a few ulps of max|x| per IMF).
//
// Ensembles (EEMD, CEEMDAN):
//   - Member i adds Gaussian white noise drawn from its own generator, seeded from (seed, i)
//     (splitmix64 of both into std::mt19937_64, Box-Muller normals), so members do not depend on
//     which thread runs them. Members run in batches of `threads` on as many threads
//     (framework/parallel.hpp); their contributions are summed in member order 0, 1, ..., I-1, so
//     the output is bit-identical for any thread count.
//   - noise_strength is relative to the population standard deviation of x (EEMD: the added noise
//     has std noise_strength * std(x); Wu & Huang 2009 recommend 0.2 with I = 100).
//   - EEMD IMF alignment: member k-th IMFs are averaged slot by slot; K = max_imfs when given,
//     otherwise the largest member IMF count, members with fewer IMFs contributing zeros to the
//     missing slots. The residue is NOT the mean of the member residues: it is set explicitly to
//     x - sum_k imf_k, which the mean would miss by the mean of the added noise.
//   - CEEMDAN computes one mode per stage from the common residue, so members are aligned by
//     construction. With noise residues w_i^(k) = w_i - E_1(w_i) - ... - E_k(w_i) kept per member
//     (E_k = k-th EMD mode, extracted lazily one per stage, so the noise of every member is
//     decomposed exactly once):
//       Torres2011     imf_1 = <E_1(x + eps0 std(x) w_i)>,
//                      imf_{k+1} = <E_1(r_k + eps0 std(r_k) E_k(w_i) / std(E_k(w_i)))>,
//                      r_{k+1} = r_k - imf_{k+1}     (paper eqs. for steps 1-4, scaling of the
//                      authors' reference code: each noise mode normalized to unit std);
//       Colominas2014  r_1 = <M(x + eps0 std(x) E_1(w_i) / std(E_1(w_i)))>, imf_1 = x - r_1,
//                      r_k = <M(r_{k-1} + eps0 std(r_{k-1}) E_k(w_i))>, imf_k = r_{k-1} - r_k,
//                      with M(y) = y - E_1(y) the local mean (paper eqs. 4-7, beta_k = eps0 std(r_k)).
//     A member whose noise has no k-th mode left (fewer than 3 extrema) adds no noise at that stage,
//     as in the authors' code; E_1(y) of a y with too few extrema is 0. Stages continue until the
//     residue has too few extrema or max_imfs (0: floor(log2 N)) is reached.
//
// Cost (N samples, K IMFs, S sifts per IMF, I members):
//   emd      O(S K N) time: one sift is one streaming pass over the samples in cache-sized blocks
//            (envelope evaluation walking the knots in order, mean removal, the Cauchy sums, then
//            the extrema and zero crossings of the new candidate while the block is still in
//            cache) plus O(number of extrema) for the splines (the two envelopes' systems
//            eliminated from both ends at once, four sweeps in four vector lanes, and substituted
//            back the same way; one stored value per knot). Extrema under 9 samples apart on
//            average have their envelopes evaluated piece by piece, four pieces at a time in
//            vector lanes, into block buffers, each piece 4 samples at a time with as many groups
//            as a piece 1.25 times the average needs; sparser ones have the mean removed interval
//            by interval. Extrema are found with AVX2 4 candidates at a time, packed by a lane
//            permutation (under 4 samples apart), or from 64-sample bit masks (sparser); without
//            AVX2 one candidate at a time with no branch on the data; blocks with flat runs search
//            for each turn. The vectorized loops are compiled for AVX2 and baseline x86-64
//            (framework/simd.hpp), with the same results.
//            O(N K) memory for the output plus O(N) workspace allocated once per call.
//   eemd     I times emd, spread over `threads`; memory O(N K (threads + 1)).
//   ceemdan  I (K + 1) single-IMF extractions plus one EMD of each member's noise, spread over
//            `threads`; memory O(N I) for the members' noise residues plus O(N K).
//
// Errors: std::invalid_argument for a bad configuration (e.g. s_number < 1), std::domain_error for
// bad data (a non-finite sample). An empty signal, or one with too few extrema, decomposes into
// zero IMFs and residue = x.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

namespace driftlab::emd {

enum class StopRule { SNumber, SNumberSteady, CauchySd, FixedSifts };
enum class EndPolicy { Mirror, Linear };
enum class CeemdanVariant { Torres2011, Colominas2014 };

// Progress of a decomposition: called on the calling thread (never from a worker) with the
// fraction of the work done, in [0, 1), non-decreasing; emd after each IMF, eemd after each batch
// of members, ceemdan after each batch of members of each stage. The fraction counts the IMF cap
// (max_imfs, or floor(log2 N)) as the number of IMFs, so it jumps when the decomposition stops
// earlier. Empty: not called. It never changes the result.
using Progress = std::function<void(double fraction)>;

struct SiftConfig {
  StopRule stop_rule = StopRule::SNumber;
  int s_number = 4;           // S of SNumber and SNumberSteady
  double sd_threshold = 0.2;  // Cauchy SD threshold (dimensionless)
  int fixed_sifts = 10;       // sifts per IMF for FixedSifts
  int max_sifts = 50;         // cap for every rule
  EndPolicy end_policy = EndPolicy::Mirror;
};

struct EmdConfig {
  SiftConfig sift;
  int max_imfs = 0;  // 0: until the residue has too few extrema, at most floor(log2 N)
  Progress progress;
};

struct EnsembleConfig {
  SiftConfig sift;
  int max_imfs = 0;             // EEMD: fixed K when > 0; CEEMDAN: cap on stages (0: floor(log2 N))
  int ensemble_size = 100;      // I, number of noise realizations
  double noise_strength = 0.2;  // eps0, noise std relative to std(x)
  std::uint64_t seed = 1;
  unsigned threads = 1;  // results do not depend on it
  Progress progress;
};

struct CeemdanConfig {
  EnsembleConfig ensemble;
  CeemdanVariant variant = CeemdanVariant::Torres2011;
};

struct Result {
  Eigen::MatrixXd imfs;     // samples x K, highest frequency first
  Eigen::VectorXd residue;  // x - sum of the IMFs
  // Sifts spent on each IMF: EMD per IMF; EEMD and CEEMDAN summed over the members (the noise's
  // own decomposition in CEEMDAN not included).
  std::vector<long> sifts;
};

Result emd(const Eigen::VectorXd& x, const EmdConfig& config);
Result eemd(const Eigen::VectorXd& x, const EnsembleConfig& config);
Result ceemdan(const Eigen::VectorXd& x, const CeemdanConfig& config);

// Overall orthogonality index, Huang 1998 eq. 6.5 with the sums over time taken before the ratio:
//   IO = sum_t sum_{j != k} c_j(t) c_k(t) / sum_t x(t)^2,
// over the IMFs and the residue (c_{K+1}). Because the components sum to x this equals
// 1 - sum_j sum_t c_j(t)^2 / sum_t x(t)^2. Near 0 for an orthogonal decomposition; Huang reports
// values of order 1e-3 to 1e-2 for well-behaved signals. O(N K). Requires sum x^2 > 0.
double orthogonality_index(const Eigen::VectorXd& x, const Eigen::MatrixXd& imfs, const Eigen::VectorXd& residue);

}  // namespace driftlab::emd
