#include "twinwatch/ui/html_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <tuple>

#include "twinwatch/core/error.hpp"

namespace twinwatch::ui {

namespace {

constexpr const char* kPalette[] = {"#268bd2", "#dc322f", "#859900", "#b58900", "#6c71c4", "#2aa198", "#d33682", "#cb4b16"};
constexpr int kMarginLeft = 64, kMarginRight = 150, kMarginTop = 24, kMarginBottom = 36;

// "nice" tick step (1, 2, 5 x 10^k) for a range split into about `target` parts
double nice_step(double range, int target) {
  if (!(range > 0.0)) return 1.0;
  const double raw = range / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double r = raw / mag;
  const double m = r < 1.5 ? 1.0 : r < 3.5 ? 2.0 : r < 7.5 ? 5.0 : 10.0;
  return m * mag;
}

// the x range a plot draws: [x0, x1], one unit wide where the two are equal
std::pair<double, double> drawn_range(double x0, double x1) {
  if (!(x1 >= x0)) return {0.0, 1.0};
  return {x0, x1 == x0 ? x0 + 1.0 : x1};
}

std::string fmt_tick(double v) {
  if (v == 0.0) return "0";
  const double a = std::abs(v);
  if (a >= 1e4 || a < 1e-3) return fmt::format("{:.2g}", v);
  return fmt::format("{:.4g}", v);
}

}  // namespace

std::string HtmlReport::escape(const std::string& s) {
  std::string o;
  o.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}


SeriesEnvelope::SeriesEnvelope(double x0, double x1, int columns) : columns_(std::max(1, columns)) {
  if (!std::isfinite(x0) || !std::isfinite(x1) || x1 < x0)
    throw InvalidArgument(fmt::format("series envelope: x range [{}, {}], expected finite with x1 >= x0", x0, x1));
  std::tie(x0_, x1_) = drawn_range(x0, x1);
}

void SeriesEnvelope::add_to_columns(double x, double y) {
  const int c = std::clamp(static_cast<int>((x - x0_) / (x1_ - x0_) * (columns_ - 1)), 0, columns_ - 1);
  if (cols_.empty() || cols_.back().index != c) {
    cols_.push_back({c, y, y});
  } else {
    cols_.back().lo = std::min(cols_.back().lo, y);
    cols_.back().hi = std::max(cols_.back().hi, y);
  }
}

void SeriesEnvelope::to_columns() {
  for (const auto& [x, y] : raw_) add_to_columns(x, y);
  raw_ = {};
}

void SeriesEnvelope::add(double x, double y) {
  ++added_;
  const bool finite = std::isfinite(x) && std::isfinite(y);
  if (added_ <= static_cast<size_t>(2 * columns_)) {
    if (finite) raw_.emplace_back(x, y);
    return;
  }
  if (added_ == static_cast<size_t>(2 * columns_) + 1) to_columns();
  if (finite) add_to_columns(x, y);
}

std::pair<double, double> SeriesEnvelope::y_extent() const {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& [x, y] : raw_) lo = std::min(lo, y), hi = std::max(hi, y);
  for (const Column& c : cols_) lo = std::min(lo, c.lo), hi = std::max(hi, c.hi);
  if (!(hi >= lo)) return {NAN, NAN};
  return {lo, hi};
}

std::string SeriesEnvelope::points(const std::function<double(double)>& X, const std::function<double(double)>& Y, double left) const {
  std::string pts;
  for (const auto& [x, y] : raw_) pts += fmt::format("{:.1f},{:.1f} ", X(x), Y(y));
  for (const Column& c : cols_) {
    const double px = left + c.index + 0.5;
    pts += fmt::format("{:.1f},{:.1f} {:.1f},{:.1f} ", px, Y(c.hi), px, Y(c.lo));
  }
  return pts;
}

int Plot::columns() const { return std::max(1, static_cast<int>(width - kMarginLeft - kMarginRight)); }

std::string render_svg(const Plot& p) {
  // data ranges over all finite points (the x range given, if it is)
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  for (const PlotSeries& s : p.series) {
    if (s.reduced) {
      if (!s.x.empty() || !s.y.empty())
        throw InvalidArgument(fmt::format("plot '{}': series '{}' is given both reduced and as {} points, expected one", p.title, s.name, s.x.size()));
      const auto [lo, hi] = s.reduced->y_extent();
      if (std::isfinite(lo)) y0 = std::min(y0, lo), y1 = std::max(y1, hi);
      continue;
    }
    if (s.x.size() != s.y.size())
      throw InvalidArgument(fmt::format("plot '{}': series '{}' has {} x values and {} y values, expected equal",
                                        p.title, s.name, s.x.size(), s.y.size()));
    for (size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      x0 = std::min(x0, s.x[i]);
      x1 = std::max(x1, s.x[i]);
      y0 = std::min(y0, s.y[i]);
      y1 = std::max(y1, s.y[i]);
    }
  }
  if (p.x_range) std::tie(x0, x1) = *p.x_range;
  std::tie(x0, x1) = drawn_range(x0, x1);
  if (!(y1 >= y0)) y0 = 0.0, y1 = 1.0;
  if (y1 == y0) y0 -= 0.5, y1 += 0.5;
  const double ypad = 0.05 * (y1 - y0);
  y0 -= ypad;
  y1 += ypad;

  const int W = p.width, H = p.height;
  const double pw = W - kMarginLeft - kMarginRight, ph = H - kMarginTop - kMarginBottom;
  auto X = [&](double x) { return kMarginLeft + (x - x0) / (x1 - x0) * pw; };
  auto Y = [&](double y) { return kMarginTop + (y1 - y) / (y1 - y0) * ph; };

  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" viewBox=\"0 0 {} {}\" "
      "font-family=\"sans-serif\" font-size=\"11\">\n",
      W, H, W, H);
  svg += fmt::format("<text x=\"{}\" y=\"14\" font-weight=\"bold\">{}</text>\n", kMarginLeft, HtmlReport::escape(p.title));
  // spans first, under the lines
  for (const PlotSpan& s : p.spans) {
    const double a = std::clamp(X(s.x0), double(kMarginLeft), kMarginLeft + pw);
    const double b = std::clamp(X(s.x1), double(kMarginLeft), kMarginLeft + pw);
    svg += fmt::format("<rect x=\"{:.1f}\" y=\"{}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"{}\"><title>{}</title></rect>\n",
                       a, kMarginTop, std::max(b - a, 1.0), ph, s.color, HtmlReport::escape(s.label));
  }
  // axes and ticks
  svg += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"none\" stroke=\"#999\"/>\n",
                     kMarginLeft, kMarginTop, pw, ph);
  const double xs = nice_step(x1 - x0, 8), ys = nice_step(y1 - y0, 5);
  for (double t = std::ceil(x0 / xs) * xs; t <= x1 + 1e-12; t += xs)
    svg += fmt::format("<line x1=\"{0:.1f}\" x2=\"{0:.1f}\" y1=\"{1}\" y2=\"{2:.1f}\" stroke=\"#eee\"/>"
                       "<text x=\"{0:.1f}\" y=\"{3:.1f}\" text-anchor=\"middle\">{4}</text>\n",
                       X(t), kMarginTop, kMarginTop + ph, kMarginTop + ph + 14, fmt_tick(t));
  for (double t = std::ceil(y0 / ys) * ys; t <= y1 + 1e-12; t += ys)
    svg += fmt::format("<line x1=\"{0}\" x2=\"{1:.1f}\" y1=\"{2:.1f}\" y2=\"{2:.1f}\" stroke=\"#eee\"/>"
                       "<text x=\"{3}\" y=\"{4:.1f}\" text-anchor=\"end\">{5}</text>\n",
                       kMarginLeft, kMarginLeft + pw, Y(t), kMarginLeft - 4, Y(t) + 4, fmt_tick(t));
  svg += fmt::format("<text x=\"{:.1f}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n", kMarginLeft + pw / 2, H - 4,
                     HtmlReport::escape(p.x_label));
  svg += fmt::format("<text x=\"12\" y=\"{:.1f}\" text-anchor=\"middle\" transform=\"rotate(-90 12 {:.1f})\">{}</text>\n",
                     kMarginTop + ph / 2, kMarginTop + ph / 2, HtmlReport::escape(p.y_label));

  // series: min/max envelope per pixel column keeps every peak of long signals (SeriesEnvelope)
  const int columns = p.columns();
  for (size_t si = 0; si < p.series.size(); ++si) {
    const PlotSeries& s = p.series[si];
    const std::string color = s.color.empty() ? kPalette[si % std::size(kPalette)] : s.color;
    std::string pts;
    if (s.reduced) {
      const SeriesEnvelope& e = *s.reduced;
      if (e.x0() != x0 || e.x1() != x1 || e.columns() != columns)
        throw InvalidArgument(fmt::format("plot '{}': series '{}' was reduced over x [{}, {}] in {} columns, the plot draws [{}, {}] in {}",
                                          p.title, s.name, e.x0(), e.x1(), e.columns(), x0, x1, columns));
      pts = e.points(X, Y, kMarginLeft);
    } else {
      SeriesEnvelope e(x0, x1, columns);
      for (size_t i = 0; i < s.x.size(); ++i) e.add(s.x[i], s.y[i]);
      pts = e.points(X, Y, kMarginLeft);
    }
    svg += fmt::format("<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"1.2\"{} points=\"{}\"/>\n", color,
                       s.dashed ? " stroke-dasharray=\"5,3\"" : "", pts);
    // legend
    const double ly = kMarginTop + 10 + 14.0 * static_cast<double>(si);
    svg += fmt::format("<line x1=\"{0:.1f}\" x2=\"{1:.1f}\" y1=\"{2:.1f}\" y2=\"{2:.1f}\" stroke=\"{3}\" stroke-width=\"2\"{4}/>"
                       "<text x=\"{5:.1f}\" y=\"{6:.1f}\">{7}</text>\n",
                       kMarginLeft + pw + 8, kMarginLeft + pw + 28, ly, color, s.dashed ? " stroke-dasharray=\"5,3\"" : "",
                       kMarginLeft + pw + 32, ly + 4, HtmlReport::escape(s.name));
  }
  svg += "</svg>\n";
  return svg;
}

HtmlReport::HtmlReport(std::string title) : title_(std::move(title)) {}

void HtmlReport::add_heading(const std::string& text, int level) {
  level = std::clamp(level, 1, 4);
  body_ += fmt::format("<h{0}>{1}</h{0}>\n", level, escape(text));
}

void HtmlReport::add_paragraph(const std::string& text) { body_ += "<p>" + escape(text) + "</p>\n"; }

void HtmlReport::add_table(const std::string& caption, const std::vector<std::string>& header,
                           const std::vector<std::vector<std::string>>& rows) {
  std::string t = "<table>\n";
  if (!caption.empty()) t += "<caption>" + escape(caption) + "</caption>\n";
  t += "<tr>";
  for (const auto& h : header) t += "<th>" + escape(h) + "</th>";
  t += "</tr>\n";
  for (size_t r = 0; r < rows.size(); ++r) {
    if (rows[r].size() != header.size())
      throw InvalidArgument(fmt::format("table '{}': row {} has {} cells, expected {} (the header's)", caption, r,
                                        rows[r].size(), header.size()));
    t += "<tr>";
    for (const auto& c : rows[r]) t += "<td>" + escape(c) + "</td>";
    t += "</tr>\n";
  }
  body_ += t + "</table>\n";
}

void HtmlReport::add_plot(const Plot& plot) { body_ += "<figure>" + render_svg(plot) + "</figure>\n"; }

std::string HtmlReport::render() const {
  return fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{0}</title>\n"
      "<style>body{{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}}"
      "table{{border-collapse:collapse;margin:1em 0}}td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}}"
      "th{{background:#f4f4f4}}caption{{font-weight:bold;text-align:left;padding:4px 0}}figure{{margin:0.5em 0}}</style>\n"
      "</head><body>\n<h1>{0}</h1>\n{1}</body></html>\n",
      escape(title_), body_);
}

void HtmlReport::write(const std::string& path) const {
  std::ofstream f(path, std::ios::binary);
  if (!f) throw PathError(path + ": cannot open for writing");
  f << render();
  if (!f) throw std::runtime_error(path + ": write failed");
}

}  // namespace twinwatch::ui
