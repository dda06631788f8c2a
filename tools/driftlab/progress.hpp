// Progress of the `driftlab` commands on stderr, in one of three modes:
//   Terminal  stderr is a terminal: one line redrawn in place (at most every kRedrawS s, and at
//             the start and end of each task), "label  NN%  elapsed 0:12, about 0:30 left";
//   Lines     stderr is a file or a pipe: plain lines, one when a task starts, one when it ends
//             ("done in 12.3 s"), and in between at most one every `line_interval_s` s across all
//             tasks (kLineIntervalS, or $DRIFTLAB_PROGRESS_INTERVAL_S), each with the percentage,
//             the elapsed and the estimated remaining time;
//   Off       --quiet: nothing.
// A task is named by its label; it starts with its first update and ends with fraction >= 1.
// Remaining time is elapsed * (1 - f) / f, shown once f >= kMinEstimateFraction and at least
// kMinEstimateS have passed (a linear extrapolation: tasks whose pieces differ in cost make it
// coarse). Safe to call from several threads; calls are serialized.
#pragma once

#include <chrono>
#include <cstdio>
#include <map>
#include <mutex>
#include <string>

namespace driftlab::cli {

class ProgressDisplay {
 public:
  enum class Mode { Off, Terminal, Lines };
  static constexpr double kRedrawS = 0.1;               // terminal redraws, s
  static constexpr double kLineIntervalS = 5.0;         // plain lines between a task's start and end, s
  static constexpr double kMinEstimateFraction = 0.02;  // fraction before a remaining time is shown
  static constexpr double kMinEstimateS = 1.0;          // elapsed time before a remaining time is shown, s

  // Writes to `out` (stderr in the commands); Lines mode writes at most one line per
  // `line_interval_s` (s, >= 0) between a task's start and end.
  ProgressDisplay(Mode mode, std::FILE* out, double line_interval_s = kLineIntervalS)
      : mode_(mode), out_(out), line_interval_s_(line_interval_s) {}
  // The mode for a command: Off when quiet, else Terminal when stderr is a terminal, else Lines.
  static Mode mode_for(bool quiet);
  // The interval of plain lines: $DRIFTLAB_PROGRESS_INTERVAL_S when set (a finite number >= 0, s;
  // otherwise a ConfigError naming it), else kLineIntervalS.
  static double line_interval_from_environment();

  Mode mode() const { return mode_; }
  // Reports that task `label` is `fraction` done (clamped to [0, 1]).
  void update(const std::string& label, double fraction);

 private:
  using Clock = std::chrono::steady_clock;
  void draw_terminal(const std::string& label, double fraction, double elapsed_s, bool done);
  void write_line(const std::string& label, double fraction, double elapsed_s, bool started, bool done);

  Mode mode_;
  std::FILE* out_;
  double line_interval_s_;
  std::mutex mutex_;
  std::map<std::string, Clock::time_point> started_;  // tasks under way: label -> start
  Clock::time_point last_output_{};                   // last redraw (Terminal) or line (Lines)
};

// "12.3 s" below a minute, else "m:ss" or "h:mm:ss".
std::string duration_text(double seconds);

}  // namespace driftlab::cli
