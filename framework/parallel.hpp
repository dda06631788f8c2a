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
//
// parallel_graph(deps, threads, body): the same for items that depend on each other (a pipeline's
// steps). deps[i] lists the items that must finish before item i starts; every one is < i, so the
// index order is an order a serial loop could run them in.
//
// Contract:
//   - body(i) is called at most once per item, after every item in deps[i] has returned from body.
//   - At most max(threads, 1) items run at once (the calling thread is one of the workers). When a
//     worker is free it starts the ready item with the smallest index.
//   - Exceptions: once an item has failed, no item with a larger index starts (running ones
//     finish); items with a smaller index still run. After every started item has finished, the
//     exception of the failed item with the smallest index is rethrown: the one a serial loop would
//     have thrown, with every item before it run. Items after it may or may not have run.
//   - Determinism is the caller's part, as for parallel_for: body(i) reads only what its deps
//     wrote, and writes only its own places.
//   - threads <= 1 runs the items in index order on the calling thread.
// Cost: one mutex and condition variable; scheduling costs microseconds per item, so items should
// be whole steps, not loop bodies.
#pragma once

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <mutex>
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

template <class Body>
void parallel_graph(const std::vector<std::vector<std::size_t>>& deps, unsigned threads, const Body& body) {
  const std::size_t count = deps.size();
  if (threads <= 1 || count <= 1) {
    for (std::size_t i = 0; i < count; ++i) body(i);
    return;
  }
  std::vector<std::vector<std::size_t>> dependents(count);
  std::vector<std::size_t> waiting_on(count);
  for (std::size_t i = 0; i < count; ++i) {
    waiting_on[i] = deps[i].size();
    for (std::size_t d : deps[i]) dependents[d].push_back(i);
  }
  std::vector<bool> started(count, false);
  std::vector<std::exception_ptr> errors(count);
  std::size_t first_failed = count;
  std::size_t running = 0;
  std::mutex mutex;
  std::condition_variable changed;
  const auto next_ready = [&]() -> std::size_t {  // under the lock; count when none
    for (std::size_t i = 0; i < first_failed; ++i)
      if (!started[i] && waiting_on[i] == 0) return i;
    return count;
  };
  const auto work = [&] {
    std::unique_lock<std::mutex> lock(mutex);
    for (;;) {
      std::size_t item = count;
      changed.wait(lock, [&] { return (item = next_ready()) < count || running == 0; });
      if (item == count) return;  // nothing ready and nothing running that could make something ready
      started[item] = true;
      ++running;
      lock.unlock();
      std::exception_ptr error;
      try {
        body(item);
      } catch (...) {
        error = std::current_exception();
      }
      lock.lock();
      --running;
      if (error) {
        errors[item] = error;
        first_failed = std::min(first_failed, item);
      } else {
        for (std::size_t d : dependents[item]) --waiting_on[d];
      }
      changed.notify_all();
    }
  };
  const std::size_t workers = std::min<std::size_t>(threads, count);
  std::vector<std::thread> pool;
  pool.reserve(workers - 1);
  try {
    for (std::size_t w = 1; w < workers; ++w) pool.emplace_back(work);
  } catch (...) {  // fewer threads than asked: the ones started and this one do the work
  }
  work();
  for (std::thread& t : pool) t.join();
  if (first_failed < count) std::rethrow_exception(errors[first_failed]);
}

}  // namespace driftlab
