#pragma once
/// @file html_report.hpp
/// A self-contained HTML report: headings, paragraphs, tables and line plots rendered as inline
/// SVG (no scripts, no external files), so a report can be mailed or archived as one file.
/// Long series are reduced to a min/max envelope per pixel column, so a one-hour 500 Hz
/// recording still renders every peak.
#include <string>
#include <vector>

namespace twinwatch::ui {

/// One line in a plot.
struct PlotSeries {
  std::string name;
  std::vector<double> x;
  std::vector<double> y;
  std::string color;    ///< CSS colour; "" picks from the palette
  bool dashed = false;
};

/// A shaded interval on the x axis (e.g. an alert span or a ground-truth fault interval).
struct PlotSpan {
  double x0 = 0.0;
  double x1 = 0.0;
  std::string label;
  std::string color = "rgba(220,50,47,0.15)";
};

struct Plot {
  std::string title;
  std::string x_label;
  std::string y_label;
  std::vector<PlotSeries> series;
  std::vector<PlotSpan> spans;
  int width = 900;   ///< [px]
  int height = 220;  ///< [px]
};

class HtmlReport {
 public:
  explicit HtmlReport(std::string title);

  void add_heading(const std::string& text, int level = 2);
  /// Plain text paragraph (escaped).
  void add_paragraph(const std::string& text);
  /// A table; every row must have as many cells as the header (throws InvalidArgument naming the row).
  void add_table(const std::string& caption, const std::vector<std::string>& header,
                 const std::vector<std::vector<std::string>>& rows);
  /// A line plot. Series with x/y of different lengths throw InvalidArgument naming the series.
  void add_plot(const Plot& plot);

  /// The whole page.
  std::string render() const;
  /// Writes render() to `path`; throws std::runtime_error naming the path on failure.
  void write(const std::string& path) const;

  /// Escapes &, <, >, " for HTML text and attributes.
  static std::string escape(const std::string& s);

 private:
  std::string title_;
  std::string body_;
};

/// Renders one plot as an SVG element (exposed for tests).
std::string render_svg(const Plot& plot);

}  // namespace twinwatch::ui
