// Self-contained HTML reports: one file with its CSS and figures (inline SVG) inside, no network
// references of any kind, so it opens the same anywhere, offline. Used by the commands that write
// a report.html (run, calibrate, compare, nav, discrepancy).
//
//   HtmlReport report("driftlab run: li2023 on oven.csv");
//   report.section("Table 2").paragraph("B from the flat floor of the Allan deviation ...");
//   report.table({"Allan figures per stage", {"stage", "B (°/h)"}, {{"original", 34.66}}, "CI 68.3 %"});
//   report.figure(allan_figure, "Allan deviation of every stage, with 68.3 % intervals");
//   report.write(out / "report.html");   // atomic (framework/atomic_file.hpp)
//
// Contracts: every text argument is plain text (escaped here, never interpreted as HTML).
// Tables and figures are numbered in order of addition ("Table 1.", "Figure 1."); a table without a
// caption has no number. Numbers are written with `digits` significant digits in the C locale,
// integers in full, non-finite values as "–". figure() renders through render_svg (plot.hpp) and
// throws its PlotError; figure_svg() takes an SVG document made elsewhere (for example by
// render_svg beforehand). write() throws DataError when the file cannot be written.
#pragma once

#include <filesystem>
#include <string>
#include <variant>
#include <vector>

#include "framework/number_text.hpp"
#include "tools/driftlab/plot.hpp"

namespace driftlab::cli {

// A link to a file beside the report: `href` a relative path (escaped; the report stays offline).
struct HtmlLink {
  std::string text, href;
};
using HtmlCell = std::variant<std::string, double, HtmlLink>;  // text (left), number (right-aligned) or link

struct HtmlTable {
  std::string caption;              // "Table N. caption"; empty = unnumbered
  std::vector<std::string> header;  // column names with units, e.g. "B (°/h)"
  std::vector<std::vector<HtmlCell>> rows;
  std::string note;  // below the table: sources, estimator, confidence level
  int digits = 4;    // significant digits of non-integer numbers
};

class HtmlReport {
 public:
  explicit HtmlReport(std::string title);  // <title> and the page's <h1>

  HtmlReport& section(const std::string& heading, int level = 2);  // <h2> (level 2..4)
  HtmlReport& paragraph(const std::string& text);
  HtmlReport& preformatted(const std::string& text);  // commands, file paths, logs
  HtmlReport& table(const HtmlTable& table);
  HtmlReport& figure(const Figure& figure, const std::string& caption);
  HtmlReport& figure_svg(const std::string& svg, const std::string& caption);
  // figure(), or when gnuplot fails (PlotError) a paragraph saying why: the numbers stand without it.
  HtmlReport& figure_or_note(const Figure& figure, const std::string& caption);

  std::string html() const;  // the whole document
  void write(const std::filesystem::path& path) const;

 private:
  std::string title_;
  std::string body_;
  int tables_ = 0, figures_ = 0;
};

std::string html_escape(const std::string& text);

// An SVG document (from render_svg) made fit to sit inside HTML beside others: no XML prolog, no
// namespace URIs (the HTML parser supplies them), no ids of gnuplot's own, the remaining ids and
// references prefixed with `id_prefix` (unique per figure in a page), and never drawn wider than
// its own width (so text keeps its size in points: a narrow figure is not blown up).
std::string inline_svg(std::string svg, const std::string& id_prefix);

}  // namespace driftlab::cli
