#include "plugins/sample_entropy/sample_entropy.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "plugins/builtins.hpp"
#include "framework/error.hpp"
#include "framework/params_io.hpp"
#include "framework/registry.hpp"

namespace driftlab {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

std::vector<double> gaussian_noise(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const auto uniform = [&] { return (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53; };
  std::vector<double> x(n);
  for (std::size_t i = 0; i < n; i += 2) {
    const double radius = std::sqrt(-2.0 * std::log(uniform()));
    const double angle = 2.0 * kPi * uniform();
    x[i] = radius * std::cos(angle);
    if (i + 1 < n) x[i + 1] = radius * std::sin(angle);
  }
  return x;
}

// The definition (Richman & Moorman 2000, PhysioNet sampen.c counts), O(N^2 m).
struct NaiveCounts {
  std::int64_t a = 0, b = 0;
};
NaiveCounts naive_counts(const std::vector<double>& x, int m, double r) {
  NaiveCounts c;
  const std::size_t length = static_cast<std::size_t>(m);
  if (x.size() <= length + 1) return c;
  const std::size_t templates = x.size() - length;
  for (std::size_t i = 0; i < templates; ++i) {
    for (std::size_t j = i + 1; j < templates; ++j) {
      std::size_t k = 0;
      while (k < length && std::fabs(x[i + k] - x[j + k]) < r) ++k;
      if (k < length) continue;
      ++c.b;
      if (std::fabs(x[i + length] - x[j + length]) < r) ++c.a;
    }
  }
  return c;
}

std::filesystem::path physionet_dir() {
  return std::filesystem::path(DRIFTLAB_SHARED_DATA) / "real" / "physionet-sampen";
}

std::vector<double> read_sampentest() {
  std::ifstream in(physionet_dir() / "sampentest.txt");
  std::vector<double> x;
  double v = 0.0;
  while (in >> v) x.push_back(v);
  return x;
}

struct Expected {
  int m;
  double r;
  bool normalize;
  std::string value;  // as printed, "Inf" included
  std::string implementation;
};

std::vector<Expected> read_expected() {
  std::ifstream in(physionet_dir() / "expected.csv");
  std::vector<Expected> rows;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (cells.size() < 8) continue;
    rows.push_back({std::stoi(cells[1]), std::stod(cells[2]), cells[3] == "yes", cells[5], cells[7]});
  }
  return rows;
}

TEST(SampleEntropy, ReproducesPhysioNetPublishedValuesOnSampentest) {
  if (!std::filesystem::exists(physionet_dir() / "expected.csv")) {
    GTEST_SKIP() << "PhysioNet reference data not found in " << physionet_dir();
  }
  // sampen.c prints six decimals: half a unit in the last printed place.
  constexpr double kPrintedSixDecimals = 0.5e-6;
  const auto x = read_sampentest();
  ASSERT_EQ(x.size(), 1024u);
  int checked = 0;
  for (const auto& e : read_expected()) {
    if (e.implementation.rfind("PhysioNet sampen.c", 0) != 0) continue;
    ASSERT_TRUE(e.normalize);
    const auto result = sampen::sample_entropy_relative(x, e.m, e.r);
    if (e.value == "Inf") {
      EXPECT_EQ(result.status, sampen::Status::NoMatches) << "m = " << e.m;
      EXPECT_EQ(result.a, 0) << "m = " << e.m;
      EXPECT_GT(result.b, 0) << "m = " << e.m;
      EXPECT_EQ(result.value, kInf) << "m = " << e.m;
    } else {
      EXPECT_TRUE(result.finite()) << "m = " << e.m;
      EXPECT_NEAR(result.value, std::stod(e.value), kPrintedSixDecimals) << "m = " << e.m;
    }
    ++checked;
  }
  EXPECT_EQ(checked, 6);  // m = 0 .. 5
}

TEST(SampleEntropy, MatchesTheFullPrecisionPythonPortWithAndWithoutNormalisation) {
  if (!std::filesystem::exists(physionet_dir() / "expected.csv")) {
    GTEST_SKIP() << "PhysioNet reference data not found in " << physionet_dir();
  }
  // Same counts, so only the rounding of -log(A / B) and of the normalisation can differ.
  constexpr double kLogRounding = 1e-12;
  const auto x = read_sampentest();
  int checked = 0;
  for (const auto& e : read_expected()) {
    if (e.implementation.rfind("Kinsa/sampen", 0) != 0) continue;
    const auto result =
        e.normalize ? sampen::sample_entropy_relative(x, e.m, e.r) : sampen::sample_entropy(x, e.m, e.r);
    EXPECT_NEAR(result.value, std::stod(e.value), kLogRounding) << "m = " << e.m << " normalize " << e.normalize;
    ++checked;
  }
  EXPECT_EQ(checked, 8);
}

TEST(SampleEntropy, ProfileGivesTheSameCountsAsSingleCalls) {
  const auto x = gaussian_noise(500, 7);
  const auto profile = sampen::sample_entropy_profile(x, 4, 0.3);
  ASSERT_EQ(profile.size(), 5u);
  for (int m = 0; m <= 4; ++m) {
    const auto single = sampen::sample_entropy(x, m, 0.3);
    EXPECT_EQ(profile[static_cast<std::size_t>(m)].a, single.a);
    EXPECT_EQ(profile[static_cast<std::size_t>(m)].b, single.b);
  }
}

constexpr std::array kCountings = {sampen::Counting::Automatic, sampen::Counting::Enumerate,
                                   sampen::Counting::RangeCount};

// Smooth records match almost everywhere (the enumeration's quadratic case, which range counting
// bounds; at this length Automatic still enumerates): a random walk and a slow sine with a little
// noise.
TEST(SampleEntropy, CountsEqualTheNaiveDefinitionOnSmoothRecords) {
  const std::size_t n = 3000;
  const auto steps = gaussian_noise(n, 77);
  std::vector<double> walk(n), sine(n);
  double position = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    walk[i] = position += steps[i];
    sine[i] = std::sin(2.0 * kPi * static_cast<double>(i) / 700.0) + 0.01 * steps[i];
  }
  for (const auto* x : {&walk, &sine}) {
    for (int m = 1; m <= 2; ++m) {
      const double r = 0.2 * sampen::population_sd(*x);
      const auto naive = naive_counts(*x, m, r);
      for (const auto counting : kCountings) {
        const auto fast = sampen::sample_entropy(*x, m, r, counting);
        ASSERT_EQ(fast.a, naive.a) << "m " << m << " counting " << static_cast<int>(counting);
        ASSERT_EQ(fast.b, naive.b) << "m " << m << " counting " << static_cast<int>(counting);
      }
    }
  }
}

TEST(SampleEntropy, CountsEqualTheNaiveDefinitionOnGaussianData) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    for (const std::size_t n : {2u, 3u, 10u, 97u, 400u, 900u}) {
      const auto x = gaussian_noise(n, seed * 1000 + n);
      for (int m = 0; m <= 5; ++m) {
        for (const double r : {0.05, 0.2, 0.5, 1.5}) {
          const auto naive = naive_counts(x, m, r);
          for (const auto counting : kCountings) {
            const auto fast = sampen::sample_entropy(x, m, r, counting);
            ASSERT_EQ(fast.a, naive.a) << "seed " << seed << " n " << n << " m " << m << " r " << r << " counting "
                                       << static_cast<int>(counting);
            ASSERT_EQ(fast.b, naive.b) << "seed " << seed << " n " << n << " m " << m << " r " << r << " counting "
                                       << static_cast<int>(counting);
          }
        }
      }
    }
  }
}

TEST(SampleEntropy, CountsEqualTheNaiveDefinitionOnIntegerDataWithTiesAtTheTolerance) {
  // Integer samples and integer r put many differences exactly at |d| = r, which must not match.
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    std::mt19937_64 rng(seed);
    for (const std::size_t n : {50u, 300u, 800u}) {
      for (const std::uint64_t levels : {2u, 5u, 12u}) {
        std::vector<double> x(n);
        for (auto& v : x) v = static_cast<double>(rng() % levels);
        for (int m = 0; m <= 4; ++m) {
          for (const double r : {0.0, 1.0, 2.0, 3.0}) {
            const auto naive = naive_counts(x, m, r);
            for (const auto counting : kCountings) {
              const auto fast = sampen::sample_entropy(x, m, r, counting);
              ASSERT_EQ(fast.a, naive.a) << "seed " << seed << " n " << n << " levels " << levels << " m " << m << " r "
                                         << r << " counting " << static_cast<int>(counting);
              ASSERT_EQ(fast.b, naive.b) << "seed " << seed << " n " << n << " levels " << levels << " m " << m << " r "
                                         << r << " counting " << static_cast<int>(counting);
            }
          }
        }
      }
    }
  }
}

TEST(SampleEntropy, WhiteNoiseIsNearItsClosedFormAndASineIsLow) {
  // For i.i.d. Gaussian samples A/B -> P(|X - Y| < r sd) = erf(r / 2), so SampEn -> -ln erf(r / 2)
  // (2.1848 at r = 0.2). Sampling error of A/B at N = 20000: a few hundredths.
  constexpr double kSamplingTolerance = 0.05;
  constexpr double kSineCeiling = 0.5;  // a sine is almost perfectly predictable
  const auto noise = sampen::sample_entropy_relative(gaussian_noise(20000, 3), 2, 0.2);
  EXPECT_NEAR(noise.value, -std::log(std::erf(0.1)), kSamplingTolerance);

  std::vector<double> sine(20000);
  for (std::size_t i = 0; i < sine.size(); ++i) sine[i] = std::sin(2.0 * kPi * static_cast<double>(i) / 50.0);
  const auto regular = sampen::sample_entropy_relative(sine, 2, 0.2);
  ASSERT_TRUE(regular.finite());
  EXPECT_LT(regular.value, kSineCeiling);
}

TEST(SampleEntropy, ReportsInfinityInsteadOfFailingWhenNothingMatches) {
  const std::vector<double> constant(100, 3.0);  // population SD 0 -> r = 0 -> nothing matches
  const auto flat = sampen::sample_entropy_relative(constant, 2, 0.2);
  EXPECT_EQ(flat.status, sampen::Status::Undefined);
  EXPECT_EQ(flat.value, kInf);

  const std::vector<double> short_signal{1.0, 2.0, 3.0};
  const auto too_short = sampen::sample_entropy(short_signal, 2, 10.0);
  EXPECT_EQ(too_short.status, sampen::Status::Undefined);
  EXPECT_EQ(too_short.b, 0);

  const std::vector<double> one_single_match{0.0, 5.0, 0.5, 20.0, 40.0, 60.0};  // B = 1, A = 0
  const auto no_long_match = sampen::sample_entropy(one_single_match, 1, 1.0);
  EXPECT_EQ(no_long_match.status, sampen::Status::NoMatches);
  EXPECT_EQ(no_long_match.b, 1);
  EXPECT_EQ(no_long_match.value, kInf);
}

TEST(SampleEntropy, RejectsNonFiniteSamplesAndNegativeParameters) {
  const std::vector<double> bad{1.0, std::nan(""), 2.0};
  EXPECT_THROW(sampen::sample_entropy(bad, 1, 0.2), std::invalid_argument);
  EXPECT_THROW(sampen::sample_entropy(gaussian_noise(10, 1), -1, 0.2), std::invalid_argument);
  EXPECT_THROW(sampen::sample_entropy(gaussian_noise(10, 1), 2, -0.1), std::invalid_argument);
}

std::vector<sampen::Group> groups_of(const std::vector<sampen::GroupDecision>& decisions) {
  std::vector<sampen::Group> g;
  for (const auto& d : decisions) g.push_back(d.group);
  return g;
}

using sampen::Group;

TEST(SampleEntropyGrouping, GapsRuleCutsAtTheTwoLargestGapsBetweenSortedValues) {
  // IMF order deliberately not monotone: the rule works on values, not positions.
  const std::vector<double> se{2.1, 1.2, 1.9, 0.3, 1.1, 0.1, 0.25};
  // sorted: 2.1 1.9 | 1.2 1.1 | 0.3 0.25 0.1 ; gaps 0.2 0.7 0.1 0.8 0.05 0.15
  const auto decisions = sampen::group_by_gaps(se);
  const std::vector<Group> expected{Group::Noise, Group::Mixed, Group::Noise, Group::Drift,
                                    Group::Mixed, Group::Drift, Group::Drift};
  EXPECT_EQ(groups_of(decisions), expected);
  for (const auto& d : decisions) {
    EXPECT_NE(d.reason.find("-> " + sampen::to_string(d.group)), std::string::npos) << d.reason;
  }
}

TEST(SampleEntropyGrouping, GapsRuleTreatsInfinityAsTheHighestEntropy) {
  const std::vector<double> se{kInf, 2.0, 1.9, 0.1};
  const std::vector<Group> expected{Group::Noise, Group::Mixed, Group::Mixed, Group::Drift};
  EXPECT_EQ(groups_of(sampen::group_by_gaps(se)), expected);
  const std::vector<double> two_infinite{kInf, kInf, 1.0, 0.9, 0.1};
  const std::vector<Group> expected_two{Group::Noise, Group::Noise, Group::Mixed, Group::Mixed, Group::Drift};
  EXPECT_EQ(groups_of(sampen::group_by_gaps(two_infinite)), expected_two);
}

TEST(SampleEntropyGrouping, GapsRuleWithoutEnoughGapsHasNoMixedOrOnlyMixed) {
  const std::vector<Group> one_gap{Group::Noise, Group::Drift};
  EXPECT_EQ(groups_of(sampen::group_by_gaps(std::vector<double>{1.0, 0.5})), one_gap);
  const std::vector<Group> two_levels{Group::Drift, Group::Noise, Group::Drift};
  EXPECT_EQ(groups_of(sampen::group_by_gaps(std::vector<double>{0.5, 1.0, 0.5})), two_levels);
  const std::vector<Group> none{Group::Mixed, Group::Mixed};
  EXPECT_EQ(groups_of(sampen::group_by_gaps(std::vector<double>{0.7, 0.7})), none);
  EXPECT_EQ(groups_of(sampen::group_by_gaps(std::vector<double>{0.7})), std::vector<Group>{Group::Mixed});
  EXPECT_TRUE(sampen::group_by_gaps(std::vector<double>{}).empty());
}

TEST(SampleEntropyGrouping, ThresholdsRuleUsesStrictBoundsAndRejectsCrossedThresholds) {
  const std::vector<double> se{1.5, 1.0, 0.6, 0.2, 0.1, kInf};
  const std::vector<Group> expected{Group::Noise, Group::Mixed, Group::Mixed, Group::Mixed, Group::Drift, Group::Noise};
  EXPECT_EQ(groups_of(sampen::group_by_thresholds(se, 1.0, 0.2)), expected);
  EXPECT_THROW(sampen::group_by_thresholds(se, 0.2, 0.2), std::invalid_argument);
}

class SampleEntropyPlugin : public ::testing::Test {
 protected:
  SampleEntropyPlugin() { register_builtin_plugins(registry_); }

  std::unique_ptr<Classifier> make(const std::vector<std::string>& assignments) {
    const auto params = params_from_assignments(registry_, "classifier/sample_entropy", assignments);
    return registry_.create_as<Classifier>(PluginSpec{"classifier/sample_entropy", params});
  }

  // Columns: white noise, a 10-sample-period sine with a little noise, a slow sine.
  static Eigen::MatrixXd three_imfs() {
    constexpr Eigen::Index kSamples = 4000;
    const auto noise = gaussian_noise(2 * kSamples, 11);
    Eigen::MatrixXd imfs(kSamples, 3);
    for (Eigen::Index i = 0; i < kSamples; ++i) {
      const double t = static_cast<double>(i);
      imfs(i, 0) = noise[static_cast<std::size_t>(i)];
      imfs(i, 1) = std::sin(2.0 * kPi * t / 10.0) + 0.3 * noise[static_cast<std::size_t>(kSamples + i)];
      imfs(i, 2) = std::sin(2.0 * kPi * t / 2000.0);
    }
    return imfs;
  }

  Registry registry_;
};

TEST_F(SampleEntropyPlugin, GroupsNoiseOscillationAndTrendAndLogsEveryDecision) {
  auto classifier = make({});
  RunContext ctx;
  const auto c = classifier->classify(three_imfs(), ctx);
  const std::vector<ImfGroup> expected{ImfGroup::Noise, ImfGroup::Mixed, ImfGroup::Drift};
  EXPECT_EQ(c.groups, expected);
  ASSERT_EQ(c.reasons.size(), 3u);
  ASSERT_EQ(c.scores.size(), 3u);
  EXPECT_GT(c.scores[0], c.scores[1]);
  EXPECT_GT(c.scores[1], c.scores[2]);
  ASSERT_EQ(ctx.diagnostics["sample_entropy"].size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(ctx.diagnostics["sample_entropy"][k]["reason"], c.reasons[k]);
    EXPECT_GT(ctx.diagnostics["sample_entropy"][k]["b"].get<std::int64_t>(), 0);
  }
}

TEST_F(SampleEntropyPlugin, GivesTheSameResultOnAnyNumberOfThreads) {
  auto classifier = make({"m=3", "rule=thresholds", "noise_above=1.5", "drift_below=0.1"});
  RunContext one, three;
  three.threads = 3;
  const auto a = classifier->classify(three_imfs(), one);
  const auto b = classifier->classify(three_imfs(), three);
  EXPECT_EQ(a.scores, b.scores);
  EXPECT_EQ(a.groups, b.groups);
  EXPECT_EQ(a.reasons, b.reasons);
}

TEST_F(SampleEntropyPlugin, RejectsThresholdsInTheWrongOrderNamingBothParameters) {
  try {
    make({"rule=thresholds", "noise_above=0.1", "drift_below=0.5"});
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("noise_above"), std::string::npos) << what;
    EXPECT_NE(what.find("drift_below"), std::string::npos) << what;
  }
}

TEST_F(SampleEntropyPlugin, ReportsNonFiniteImfSamplesAsDataErrors) {
  auto classifier = make({});
  Eigen::MatrixXd imfs = three_imfs();
  imfs(5, 1) = std::nan("");
  RunContext ctx;
  EXPECT_THROW(classifier->classify(imfs, ctx), DataError);
}

}  // namespace
}  // namespace driftlab
