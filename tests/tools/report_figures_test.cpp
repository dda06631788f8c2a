// Figures a gyro engineer reads at a glance (issue 29): every report's HTML and every --plot SVG,
// made by the real commands on small records, read as text:
//   - every figure has a caption, figures and tables are numbered 1, 2, 3, ... in order, and no
//     two figures claim the same figure of the paper;
//   - every axis label (the rotated y labels, and the x labels: the plain non-numeric 11-pt texts
//     gnuplot centres under a panel) names a unit in parentheses, and every panel has a y label;
//   - no legend entry (gnuplot's <title> of a plot item) is a pipeline-internal name: a port
//     "step.port", a "stage_..." step or a bare snake_case name ("px4_polynomial").
// The commands: run (li2023 on a 40-min FMVMG oven start), compare (li2023 and the polynomial
// baseline), allan --plot, discrepancy --html, calibrate --report, fleet (8 units, the fewest that
// `simulate --fleet` plants its faults in) and nav when MRPT is built.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <regex>
#include <string>
#include <vector>

#include "tests/tools/cli_harness.hpp"

namespace driftlab {
namespace {

namespace fs = std::filesystem;
using testing_cli::read_text;
using testing_cli::run_driftlab;

const std::string kSource = DRIFTLAB_SOURCE_DIR;

// One <text> of a gnuplot SVG with the attributes of its enclosing <g>.
struct SvgText {
  std::string text;
  bool rotated = false;
  std::string font_size;
};

std::vector<SvgText> svg_texts(const std::string& svg) {
  std::vector<SvgText> out;
  for (auto at = svg.find("<text>"); at != std::string::npos; at = svg.find("<text>", at + 6)) {
    const auto end = svg.find("</text>", at);
    const auto group = svg.rfind("<g transform=", at);
    if (end == std::string::npos || group == std::string::npos) continue;
    const std::string attributes = svg.substr(group, svg.find('>', group) - group);
    SvgText t;
    t.text = svg.substr(at + 6, end - at - 6);
    t.rotated = attributes.find("rotate(") != std::string::npos;
    const auto size = attributes.find("font-size=\"");
    if (size != std::string::npos)
      t.font_size = attributes.substr(size + 11, attributes.find('"', size + 11) - size - 11);
    out.push_back(t);
  }
  return out;
}

std::vector<std::string> between(const std::string& text, const std::string& open, const std::string& close) {
  std::vector<std::string> out;
  for (auto at = text.find(open); at != std::string::npos; at = text.find(open, at + open.size())) {
    const auto end = text.find(close, at + open.size());
    if (end == std::string::npos) break;
    out.push_back(text.substr(at + open.size(), end - at - open.size()));
  }
  return out;
}

const std::regex kUnit(R"(\(.+\))");
const std::regex kNumber(R"(\s*[-+]?[0-9.]+(e[-+]?[0-9]+)?\s*)");
// "temperature_trend.signal", "classify.mixed", "stage_rbf_ga_kf": a port or a step's name.
const std::regex kInternalName(R"((^|[\s(:])([a-z][a-z0-9_]*\.[a-z_][a-z0-9_]*|stage_[a-z0-9_]+)($|[\s),:]))");
// "px4_polynomial", "rbf_ga_kf": an entry that is one snake_case identifier (gnuplot's own
// "gnuplot_plot_1a" titles its unlabelled items).
const std::regex kIdentifier(R"([a-z0-9]+(_[a-z0-9]+)+)");

// The axis labels and legend entries of one SVG figure.
void expect_readable_svg(const std::string& svg, const std::string& what) {
  SCOPED_TRACE(what);
  std::size_t panels = 0, y_labels = 0, x_labels = 0;
  for (const auto& t : svg_texts(svg)) {
    // Tick labels: numbers, powers of ten (<tspan>s) and the empty ones of an axis shared with the panel below.
    if (t.text.empty() || t.text.find("<tspan") != std::string::npos || std::regex_match(t.text, kNumber)) continue;
    if (t.font_size == "12.00") ++panels;  // a panel's title
    if (t.font_size != "11.00") continue;  // titles (12, 13 pt) and legend entries (10 pt)
    (t.rotated ? y_labels : x_labels) += 1;
    EXPECT_TRUE(std::regex_search(t.text, kUnit)) << "axis label without a unit: '" << t.text << "'";
  }
  EXPECT_GE(y_labels, panels) << "a panel without a y label";
  EXPECT_GE(x_labels, 1u) << "no x label";
  for (const auto& entry : between(svg, "<title>", "</title>")) {
    if (entry == "Gnuplot" || entry.starts_with("gnuplot_plot_")) continue;
    EXPECT_FALSE(std::regex_search(entry, kInternalName)) << "legend entry with an internal name: '" << entry << "'";
    EXPECT_FALSE(std::regex_match(entry, kIdentifier)) << "legend entry with an internal name: '" << entry << "'";
  }
}

// Every figure of a report: its caption, its axes and legends; the numbering of figures and tables.
void expect_readable_report(const std::string& html, const std::string& what, std::size_t min_figures) {
  SCOPED_TRACE(what);
  const auto figures = between(html, "<figure", "</figure>");
  EXPECT_GE(figures.size(), min_figures);
  std::vector<std::string> papers_figures;
  for (std::size_t k = 0; k < figures.size(); ++k) {
    const auto& f = figures[k];
    const auto captions = between(f, "<figcaption>", "</figcaption>");
    ASSERT_EQ(captions.size(), 1u) << "figure " << k + 1 << " has no caption";
    const std::string number = "<b>Figure " + std::to_string(k + 1) + ".</b> ";
    ASSERT_EQ(captions[0].rfind(number, 0), 0u) << "figure " << k + 1 << " is captioned '" << captions[0] << "'";
    EXPECT_GT(captions[0].size(), number.size() + 20) << "figure " << k + 1 << ": a caption that says nothing";
    const std::regex paper(R"(paper Fig\. [0-9]+)");
    for (std::sregex_iterator m(captions[0].begin(), captions[0].end(), paper), end; m != end; ++m) {
      EXPECT_THAT(papers_figures, ::testing::Not(::testing::Contains(m->str()))) << "two figures are " << m->str();
      papers_figures.push_back(m->str());
    }
    expect_readable_svg(f, what + ", figure " + std::to_string(k + 1));
  }
  const auto tables = between(html, "<caption>", "</caption>");
  for (std::size_t k = 0; k < tables.size(); ++k)
    EXPECT_EQ(tables[k].rfind("Table " + std::to_string(k + 1) + ". ", 0), 0u) << "table caption '" << tables[k] << "'";
}

// The figure of a report whose caption holds `caption` (as the HTML writes it), empty if none.
std::string figure_captioned(const std::string& html, const std::string& caption) {
  for (const auto& f : between(html, "<figure", "</figure>"))
    if (f.find(caption) != std::string::npos) return f;
  return "";
}

// The reading guides (plot.hpp allan_guides) of the Allan curves named in `of`, in a figure: per curve
// the grey dashed -1/2 slope through N and the floor's level (gnuplot draws each as a dashed path in
// rgb(85,85,85)), and the read-off points, in the legend as "<curve>, read: N = ...".
void expect_allan_guides(const std::string& figure, const std::vector<std::string>& of) {
  std::size_t grey_dashed = 0;
  for (const auto& path : between(figure, "<path stroke='rgb( 85,  85,  85)'", "/>"))
    grey_dashed += path.find("stroke-dasharray") != std::string::npos ? 1 : 0;
  EXPECT_GE(grey_dashed, 2 * of.size()) << "the -1/2 and floor lines of every guided curve";
  for (const auto& curve : of)
    EXPECT_THAT(figure, ::testing::HasSubstr("<title>" + curve + ", read: N = ")) << "the read-off points of " << curve;
}

class ReportFigures : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const auto s = run_driftlab("simulate --device " + kSource +
                                "/devices/fmvmg.yaml --fs 5 --duration 2400 --seed 4 --out " + record().string());
    ASSERT_EQ(s.exit_code, 0) << s.err;
  }
  static fs::path dir() {
    static const fs::path d = testing_cli::scratch_dir("report_figures");
    return d;
  }
  static fs::path record() { return dir() / "oven_start.csv"; }
};

TEST_F(ReportFigures, RunReport) {
  const auto r = run_driftlab("-q run --pipeline " + kSource + "/models/pipelines/li2023.yaml --data " +
                              record().string() + " --out " + (dir() / "run").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string html = read_text(dir() / "run" / "report.html");
  expect_readable_report(html, "driftlab run", 9);
  // The stages by the pipeline's own labels; the temperature trend in words.
  EXPECT_THAT(html, ::testing::HasSubstr("<title>RBF NN + GA + KF</title>"));
  EXPECT_THAT(html, ::testing::HasSubstr("<title>temperature trend</title>"));
  EXPECT_THAT(html, ::testing::HasSubstr("<title>original record</title>"));
  // The paper's figures by the numbers li2023.yaml's reference gives them, each once.
  for (int figure = 10; figure <= 15; ++figure) {
    const std::string caption = "(paper Fig. " + std::to_string(figure) + ")";
    const auto first = html.find(caption);
    ASSERT_NE(first, std::string::npos) << caption;
    EXPECT_EQ(html.find(caption, first + 1), std::string::npos) << caption << " twice";
  }
}

TEST_F(ReportFigures, CompareReport) {
  const auto r = run_driftlab("-q compare --data " + record().string() + " --pipeline " + kSource +
                              "/models/pipelines/li2023.yaml --pipeline " + kSource +
                              "/models/pipelines/polynomial_baseline.yaml --out " + (dir() / "compare").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string html = read_text(dir() / "compare" / "report.html");
  expect_readable_report(html, "driftlab compare", 1);
  // The Allan figure reads N and B off the original record and off the intrinsic floor.
  const std::string allan = figure_captioned(html, "Allan deviation of the record");
  ASSERT_FALSE(allan.empty());
  expect_allan_guides(allan, {"original record", "intrinsic floor"});
  EXPECT_THAT(allan, ::testing::HasSubstr("Grey dashed guides, of the original record and of the intrinsic floor"));
}

TEST_F(ReportFigures, AllanPlotInDegreesPerHour) {
  const auto svg = dir() / "allan.svg";
  const auto r = run_driftlab("-q allan --data " + record().string() + " --out " + (dir() / "allan.csv").string() +
                              " --plot " + svg.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string text = read_text(svg);
  expect_readable_svg(text, "driftlab allan --plot");
  EXPECT_THAT(text, ::testing::HasSubstr("oadev (°/h)"));
  EXPECT_THAT(text, ::testing::HasSubstr("slope -1/2"));
  EXPECT_THAT(text, ::testing::Not(::testing::HasSubstr(dir().string())));  // the title names the file, not its path
}

TEST_F(ReportFigures, DiscrepancyReport) {
  const auto r =
      run_driftlab("-q discrepancy --data " + record().string() + " --device fmvmg --report " +
                   (dir() / "discrepancy.json").string() + " --html " + (dir() / "discrepancy.html").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  expect_readable_report(read_text(dir() / "discrepancy.html"), "driftlab discrepancy", 1);
}

TEST_F(ReportFigures, CalibrationReport) {
  const auto held_out = dir() / "held_out.csv";
  ASSERT_EQ(run_driftlab("simulate --device fmvmg --fs 1 --seed 2 --out " + held_out.string()).exit_code, 0);
  const auto oven = dir() / "oven.csv";
  ASSERT_EQ(run_driftlab("simulate --device fmvmg --fs 1 --seed 1 --out " + oven.string()).exit_code, 0);
  const auto r = run_driftlab("-q calibrate --data " + oven.string() + " --evaluate " + held_out.string() + " --out " +
                              (dir() / "model.json").string() + " --report " + (dir() / "calibration").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string html = read_text(dir() / "calibration" / "report.html");
  expect_readable_report(html, "driftlab calibrate", 3);
  // The Allan figure of the residuals reads N and B off the model with the least residual drift.
  const std::string allan = figure_captioned(html, "Allan deviation of every method&#39;s residual");
  ASSERT_FALSE(allan.empty());
  std::smatch guided;
  const std::regex of(R"(Grey dashed guides, of ([a-zA-Z0-9 -]+) \(the model with the least residual drift\))");
  ASSERT_TRUE(std::regex_search(allan, guided, of)) << "the caption names whose guides they are";
  EXPECT_NE(guided[1].str(), "none");
  expect_allan_guides(allan, {guided[1].str()});
}

TEST_F(ReportFigures, FleetReport) {
  ASSERT_EQ(run_driftlab("simulate --fleet 8 --device imu3 --fs 1 --seed 7 --out " + (dir() / "fleet_sim").string())
                .exit_code,
            0);
  const auto r = run_driftlab("-q fleet --manifest " + (dir() / "fleet_sim" / "manifest.csv").string() + " --out " +
                              (dir() / "fleet").string() + " --workers 2 --channels gyro");
  ASSERT_LE(r.exit_code, 1) << r.err;  // 1: a planted unit failed, the report stands
  expect_readable_report(read_text(dir() / "fleet" / "report.html"), "driftlab fleet", 1);
}

TEST_F(ReportFigures, NavPlot) {
  if (!DRIFTLAB_HAVE_MRPT) GTEST_SKIP() << "built without MRPT: driftlab nav is not built";
  const auto r = run_driftlab("-q nav --device fmvmg --out " + (dir() / "nav").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string text = read_text(dir() / "nav" / "nav.svg");
  expect_readable_svg(text, "driftlab nav");
  EXPECT_THAT(text, ::testing::HasSubstr("<title>EKF 1σ</title>"));
}

}  // namespace
}  // namespace driftlab
