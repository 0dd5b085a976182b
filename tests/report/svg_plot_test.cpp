// svg_plot: gaps and confidence split a series into paths; shades and the legend are drawn; text
// is escaped.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "../text_search.hpp"
#include "report/html_text.hpp"
#include "report/svg_plot.hpp"

using namespace posefuse::report;
using posefuse::testing::count_occurrences;

namespace {

PlotSpec one_series(std::vector<double> value, std::vector<double> confidence) {
  PlotSpec spec{"plot-x", "Title", 0.0, static_cast<double>(value.size() - 1), {}, {}};
  PlotSeries s{"flexion", "#123456", {}, std::move(value), std::move(confidence)};
  for (std::size_t i = 0; i < s.value.size(); ++i) s.t_s.push_back(static_cast<double>(i));
  spec.series.push_back(s);
  return spec;
}

}  // namespace

TEST(SvgPlot, ConfidentRunIsOnePath) {
  const std::string svg = svg_plot(one_series({10, 20, 30, 40}, {1, 1, 1, 1}));
  EXPECT_EQ(count_occurrences(svg, "<path class=\"line confident\""), 1u);
  EXPECT_EQ(count_occurrences(svg, "<path class=\"line unconfident\""), 0u);
  EXPECT_EQ(count_occurrences(svg, " L"), 3u);
  EXPECT_NE(svg.find("<svg class=\"plot\" id=\"plot-x\""), std::string::npos);
}

TEST(SvgPlot, AGapEndsThePathAndLowConfidenceGetsItsOwn) {
  const double nan = std::nan("");
  // Confident 0-1, gap at 2, confident 3-4, unconfident 5-6 (joined to 4), a single point at 8.
  const std::string svg = svg_plot(one_series({1, 2, nan, 4, 5, 6, 7, nan, 9}, {1, 1, 1, 1, 1, 0.2, 0.2, 1, 1}));
  EXPECT_EQ(count_occurrences(svg, "<path class=\"line confident\""), 2u);
  EXPECT_EQ(count_occurrences(svg, "<path class=\"line unconfident\""), 1u);  // a lone point draws no line
}

TEST(SvgPlot, ShadesAreDrawnAndListedInTheLegend) {
  PlotSpec spec = one_series({0, 10, 20}, {1, 1, 1});
  spec.shades = {{0.5, 1.5, "occluded"}, {1.6, 1.8, "occluded"}, {0.0, 0.2, "lost"}};
  const std::string svg = svg_plot(spec);
  EXPECT_EQ(count_occurrences(svg, "class=\"shade shade-occluded\""), 3u);  // two stretches and the legend key
  EXPECT_EQ(count_occurrences(svg, "class=\"shade shade-lost\""), 2u);
  EXPECT_NE(svg.find(">flexion</text>"), std::string::npos);
}

TEST(SvgPlot, EscapesTitlesAndLabels) {
  PlotSpec spec = one_series({0, 1}, {1, 1});
  spec.title = "<b>x</b> & \"y\"";
  const std::string svg = svg_plot(spec);
  EXPECT_EQ(svg.find("<b>"), std::string::npos);
  EXPECT_NE(svg.find("&lt;b&gt;x&lt;/b&gt; &amp; &quot;y&quot;"), std::string::npos);
}

TEST(HtmlText, FixedWritesADashForNonFinite) {
  EXPECT_EQ(fixed(1.25, 1), "1.2");
  EXPECT_EQ(fixed(std::nan(""), 1), "-");
  EXPECT_EQ(html_escape("a'b"), "a&#39;b");
}
