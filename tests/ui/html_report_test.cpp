#include "twinwatch/ui/html_report.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

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
