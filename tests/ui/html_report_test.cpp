#include "twinwatch/ui/html_report.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <regex>

#include "twinwatch/core/error.hpp"

namespace twinwatch::ui {
namespace {

using ::testing::HasSubstr;

TEST(HtmlReport, EscapesTextAndKeepsTablesAligned) {
  HtmlReport r("Run <1> & co");
  r.add_table("Table 3", {"joint", "RMSE"}, {{"J1", "0.036"}, {"J2", "0.041"}});
  const std::string html = r.render();
  EXPECT_THAT(html, HasSubstr("Run &lt;1&gt; &amp; co"));
  EXPECT_THAT(html, HasSubstr("<td>J2</td><td>0.041</td>"));
  EXPECT_THROW(r.add_table("bad", {"a", "b"}, {{"only one"}}), InvalidArgument);
}

TEST(RenderSvg, EnvelopeKeepsAShortPeakOfALongSeries) {
  // 100 000 samples of zero with a single-sample spike: the envelope must still reach it
  Plot p;
  p.title = "residual";
  PlotSeries s;
  s.name = "r";
  for (int i = 0; i < 100000; ++i) {
    s.x.push_back(i * 0.002);
    s.y.push_back(i == 54321 ? 10.0 : 0.0);
  }
  p.series.push_back(s);
  const std::string svg = render_svg(p);
  // the top of the plot area is y = 24 + small pad: the spike's point must be near it
  std::smatch m;
  const std::regex near_top(",(2[4-9]|3[0-9])\\.[0-9] ");
  EXPECT_TRUE(std::regex_search(svg, m, near_top)) << "spike was lost by the envelope";
  EXPECT_LT(svg.size(), 200000u) << "a long series must be reduced, not drawn point by point";
}

// a report streams a day's recording through SeriesEnvelopes instead of holding it: what it draws
// must be what the same series given whole draws, long (reduced per pixel column) or short (drawn
// point by point), with the points a series skips (not finite) among them
TEST(RenderSvg, ASeriesStreamedPointByPointDrawsAsTheSameSeriesGivenWhole) {
  for (const int n : {50, 1500, 100000}) {
    Plot whole;
    whole.title = "J2 current";
    whole.spans.push_back({0.3, 0.5, "alert"});
    PlotSeries a{"measured", {}, {}, "", false}, b{"twin", {}, {}, "", true};
    for (int i = 0; i < n; ++i) {
      const double t = 1.0 + i * 0.002;
      a.x.push_back(t);
      a.y.push_back(std::sin(40.0 * t) + (i == n / 3 ? 5.0 : 0.0));  // a one-sample peak
      b.x.push_back(t);
      b.y.push_back(i % 97 == 5 ? NAN : 0.9 * std::sin(40.0 * t));
    }
    whole.series = {a, b};
    Plot streamed = whole;
    streamed.x_range = std::make_pair(a.x.front(), a.x.back());
    for (PlotSeries& s : streamed.series) {
      SeriesEnvelope e(a.x.front(), a.x.back(), streamed.columns());
      for (size_t i = 0; i < s.x.size(); ++i) e.add(s.x[i], s.y[i]);
      s.x.clear();
      s.y.clear();
      s.reduced = e;
    }
    EXPECT_EQ(render_svg(streamed), render_svg(whole)) << n << " points";
  }
  // each run of points in a column is one min/max pair: 100 000 points draw as at most 2 per column
  Plot p;
  p.x_range = std::make_pair(0.0, 199.998);
  SeriesEnvelope e(0.0, 199.998, p.columns());
  for (int i = 0; i < 100000; ++i) e.add(i * 0.002, i == 54321 ? 10.0 : 0.0);
  EXPECT_EQ(e.y_extent(), std::make_pair(0.0, 10.0));
  p.series.push_back({"r", {}, {}, "", false, e});
  const std::string svg = render_svg(p);
  const auto from = svg.find("points=\""), to = svg.find('"', from + 8);
  const std::string pts = svg.substr(from + 8, to - from - 8);
  EXPECT_EQ(std::count(pts.begin(), pts.end(), ','), 2 * p.columns());
}

TEST(RenderSvg, AStreamedSeriesOfAnotherRangeOrWidthIsRefusedByName) {
  Plot p;
  p.title = "J1 residual";
  p.x_range = std::make_pair(0.0, 10.0);
  SeriesEnvelope e(0.0, 12.0, p.columns());
  e.add(1.0, 2.0);
  p.series.push_back({"threshold", {}, {}, "", false, e});
  try {
    render_svg(p);
    FAIL();
  } catch (const InvalidArgument& ex) {
    EXPECT_THAT(ex.what(), HasSubstr("series 'threshold' was reduced over x [0, 12]"));
  }
  p.series.front().reduced = SeriesEnvelope(0.0, 10.0, p.columns() - 1);
  EXPECT_THROW(render_svg(p), InvalidArgument);
  EXPECT_THROW(SeriesEnvelope(1.0, 0.0, 10), InvalidArgument);
  EXPECT_THROW(SeriesEnvelope(0.0, NAN, 10), InvalidArgument);
}

TEST(RenderSvg, MismatchedSeriesNamesIt) {
  Plot p;
  p.title = "t";
  p.series.push_back({"current J3", {0.0, 1.0}, {0.0}, "", false});
  try {
    render_svg(p);
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("series 'current J3' has 2 x values and 1 y values"));
  }
}

}  // namespace
}  // namespace twinwatch::ui
