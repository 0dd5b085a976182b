#pragma once
// One time plot as inline SVG: lines over time in degrees, gaps where a value is missing,
// a line drawn faint and dashed where its confidence is below kConfidentAt, and shaded spans
// (occlusions, a lost fit) behind the lines.
#include <string>
#include <vector>

#include "measures/joint_angles.hpp"

namespace posefuse::report {

using measures::kConfidentAt;

struct PlotSeries {
  std::string label;
  std::string colour;  // CSS colour
  std::vector<double> t_s;
  std::vector<double> value;       // NaN: no value (a gap in the line)
  std::vector<double> confidence;  // 0..1, one per value
};

struct Shade {
  double t0_s = 0.0, t1_s = 0.0;
  std::string kind;  // CSS class suffix and legend key: "occluded", "recovered", "lost"
};

struct PlotSpec {
  std::string id;  // the element id, e.g. "plot-right-elbow"
  std::string title;
  double t0_s = 0.0, t1_s = 1.0;  // the time axis
  std::vector<PlotSeries> series;
  std::vector<Shade> shades;
};

// An <svg> element with class "plot" and the spec's id: axes with ticks, one <path> per
// confident and per unconfident run of each series, one <rect> per shade, a legend.
std::string svg_plot(const PlotSpec& spec);

}  // namespace posefuse::report
