// Figures for command outputs (--plot) and HTML reports, drawn by gnuplot (Debian `gnuplot-nox`)
// run as a child process: the script and the data go to its stdin, the SVG comes from its stdout;
// no shell, no temporary files. Same figure (and gnuplot version) in, same SVG out.
//
// A Figure is a grid of panels (`columns` wide, filled row by row; one column = stacked panels
// sharing their left edge). A panel holds series drawn as lines, dashed lines or markers, with
// optional intervals (vertical error bars or a shaded band), optionally against a second y axis
// on the right, optionally coloured point by point by a third variable (with a colour bar).
//
// Contracts:
// - Every text (titles, labels, legend entries) is shown literally: no gnuplot enhanced-text
//   markup, no XML; write units in plain text or UTF-8 ("rate (°/h)", "tau (s)", "√Hz").
// - Non-finite points, and points <= 0 on a log axis, are left out (a line breaks there); on a log
//   y axis an interval's lower end <= 0 is drawn from the point itself.
// - The x axis spans the data (2 % more at each end when a series has markers); y axes extend to
//   whole ticks (whole decades when log). Tick steps follow the panel's size; a log axis spanning
//   less than two decades is ticked at 1, 2 and 5 times its powers of ten (never a lone tick).
//   Guide series (slope lines, model terms) never widen an axis: they are drawn within the range
//   the other series make.
// - Colours: series k of a panel takes palette_color(k) unless it names its own; the palette's 12
//   colours are told apart at a glance (for more curves, pair a colour with a dashed style).
// - Legend entries are words a reader knows ("temperature trend", "RBF NN + GA + KF"), never a
//   pipeline's port names ("temperature_trend.signal"): readable_name() turns a name into words.
//   A legend that finds no empty corner goes to the right of the plot when the panel has no right
//   axis (the data keep their range), else above the data.
// - Long series are reduced before they reach gnuplot: lines to the min and max of each pixel
//   column (in their original order), markers to one point per 3 x 3 px cell. Series with
//   intervals are drawn as given.
// - The gnuplot executable is $DRIFTLAB_GNUPLOT when set and non-empty, else `gnuplot` on PATH.
//   A missing executable, a failing run or an empty result throws PlotError.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "framework/error.hpp"
#include "models/allan/analysis.hpp"
#include "models/allan/confidence.hpp"

namespace driftlab::cli {

// gnuplot is missing, failed (message carries its diagnostics) or produced no SVG.
class PlotError : public Error {
 public:
  using Error::Error;
};

struct PlotSeries {
  std::string label;  // legend entry; empty = not in the legend
  std::vector<double> x, y;
  std::vector<double> y_low, y_high;  // optional interval per point (same length as y)
  enum class Style { Line, Dashed, Markers } style = Style::Line;
  enum class Interval { Bars, Band } interval = Interval::Bars;  // how y_low/y_high are drawn
  bool right_axis = false;                                       // drawn against the panel's second y axis
  std::vector<double> z;       // optional colour value per point (same length as y; Markers)
  std::string color;           // "#rrggbb"; empty = the palette colour of its index
  bool guide = false;          // a guide (slope line, model term): drawn thin, never widens the axes
  bool break_at_gaps = false;  // line breaks where x steps more than sampling::kGapFactor x its median step
};

struct PlotPanel {
  std::string title, x_label, y_label;  // labels carry units, e.g. "tau (s)"
  bool log_x = false, log_y = false;
  std::vector<PlotSeries> series;
  std::string y2_label;  // right axis, used by series with right_axis
  bool log_y2 = false;
  std::string z_label;  // colour bar of the series with z values
  // Auto: the corner with the least data, else above the data (the y range grows to make room).
  // No legend when no series is labelled, or the only label repeats the panel's title.
  enum class Legend { TopRight, TopLeft, BottomRight, BottomLeft, Auto, None } legend = Legend::Auto;
};

struct Figure {
  std::vector<PlotPanel> panels;  // row by row
  int width = 900;                // px, whole figure; a report page shows it about 1000 px wide, so
                                  // much wider figures get small text there
  int panel_height = 260;         // px, each row
  int columns = 1;
  std::string title;      // above all panels; may be empty
  bool shared_x = false;  // one x range for all panels, labelled only under the bottom row
                          // (rows with a panel below every one of theirs are 40 px shorter)
  bool shared_y = false;  // one left y range for all panels: panels meant to be compared
};

// Colour k of the palette (cycling after 12): "#rrggbb".
std::string palette_color(std::size_t index);

// A pipeline-internal name as words: a port suffix (".signal", ".residual", ".fitted") dropped, a
// "stage_" prefix dropped, underscores and the dot between step and port as spaces:
// "temperature_trend.signal" -> "temperature trend", "classify.mixed" -> "classify mixed". Reports
// that know better name things themselves (a stage's label, an IMF group with its IMFs).
std::string readable_name(const std::string& name);

// An Allan curve as a series: (tau, dev) with its interval [dev_lo, dev_hi], each deviation times
// `factor` (e.g. kDphPerRadPerSec for deg/h); drawn as `style` with the interval as `interval`.
PlotSeries allan_series(std::string label, std::span<const allan::Estimate> curve, double factor,
                        PlotSeries::Style style = PlotSeries::Style::Line,
                        PlotSeries::Interval interval = PlotSeries::Interval::Band);

// The reading guides of an Allan deviation plot (deviations times `factor`, in `unit`): grey
// dashed lines of slope -1/2 through N at tau = 1 s, slope 0 at the floor where B is read
// (0.664 B, or the bound's level when unresolved) and, when the term fit resolved K, slope +1/2 of
// K; and markers where N and B are read, labelled with their values. Guides: they never widen the axes.
// With `of` (the curve's name, for a figure of several curves, whose caption then says what the grey
// lines are) only the read-off points are in the legend, as "of, read: N = ...".
std::vector<PlotSeries> allan_guides(const allan::Analysis& analysis, double factor, const std::string& unit,
                                     const std::string& of = "");

// The figure as a standalone SVG document (viewBox width x rows * panel_height, less the rows
// shortened by shared_x, plus 30 px for a title).
std::string render_svg(const Figure& figure);

}  // namespace driftlab::cli
