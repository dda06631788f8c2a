// The deterministic parallel loop and dependency graph (framework/parallel.hpp).
#include "framework/parallel.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace driftlab {
namespace {

// An item whose value is sensitive to rounding, so a changed order of operations would show.
double item_value(std::size_t i) {
  double v = 1.0 / static_cast<double>(i + 3);
  for (int k = 0; k < 50; ++k) v = std::sin(v * 1.7 + static_cast<double>(i) * 1e-3);
  return v;
}

// Per-item values and their sum in index order, computed on `threads` threads.
struct Outcome {
  std::vector<double> values;
  double sum = 0.0;
  std::vector<int> calls;
};

Outcome run_items(std::size_t count, unsigned threads) {
  Outcome out;
  out.values.assign(count, 0.0);
  std::vector<std::atomic<int>> calls(count);
  parallel_for(count, threads, [&](std::size_t i) {
    out.values[i] = item_value(i);
    calls[i].fetch_add(1);
  });
  for (double v : out.values) out.sum += v;
  for (const auto& c : calls) out.calls.push_back(c.load());
  return out;
}

TEST(ParallelFor, GivesTheSameResultsOnOneTwoAndSevenThreads) {
  const Outcome one = run_items(1000, 1);
  for (unsigned threads : {2u, 7u}) {
    const Outcome many = run_items(1000, threads);
    EXPECT_EQ(many.values, one.values) << threads << " threads";
    EXPECT_EQ(many.sum, one.sum) << threads << " threads";
    EXPECT_EQ(many.calls, std::vector<int>(1000, 1)) << threads << " threads";
  }
}

TEST(ParallelFor, TreatsZeroThreadsAsOne) { EXPECT_EQ(run_items(10, 0).values, run_items(10, 1).values); }

TEST(ParallelFor, CallsNothingForZeroItems) {
  for (unsigned threads : {1u, 2u, 7u}) {
    std::atomic<int> calls{0};
    EXPECT_NO_THROW(parallel_for(0, threads, [&](std::size_t) { calls.fetch_add(1); }));
    EXPECT_EQ(calls.load(), 0);
  }
}

TEST(ParallelFor, RunsEveryItemOnceWithMoreThreadsThanItems) {
  const Outcome one = run_items(3, 1);
  const Outcome many = run_items(3, 16);
  EXPECT_EQ(many.values, one.values);
  EXPECT_EQ(many.calls, std::vector<int>(3, 1));
}

TEST(ParallelFor, PassesAnExceptionThrownInAWorkerToTheCaller) {
  for (unsigned threads : {1u, 2u, 7u}) {
    try {
      parallel_for(20, threads, [](std::size_t i) {
        if (i == 13) throw std::runtime_error("item 13");
      });
      ADD_FAILURE() << "no exception with " << threads << " threads";
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()), "item 13") << threads << " threads";
    }
  }
}

TEST(ParallelFor, RethrowsTheFailureWithTheSmallestIndexAfterRunningEveryItemBeforeIt) {
  for (unsigned threads : {1u, 2u, 7u}) {
    std::vector<std::atomic<int>> calls(100);
    try {
      parallel_for(100, threads, [&](std::size_t i) {
        calls[i].fetch_add(1);
        if (i == 40 || i == 41 || i == 90) throw std::invalid_argument("item " + std::to_string(i));
      });
      ADD_FAILURE() << "no exception with " << threads << " threads";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()), "item 40") << threads << " threads";
    }
    for (std::size_t i = 0; i <= 40; ++i)
      EXPECT_EQ(calls[i].load(), 1) << "item " << i << ", " << threads << " threads";
  }
}

// A fixed graph of 60 items, each depending on up to three earlier ones (a pipeline's shape).
std::vector<std::vector<std::size_t>> layered_graph() {
  std::vector<std::vector<std::size_t>> deps(60);
  for (std::size_t i = 1; i < deps.size(); ++i)
    for (std::size_t k = 1; k <= 3; ++k)
      if ((i * 7 + k * 13) % 5 < 2 && i >= k * 3) deps[i].push_back(i - k * 3);
  return deps;
}

TEST(ParallelGraph, StartsEveryItemOnceAndOnlyAfterItsDependenciesOnAnyThreadCount) {
  const auto deps = layered_graph();
  for (unsigned threads : {1u, 2u, 7u}) {
    std::vector<std::atomic<bool>> done(deps.size());
    std::vector<std::atomic<int>> calls(deps.size());
    std::atomic<int> early_starts{0};
    std::vector<double> values(deps.size());
    parallel_graph(deps, threads, [&](std::size_t i) {
      for (std::size_t d : deps[i])
        if (!done[d].load()) early_starts.fetch_add(1);
      calls[i].fetch_add(1);
      values[i] = item_value(i);
      for (std::size_t d : deps[i]) values[i] += values[d];
      done[i].store(true);
    });
    EXPECT_EQ(early_starts.load(), 0) << threads << " threads";
    std::vector<double> serial(deps.size());
    for (std::size_t i = 0; i < deps.size(); ++i) {
      EXPECT_EQ(calls[i].load(), 1) << "item " << i << ", " << threads << " threads";
      serial[i] = item_value(i);
      for (std::size_t d : deps[i]) serial[i] += serial[d];
    }
    EXPECT_EQ(values, serial) << threads << " threads";
  }
}

TEST(ParallelGraph, RunsIndependentItemsAtTheSameTime) {
  // Two items without dependencies on two threads: each waits (a bounded while, not a time limit on
  // the test) for the other to have started. A serial run would see one item at a time.
  std::atomic<int> inside{0}, most_at_once{0};
  parallel_graph({{}, {}}, 2, [&](std::size_t) {
    const int now = inside.fetch_add(1) + 1;
    int seen = most_at_once.load();
    while (now > seen && !most_at_once.compare_exchange_weak(seen, now)) {
    }
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (most_at_once.load() < 2 && std::chrono::steady_clock::now() < give_up) std::this_thread::yield();
    inside.fetch_sub(1);
  });
  EXPECT_EQ(most_at_once.load(), 2);
}

TEST(ParallelGraph, ThrowsTheFirstFailureInIndexOrderAfterRunningEveryItemBeforeIt) {
  // 0 .. 9; item 4 and item 7 fail; item 5 reads item 4, so it never starts.
  std::vector<std::vector<std::size_t>> deps(10);
  deps[5] = {4};
  deps[8] = {0, 2};
  for (unsigned threads : {1u, 2u, 7u}) {
    std::vector<std::atomic<int>> calls(deps.size());
    try {
      parallel_graph(deps, threads, [&](std::size_t i) {
        calls[i].fetch_add(1);
        if (i == 4 || i == 7) throw std::runtime_error("item " + std::to_string(i));
      });
      ADD_FAILURE() << "no exception with " << threads << " threads";
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()), "item 4") << threads << " threads";
    }
    for (std::size_t i = 0; i <= 4; ++i) EXPECT_EQ(calls[i].load(), 1) << "item " << i << ", " << threads << " threads";
    EXPECT_EQ(calls[5].load(), 0) << threads << " threads";
  }
}

}  // namespace
}  // namespace driftlab
