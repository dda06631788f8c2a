// FFTW plans shared by the kernels that use FFTW (decomposition/vmd, filter/tfpf).
// Plan creation and destruction are not thread-safe (FFTW manual §5.4, "Thread safety"): only
// fftw_execute* may run concurrently. Every plan is therefore made and destroyed under one
// process-wide lock. Plans use FFTW_ESTIMATE (no measurement: the same plan, and the same bits,
// on every run).
#pragma once

#include <fftw3.h>

#include <mutex>
#include <stdexcept>

namespace driftlab::fftw {

inline std::mutex& planner_mutex() {
  static std::mutex mutex;
  return mutex;
}

// Owns one plan. `make` is called under the planner lock and returns the fftw_plan.
class Plan {
 public:
  template <class Make>
  explicit Plan(Make make) {
    const std::lock_guard<std::mutex> lock(planner_mutex());
    plan_ = make();
    if (!plan_) throw std::runtime_error("FFTW could not create a plan");
  }
  ~Plan() {
    const std::lock_guard<std::mutex> lock(planner_mutex());
    fftw_destroy_plan(plan_);
  }
  Plan(const Plan&) = delete;
  Plan& operator=(const Plan&) = delete;
  fftw_plan get() const { return plan_; }

 private:
  fftw_plan plan_ = nullptr;
};

}  // namespace driftlab::fftw
