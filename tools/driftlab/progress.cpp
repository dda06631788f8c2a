#include "tools/driftlab/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "framework/error.hpp"

namespace driftlab::cli {

std::string duration_text(double seconds) {
  char text[32];
  if (seconds < 60.0) {
    std::snprintf(text, sizeof text, "%.1f s", std::max(0.0, seconds));
    return text;
  }
  const long total = std::lround(seconds);
  if (total < 3600)
    std::snprintf(text, sizeof text, "%ld:%02ld", total / 60, total % 60);
  else
    std::snprintf(text, sizeof text, "%ld:%02ld:%02ld", total / 3600, total / 60 % 60, total % 60);
  return text;
}

namespace {

// ", about 0:30 left" when an estimate is allowed, else "".
std::string remaining_text(double fraction, double elapsed_s) {
  if (fraction < ProgressDisplay::kMinEstimateFraction || elapsed_s < ProgressDisplay::kMinEstimateS) return "";
  return ", about " + duration_text(elapsed_s * (1.0 - fraction) / fraction) + " left";
}

int percent(double fraction) { return static_cast<int>(fraction * 100.0); }

}  // namespace

ProgressDisplay::Mode ProgressDisplay::mode_for(bool quiet) {
  if (quiet) return Mode::Off;
  return ::isatty(STDERR_FILENO) ? Mode::Terminal : Mode::Lines;
}

double ProgressDisplay::line_interval_from_environment() {
  const char* text = std::getenv("DRIFTLAB_PROGRESS_INTERVAL_S");
  if (!text || !*text) return kLineIntervalS;
  char* end = nullptr;
  const double seconds = std::strtod(text, &end);
  if (*end != '\0' || !std::isfinite(seconds) || seconds < 0.0)
    throw ConfigError({"", 0, "DRIFTLAB_PROGRESS_INTERVAL_S"},
                      "expected a finite number of seconds >= 0, got " + quoted_excerpt(text));
  return seconds;
}

void ProgressDisplay::update(const std::string& label, double fraction) {
  if (mode_ == Mode::Off) return;
  fraction = std::clamp(std::isfinite(fraction) ? fraction : 0.0, 0.0, 1.0);
  const std::lock_guard<std::mutex> lock(mutex_);
  const auto now = Clock::now();
  auto task = started_.find(label);
  const bool started = task == started_.end();
  if (started) task = started_.emplace(label, now).first;
  const double elapsed_s = std::chrono::duration<double>(now - task->second).count();
  const bool done = fraction >= 1.0;
  const double since_output_s = std::chrono::duration<double>(now - last_output_).count();
  if (mode_ == Mode::Terminal) {
    if (started || done || since_output_s >= kRedrawS) {
      draw_terminal(label, fraction, elapsed_s, done);
      last_output_ = now;
    }
  } else if (started || done || since_output_s >= line_interval_s_) {
    write_line(label, fraction, elapsed_s, started, done);
    last_output_ = now;
  }
  if (done) started_.erase(task);
}

void ProgressDisplay::draw_terminal(const std::string& label, double fraction, double elapsed_s, bool done) {
  std::fprintf(out_, "\r%-40s %3d%%  elapsed %s%s\033[K", label.c_str(), percent(fraction),
               duration_text(elapsed_s).c_str(), done ? "" : remaining_text(fraction, elapsed_s).c_str());
  if (done) std::fputc('\n', out_);
  std::fflush(out_);
}

void ProgressDisplay::write_line(const std::string& label, double fraction, double elapsed_s, bool started, bool done) {
  if (done && started)  // a task reported only when finished
    std::fprintf(out_, "driftlab: %s: done\n", label.c_str());
  else if (done)
    std::fprintf(out_, "driftlab: %s: done in %s\n", label.c_str(), duration_text(elapsed_s).c_str());
  else if (started)
    std::fprintf(out_, "driftlab: %s: started\n", label.c_str());
  else
    std::fprintf(out_, "driftlab: %s: %d%%, %s elapsed%s\n", label.c_str(), percent(fraction),
                 duration_text(elapsed_s).c_str(), remaining_text(fraction, elapsed_s).c_str());
  std::fflush(out_);
}

}  // namespace driftlab::cli
