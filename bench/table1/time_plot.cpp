#include "time_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace posefuse::bench {

namespace {

constexpr int kWidth = 1200, kPanelHeight = 240, kLeft = 70, kRight = 20, kTop = 28, kBottom = 26;

std::string tick_label(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", v);
  return text;
}

void draw_panel(cv::Mat& image, int y0, const std::vector<double>& t, const std::vector<bool>& shaded,
                const PlotPanel& panel) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const PlotLine& line : panel.lines) {
    for (const double v : line.y) {
      if (!std::isfinite(v)) continue;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  if (!std::isfinite(lo)) lo = 0.0, hi = 1.0;
  if (lo >= 0.0) lo = 0.0;
  if (hi - lo < 1e-9) hi = lo + 1.0;
  const double pad = 0.05 * (hi - lo);
  hi += pad;
  if (lo < 0.0) lo -= pad;
  const double t0 = t.front(), t1 = std::max(t.back(), t0 + 1e-9);
  const int plot_w = kWidth - kLeft - kRight, plot_h = kPanelHeight - kTop - kBottom;
  const auto px = [&](double time) { return kLeft + static_cast<int>(std::lround((time - t0) / (t1 - t0) * plot_w)); };
  const auto py = [&](double v) { return y0 + kTop + static_cast<int>(std::lround((hi - v) / (hi - lo) * plot_h)); };

  for (std::size_t i = 0; i < t.size(); ++i) {  // occluded frames as grey columns
    if (!shaded[i]) continue;
    const double half = 0.5 * (i + 1 < t.size() ? t[i + 1] - t[i] : t[i] - t[i - 1]);
    cv::rectangle(image, cv::Point(px(t[i] - half), py(hi)), cv::Point(px(t[i] + half), py(lo)),
                  cv::Scalar(215, 215, 215), cv::FILLED);
  }
  cv::rectangle(image, cv::Point(kLeft, py(hi)), cv::Point(kLeft + plot_w, py(lo)), cv::Scalar(0, 0, 0), 1);
  for (int k = 0; k <= 4; ++k) {
    const double v = lo + (hi - lo) * k / 4.0;
    cv::line(image, cv::Point(kLeft - 4, py(v)), cv::Point(kLeft, py(v)), cv::Scalar(0, 0, 0), 1);
    cv::putText(image, tick_label(v), cv::Point(4, py(v) + 4), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1,
                cv::LINE_AA);
  }
  for (double s = std::ceil(t0); s <= t1; s += (t1 - t0) > 30.0 ? 5.0 : 1.0) {
    cv::line(image, cv::Point(px(s), py(lo)), cv::Point(px(s), py(lo) + 4), cv::Scalar(0, 0, 0), 1);
    cv::putText(image, tick_label(s), cv::Point(px(s) - 6, py(lo) + 17), cv::FONT_HERSHEY_SIMPLEX, 0.4,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  cv::putText(image, panel.title, cv::Point(kLeft, y0 + 18), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  int legend_x = kLeft + plot_w - 170 * static_cast<int>(panel.lines.size());
  for (const PlotLine& line : panel.lines) {
    cv::line(image, cv::Point(legend_x, y0 + 14), cv::Point(legend_x + 24, y0 + 14), line.color, 2);
    cv::putText(image, line.label, cv::Point(legend_x + 30, y0 + 18), cv::FONT_HERSHEY_SIMPLEX, 0.45, line.color, 1,
                cv::LINE_AA);
    legend_x += 170;
    for (std::size_t i = 0; i + 1 < t.size() && i + 1 < line.y.size(); ++i) {
      if (!std::isfinite(line.y[i]) || !std::isfinite(line.y[i + 1])) continue;
      cv::line(image, cv::Point(px(t[i]), py(line.y[i])), cv::Point(px(t[i + 1]), py(line.y[i + 1])), line.color, 1,
               cv::LINE_AA);
    }
  }
}

}  // namespace

bool write_time_plot(const std::string& png_path, const std::vector<double>& t_s, const std::vector<bool>& shaded,
                     const std::vector<PlotPanel>& panels) {
  if (t_s.size() < 2 || shaded.size() != t_s.size()) return false;
  cv::Mat image(kPanelHeight * static_cast<int>(panels.size()) + 20, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  for (std::size_t p = 0; p < panels.size(); ++p) {
    draw_panel(image, kPanelHeight * static_cast<int>(p), t_s, shaded, panels[p]);
  }
  cv::putText(image, "time (s); grey: occluded frames", cv::Point(kLeft, image.rows - 4), cv::FONT_HERSHEY_SIMPLEX,
              0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  return cv::imwrite(png_path, image, {cv::IMWRITE_PNG_COMPRESSION, 9});
}

}  // namespace posefuse::bench
