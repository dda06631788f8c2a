#include "plugins/emd/emd.hpp"

#include "framework/parallel.hpp"
#include "framework/seeded_random.hpp"
#include "plugins/emd/emd_internal.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace driftlab::emd {

using detail::Index;
using detail::Sifter;

namespace {

void validate(const SiftConfig& c) {
  if (c.s_number < 1) throw std::invalid_argument("emd: s_number must be >= 1");
  if (!(c.sd_threshold > 0.0) || !std::isfinite(c.sd_threshold))
    throw std::invalid_argument("emd: sd_threshold must be a finite number > 0");
  if (c.fixed_sifts < 1) throw std::invalid_argument("emd: fixed_sifts must be >= 1");
  if (c.max_sifts < 1) throw std::invalid_argument("emd: max_sifts must be >= 1");
}

void validate(const EnsembleConfig& c) {
  validate(c.sift);
  if (c.max_imfs < 0) throw std::invalid_argument("emd: max_imfs must be >= 0");
  if (c.ensemble_size < 1) throw std::invalid_argument("emd: ensemble_size must be >= 1");
  if (!(c.noise_strength >= 0.0) || !std::isfinite(c.noise_strength))
    throw std::invalid_argument("emd: noise_strength must be a finite number >= 0");
  if (c.threads < 1) throw std::invalid_argument("emd: threads must be >= 1");
}

void check_finite(const Eigen::VectorXd& x) {
  for (Index i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i])) throw std::domain_error("emd: sample " + std::to_string(i) + " is not finite");
  }
}

int imf_cap(int max_imfs, Index n) {
  if (max_imfs > 0) return max_imfs;
  return n < 2 ? 0 : static_cast<int>(std::floor(std::log2(static_cast<double>(n))));
}

double population_std(const double* x, Index n) {
  if (n == 0) return 0.0;
  const Eigen::Map<const Eigen::VectorXd> v(x, n);
  return std::sqrt((v.array() - v.mean()).square().mean());
}

// One EMD: IMFs in the first `count` columns of imfs, residue in residue. Reuses its buffers
// across calls. The IMF matrix has room for `cap` columns; the pages of columns never written are
// never touched, and emd() hands the matrix over without copying it.
struct EmdWorkspace {
  explicit EmdWorkspace(const SiftConfig& sift) : sifter(sift) {}

  // `progress`, when set, is called with the fraction of `cap` IMFs extracted after each IMF.
  void decompose(const double* x, Index n, int cap, const Progress& progress = {}) {
    residue = Eigen::Map<const Eigen::VectorXd>(x, n);
    if (imfs.rows() != n || imfs.cols() < cap) imfs.resize(n, cap);
    sifts.assign(static_cast<std::size_t>(cap), 0);
    count = 0;
    while (count < cap) {
      double* imf = imfs.col(count).data();
      if (!sifter.load(residue.data(), imf, n)) break;
      sifts[count] = sifter.sift(imf, n);
      residue -= imfs.col(count);
      ++count;
      if (progress && count < cap) progress(static_cast<double>(count) / cap);
    }
  }

  Sifter sifter;
  Eigen::VectorXd residue;
  Eigen::MatrixXd imfs;
  std::vector<long> sifts;
  int count = 0;
};

void fill_gaussian(std::uint64_t seed, int member, double* out, Index n) {
  std::mt19937_64 rng(splitmix64(splitmix64(seed) + static_cast<std::uint64_t>(member)));
  constexpr double kTwoPow53 = 9007199254740992.0;
  for (Index i = 0; i < n; i += 2) {
    const double u1 = static_cast<double>((rng() >> 11) + 1) / kTwoPow53;
    const double u2 = static_cast<double>(rng() >> 11) / kTwoPow53;
    const double radius = std::sqrt(-2.0 * std::log(u1));
    const double angle = 2.0 * std::numbers::pi * u2;
    out[i] = radius * std::cos(angle);
    if (i + 1 < n) out[i + 1] = radius * std::sin(angle);
  }
}

// Runs work(member, slot) for every member and reduce(member, slot) in member order 0, 1, ...,
// members - 1. Members go in batches of `threads` (at most `members`) through parallel_for, member
// first + k of a batch in slot k < threads, and a batch is reduced before the next one starts, so
// a slot's buffers serve one member at a time. `reduced(done)`, when given, is called after each
// batch with the number of members reduced so far.
template <class Work, class Reduce>
void for_members_in_order(int members, unsigned threads, Work work, Reduce reduce,
                          const std::function<void(int done)>& reduced = {}) {
  const int batch = static_cast<int>(std::min<unsigned>(std::max(threads, 1u), static_cast<unsigned>(members)));
  for (int first = 0; first < members; first += batch) {
    const int size = std::min(batch, members - first);
    parallel_for(static_cast<std::size_t>(size), threads,
                 [&](std::size_t k) { work(first + static_cast<int>(k), static_cast<unsigned>(k)); });
    for (int k = 0; k < size; ++k) reduce(first + k, static_cast<unsigned>(k));
    if (reduced) reduced(first + size);
  }
}

Eigen::MatrixXd stack(const std::vector<Eigen::VectorXd>& columns, int count, Index n) {
  Eigen::MatrixXd out(n, count);
  for (int k = 0; k < count; ++k) out.col(k) = columns[k];
  return out;
}

}  // namespace

Result emd(const Eigen::VectorXd& x, const EmdConfig& config) {
  validate(config.sift);
  if (config.max_imfs < 0) throw std::invalid_argument("emd: max_imfs must be >= 0");
  check_finite(x);
  const Index n = x.size();
  EmdWorkspace ws(config.sift);
  ws.decompose(x.data(), n, imf_cap(config.max_imfs, n), config.progress);
  Result result;
  result.imfs = std::move(ws.imfs);
  result.imfs.conservativeResize(n, ws.count);  // drops the unused columns in place
  result.residue = std::move(ws.residue);
  result.sifts.assign(ws.sifts.begin(), ws.sifts.begin() + ws.count);
  return result;
}

Result eemd(const Eigen::VectorXd& x, const EnsembleConfig& config) {
  validate(config);
  check_finite(x);
  const Index n = x.size();
  const int cap = imf_cap(config.max_imfs, n);
  const double noise_std = config.noise_strength * population_std(x.data(), n);

  struct Worker {
    EmdWorkspace emd;
    Eigen::VectorXd member;
  };
  std::vector<Worker> workers;  // built in place: a sifter's buffers are not copied
  for (unsigned w = 0; w < std::max(1u, config.threads); ++w) workers.push_back({EmdWorkspace(config.sift), {}});
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(n, cap);
  std::vector<long> sifts(cap, 0);
  int widest = 0;

  for_members_in_order(
      config.ensemble_size, config.threads,
      [&](int i, unsigned w) {
        Worker& worker = workers[w];
        worker.member.resize(n);
        fill_gaussian(config.seed, i, worker.member.data(), n);
        worker.member = x + noise_std * worker.member;
        worker.emd.decompose(worker.member.data(), n, cap);
      },
      [&](int, unsigned w) {
        const EmdWorkspace& ws = workers[w].emd;
        for (int k = 0; k < ws.count; ++k) {
          sum.col(k) += ws.imfs.col(k);
          sifts[k] += ws.sifts[k];
        }
        widest = std::max(widest, ws.count);
      },
      [&](int done) {
        if (config.progress && done < config.ensemble_size)
          config.progress(static_cast<double>(done) / config.ensemble_size);
      });

  const int count = config.max_imfs > 0 ? cap : widest;
  Result result;
  result.imfs = sum.leftCols(count) / static_cast<double>(config.ensemble_size);
  result.residue = x;
  for (int k = 0; k < count; ++k) result.residue -= result.imfs.col(k);
  result.sifts.assign(sifts.begin(), sifts.begin() + count);
  return result;
}

Result ceemdan(const Eigen::VectorXd& x, const CeemdanConfig& config) {
  const EnsembleConfig& ens = config.ensemble;
  validate(ens);
  check_finite(x);
  const Index n = x.size();
  const int members = ens.ensemble_size;
  const int cap = imf_cap(ens.max_imfs, n);
  const bool torres = config.variant == CeemdanVariant::Torres2011;

  Eigen::MatrixXd noise(n, members);  // per member: w_i minus the modes extracted so far
  std::vector<char> noise_left(members, 1);

  struct Worker {
    explicit Worker(const SiftConfig& sift) : sifter(sift) {}
    Sifter sifter;
    Eigen::VectorXd mode, y, first;
    long sifts = 0;
  };
  std::vector<Worker> workers;  // built in place: a sifter's buffers are not copied
  for (unsigned w = 0; w < std::max(1u, ens.threads); ++w) workers.emplace_back(ens.sift);
  Sifter residue_check(ens.sift);
  Eigen::VectorXd scratch(n);

  std::vector<Eigen::VectorXd> imfs;
  std::vector<long> sifts;
  Eigen::VectorXd residue = x;
  Eigen::VectorXd sum(n);

  for (int stage = 0; stage < cap; ++stage) {
    if (!residue_check.load(residue.data(), scratch.data(), n)) break;
    const double residue_std = population_std(residue.data(), n);
    sum.setZero();
    long stage_sifts = 0;

    for_members_in_order(
        members, ens.threads,
        [&](int i, unsigned w) {
          Worker& worker = workers[w];
          worker.mode.resize(n);
          worker.y.resize(n);
          worker.first.resize(n);
          double* w_i = noise.col(i).data();
          if (stage == 0) fill_gaussian(ens.seed, i, w_i, n);
          double scale = 0.0;
          if (torres && stage == 0) {
            worker.mode = noise.col(i);
            scale = ens.noise_strength * residue_std;
          } else if (noise_left[i] && worker.sifter.load(w_i, worker.mode.data(), n)) {
            worker.sifter.sift(worker.mode.data(), n);
            noise.col(i) -= worker.mode;
            const double mode_std = population_std(worker.mode.data(), n);
            if (torres || stage == 0)
              scale = mode_std > 0.0 ? ens.noise_strength * residue_std / mode_std : 0.0;
            else
              scale = ens.noise_strength * residue_std;
          } else {
            noise_left[i] = 0;
          }
          if (scale > 0.0)
            worker.y = residue + scale * worker.mode;
          else
            worker.y = residue;
          worker.sifts = 0;
          if (worker.sifter.load(worker.y.data(), worker.first.data(), n))
            worker.sifts = worker.sifter.sift(worker.first.data(), n);
          else
            worker.first.setZero();
          if (!torres) worker.first = worker.y - worker.first;
        },
        [&](int, unsigned w) {
          sum += workers[w].first;
          stage_sifts += workers[w].sifts;
        },
        [&](int done) {
          if (!ens.progress) return;
          const double fraction = (stage + static_cast<double>(done) / members) / cap;
          if (fraction < 1.0) ens.progress(fraction);
        });

    sum /= static_cast<double>(members);
    if (torres) {
      imfs.push_back(sum);
      residue -= sum;
    } else {
      imfs.push_back(residue - sum);
      residue = sum;
    }
    sifts.push_back(stage_sifts);
  }

  Result result;
  result.imfs = stack(imfs, static_cast<int>(imfs.size()), n);
  result.residue = std::move(residue);
  result.sifts = std::move(sifts);
  return result;
}

double orthogonality_index(const Eigen::VectorXd& x, const Eigen::MatrixXd& imfs, const Eigen::VectorXd& residue) {
  if (imfs.rows() != x.size() || residue.size() != x.size())
    throw std::invalid_argument("orthogonality_index: IMFs, residue and signal lengths differ");
  const double signal_energy = x.squaredNorm();
  if (!(signal_energy > 0.0)) throw std::domain_error("orthogonality_index: the signal has zero energy");
  const double component_energy = imfs.colwise().squaredNorm().sum() + residue.squaredNorm();
  return (signal_energy - component_energy) / signal_energy;
}

}  // namespace driftlab::emd
