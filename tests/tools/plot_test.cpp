// Figures drawn by gnuplot (tools/driftlab/plot.hpp) and the HTML report writer
// (tools/driftlab/html_report.hpp).
#include "tools/driftlab/plot.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <set>
#include <sstream>

#include "tools/driftlab/html_report.hpp"

namespace driftlab::cli {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

// Plot elements (series, or their band) in gnuplot's SVG: distinct ids, since an opaque legend is
// drawn a second time with the same ids.
std::size_t plot_elements(const std::string& svg) {
  std::set<std::string> ids;
  const std::regex id(R"re(id="(gnuplot_plot_[0-9a-z]+)")re");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), id); it != std::sregex_iterator(); ++it)
    ids.insert((*it)[1]);
  return ids.size();
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size())) ++n;
  return n;
}

PlotSeries line(const std::string& label, std::vector<double> x, std::vector<double> y,
                PlotSeries::Style style = PlotSeries::Style::Line) {
  PlotSeries s;
  s.label = label;
  s.x = std::move(x);
  s.y = std::move(y);
  s.style = style;
  return s;
}

// The x pixel coordinates of the first path drawn for plot element `id` (e.g. "gnuplot_plot_1a").
std::vector<double> path_x(const std::string& svg, const std::string& id) {
  const auto group = svg.find("id=\"" + id + "\"");
  const auto d = svg.find("d='M", group);
  const auto end = svg.find('\'', d + 3);
  const std::string path = svg.substr(d + 3, end - d - 3);
  std::vector<double> xs;
  const std::regex point(R"([ML]([-0-9.]+),([-0-9.]+))");
  for (auto it = std::sregex_iterator(path.begin(), path.end(), point); it != std::sregex_iterator(); ++it)
    xs.push_back(std::stod((*it)[1]));
  return xs;
}

// Drives gnuplot through $DRIFTLAB_GNUPLOT for one test, restoring the previous value.
class GnuplotOverride {
 public:
  explicit GnuplotOverride(const char* path) {
    if (const char* old = std::getenv("DRIFTLAB_GNUPLOT")) old_ = old, had_ = true;
    ::setenv("DRIFTLAB_GNUPLOT", path, 1);
  }
  ~GnuplotOverride() {
    if (had_)
      ::setenv("DRIFTLAB_GNUPLOT", old_.c_str(), 1);
    else
      ::unsetenv("DRIFTLAB_GNUPLOT");
  }

 private:
  std::string old_;
  bool had_ = false;
};

Figure two_panels() {
  Figure f;
  PlotPanel a{
      "rate",
      "t (s)",
      "rate (°/h)",
      false,
      false,
      {line("raw", {0, 1, 2, 3}, {1, 3, 2, 4}), line("model", {0, 1, 2, 3}, {1, 2, 3, 4}, PlotSeries::Style::Dashed)}};
  PlotPanel b{"temperature", "t (s)", "T (°C)",
              false,         false,   {line("case", {0, 1, 2, 3}, {20, 21, 23, 22}, PlotSeries::Style::Markers)}};
  f.panels = {a, b};
  return f;
}

TEST(Plot, DrawsOnePlotElementPerSeriesInEveryPanel) {
  const std::string svg = render_svg(two_panels());
  EXPECT_THAT(svg, HasSubstr("<svg"));
  EXPECT_THAT(svg, HasSubstr("</svg>"));
  EXPECT_EQ(plot_elements(svg), 3u);
  for (const char* text : {">raw<", ">model<", ">case<", "rate (°/h)", "T (°C)", "t (s)"})
    EXPECT_THAT(svg, HasSubstr(text));
}

TEST(Plot, ShowsLabelsLiterallyAndEscapedWithoutBreakingTheScript) {
  Figure f;
  const std::string nasty = "a<b> & 'c' x_y^2 {z} @q\nset output '/tmp/pwned'";
  f.title = nasty;
  f.panels.push_back({nasty, nasty, nasty, false, false, {line(nasty, {0, 1}, {0, 1})}});
  const std::string svg = render_svg(f);
  EXPECT_THAT(svg, HasSubstr("a&lt;b> &amp; 'c' x_y^2 {z} @q set output '/tmp/pwned'"));
  EXPECT_THAT(svg, Not(HasSubstr("a<b")));
  EXPECT_FALSE(std::filesystem::exists("/tmp/pwned"));
}

TEST(Plot, PlacesDecadesEvenlyOnALogAxis) {
  Figure f;
  f.panels.push_back({"Allan deviation",
                      "tau (s)",
                      "sigma (°/h)",
                      true,
                      true,
                      {line("adev", {0.01, 0.1, 1, 10, 100}, {30, 10, 3, 1, 0.3})}});
  const auto xs = path_x(render_svg(f), "gnuplot_plot_1a");
  ASSERT_EQ(xs.size(), 5u);
  constexpr double kPixelRounding = 0.02;  // gnuplot writes coordinates with two decimals
  for (std::size_t i = 2; i < xs.size(); ++i) EXPECT_NEAR(xs[i] - xs[i - 1], xs[1] - xs[0], kPixelRounding);
}

TEST(Plot, LeavesOutPointsALogAxisCannotShow) {
  Figure f;
  f.panels.push_back({"", "tau (s)", "sigma", true, true, {line("adev", {-1, 0, 1, 10, 100}, {1, 1, 0, 2, 3})}});
  EXPECT_EQ(path_x(render_svg(f), "gnuplot_plot_1a").size(), 2u);
}

TEST(Plot, ReducesALongSeriesToAnEnvelopePerPixelColumnKeepingItsExtremes) {
  constexpr int kSamples = 1'000'000;
  PlotSeries s;
  s.label = "sine";
  for (int i = 0; i < kSamples; ++i) {
    s.x.push_back(i * 0.01);
    s.y.push_back(std::sin(i * 0.001));
  }
  s.y[kSamples / 2] = 5.0;  // a one-sample spike must survive the reduction
  Figure f;
  f.panels.push_back({"long", "t (s)", "y", false, false, {s}});
  const std::string svg = render_svg(f);
  const auto xs = path_x(svg, "gnuplot_plot_1a");
  EXPECT_LE(xs.size(), 2u * static_cast<std::size_t>(f.width));
  EXPECT_GE(xs.size(), static_cast<std::size_t>(f.width) / 2);
  EXPECT_LT(svg.size(), 200'000u);
  EXPECT_THAT(svg, HasSubstr(">5</tspan>"));  // the y axis reaches the spike
}

TEST(Plot, ReducesADenseScatterToOneMarkerPerCell) {
  PlotSeries s = line("cloud", {}, {}, PlotSeries::Style::Markers);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uniform(-10, 10);
  for (int i = 0; i < 200'000; ++i) {
    s.x.push_back(uniform(rng));
    s.y.push_back(uniform(rng));
  }
  Figure f;
  f.panels.push_back({"scatter", "x", "y", false, false, {s}});
  const std::string svg = render_svg(f);
  const std::size_t cells = (f.width / 3) * (f.panel_height / 3);
  EXPECT_LT(count(svg, "<use "), cells);
  EXPECT_GT(count(svg, "<use "), cells / 4);  // the cloud still fills the panel
}

TEST(Plot, DrawsBandsErrorBarsASecondAxisAndAColourScale) {
  PlotSeries band = line("adev with 68 % interval", {1, 10, 100}, {10, 3, 1});
  band.y_low = {8, 2, 0.5};
  band.y_high = {12, 4, 2};
  band.interval = PlotSeries::Interval::Band;
  PlotSeries bars = band;
  bars.label = "bars";
  bars.style = PlotSeries::Style::Markers;
  bars.interval = PlotSeries::Interval::Bars;
  PlotSeries temp = line("temperature", {0, 1, 2}, {20, 30, 40});
  temp.right_axis = true;
  PlotSeries coloured = line("by time", {0, 1, 2}, {1, 2, 3}, PlotSeries::Style::Markers);
  coloured.z = {0, 50, 100};
  Figure f;
  f.columns = 2;
  f.panels.push_back({"allan", "tau (s)", "sigma (°/h)", true, true, {band, bars}});
  PlotPanel two{
      "rate and temperature", "t (s)", "rate (°/h)", false, false, {line("rate", {0, 1, 2}, {5, 4, 6}), temp}};
  two.y2_label = "temperature (°C)";
  f.panels.push_back(two);
  PlotPanel three{"residual", "T (°C)", "residual (°/h)", false, false, {coloured}};
  three.z_label = "time (h)";
  f.panels.push_back(three);
  const std::string svg = render_svg(f);
  EXPECT_THAT(svg, HasSubstr("temperature (°C)"));
  EXPECT_THAT(svg, HasSubstr("time (h)"));
  EXPECT_THAT(svg, HasSubstr("fill-opacity"));  // the shaded band
  EXPECT_EQ(plot_elements(svg), 6u);            // band + line, bars, rate, temperature, coloured
}

TEST(Plot, StreamsAFigureLargerThanThePipeBuffersBothWays) {
  Figure f;
  for (int p = 0; p < 12; ++p) {
    PlotSeries s = line("points with intervals", {}, {}, PlotSeries::Style::Markers);
    for (int i = 0; i < 2000; ++i) {
      s.x.push_back(i);
      s.y.push_back(std::sin(i * 0.01 + p));
      s.y_low.push_back(s.y.back() - 0.1);
      s.y_high.push_back(s.y.back() + 0.1);
    }
    f.panels.push_back({"panel " + std::to_string(p), "x", "y", false, false, {s}});
  }
  const std::string svg = render_svg(f);
  EXPECT_GT(svg.size(), 1'000'000u);
  EXPECT_THAT(svg, HasSubstr("panel 11"));
}

TEST(Plot, LabelsASharedXAxisOnceUnderTheBottomPanel) {
  Figure f;
  f.shared_x = true;
  for (int p = 0; p < 3; ++p)
    f.panels.push_back({"imf" + std::to_string(p + 1),
                        "t (s)",
                        "rate (°/h)",
                        false,
                        false,
                        {line("imf", {0, 5.0 * (p + 1)}, {0, 1})}});
  const std::string svg = render_svg(f);
  EXPECT_EQ(count(svg, ">t (s)<"), 1u);
  EXPECT_THAT(svg, HasSubstr("viewBox=\"0 0 900 700\""));  // 3 x 260 px, two rows 40 px shorter
  const auto first = path_x(svg, "gnuplot_plot_1a"), last = path_x(svg, "gnuplot_plot_1c");
  ASSERT_EQ(first.size(), 2u);
  ASSERT_EQ(last.size(), 2u);
  EXPECT_EQ(first[0], last[0]);  // one x range: t = 0 at the same place in every panel
  EXPECT_LT(first[1], last[1]);
}

// The d attribute of the first path drawn for plot element `id`.
std::string path_of(const std::string& svg, const std::string& id) {
  const auto d = svg.find("d='M", svg.find("id=\"" + id + "\""));
  return svg.substr(d + 3, svg.find('\'', d + 3) - d - 3);
}

TEST(Plot, SharesOneYRangeWhenAsked) {
  Figure f;
  f.columns = 2;
  f.panels.push_back({"small", "T (°C)", "residual (°/h)", false, false, {line("a", {0, 1}, {0, 1})}});
  f.panels.push_back({"large", "T (°C)", "residual (°/h)", false, false, {line("b", {0, 1}, {0, 100})}});
  EXPECT_EQ(count(render_svg(f), ">100<"), 1u);
  f.shared_y = true;
  EXPECT_EQ(count(render_svg(f), ">100<"), 2u);  // the top tick of both panels
}

TEST(Plot, GuidesNeverWidenAnAxis) {
  Figure f;
  f.panels.push_back({"adev", "tau (s)", "sigma (°/h)", true, true, {line("adev", {1, 10, 100}, {3, 1, 2})}});
  const std::string alone = path_of(render_svg(f), "gnuplot_plot_1a");
  auto slope = line("slope -1/2", {1, 10, 100}, {1e3, 3e2, 1e2}, PlotSeries::Style::Dashed);
  slope.guide = true;
  f.panels[0].series.push_back(slope);
  f.panels[0].legend = PlotPanel::Legend::None;
  EXPECT_EQ(path_of(render_svg(f), "gnuplot_plot_1a"), alone);  // the data where they were
}

TEST(Plot, BreaksALineAtARecordsGapsWhenAsked) {
  Figure f;
  auto bursts = line("bursts", {0, 1, 2, 3, 50, 51, 52, 53}, {0, 1, 0, 1, 0, 1, 0, 1});
  f.panels.push_back({"", "time (s)", "rate (°/h)", false, false, {bursts}});
  EXPECT_EQ(count(path_of(render_svg(f), "gnuplot_plot_1a"), "M"), 1u);
  f.panels[0].series[0].break_at_gaps = true;
  EXPECT_EQ(count(path_of(render_svg(f), "gnuplot_plot_1a"), "M"), 2u);
}

TEST(Plot, TicksALogAxisUnderTwoDecadesAtOneTwoAndFive) {
  Figure f;
  f.panels.push_back({"spectrum", "period (s)", "amplitude (°/h)", true, false, {line("a", {30, 400}, {1, 2})}});
  const std::string svg = render_svg(f);
  for (const char* tick : {">50<", ">100<", ">200<"}) EXPECT_THAT(svg, HasSubstr(tick));
}

TEST(Plot, NamesPipelinePortsInWordsAndColoursFromOnePalette) {
  EXPECT_EQ(readable_name("temperature_trend.signal"), "temperature trend");
  EXPECT_EQ(readable_name("stage_rbf_ga_kf.signal"), "rbf ga kf");
  EXPECT_EQ(readable_name("mixed_rbf_ga.residual"), "mixed rbf ga");
  EXPECT_EQ(readable_name("classify.mixed"), "classify mixed");
  std::set<std::string> colours;
  for (std::size_t k = 0; k < 12; ++k) colours.insert(palette_color(k));
  EXPECT_EQ(colours.size(), 12u);
  EXPECT_EQ(palette_color(12), palette_color(0));
}

TEST(Plot, AllanGuidesShowTheSlopesAndWhereNAndBAreRead) {
  allan::Analysis a;
  for (double tau : {0.1, 1.0, 10.0, 100.0}) a.curve.push_back({1, tau, 0.01 / std::sqrt(tau), 0, 0});
  a.arw_rad_sqrt_s = 0.01;
  a.bias_instability = {true, 0.002, 0.0018, 0.0022, 100.0, 100.0};
  const auto guides = allan_guides(a, 2.0, "°/h");
  ASSERT_EQ(guides.size(), 3u);  // slope -1/2, slope 0, the read-off points (no K without a fit)
  for (const auto& g : guides) EXPECT_TRUE(g.guide) << g.label;
  EXPECT_DOUBLE_EQ(guides[0].y[1], 0.02);                                    // N / sqrt(tau) at tau = 1 s
  EXPECT_DOUBLE_EQ(guides[1].y[0], 0.002 * allan::kFlickerFloorFactor * 2);  // the floor 0.664 B
  EXPECT_EQ(guides[2].x, (std::vector<double>{1.0, 100.0}));
  EXPECT_THAT(guides[2].label, HasSubstr("N = 0.02 °/h/√Hz at 1 s; B = 0.004 °/h at 100 s"));
}

TEST(Plot, DrawsAPanelWithoutDataAsEmpty) {
  Figure f;
  f.panels.push_back({"nothing yet", "x", "y", true, true, {line("none", {}, {})}});
  EXPECT_THAT(render_svg(f), HasSubstr("no data"));
}

TEST(Plot, GivesTheSameSvgForTheSameFigure) { EXPECT_EQ(render_svg(two_panels()), render_svg(two_panels())); }

TEST(Plot, ThrowsAPlotErrorNamingTheExecutableWhenGnuplotIsMissing) {
  GnuplotOverride missing("/nonexistent/driftlab/gnuplot");
  try {
    render_svg(two_panels());
    FAIL() << "no PlotError";
  } catch (const PlotError& e) {
    EXPECT_THAT(e.what(), HasSubstr("/nonexistent/driftlab/gnuplot"));
    EXPECT_THAT(e.what(), HasSubstr("gnuplot-nox"));
  }
}

TEST(Plot, ThrowsAPlotErrorWhenGnuplotFails) {
  GnuplotOverride failing("false");
  EXPECT_THROW(render_svg(two_panels()), PlotError);
}

// Checks that every element opened is closed in order (void elements and <x/> excepted).
bool well_nested(const std::string& html, std::string& problem) {
  static const std::set<std::string> kVoid = {"meta", "br", "hr", "img", "link", "input", "col", "wbr"};
  std::vector<std::string> open;
  std::size_t at = 0;
  while ((at = html.find('<', at)) != std::string::npos) {
    const auto end = html.find('>', at);
    if (end == std::string::npos) return problem = "unterminated tag", false;
    std::string tag = html.substr(at + 1, end - at - 1);
    at = end + 1;
    if (tag.empty() || tag[0] == '!' || tag[0] == '?') continue;
    const bool closing = tag[0] == '/';
    const bool self_closing = tag.back() == '/';
    const std::string name = tag.substr(closing, tag.find_first_of(" \t\n/>", closing) - closing);
    if (closing) {
      if (open.empty() || open.back() != name)
        return problem = "</" + name + "> closes " + (open.empty() ? "nothing" : open.back()), false;
      open.pop_back();
    } else if (!self_closing && !kVoid.count(name)) {
      open.push_back(name);
    }
  }
  if (!open.empty()) return problem = "<" + open.back() + "> never closed", false;
  return true;
}

HtmlReport sample_report() {
  HtmlReport r("driftlab run <li2023> & friends");
  r.section("Table 2").paragraph("B falls at every stage: 34.66 -> 3.589 °/h <really>.");
  r.table({"Allan figures per stage",
           {"stage", "B (°/h)", "N (°/h/√Hz)", "blocks"},
           {{std::string("original"), 34.66, 99.608, 16200.0}, {std::string("rbf_ga_kf"), 3.589, NAN, 3.0}},
           "68.3 % intervals <chi2>"});
  r.figure(two_panels(), "raw rate and temperature");
  r.section("Allan", 3).figure(two_panels(), "again, with its own ids").preformatted("driftlab run --out 'x y'");
  return r;
}

TEST(HtmlReport, IsWellNestedAndNumbersItsTablesAndFigures) {
  const std::string html = sample_report().html();
  std::string problem;
  EXPECT_TRUE(well_nested(html, problem)) << problem;
  EXPECT_THAT(html, HasSubstr("<!DOCTYPE html>"));
  EXPECT_THAT(html, HasSubstr("<meta charset=\"utf-8\">"));
  EXPECT_THAT(html, HasSubstr("Table 1. Allan figures per stage"));
  EXPECT_THAT(html, HasSubstr("<b>Figure 1.</b> raw rate and temperature"));
  EXPECT_THAT(html, HasSubstr("<b>Figure 2.</b> again"));
  EXPECT_EQ(count(html, "<svg"), 2u);
  EXPECT_EQ(count(html, "style=\"max-width:900px\" viewBox"), 2u);  // never scaled above its own size
  EXPECT_EQ(count(html, "<?xml"), 0u);
}

TEST(HtmlReport, EscapesTextAndFormatsNumbers) {
  const std::string html = sample_report().html();
  EXPECT_THAT(html, HasSubstr("<title>driftlab run &lt;li2023&gt; &amp; friends</title>"));
  EXPECT_THAT(html, HasSubstr("3.589 °/h &lt;really&gt;."));
  EXPECT_THAT(html, HasSubstr("<td class=\"n\">99.61</td>"));
  EXPECT_THAT(html, HasSubstr("<td class=\"n\">16200</td>"));
  EXPECT_THAT(html, HasSubstr("<td class=\"n\">–</td>"));
  EXPECT_THAT(html, HasSubstr("<pre>driftlab run --out &#39;x y&#39;</pre>"));
}

TEST(HtmlReport, ReferencesNothingOutsideTheFileAndKeepsIdsUnique) {
  const std::string html = sample_report().html();
  EXPECT_THAT(html, Not(HasSubstr("http://")));
  EXPECT_THAT(html, Not(HasSubstr("https://")));
  EXPECT_THAT(html, Not(HasSubstr("<script")));
  EXPECT_THAT(html, Not(HasSubstr("<link")));
  EXPECT_THAT(html, Not(HasSubstr("@import")));
  std::set<std::string> ids;
  const std::regex id(R"re(\sid=["']([^"']+)["'])re");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), id); it != std::sregex_iterator(); ++it)
    EXPECT_TRUE(ids.insert((*it)[1]).second) << "duplicate id " << (*it)[1];
  const std::regex href(R"re(href=["']#([^"']+)["'])re");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), href); it != std::sregex_iterator(); ++it)
    EXPECT_TRUE(ids.count((*it)[1])) << "dangling reference #" << (*it)[1];
}

TEST(HtmlReport, WritesTheFileAtomicallyLeavingNothingElse) {
  const auto dir = std::filesystem::temp_directory_path() / ("driftlab_html_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto report = sample_report();
  report.write(dir / "report.html");
  std::ifstream in(dir / "report.html");
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), report.html());
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), std::filesystem::directory_iterator()), 1);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace driftlab::cli
