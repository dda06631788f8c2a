// The sampling facts of a record and its time blocks (framework/sampling.hpp), and the facts a
// TimeSeries carries (framework/time_series.hpp).
#include "framework/sampling.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "framework/time_series.hpp"

namespace driftlab {
namespace {

Eigen::VectorXd to_vector(const std::vector<double>& t) {
  return Eigen::Map<const Eigen::VectorXd>(t.data(), static_cast<Eigen::Index>(t.size()));
}

// Bursts of `per_burst` samples at 10 Hz, one every `period_s` seconds.
Eigen::VectorXd bursts(int count, int per_burst, double period_s) {
  std::vector<double> t;
  for (int b = 0; b < count; ++b)
    for (int i = 0; i < per_burst; ++i) t.push_back(period_s * b + 0.1 * i);
  return to_vector(t);
}

TEST(SamplingFacts, NameEvenSamplingRegularBurstsAndAnIrregularRecord) {
  const auto even = sampling::facts_of(Eigen::VectorXd::LinSpaced(101, 0.0, 10.0));
  EXPECT_EQ(even.layout(), sampling::Layout::Even);
  EXPECT_DOUBLE_EQ(even.mean_rate_hz, 10.0);
  ASSERT_EQ(even.segments.size(), 1u);
  EXPECT_EQ(even.segments[0].samples, 101);

  const auto regular = sampling::facts_of(bursts(5, 50, 300.0));
  EXPECT_EQ(regular.layout(), sampling::Layout::RegularBursts);
  EXPECT_EQ(regular.gaps, 4);
  EXPECT_EQ(regular.segments.size(), 5u);
  EXPECT_DOUBLE_EQ(regular.shortest_period_s, 300.0);

  std::vector<double> one_gap;
  for (int i = 0; i < 100; ++i) one_gap.push_back(i < 50 ? 0.1 * i : 100.0 + 0.1 * i);
  const auto irregular = sampling::facts_of(to_vector(one_gap));
  EXPECT_EQ(irregular.layout(), sampling::Layout::Irregular);
  EXPECT_EQ(irregular.first_gap_index, 49);
}

TEST(TimeSeriesSampling, CarriesTheFactsOfItsTimeStampsAndTheirGapFactor) {
  // Steps of 0.1 s with one of 0.25 s: a gap for the factor 2, none for the default 3.
  std::vector<double> t;
  for (int i = 0; i < 20; ++i) t.push_back(0.1 * i + (i >= 10 ? 0.15 : 0.0));
  TimeSeries record(to_vector(t));
  EXPECT_TRUE(record.sampling_facts().evenly_sampled());
  EXPECT_DOUBLE_EQ(record.sampling_facts().gap_factor, sampling::kGapFactor);
  record.set_gap_factor(2.0);
  EXPECT_EQ(record.sampling_facts().gaps, 1);
  EXPECT_EQ(record.sampling_facts().first_gap_index, 9);
  EXPECT_EQ(TimeSeries(to_vector(t), 2.0).sampling_facts().gaps, 1);
  EXPECT_DOUBLE_EQ(record.sample_rate_hz(), 19.0 / (t.back() - t.front()));
  EXPECT_EQ(TimeSeries().sample_rate_hz(), 0.0);
}

TEST(TimeBlocks, PutTimeStampsThatDoNotAddUpExactlyInTheBlockTheyNameAndSkipEmptyBlocks) {
  // Stamps 17.1 + k / 10 s: (17.1 + 60.0) - 17.1 falls an ulp below 60.0 in binary, and the sample
  // at k = 600 must still open block 1.
  std::vector<double> t;
  for (int k = 0; k < 1800; ++k) t.push_back(17.1 + k / 10.0);
  const auto blocks = sampling::time_blocks(to_vector(t), 60.0);
  ASSERT_EQ(blocks.size(), 3u);
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    EXPECT_EQ(blocks[b].first, static_cast<Eigen::Index>(600 * b));
    EXPECT_EQ(blocks[b].samples, 600);
    EXPECT_EQ(blocks[b].number, static_cast<long>(b));
  }
  const auto burst_blocks = sampling::time_blocks(bursts(3, 50, 300.0), 60.0);
  ASSERT_EQ(burst_blocks.size(), 3u);
  EXPECT_EQ(burst_blocks[1].number, 5);
  EXPECT_EQ(burst_blocks[2].first, 100);
  EXPECT_THROW(sampling::time_blocks(to_vector(t), 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace driftlab
