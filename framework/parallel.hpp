// parallel_for: the one loop that spreads independent work items over threads, used by every
// kernel that runs in parallel (ridge blocks, GA and pagmo evaluations, sample entropy per IMF,
// ensemble EMD members). Header-only, std only, so kernels (Eigen/std only) may use it.
//
// parallel_for(count, threads, body) calls body(i) exactly once for every i in [0, count) (unless
// an item fails, below) and returns when all calls have finished.
//
// Contract:
//   - Chunking is fixed: with workers = min(max(threads, 1), count), item i goes to worker
//     i % workers, and each worker takes its items in increasing order. Worker 0 is the calling
//     thread; the others are std::threads started for this call and joined before it returns. If
//     the system refuses to start a thread, the calling thread also runs that worker's items.
//   - Determinism is the caller's part: body(i) must compute item i from i and from data no other
//     item writes, and write only places no other item touches (e.g. results[i]). The result then
//     never depends on the thread count. Reductions over the items are left to the caller: store
//     per-item results and combine them in index order after the call.
//   - body is called from several threads at once.
//   - Exceptions: an exception leaving body(i) is caught; once an item has failed, the items with a
//     larger index may be skipped (never one with a smaller index). After all threads have joined,
//     the exception of the failed item with the smallest index is rethrown: the one a serial loop
//     would have thrown.
//   - threads = 0 counts as 1; with one worker (or count <= 1) the items run on the calling thread
//     and no thread is started. count = 0 calls nothing.
//
// Cost: workers - 1 thread starts and joins per call (some tens of microseconds), so items should
// be much larger than that. Items are dealt round-robin, not stolen: items of very unequal cost
// keep the other workers waiting for the slowest.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <thread>
#include <vector>

namespace driftlab {

template <class Body>
void parallel_for(std::size_t count, unsigned threads, const Body& body) {
  const std::size_t workers = std::min<std::size_t>(std::max(threads, 1u), count);
  if (workers <= 1) {
    for (std::size_t i = 0; i < count; ++i) body(i);
    return;
  }
  // Per worker, its first failed item (the smallest index among its items, taken in order).
  struct Failure {
    std::size_t index = 0;
    std::exception_ptr error;
  };
  std::vector<Failure> failures(workers);
  std::atomic<std::size_t> first_failed{count};
  const auto run = [&](std::size_t worker) {
    for (std::size_t i = worker; i < count; i += workers) {
      if (i > first_failed.load(std::memory_order_relaxed)) return;
      try {
        body(i);
      } catch (...) {
        failures[worker] = {i, std::current_exception()};
        std::size_t seen = first_failed.load(std::memory_order_relaxed);
        while (i < seen && !first_failed.compare_exchange_weak(seen, i, std::memory_order_relaxed)) {
        }
        return;
      }
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(workers - 1);
  std::size_t started = 1;
  try {
    for (; started < workers; ++started) pool.emplace_back(run, started);
  } catch (...) {  // no thread for workers [started, workers): they run here
  }
  for (std::size_t w = started; w < workers; ++w) run(w);
  run(0);
  for (std::thread& t : pool) t.join();
  const Failure* first = nullptr;
  for (const Failure& f : failures) {
    if (f.error && (!first || f.index < first->index)) first = &f;
  }
  if (first) std::rethrow_exception(first->error);
}

}  // namespace driftlab
