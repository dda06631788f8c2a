#include "plugins/vmd/fftw_plans.hpp"

namespace driftlab::fftw {

std::mutex& planner_mutex() {
  static std::mutex mutex;
  return mutex;
}

}  // namespace driftlab::fftw
