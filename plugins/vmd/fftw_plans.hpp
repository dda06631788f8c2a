// FFTW plan creation and destruction are not thread-safe (FFTW manual §5.4, "Thread safety"):
// only fftw_execute* may run concurrently. Every driftlab kernel that plans with FFTW takes this one
// process-wide lock around fftw_plan_* and fftw_destroy_plan. Plans are made with FFTW_ESTIMATE
// (no measurement, so the same plan and the same bits on every run).
#pragma once

#include <mutex>

namespace driftlab::fftw {

std::mutex& planner_mutex();

}  // namespace driftlab::fftw
