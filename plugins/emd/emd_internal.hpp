// Internal to the EMD kernel (not part of the emd.hpp API): what its five files share.
//   extrema.cpp         interior extrema and zero crossings (AVX2 and portable scans)
//   end_conditions.cpp  the knots added beyond each end of an envelope (Mirror, Linear)
//   splines.cpp         not-a-knot envelope fits, their evaluation and the mean removal
//   sifting.cpp         Sifter: one IMF by repeated sifts
//   emd.cpp             emd, eemd and ceemdan (ensemble members through parallel_for)
// The methods, their conventions and their cost are documented in emd.hpp.
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <vector>

#include "plugins/emd/emd.hpp"

namespace driftlab::emd::detail {

using Index = std::ptrdiff_t;

constexpr int kNearest = 3;      // extrema of each kind looked at near an end
constexpr int kMaxEndKnots = 2;  // knots an end policy adds beyond an end, per envelope
constexpr Index kPad = kMaxEndKnots;
constexpr Index kWrittenPast = 3;  // extrema slots written past the last extremum by a scan
constexpr Index kGroup = 4;        // samples per vector group in the envelope evaluation

// Sifting storage, written before it is read: allocated without zeroing, so that pages never
// written (the capacity is sized for the densest possible extrema) are never touched. reserve()
// does not keep the contents.
class Buffer {
 public:
  void reserve(std::size_t capacity) {
    if (capacity <= capacity_) return;
    values_ = std::make_unique_for_overwrite<double[]>(capacity);
    capacity_ = capacity;
  }
  std::size_t capacity() const { return capacity_; }
  double* data() const { return values_.get(); }
  double& operator[](Index i) const { return values_[i]; }

 private:
  std::unique_ptr<double[]> values_;
  std::size_t capacity_ = 0;
};

struct Extrema {
  Buffer pos, val;  // interior extrema at [kPad, kPad + count), end knots around them
  Index count = 0;
};

struct ExtremaSet {
  Extrema max, min;
  Index zero_crossings = 0;

  bool siftable() const { return max.count >= 1 && min.count >= 1 && max.count + min.count >= 3; }
};

// ---- extrema.cpp ----------------------------------------------------------------------------

// True when the extrema of e lie more than 4 samples apart on average over n samples: their
// successor's extrema are then searched with the bit-mask scan (a hint for speed only).
bool sparse_extrema(const ExtremaSet& e, Index n);

// Interior extrema and zero crossings of a signal scanned block by block, in order, into `out`
// (counts added to). A flat run of equal samples that is a peak or a trough counts once, at its
// middle sample. A zero crossing is a change of sign bit between neighbouring samples.
class ExtremaScanner {
 public:
  // `sparse`: extrema expected more than 4 samples apart (a hint for speed only).
  ExtremaScanner(ExtremaSet& out, bool sparse) : out_(out), sparse_(sparse) {}

  // Scans x[i] for i in [from, to), from >= 1; x[0, from) must be the samples scanned before.
  // Blocks without two equal neighbouring samples in x[from - 2, to) take the branch-free strict
  // test; the others search for each change of direction.
  void scan(const double* x, Index from, Index to);

 private:
  void search(const double* x, Index from, Index to);

  ExtremaSet& out_;
  bool sparse_;
  int direction_ = 0;
};

// All interior extrema and zero crossings of x[0, n) into out (reset first).
void find_extrema(const double* x, Index n, bool sparse, ExtremaSet& out);

// ---- end_conditions.cpp ---------------------------------------------------------------------

// Extrema of one kind nearest to one end, nearest first; s = distance from the end sample.
struct NearEnd {
  std::array<double, kNearest> s{}, val{};
  int count = 0;
};

// Knots added beyond one end, nearest to the signal first; s <= 0.
struct EndKnots {
  std::array<double, kMaxEndKnots> s{}, val{};
  int count = 0;

  void add(double si, double vi) {
    s[count] = si;
    val[count] = vi;
    ++count;
  }
};

// The extrema of e nearest to sample 0, and to sample n - 1.
NearEnd near_start(const Extrema& e);
NearEnd near_finish(const Extrema& e, Index n);

// EndPolicy::Mirror at one end (emd.hpp): the knots of both envelopes from the extrema nearest to
// that end and the end sample's value.
void mirror_end(const NearEnd& max, const NearEnd& min, double end_value, EndKnots& max_knots, EndKnots& min_knots);

// EndPolicy::Linear at one end (emd.hpp): the one knot of the upper (or lower) envelope.
EndKnots linear_end(const NearEnd& near, double end_value, bool upper);

// ---- splines.cpp ----------------------------------------------------------------------------

// A cubic spline in the second-derivative form: knots (x[k], y[k]) and second derivatives m[k],
// k < knots. On [x_j, x_{j+1}], with h = x_{j+1} - x_j and dt = t - x_j,
//   S(t) = y_j + dt (b + dt (c + dt d)),  b = (y_{j+1} - y_j)/h - h (2 m_j + m_{j+1})/6,
//   c = m_j / 2,  d = (m_{j+1} - m_j) / (6 h);
// the coefficients are formed when a piece is evaluated, so a fit writes one value per knot.
struct Spline {
  const double *x = nullptr, *y = nullptr, *m = nullptr;
  Index knots = 0;
};

struct SplineScratch {
  Buffer second, ratio;

  void reserve(std::size_t capacity) {
    second.reserve(capacity);
    ratio.reserve(capacity);
  }
};

// One spline's knots (x[k], y[k]), k < n, x strictly increasing whole numbers, and where its fit
// writes: the second derivatives m (n values) and, for the rows solved one at a time, ratio.
struct SplineSystem {
  const double *x, *y;
  Index n;
  double *m, *ratio;
};

// Rows eliminated in vector lanes: ratio and second of lane l at step t in [4 t + l].
struct LaneScratch {
  Buffer ratio, second;

  void reserve(std::size_t capacity) {
    ratio.reserve(2 * capacity);
    second.reserve(2 * capacity);
  }
};

// Not-a-knot cubic splines through two knot sets (n >= 2 each), fitted together: fills m. The
// tridiagonal system of each spline with n >= 4 (rows 1..R, R = n - 2, for M_1..M_R; M_0 and
// M_{n-1} eliminated by the not-a-knot conditions) is eliminated from both ends at once, forward
// from row 1 and backward from row R, the four sweeps of the two splines in the four lanes of a
// vector (each waits on its previous row, four chains in flight overlap). The sweeps meet at rows
// meet, meet + 1 (meet = R - common - 1; the rows between the lanes' common reach and meet are
// swept forward one at a time), whose two eliminated equations give M_meet and M_{meet+1}; the
// back substitution then runs from there towards both ends, again four chains in four lanes.
void fit_splines(const SplineSystem& a, const SplineSystem& b, LaneScratch& scratch);

// Values of a spline at the samples t in [from, to) into out[t - from], writing up to
// groups * kGroup - 1 values past `to`. Piece j serves t in [x_j, x_{j+1}) (the last piece also
// beyond its right knot); `piece` is the piece serving `from` on entry (or an earlier one) and the
// one serving `to` on return. Each piece is evaluated kGroup samples at a time (vectorized), at
// least `groups` groups whatever its length, overwriting the next piece's first samples when it is
// shorter: the densely packed knots of the first IMFs (pieces of 1 to 8 samples) then cost no
// mispredicted branch. Whole pieces inside the block go four at a time, their cubics formed in
// vector lanes and evaluated at the same offsets (groups = 2..6; a transpose turns the offsets'
// vectors into the pieces' groups).
void evaluate_block(const Spline& spline, Index& piece, Index from, Index to, Index groups, double* out);

// h[i] -= (upper[i] + lower[i]) / 2 for i < count. With `sums`, adds sum h^2 and sum mean^2
// (before the subtraction) to sums[0] and sums[1].
void subtract_mean(double* h, const double* upper, const double* lower, Index count);
void subtract_mean(double* h, const double* upper, const double* lower, Index count, double* sums);

// h[t] -= (upper(t) + lower(t)) / 2 for t in [from, to), for sparse knots: one interval between
// consecutive knots of either spline at a time, the mean of the two pieces expanded about the
// interval's first sample, so each sample costs one cubic. `upper_piece` and `lower_piece` carry
// the pieces from block to block as in evaluate_block. With `sums`, adds sum h^2 and sum mean^2
// (before the subtraction) to sums[0] and sums[1].
void subtract_mean_by_intervals(const Spline& upper, const Spline& lower, Index& upper_piece, Index& lower_piece,
                                double* h, Index from, Index to);
void subtract_mean_by_intervals(const Spline& upper, const Spline& lower, Index& upper_piece, Index& lower_piece,
                                double* h, Index from, Index to, double* sums);

// ---- sifting.cpp ----------------------------------------------------------------------------

// Sifting workspace: buffers sized once per signal length, reused by every sift.
class Sifter {
 public:
  explicit Sifter(const SiftConfig& config) : config_(config) {}

  // Copies r into h while finding its extrema; false when r has too few extrema to sift.
  bool load(const double* r, double* h, Index n);

  // Sifts the loaded candidate h into an IMF; returns the number of sifts.
  long sift(double* h, Index n);

 private:
  static constexpr Index kBlock = 2048;
  static constexpr Index kDenseSpacing = 9;
  static constexpr Index kMaxGroups = 16;

  static Index groups_per_piece(Index knots, Index n);
  static Index add_end_knots(Extrema& e, const EndKnots& start, const EndKnots& finish, Index n);
  void reserve(Index n);
  void build_envelopes(const double* h, Index n);
  double sift_pass(double* h, Index n);

  SiftConfig config_;
  // Whether the last IMF's extrema were sparse: the residue left after it is no denser, so its
  // extrema search takes the bit-mask scan (a hint for speed only).
  bool sparse_residue_ = false;
  std::array<ExtremaSet, 2> sets_;
  int current_ = 0;
  SplineScratch upper_scratch_, lower_scratch_;
  LaneScratch lane_scratch_;
  Spline upper_, lower_;  // envelopes of the current candidate (knots in sets_[current_])
  std::vector<double> upper_values_ = std::vector<double>(kBlock + kMaxGroups * kGroup),
                      lower_values_ = std::vector<double>(kBlock + kMaxGroups * kGroup);  // one block each
};

}  // namespace driftlab::emd::detail
