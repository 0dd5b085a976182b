#pragma once
// Small OpenCV line plots over time with shaded intervals (paper 1, Figs. 4-6: errors over time,
// occluded frames highlighted), stacked into one PNG.
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace posefuse::bench {

struct PlotLine {
  std::string label;
  std::vector<double> y;  // one per t; NaN leaves a hole
  cv::Scalar color;       // BGR
};

struct PlotPanel {
  std::string title;  // includes the unit
  std::vector<PlotLine> lines;
};

// t and shaded (one flag per t) are shared by all panels; y ranges are taken from the data
// (0 at the bottom when every value is >= 0). Returns false when the PNG cannot be written.
bool write_time_plot(const std::string& png_path, const std::vector<double>& t_s, const std::vector<bool>& shaded,
                     const std::vector<PlotPanel>& panels);

}  // namespace posefuse::bench
