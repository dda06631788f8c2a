// Minimal SVG line plots for command outputs (--plot): stacked panels sharing a width, linear or
// log axes with decade/nice ticks, lines, dashed lines, markers and vertical error bars, a legend.
// Long series are reduced to a per-pixel min/max envelope, so a 1e7-sample plot stays small.
#pragma once

#include <string>
#include <vector>

namespace driftlab::cli {

struct PlotSeries {
  std::string label;
  std::vector<double> x, y;
  std::vector<double> y_low, y_high;  // optional error bars (same length as y)
  enum class Style { Line, Dashed, Markers } style = Style::Line;
};

struct PlotPanel {
  std::string title, x_label, y_label;  // labels carry units, e.g. "tau (s)"
  bool log_x = false, log_y = false;
  std::vector<PlotSeries> series;
};

struct Figure {
  std::vector<PlotPanel> panels;  // stacked top to bottom
  int width = 900;
  int panel_height = 260;
};

std::string render_svg(const Figure& figure);

}  // namespace driftlab::cli
