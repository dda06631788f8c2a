#include "tools/driftlab/html_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "framework/atomic_file.hpp"

namespace driftlab::cli {
namespace {

constexpr const char* kStyle =
    "body{font-family:system-ui,-apple-system,'Segoe UI',Roboto,'DejaVu Sans',sans-serif;max-width:1000px;"
    "margin:2em auto;padding:0 1em;color:#222;line-height:1.45}"
    "h1{font-size:1.6em;border-bottom:2px solid #ddd;padding-bottom:.2em}h2{font-size:1.3em;margin-top:1.6em}"
    "h3,h4{font-size:1.08em}"
    "table{border-collapse:collapse;margin:.6em 0;font-size:.95em}"
    "th,td{border:1px solid #ccc;padding:3px 9px}th{background:#f2f2f2;text-align:left}"
    "td.n{text-align:right;font-variant-numeric:tabular-nums}caption{caption-side:top;text-align:left;"
    "font-weight:600;padding:.2em 0}.note{font-size:.88em;color:#555;margin-top:-.2em}"
    "figure{margin:1.2em 0;break-inside:avoid}figure svg{display:block;width:100%;height:auto;margin:0 auto}"
    "figcaption{font-size:.92em;color:#333;margin-top:.3em}"
    "pre{background:#f6f6f6;padding:.5em;overflow-x:auto;font-size:.88em}";

void replace_all(std::string& s, const std::string& from, const std::string& to) {
  for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
    s.replace(at, from.size(), to);
}

}  // namespace

std::string html_escape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string inline_svg(std::string svg, const std::string& id_prefix) {
  const std::size_t start = svg.find("<svg");
  if (start != std::string::npos) svg.erase(0, start);
  for (const char* attribute :
       {" xmlns=\"http://www.w3.org/2000/svg\"", " xmlns:xlink=\"http://www.w3.org/1999/xlink\""})
    replace_all(svg, attribute, "");
  replace_all(svg, "<title>Gnuplot</title>", "");
  const std::size_t box = svg.find("viewBox=\"0 0 ");
  if (box != std::string::npos && box < svg.find('>')) {
    const std::size_t width_at = box + 13;
    const std::string width = svg.substr(width_at, svg.find(' ', width_at) - width_at);
    svg.insert(box, "style=\"max-width:" + width + "px\" ");
  }
  for (std::size_t at = svg.find(" id=\"gnuplot_"); at != std::string::npos; at = svg.find(" id=\"gnuplot_", at))
    svg.erase(at, svg.find('"', at + 5) + 1 - at);
  for (const char* token : {" id='", " id=\"", "href='#", "href=\"#", "url(#"})
    replace_all(svg, token, token + id_prefix);
  return svg;
}

HtmlReport::HtmlReport(std::string title) : title_(std::move(title)) {}

HtmlReport& HtmlReport::section(const std::string& heading, int level) {
  const std::string h = "h" + std::to_string(std::clamp(level, 2, 4));
  body_ += "<" + h + ">" + html_escape(heading) + "</" + h + ">\n";
  return *this;
}

HtmlReport& HtmlReport::paragraph(const std::string& text) {
  body_ += "<p>" + html_escape(text) + "</p>\n";
  return *this;
}

HtmlReport& HtmlReport::preformatted(const std::string& text) {
  body_ += "<pre>" + html_escape(text) + "</pre>\n";
  return *this;
}

HtmlReport& HtmlReport::table(const HtmlTable& t) {
  body_ += "<table>\n";
  if (!t.caption.empty())
    body_ += "<caption>Table " + std::to_string(++tables_) + ". " + html_escape(t.caption) + "</caption>\n";
  if (!t.header.empty()) {
    body_ += "<thead><tr>";
    for (const auto& h : t.header) body_ += "<th>" + html_escape(h) + "</th>";
    body_ += "</tr></thead>\n";
  }
  body_ += "<tbody>\n";
  for (const auto& row : t.rows) {
    body_ += "<tr>";
    for (const auto& cell : row) {
      if (const auto* v = std::get_if<double>(&cell))
        body_ += "<td class=\"n\">" + format_number(*v, t.digits) + "</td>";
      else if (const auto* l = std::get_if<HtmlLink>(&cell))
        body_ += "<td><a href=\"" + html_escape(l->href) + "\">" + html_escape(l->text) + "</a></td>";
      else
        body_ += "<td>" + html_escape(std::get<std::string>(cell)) + "</td>";
    }
    body_ += "</tr>\n";
  }
  body_ += "</tbody></table>\n";
  if (!t.note.empty()) body_ += "<p class=\"note\">" + html_escape(t.note) + "</p>\n";
  return *this;
}

HtmlReport& HtmlReport::figure_or_note(const Figure& f, const std::string& caption) {
  try {
    return figure(f, caption);
  } catch (const PlotError& err) {
    return paragraph(std::string("(figure not drawn: ") + err.what() + ")");
  }
}

HtmlReport& HtmlReport::figure(const Figure& f, const std::string& caption) {
  return figure_svg(render_svg(f), caption);
}

HtmlReport& HtmlReport::figure_svg(const std::string& svg, const std::string& caption) {
  ++figures_;
  body_ += "<figure id=\"figure-" + std::to_string(figures_) + "\">\n" +
           inline_svg(svg, "f" + std::to_string(figures_) + "-") + "<figcaption><b>Figure " + std::to_string(figures_) +
           ".</b> " + html_escape(caption) + "</figcaption>\n</figure>\n";
  return *this;
}

std::string HtmlReport::html() const {
  return "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
         "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>" +
         html_escape(title_) + "</title>\n<style>" + kStyle + "</style>\n</head>\n<body>\n<h1>" + html_escape(title_) +
         "</h1>\n" + body_ + "</body>\n</html>\n";
}

void HtmlReport::write(const std::filesystem::path& path) const { write_file_atomically(path, html()); }

}  // namespace driftlab::cli
