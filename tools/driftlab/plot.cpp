#include "tools/driftlab/plot.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "framework/number_text.hpp"
#include "framework/sampling.hpp"

extern char** environ;

namespace driftlab::cli {
namespace {

// Tableau's ten and two darker ones: neighbours in the list differ in hue and lightness.
constexpr std::array<const char*, 12> kColors = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b",
                                                 "#e377c2", "#17becf", "#7f7f7f", "#bcbd22", "#000000", "#393b79"};
constexpr std::size_t kReduceLinesAbove = 4;  // points per pixel column before lines are reduced
constexpr std::size_t kReduceMarkersAbove = 2000;
constexpr long kMarkerCellPx = 3;          // about a marker's diameter
constexpr double kCharWidthPx = 6.6;       // gnuplot's character width at 11 pt, for margins
constexpr double kVerticalMarginsPx = 86;  // title, x tick labels and x label of a panel
constexpr long kHiddenXAxisPx = 40;        // what a panel without x labels saves (bmargin 3.5 -> 0.8)

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

// A gnuplot single-quoted string: only '' is special; line breaks would end the command.
std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'')
      out += "''";
    else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      out += ' ';
    else
      out += c;
  }
  return out + "'";
}

bool usable(double v, bool log) { return std::isfinite(v) && (!log || v > 0); }

struct Range {
  double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
  bool log = false;
  void add(double v) {
    if (!usable(v, log)) return;
    const double u = log ? std::log10(v) : v;
    lo = std::min(lo, u), hi = std::max(hi, u);
  }
  bool empty() const { return !(hi >= lo); }
  // Index of the cell of v among `cells` equal cells of the range.
  long cell(double v, long cells) const {
    const double u = log ? std::log10(v) : v;
    if (!(hi > lo)) return 0;
    return std::clamp(static_cast<long>((u - lo) / (hi - lo) * static_cast<double>(cells)), 0L, cells - 1);
  }
};

struct Point {
  double x, y, low, high, z;
};

// The series' points in order; a NaN x marks a break in the line.
std::vector<Point> points_of(const PlotSeries& s, bool log_x, bool log_y) {
  const std::size_t n = std::min(s.x.size(), s.y.size());
  const bool interval = s.y_low.size() == n && s.y_high.size() == n && n > 0;
  const bool coloured = s.z.size() == n && n > 0;
  std::vector<Point> out;
  out.reserve(n);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  double gap = std::numeric_limits<double>::infinity();
  if (s.break_at_gaps && n > 2) {
    std::vector<double> steps;
    for (std::size_t i = 1; i < n; ++i)
      if (std::isfinite(s.x[i] - s.x[i - 1])) steps.push_back(std::abs(s.x[i] - s.x[i - 1]));
    if (!steps.empty()) {
      std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
      gap = sampling::kGapFactor * steps[steps.size() / 2];  // the records' gap rule
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0 && !out.empty() && !std::isnan(out.back().x) && std::abs(s.x[i] - out.back().x) > gap)
      out.push_back({nan, nan, nan, nan, nan});
    if (!usable(s.x[i], log_x) || !usable(s.y[i], log_y) || (coloured && !std::isfinite(s.z[i]))) {
      if (!out.empty() && !std::isnan(out.back().x)) out.push_back({nan, nan, nan, nan, nan});
      continue;
    }
    Point p{s.x[i], s.y[i], s.y[i], s.y[i], coloured ? s.z[i] : 0.0};
    if (interval) {
      p.low = usable(s.y_low[i], log_y) ? s.y_low[i] : s.y[i];
      p.high = usable(s.y_high[i], log_y) ? s.y_high[i] : s.y[i];
    }
    out.push_back(p);
  }
  while (!out.empty() && std::isnan(out.back().x)) out.pop_back();
  return out;
}

// Lines: each run of consecutive points in one pixel column becomes its min and max, in order; the
// first and last points stay, so the line spans the same x range.
std::vector<Point> reduce_line(const std::vector<Point>& pts, const Range& xr, long columns) {
  std::vector<Point> out;
  std::size_t i = 0;
  while (i < pts.size()) {
    if (std::isnan(pts[i].x)) {
      out.push_back(pts[i++]);
      continue;
    }
    const long c = xr.cell(pts[i].x, columns);
    std::size_t lo = i, hi = i, j = i;
    while (j < pts.size() && !std::isnan(pts[j].x) && xr.cell(pts[j].x, columns) == c) {
      if (pts[j].y < pts[lo].y) lo = j;
      if (pts[j].y > pts[hi].y) hi = j;
      ++j;
    }
    out.push_back(pts[std::min(lo, hi)]);
    if (lo != hi) out.push_back(pts[std::max(lo, hi)]);
    i = j;
  }
  const auto same = [](const Point& a, const Point& b) { return a.x == b.x && a.y == b.y; };
  if (!pts.empty() && !same(out.front(), pts.front())) out.insert(out.begin(), pts.front());
  if (!pts.empty() && !same(out.back(), pts.back())) out.push_back(pts.back());
  return out;
}

// Markers: the first point that lands on each cell of a columns x rows grid.
std::vector<Point> reduce_markers(const std::vector<Point>& pts, const Range& xr, const Range& yr, long columns,
                                  long rows) {
  std::vector<bool> seen(static_cast<std::size_t>(columns * rows), false);
  std::vector<Point> out;
  for (const auto& p : pts) {
    if (std::isnan(p.x)) continue;
    const auto k = static_cast<std::size_t>(xr.cell(p.x, columns) * rows + yr.cell(p.y, rows));
    if (seen[k]) continue;
    seen[k] = true;
    out.push_back(p);
  }
  return out;
}

std::string color_of(const PlotSeries& s, std::size_t index) {
  return s.color.empty() ? palette_color(index) : s.color;
}

// Panel geometry, in px of the SVG's viewBox (gnuplot's margins are in characters of ~6.6 x 15 px).
struct Geometry {
  double plot_width, plot_height;
};

// An axis range in data units, with the tick step (0: gnuplot's own, used on log axes).
struct Axis {
  double lo = 0, hi = 1, step = 0;
  bool log = false;
  double u(double v) const { return log ? std::log10(v) : v; }
  double fraction(double v) const { return (u(v) - u(lo)) / (u(hi) - u(lo)); }
  void raise_top(double fraction_of_height) {
    const double span = u(hi) - u(lo), top = u(hi) + span * fraction_of_height / (1 - fraction_of_height);
    hi = log ? std::pow(10.0, top) : top;
  }
};

double nice_step(double raw) {
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double r = raw / mag;
  return (r < 1.5 ? 1 : r < 3.5 ? 2 : r < 7.5 ? 5 : 10) * mag;
}

// The data range with about `ticks` ticks; `extend` widens it to whole steps (whole decades when
// log), `pad` adds that fraction of the span at both ends.
Axis make_axis(const Range& r, bool log, double ticks, bool extend, double pad) {
  double lo = r.empty() ? 0 : r.lo, hi = r.empty() ? 1 : r.hi;
  if (hi - lo <= 1e-12 * std::max(1.0, std::abs(lo))) {
    const double half = log ? 0.5 : lo != 0 ? std::abs(lo) * 0.1 : 1.0;
    lo -= half, hi += half;
  }
  lo -= pad * (hi - lo), hi += pad * (hi - lo);
  Axis a;
  a.log = log;
  if (log) {
    if (extend) lo = std::floor(lo + 1e-9), hi = std::ceil(hi - 1e-9);
    a.lo = std::pow(10.0, lo), a.hi = std::pow(10.0, hi);
    return a;
  }
  a.step = nice_step((hi - lo) / std::max(2.0, ticks));
  if (extend) lo = std::floor(lo / a.step + 1e-9) * a.step, hi = std::ceil(hi / a.step - 1e-9) * a.step;
  a.lo = lo, a.hi = hi;
  return a;
}

std::string range_commands(const char* name, const Axis& a) {
  std::string out = std::string("set ") + name + "range [" + number(a.lo) + ":" + number(a.hi) + "]\n";
  if (a.step > 0) out += std::string("set ") + name + "tics " + number(a.step) + "\n";
  if (a.log && a.hi < 100 * a.lo) {  // under two decades: ticks at 1, 2 and 5 (or every digit) x 10^k
    for (const std::vector<double>& mantissas : {std::vector<double>{1, 2, 5}, {1, 2, 3, 4, 5, 6, 7, 8, 9}}) {
      std::string list;
      int ticks = 0;
      for (double decade = std::pow(10.0, std::floor(std::log10(a.lo))); decade <= a.hi; decade *= 10)
        for (double m : mantissas)
          if (m * decade >= a.lo * (1 - 1e-9) && m * decade <= a.hi * (1 + 1e-9))
            list += (ticks++ ? "," : "") + number(m * decade);
      if (ticks < 2 && mantissas.size() == 3) continue;
      out +=
          std::string("set ") + name + "tics (" + list + ")\nset format " + name + " '%g'\nunset m" + name + "tics\n";
      break;
    }
  }
  return out;
}

std::size_t display_length(const std::string& s) {
  return static_cast<std::size_t>(std::count_if(s.begin(), s.end(), [](char c) { return (c & 0xC0) != 0x80; }));
}

// The legend's place: the requested corner, or (Auto) the corner where the least data lies; when
// every corner holds data, top right above the data, whose y axes get that much headroom.
// A legend beside the plot takes a right margin for `beside_chars` characters (the longest entry
// of the figure's column, so that stacked panels keep one plot width).
std::string legend_command(const PlotPanel& panel, const std::vector<std::vector<Point>>& data, const Axis& x, Axis& y,
                           Axis& y2, const Geometry& g, std::size_t beside_chars) {
  std::size_t labelled = 0, longest = 0;
  for (const auto& s : panel.series)
    if (!s.label.empty()) ++labelled, longest = std::max(longest, display_length(s.label));
  const bool only_the_title =
      labelled == 1 && std::any_of(panel.series.begin(), panel.series.end(),
                                   [&](const auto& s) { return !s.label.empty() && s.label == panel.title; });
  if (panel.legend == PlotPanel::Legend::None || labelled == 0 || only_the_title) return "unset key\n";
  const std::string style = " opaque box lc rgb '#bbbbbb' samplen 2.5 spacing 1.1 font ',10'\n";
  const char* names[] = {"top right", "top left", "bottom right", "bottom left"};
  if (panel.legend != PlotPanel::Legend::Auto)
    return std::string("set key inside ") + names[static_cast<int>(panel.legend)] + style;

  const double kw = std::min(0.9, (static_cast<double>(longest) * 6.0 + 60.0) / g.plot_width);
  const double kh = std::min(0.9, (static_cast<double>(labelled) * 14.0 + 12.0) / g.plot_height);
  std::array<std::size_t, 4> crowd{};
  const auto count = [&](double fx, double fy) {
    const bool right = fx > 1 - kw, left = fx<kw, top = fy> 1 - kh, bottom = fy < kh;
    crowd[0] += right && top, crowd[1] += left && top, crowd[2] += right && bottom, crowd[3] += left && bottom;
  };
  for (std::size_t k = 0; k < data.size(); ++k) {
    const Axis& ya = panel.series[k].right_axis ? y2 : y;
    const bool line = panel.series[k].style != PlotSeries::Style::Markers;
    const auto& pts = data[k];
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (std::isnan(pts[i].x)) continue;
      const double fx = x.fraction(pts[i].x);
      for (double v : {pts[i].y, pts[i].low, pts[i].high}) count(fx, ya.fraction(v));
      if (!line || i + 1 == pts.size() || std::isnan(pts[i + 1].x) || pts.size() > 1000) continue;
      constexpr int kSteps = 16;  // a few points along each segment of a short line
      for (int j = 1; j < kSteps; ++j) {
        const double t = static_cast<double>(j) / kSteps;
        count(fx + t * (x.fraction(pts[i + 1].x) - fx),
              ya.fraction(pts[i].y) + t * (ya.fraction(pts[i + 1].y) - ya.fraction(pts[i].y)));
      }
    }
  }
  const auto best = static_cast<std::size_t>(std::min_element(crowd.begin(), crowd.end()) - crowd.begin());
  if (crowd[best] == 0) return std::string("set key inside ") + names[best] + style;
  const bool right_axis =
      std::any_of(panel.series.begin(), panel.series.end(), [](const auto& s) { return s.right_axis; });
  if (!right_axis)  // beside the plot, in a right margin wide enough for the longest entry
    return "set rmargin " +
           std::to_string(static_cast<int>(static_cast<double>(std::max(longest, beside_chars)) * 0.95) + 9) +
           "\nset key outside right top" + style;
  y.raise_top(kh + 0.02);
  y2.raise_top(kh + 0.02);
  return std::string("set key inside top right") + style;
}

// Where a panel goes: the commands that put it in its cell of the figure (after `reset`), whether it
// labels its x axis, and the x range it shares with the others (empty: its own).
struct Placement {
  std::string commands;
  bool x_labels = true;
  Range shared_x, shared_y;
  std::size_t legend_chars = 0;  // the longest legend entry of the panel's column
};

void panel_script(std::string& script, const PlotPanel& panel, std::size_t index, const Geometry& g,
                  bool any_right_axis, const Placement& place) {
  const auto columns = static_cast<long>(g.plot_width), rows = static_cast<long>(g.plot_height);
  Range xr, yr, y2r;
  xr.log = panel.log_x, yr.log = panel.log_y, y2r.log = panel.log_y2;
  std::vector<std::vector<Point>> data;
  for (const auto& s : panel.series) {
    auto pts = points_of(s, panel.log_x, s.right_axis ? panel.log_y2 : panel.log_y);
    for (const auto& p : pts) {
      if (s.guide) continue;
      xr.add(p.x);
      (s.right_axis ? y2r : yr).add(p.low), (s.right_axis ? y2r : yr).add(p.high);
    }
    data.push_back(std::move(pts));
  }
  if (!place.shared_x.empty()) xr = place.shared_x;
  if (!place.shared_y.empty()) yr = place.shared_y;
  for (std::size_t k = 0; k < data.size(); ++k) {
    const auto& s = panel.series[k];
    if (!s.y_low.empty() || !s.y_high.empty()) continue;
    if (s.style == PlotSeries::Style::Markers) {
      if (data[k].size() > kReduceMarkersAbove)
        data[k] = reduce_markers(data[k], xr, s.right_axis ? y2r : yr, std::max(1L, columns / kMarkerCellPx),
                                 std::max(1L, rows / kMarkerCellPx));
    } else if (data[k].size() > kReduceLinesAbove * static_cast<std::size_t>(columns)) {
      data[k] = reduce_line(data[k], xr, columns);
    }
  }

  const std::string tag = "$p" + std::to_string(index) + "s";
  for (std::size_t k = 0; k < data.size(); ++k) {
    script += tag + std::to_string(k) + " << EOD\n";
    for (const auto& p : data[k]) {
      if (std::isnan(p.x)) {
        script += "\n";
        continue;
      }
      script += number(p.x) + " " + number(p.y) + " " + number(p.low) + " " + number(p.high) + " " + number(p.z) + "\n";
    }
    script += "EOD\n";
  }

  const bool markers = std::any_of(panel.series.begin(), panel.series.end(),
                                   [](const auto& s) { return s.style == PlotSeries::Style::Markers; });
  const Axis x = make_axis(xr, panel.log_x, g.plot_width / 90.0, false, markers ? 0.02 : 0.0);
  Axis y = make_axis(yr, panel.log_y, g.plot_height / 38.0, true, 0.0);
  Axis y2 = make_axis(y2r, panel.log_y2, g.plot_height / 38.0, true, 0.0);
  const std::string key = legend_command(panel, data, x, y, y2, g, place.legend_chars);

  script += "reset\n" + place.commands + "set encoding utf8\nset lmargin 12\nset bmargin 3.5\nset tmargin 2.2\n";
  script += any_right_axis ? "set rmargin 12\n" : "set rmargin 4\n";
  script += "set grid xtics ytics lc rgb '#dddddd' lw 1 dt solid\nset border lc rgb '#444444'\n";
  script += "set title " + quoted(panel.title) + " noenhanced font ',12'\n";
  script += "set xlabel " + quoted(panel.x_label) + " noenhanced offset 0,0.3\n";
  script += "set ylabel " + quoted(panel.y_label) + " noenhanced\n";
  script += "set format x '%g'\nset format y '%g'\nset xtics nomirror out\nset ytics out\n";
  if (panel.log_x) script += "set logscale x\nset format x '10^{%L}'\nset mxtics 10\n";
  if (panel.log_y) script += "set logscale y\nset format y '10^{%L}'\nset mytics 10\n";
  script += range_commands("x", x) + range_commands("y", y);
  const bool right = std::any_of(panel.series.begin(), panel.series.end(), [](const auto& s) { return s.right_axis; });
  if (right) {
    script += "set ytics nomirror\nset y2tics out\nset format y2 '%g'\nset y2label " + quoted(panel.y2_label) +
              " noenhanced\n";
    if (panel.log_y2) script += "set logscale y2\nset format y2 '10^{%L}'\n";
    script += range_commands("y2", y2);
  }
  const bool coloured = std::any_of(panel.series.begin(), panel.series.end(),
                                    [](const auto& s) { return !s.z.empty() && s.z.size() == s.y.size(); });
  if (coloured)
    script +=
        "set palette defined (0 '#440154', 0.25 '#3b528b', 0.5 '#21918c', 0.75 '#5ec962', 1 '#fde725')\n"
        "set cblabel " +
        quoted(panel.z_label) + " noenhanced\nset format cb '%g'\n";
  else
    script += "unset colorbox\n";
  if (!place.x_labels) script += "set format x ''\nunset xlabel\nset bmargin 0.8\n";
  script += key;

  std::vector<std::string> bands, items;
  for (std::size_t k = 0; k < data.size(); ++k) {
    const auto& s = panel.series[k];
    if (data[k].empty()) continue;
    const std::string src = tag + std::to_string(k);
    const std::string axes = s.right_axis ? " axes x1y2" : "";
    const std::string lc = " lc rgb '" + color_of(s, k) + "'";
    const std::string width = s.guide ? " lw 1" : " lw 1.3";
    const std::string title = s.label.empty() ? " notitle" : " title " + quoted(s.label) + " noenhanced";
    const bool interval = !s.y_low.empty() && s.y_low.size() == s.y.size() && s.y_high.size() == s.y.size();
    const bool band = interval && s.interval == PlotSeries::Interval::Band;
    if (band)
      bands.push_back(src + " using 1:3:4" + axes + " with filledcurves fs transparent solid 0.18 noborder" + lc +
                      " notitle");
    const bool z = s.z.size() == s.y.size() && !s.z.empty();
    std::string item;
    if (s.style == PlotSeries::Style::Markers) {
      if (interval && !band)
        item = src + " using 1:2:3:4" + axes + " with yerrorbars pt 7 ps 0.45 lw 1" + lc;
      else if (z)
        item = src + " using 1:2:5" + axes + " with points pt 7 ps 0.35 lc palette";
      else
        item = src + " using 1:2" + axes + " with points pt 7 ps 0.45" + lc;
    } else {
      const std::string dash = s.style == PlotSeries::Style::Dashed ? " dt (6,4)" : "";
      if (interval && !band)
        items.push_back(src + " using 1:2:3:4" + axes + " with yerrorbars pt 7 ps 0.3 lw 1" + lc + " notitle");
      item = src + " using 1:2" + axes + " with lines" + width + dash + lc;
    }
    items.push_back(item + title);
  }
  if (bands.empty() && items.empty()) {
    script += "set label 1 'no data' at graph 0.5,0.5 center\nplot NaN notitle\n";
    return;
  }
  std::string plot = "plot ";
  bool first = true;
  for (const auto* list : {&bands, &items})
    for (const auto& i : *list) {
      plot += (first ? "" : ", \\\n  ") + i;
      first = false;
    }
  script += plot + "\n";
}

std::string gnuplot_executable() {
  const char* env = std::getenv("DRIFTLAB_GNUPLOT");
  return env != nullptr && *env != '\0' ? env : "gnuplot";
}

struct Pipe {
  int fd[2] = {-1, -1};
  Pipe() {
    if (::pipe2(fd, O_CLOEXEC) != 0)
      throw PlotError(std::string("cannot create a pipe for gnuplot: ") + std::strerror(errno));
  }
  ~Pipe() {
    close_end(0);
    close_end(1);
  }
  void close_end(int e) {
    if (fd[e] >= 0) ::close(fd[e]);
    fd[e] = -1;
  }
  Pipe(const Pipe&) = delete;
  Pipe& operator=(const Pipe&) = delete;
};

// Blocks SIGPIPE in this thread while it writes to gnuplot, so a gnuplot that dies early shows up
// as EPIPE; a SIGPIPE raised meanwhile is consumed before the mask is restored.
class SigpipeBlock {
 public:
  SigpipeBlock() {
    sigemptyset(&pipe_);
    sigaddset(&pipe_, SIGPIPE);
    pthread_sigmask(SIG_BLOCK, &pipe_, &old_);
  }
  ~SigpipeBlock() {
    const timespec zero{0, 0};
    while (sigtimedwait(&pipe_, nullptr, &zero) > 0) {
    }
    pthread_sigmask(SIG_SETMASK, &old_, nullptr);
  }
  SigpipeBlock(const SigpipeBlock&) = delete;
  SigpipeBlock& operator=(const SigpipeBlock&) = delete;

 private:
  sigset_t pipe_, old_;
};

std::string run_gnuplot(const std::string& script) {
  const std::string exe = gnuplot_executable();
  Pipe in, out, err;
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, in.fd[0], 0);
  posix_spawn_file_actions_adddup2(&actions, out.fd[1], 1);
  posix_spawn_file_actions_adddup2(&actions, err.fd[1], 2);
  std::vector<std::string> env_text = {"LC_ALL=C"};
  for (char** e = environ; *e != nullptr; ++e)
    if (std::strncmp(*e, "LC_ALL=", 7) != 0 && std::strncmp(*e, "GNUPLOT_", 8) != 0) env_text.emplace_back(*e);
  std::vector<char*> env;
  for (auto& e : env_text) env.push_back(e.data());
  env.push_back(nullptr);
  std::string arg0 = exe, arg1 = "--default-settings";
  char* argv[] = {arg0.data(), arg1.data(), nullptr};
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, exe.c_str(), &actions, nullptr, argv, env.data());
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0)
    throw PlotError("cannot run gnuplot '" + exe + "': " + std::strerror(spawned) +
                    " (install Debian's gnuplot-nox, see tools/install-deps.sh, or set DRIFTLAB_GNUPLOT)");
  in.close_end(0), out.close_end(1), err.close_end(1);
  // Non-blocking writes: poll's POLLOUT promises room for one page, not for a whole buffer, and a
  // blocked write while gnuplot waits for us to read its output would deadlock both.
  ::fcntl(in.fd[1], F_SETFL, ::fcntl(in.fd[1], F_GETFL) | O_NONBLOCK);

  std::string svg, messages;
  {
    SigpipeBlock block;
    std::size_t written = 0;
    std::array<char, 65536> buf;
    while (out.fd[0] >= 0 || err.fd[0] >= 0) {
      std::array<pollfd, 3> fds{};
      nfds_t n = 0;
      const auto watch = [&](int fd, short events) {
        if (fd >= 0) fds[n++] = {fd, events, 0};
      };
      watch(out.fd[0], POLLIN), watch(err.fd[0], POLLIN), watch(in.fd[1], POLLOUT);
      if (::poll(fds.data(), n, -1) < 0) {
        if (errno == EINTR) continue;
        break;
      }
      for (nfds_t i = 0; i < n; ++i) {
        if (fds[i].revents == 0) continue;
        const int fd = fds[i].fd;
        if (fd == in.fd[1]) {
          const ssize_t w =
              ::write(fd, script.data() + written, std::min<std::size_t>(script.size() - written, buf.size()));
          if (w > 0) written += static_cast<std::size_t>(w);
          if (w < 0 && errno != EINTR && errno != EAGAIN) in.close_end(1);
          if (written == script.size()) in.close_end(1);
          continue;
        }
        const ssize_t r = ::read(fd, buf.data(), buf.size());
        if (r > 0)
          (fd == out.fd[0] ? svg : messages).append(buf.data(), static_cast<std::size_t>(r));
        else if (r == 0 || errno != EINTR)
          (fd == out.fd[0] ? out : err).close_end(0);
      }
    }
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (messages.size() > 2000) messages.resize(2000);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw PlotError("gnuplot '" + exe + "' failed (" +
                    (WIFEXITED(status) ? "exit code " + std::to_string(WEXITSTATUS(status))
                                       : "signal " + std::to_string(WTERMSIG(status))) +
                    "): " + messages);
  if (svg.find("</svg>") == std::string::npos) throw PlotError("gnuplot '" + exe + "' wrote no SVG: " + messages);
  return svg;
}

}  // namespace

std::string palette_color(std::size_t index) { return kColors[index % kColors.size()]; }

std::string readable_name(const std::string& name) {
  std::string text = name;
  for (const char* port : {".signal", ".residual", ".fitted"})
    if (text.size() > std::strlen(port) && text.ends_with(port)) text.resize(text.size() - std::strlen(port));
  if (text.starts_with("stage_")) text.erase(0, 6);
  std::replace(text.begin(), text.end(), '_', ' ');
  std::replace(text.begin(), text.end(), '.', ' ');
  return text;
}

std::vector<PlotSeries> allan_guides(const allan::Analysis& a, double factor, const std::string& unit,
                                     const std::string& of) {
  std::vector<PlotSeries> out;
  if (a.curve.empty()) return out;
  const auto guide = [&](const std::string& label, PlotSeries::Style style, auto dev) {
    PlotSeries s;
    if (of.empty()) s.label = label;
    s.style = style;
    s.guide = true;
    s.color = "#555555";
    for (const auto& e : a.curve) s.x.push_back(e.tau), s.y.push_back(dev(e.tau) * factor);
    out.push_back(std::move(s));
  };
  const double n = a.arw_rad_sqrt_s;
  const auto& b = a.bias_instability;
  const double floor = b.value * allan::kFlickerFloorFactor;
  guide("slope -1/2: N (white noise)", PlotSeries::Style::Dashed, [&](double tau) { return n / std::sqrt(tau); });
  guide(b.resolved ? "slope 0: 0.664 B (flicker floor)" : "slope 0: lowest point (B only bounded)",
        PlotSeries::Style::Dashed, [&](double) { return floor; });
  if (a.fit && (*a.fit)[allan::Term::K].resolved) {
    const double k = (*a.fit)[allan::Term::K].value;
    guide("slope +1/2: K (rate random walk)", PlotSeries::Style::Dashed,
          [&](double tau) { return k * std::sqrt(tau / 3.0); });
  }
  PlotSeries read;
  read.style = PlotSeries::Style::Markers;
  read.guide = true;
  read.color = "#000000";
  read.label = (of.empty() ? "" : of + ", ") + "read: N = " + format_number(n * factor, 3) + " " + unit +
               "/√Hz at 1 s; B " +
               (b.resolved ? "= " + format_number(b.value * factor, 3) : "< " + format_number(b.high * factor, 3)) +
               " " + unit + " at " + format_number(b.tau_s, 3) + " s";
  if (a.curve.front().tau <= 1.0 && a.curve.back().tau >= 1.0) read.x.push_back(1.0), read.y.push_back(n * factor);
  read.x.push_back(b.tau_s), read.y.push_back(floor * factor);
  out.push_back(std::move(read));
  return out;
}

PlotSeries allan_series(std::string label, std::span<const allan::Estimate> curve, double factor,
                        PlotSeries::Style style, PlotSeries::Interval interval) {
  PlotSeries s;
  s.label = std::move(label);
  s.style = style;
  s.interval = interval;
  for (const auto& e : curve) {
    s.x.push_back(e.tau);
    s.y.push_back(e.dev * factor);
    s.y_low.push_back(e.dev_lo * factor);
    s.y_high.push_back(e.dev_hi * factor);
  }
  return s;
}

std::string render_svg(const Figure& figure) {
  const long columns = std::max(1, figure.columns);
  const long rows = std::max<long>(1, (static_cast<long>(figure.panels.size()) + columns - 1) / columns);
  const long title_px = figure.title.empty() ? 0 : 30;
  const auto n = static_cast<long>(figure.panels.size());
  // With shared_x, a row whose panels all have another panel below them leaves out its x labels.
  const auto row_labels = [&](long row) { return !figure.shared_x || (row + 2) * columns > n; };
  std::vector<long> row_top(static_cast<std::size_t>(rows) + 1, title_px);
  for (long r = 0; r < rows; ++r)
    row_top[static_cast<std::size_t>(r) + 1] =
        row_top[static_cast<std::size_t>(r)] + figure.panel_height - (row_labels(r) ? 0 : kHiddenXAxisPx);
  const long height = row_top.back();
  const bool any_right = std::any_of(figure.panels.begin(), figure.panels.end(), [](const PlotPanel& p) {
    return std::any_of(p.series.begin(), p.series.end(), [](const PlotSeries& s) { return s.right_axis; });
  });
  Range shared, shared_y;
  if (figure.shared_x && !figure.panels.empty()) {
    shared.log = figure.panels.front().log_x;
    for (const auto& panel : figure.panels)
      for (const auto& s : panel.series)
        for (double v : s.x) shared.add(v);
  }
  if (figure.shared_y && !figure.panels.empty()) {
    shared_y.log = figure.panels.front().log_y;
    for (const auto& panel : figure.panels)
      for (const auto& s : panel.series)
        if (!s.right_axis && !s.guide)
          for (const auto& p : points_of(s, panel.log_x, panel.log_y)) shared_y.add(p.low), shared_y.add(p.high);
  }

  std::string script = "set terminal svg size " + std::to_string(figure.width) + "," + std::to_string(height) +
                       " dynamic enhanced font 'sans,11'\nset output\nset encoding utf8\n";
  script += "set multiplot\n";
  const Geometry g{std::max(50.0, figure.width / static_cast<double>(columns) - (any_right ? 24 : 16) * kCharWidthPx),
                   std::max(40.0, figure.panel_height - kVerticalMarginsPx)};
  const auto screen = [&](long px) { return number(static_cast<double>(px) / static_cast<double>(height)); };
  for (std::size_t p = 0; p < figure.panels.size(); ++p) {
    const auto row = static_cast<long>(p) / columns, column = static_cast<long>(p) % columns;
    const auto r = static_cast<std::size_t>(row);
    Placement place;
    place.x_labels = row_labels(row);
    place.shared_x = shared;
    place.shared_y = shared_y;
    for (std::size_t q = static_cast<std::size_t>(column); q < figure.panels.size();
         q += static_cast<std::size_t>(columns))
      for (const auto& s : figure.panels[q].series)
        place.legend_chars = std::max(place.legend_chars, display_length(s.label));
    place.commands = "set origin " + number(static_cast<double>(column) / static_cast<double>(columns)) + "," +
                     screen(height - row_top[r + 1]) + "\nset size " + number(1.0 / static_cast<double>(columns)) +
                     "," + screen(row_top[r + 1] - row_top[r]) + "\n";
    if (p == 0 && !figure.title.empty())
      place.commands += "set label 99 " + quoted(figure.title) + " noenhanced at screen 0.5," +
                        number(1.0 - 0.55 * static_cast<double>(title_px) / static_cast<double>(height)) +
                        " center font ',13'\n";
    panel_script(script, figure.panels[p], p, g, any_right, place);
  }
  script += "unset multiplot\n";
  return run_gnuplot(script);
}

}  // namespace driftlab::cli
