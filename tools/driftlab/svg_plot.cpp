#include "tools/driftlab/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace driftlab::cli {
namespace {

const char* kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf"};
constexpr int kLeft = 80, kRight = 20, kTop = 30, kBottom = 45;

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else out += c;
  }
  return out;
}

struct Axis {
  double lo = 0, hi = 1;
  bool log = false;
  double map(double v, double p0, double p1) const {
    const double a = log ? std::log10(lo) : lo, b = log ? std::log10(hi) : hi;
    const double t = ((log ? std::log10(v) : v) - a) / (b - a);
    return p0 + t * (p1 - p0);
  }
  std::vector<double> ticks() const {
    std::vector<double> out;
    if (log) {
      for (double e = std::floor(std::log10(lo)); e <= std::ceil(std::log10(hi)); ++e) {
        const double v = std::pow(10.0, e);
        if (v >= lo * 0.999 && v <= hi * 1.001) out.push_back(v);
      }
      return out;
    }
    const double raw = (hi - lo) / 6.0;
    const double mag = std::pow(10.0, std::floor(std::log10(raw)));
    const double step = raw / mag < 2 ? 2 * mag : raw / mag < 5 ? 5 * mag : 10 * mag;
    for (double v = std::ceil(lo / step) * step; v <= hi + 1e-9 * step; v += step) out.push_back(std::abs(v) < 1e-12 * step ? 0.0 : v);
    return out;
  }
};

Axis fit_axis(const PlotPanel& panel, bool is_x) {
  Axis axis;
  axis.log = is_x ? panel.log_x : panel.log_y;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& s : panel.series) {
    const auto consider = [&](double v) {
      if (!std::isfinite(v) || (axis.log && v <= 0)) return;
      lo = std::min(lo, v), hi = std::max(hi, v);
    };
    for (double v : is_x ? s.x : s.y) consider(v);
    if (!is_x) {
      for (double v : s.y_low) consider(v);
      for (double v : s.y_high) consider(v);
    }
  }
  if (!std::isfinite(lo)) lo = axis.log ? 1 : 0, hi = axis.log ? 10 : 1;
  if (hi <= lo) hi = axis.log ? lo * 10 : lo + 1;
  if (axis.log) {
    axis.lo = std::pow(10.0, std::floor(std::log10(lo))), axis.hi = std::pow(10.0, std::ceil(std::log10(hi)));
  } else {
    const double pad = 0.05 * (hi - lo);
    axis.lo = is_x ? lo : lo - pad, axis.hi = is_x ? hi : hi + pad;
  }
  return axis;
}

// Keeps at most ~2 points per pixel column: the min and max of each column, in order.
std::vector<std::pair<double, double>> envelope(const PlotSeries& s, const Axis& ax, double x0, double x1) {
  std::vector<std::pair<double, double>> pts;
  const std::size_t n = std::min(s.x.size(), s.y.size());
  if (n < 4000) {
    for (std::size_t i = 0; i < n; ++i) pts.emplace_back(s.x[i], s.y[i]);
    return pts;
  }
  const int columns = static_cast<int>(x1 - x0);
  std::size_t i = 0;
  for (int c = 0; c < columns && i < n; ++c) {
    std::size_t lo = i, hi = i, j = i;
    while (j < n && ax.map(s.x[j], x0, x1) < x0 + c + 1) {
      if (s.y[j] < s.y[lo]) lo = j;
      if (s.y[j] > s.y[hi]) hi = j;
      ++j;
    }
    if (j == i) j = i + 1;
    pts.emplace_back(s.x[std::min(lo, hi)], s.y[std::min(lo, hi)]);
    if (lo != hi) pts.emplace_back(s.x[std::max(lo, hi)], s.y[std::max(lo, hi)]);
    i = j;
  }
  return pts;
}

}  // namespace

std::string render_svg(const Figure& figure) {
  const int height = static_cast<int>(figure.panels.size()) * figure.panel_height;
  std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(figure.width) +
                    "\" height=\"" + std::to_string(height) +
                    "\" font-family=\"sans-serif\" font-size=\"11\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  for (std::size_t p = 0; p < figure.panels.size(); ++p) {
    const auto& panel = figure.panels[p];
    const double top = static_cast<double>(p) * figure.panel_height + kTop;
    const double bottom = static_cast<double>(p + 1) * figure.panel_height - kBottom;
    const double left = kLeft, right = figure.width - kRight;
    const Axis ax = fit_axis(panel, true), ay = fit_axis(panel, false);
    svg += "<text x=\"" + num((left + right) / 2) + "\" y=\"" + num(top - 10) + "\" text-anchor=\"middle\" font-size=\"13\">" +
           escape(panel.title) + "</text>\n";
    svg += "<rect x=\"" + num(left) + "\" y=\"" + num(top) + "\" width=\"" + num(right - left) + "\" height=\"" +
           num(bottom - top) + "\" fill=\"none\" stroke=\"#444\"/>\n";
    for (double t : ax.ticks()) {
      const double x = ax.map(t, left, right);
      svg += "<line x1=\"" + num(x) + "\" y1=\"" + num(top) + "\" x2=\"" + num(x) + "\" y2=\"" + num(bottom) +
             "\" stroke=\"#ddd\"/><text x=\"" + num(x) + "\" y=\"" + num(bottom + 14) + "\" text-anchor=\"middle\">" + num(t) + "</text>\n";
    }
    for (double t : ay.ticks()) {
      const double y = ay.map(t, bottom, top);
      svg += "<line x1=\"" + num(left) + "\" y1=\"" + num(y) + "\" x2=\"" + num(right) + "\" y2=\"" + num(y) +
             "\" stroke=\"#ddd\"/><text x=\"" + num(left - 4) + "\" y=\"" + num(y + 4) + "\" text-anchor=\"end\">" + num(t) + "</text>\n";
    }
    svg += "<text x=\"" + num((left + right) / 2) + "\" y=\"" + num(bottom + 32) + "\" text-anchor=\"middle\">" +
           escape(panel.x_label) + "</text>\n";
    svg += "<text transform=\"translate(" + num(left - 55) + "," + num((top + bottom) / 2) +
           ") rotate(-90)\" text-anchor=\"middle\">" + escape(panel.y_label) + "</text>\n";
    for (std::size_t k = 0; k < panel.series.size(); ++k) {
      const auto& s = panel.series[k];
      const std::string color = kColors[k % std::size(kColors)];
      const auto pts = envelope(s, ax, left, right);
      const auto visible = [&](double x, double y) {
        return std::isfinite(x) && std::isfinite(y) && !(ax.log && x <= 0) && !(ay.log && y <= 0);
      };
      if (s.style == PlotSeries::Style::Markers) {
        for (std::size_t i = 0; i < pts.size(); ++i) {
          if (!visible(pts[i].first, pts[i].second)) continue;
          const double x = ax.map(pts[i].first, left, right), y = ay.map(pts[i].second, bottom, top);
          svg += "<circle cx=\"" + num(x) + "\" cy=\"" + num(y) + "\" r=\"2.5\" fill=\"" + color + "\"/>\n";
        }
      } else {
        std::string path;
        for (const auto& [xv, yv] : pts) {
          if (!visible(xv, yv)) continue;
          path += (path.empty() ? "M" : "L") + num(ax.map(xv, left, right)) + "," + num(ay.map(yv, bottom, top));
        }
        svg += "<path d=\"" + path + "\" fill=\"none\" stroke=\"" + color + "\" stroke-width=\"1.2\"" +
               (s.style == PlotSeries::Style::Dashed ? " stroke-dasharray=\"5,3\"" : "") + "/>\n";
      }
      for (std::size_t i = 0; i < s.y_low.size() && i < s.x.size() && i < s.y_high.size(); ++i) {
        if (!visible(s.x[i], s.y_low[i]) || !visible(s.x[i], s.y_high[i])) continue;
        const double x = ax.map(s.x[i], left, right);
        svg += "<line x1=\"" + num(x) + "\" y1=\"" + num(ay.map(s.y_low[i], bottom, top)) + "\" x2=\"" + num(x) +
               "\" y2=\"" + num(ay.map(s.y_high[i], bottom, top)) + "\" stroke=\"" + color + "\"/>\n";
      }
      const double ly = top + 14 + 14 * static_cast<double>(k);
      svg += "<line x1=\"" + num(right - 150) + "\" y1=\"" + num(ly - 4) + "\" x2=\"" + num(right - 130) + "\" y2=\"" +
             num(ly - 4) + "\" stroke=\"" + color + "\" stroke-width=\"2\"/><text x=\"" + num(right - 125) + "\" y=\"" +
             num(ly) + "\">" + escape(s.label) + "</text>\n";
    }
  }
  return svg + "</svg>\n";
}

}  // namespace driftlab::cli
