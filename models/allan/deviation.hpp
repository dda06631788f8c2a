// Allan-family deviations of a rate (frequency-like) or angle (phase-like) series.
//
// Definitions follow NIST SP 1065 "Handbook of Frequency Stability Analysis" (Riley 2008), which
// matches IEEE Std 1139-2008 and, for gyros, IEEE Std 952-1997 Annex C (an angular rate is the
// "fractional frequency" y, the integrated angle is the "phase" x). Everything is computed from the
// angle samples x_0..x_{n-1} (rad), spaced tau0 (s); tau = m*tau0 with averaging factor m:
//
//   ADEV   (SP1065 5.2.2)  sigma^2 = sum_{k} (x_{(k+2)m} - 2x_{(k+1)m} + x_{km})^2 / (2 M tau^2),
//                          non-overlapping, M = floor((n-1)/m) - 1 terms.
//   OADEV  (5.2.4)         same second difference at every start i, M = n - 2m terms.
//   MDEV   (5.2.5)         sigma^2 = sum_j (sum_{i=j}^{j+m-1} (x_{i+2m} - 2x_{i+m} + x_i))^2
//                                    / (2 m^2 tau^2 M),  M = n - 3m + 1 terms.
//   HDEV   (5.2.8)         sigma^2 = sum_k (x_{(k+3)m} - 3x_{(k+2)m} + 3x_{(k+1)m} - x_{km})^2
//                                    / (6 M tau^2), non-overlapping, M = floor((n-1)/m) - 2.
//   OHDEV  (5.2.9)         same third difference at every start i, M = n - 3m terms.
//   TOTDEV (5.2.11)        OADEV of the angle extended by reflection at both ends,
//                          x*_{-j} = 2x_0 - x_j and x*_{n-1+j} = 2x_{n-1} - x_{n-1-j}
//                          (j = 1..n-2), summed over the n-2 interior points:
//                          sigma^2 = sum_{i=1}^{n-2} (x*_{i-m} - 2x*_i + x*_{i+m})^2 / (2 tau^2 (n-2)).
//                          No bias correction (as Stable32 and the SP1065 NBS14 tables).
// A deviation has the unit of the rate (rad/s for angles in rad). A rate series y_0..y_{N-1} becomes
// the angle x_0 = 0, x_{k+1} = x_k + tau0 (y_k - mean(y)); removing the mean (a straight line in x)
// leaves every statistic unchanged and keeps the differences well conditioned.
//
// Cost: angle_from_rate O(N) (in place for an rvalue rate). deviations(): O(n) per averaging
// factor for every kind (running window for MDEV, strided sums for ADEV/HDEV; for the overlapping
// kinds and TOTDEV, short lags are swept along the record in cache-sized blocks that serve all of
// them, and lags that are multiples of a row width of ~n/512 samples are summed on column strips
// copied into an L2-sized buffer, so an octave grid reads the record from memory twice rather than
// once per lag). Memory O(n) (TOTDEV keeps the reflected record, 3n values).
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

namespace driftlab::allan {

enum class Kind { Adev, Oadev, Mdev, Hdev, Ohdev, Totdev };

// "adev", "oadev", "mdev", "hdev", "ohdev", "totdev".
std::string_view kind_name(Kind kind);
std::optional<Kind> parse_kind(std::string_view name);

// True for the Hadamard kinds (third differences: insensitive to a linear rate drift).
bool is_hadamard(Kind kind);

// Angle samples (n = rate.size() + 1) from rate samples spaced tau0 s, mean rate removed.
Eigen::VectorXd angle_from_rate(const Eigen::Ref<const Eigen::VectorXd>& rate, double tau0);

// The same, integrated in place: the rate's storage becomes the angle's (grown by one sample), so
// no second record-sized buffer is allocated. For long records that allocation costs about as much
// as the integration (page faults: ~50 ms for 1e7 samples on the reference machine).
Eigen::VectorXd angle_from_rate(Eigen::VectorXd&& rate, double tau0);

// Number of terms behind the estimate at averaging factor m for n angle samples (0 when the
// record is too short for that m).
std::size_t term_count(Kind kind, std::size_t n_angle, std::size_t m);

// Largest averaging factor with at least one term (TOTDEV: n-1, the reflected record's limit).
std::size_t max_factor(Kind kind, std::size_t n_angle);

struct Deviation {
  std::size_t m = 0;      // averaging factor
  double tau = 0.0;       // s
  double dev = 0.0;       // unit of the rate
  std::size_t terms = 0;  // number of terms summed
};

// Deviation at each averaging factor (in the given order). Throws driftlab::DataError when a
// factor is 0 or exceeds max_factor, or the record has fewer than 3 angle samples (4 for Hadamard).
std::vector<Deviation> deviations(Kind kind, const Eigen::Ref<const Eigen::VectorXd>& angle, double tau0,
                                  std::span<const std::size_t> factors);

}  // namespace driftlab::allan
