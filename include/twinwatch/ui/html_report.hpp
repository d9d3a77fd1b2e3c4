#pragma once
/// @file html_report.hpp
/// A self-contained HTML report: headings, paragraphs, tables and line plots rendered as inline
/// SVG (no scripts, no external files), so a report can be mailed or archived as one file.
/// Long series are reduced to a min/max envelope per pixel column, so a one-hour 500 Hz
/// recording still renders every peak.
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace twinwatch::ui {

/// What a plot draws of one series over an x range [x0, x1] known ahead, fed a point at a time: the
/// points themselves while there are at most two per pixel column, else their min/max per pixel
/// column (every peak kept). It holds no more than that, so a report streams a day's recording
/// through one of these per line instead of holding its samples (cli report). A point whose x or y is
/// not finite is counted, not drawn, as a series given whole.
class SeriesEnvelope {
 public:
  /// `columns`: the plot's (Plot::columns()); x1 == x0 draws as [x0, x0 + 1], as a plot does
  SeriesEnvelope(double x0, double x1, int columns);
  void add(double x, double y);
  double x0() const { return x0_; }
  double x1() const { return x1_; }
  int columns() const { return columns_; }
  /// the finite y drawn (NaN, NaN while none)
  std::pair<double, double> y_extent() const;
  /// the SVG polyline's points for the plot's pixel maps X (x -> px) and Y (y -> px); `left` is the
  /// pixel at which column 0 begins
  std::string points(const std::function<double(double)>& X, const std::function<double(double)>& Y, double left) const;

 private:
  struct Column {
    int index;
    double lo, hi;
  };
  void to_columns();
  void add_to_columns(double x, double y);
  double x0_, x1_;
  int columns_;
  size_t added_ = 0;
  std::vector<std::pair<double, double>> raw_;  // the finite points, while added_ <= 2 columns
  std::vector<Column> cols_;                     // a column's run (a new one each time x moves to another column)
};

/// One line in a plot.
struct PlotSeries {
  std::string name;
  std::vector<double> x;
  std::vector<double> y;
  std::string color;    ///< CSS colour; "" picks from the palette
  bool dashed = false;
  /// instead of x / y (left empty): the series as it was streamed; its range and columns must be the
  /// plot's (Plot::x_range, Plot::columns()), else the plot throws InvalidArgument naming the series
  std::optional<SeriesEnvelope> reduced = std::nullopt;
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
  /// the x axis' extent; default: that of the series' finite points (needed by a reduced series)
  std::optional<std::pair<double, double>> x_range;
  /// pixel columns of the plotting area (a series reduced for this plot needs as many)
  int columns() const;
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
