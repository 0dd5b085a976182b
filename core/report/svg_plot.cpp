#include "report/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "report/html_text.hpp"

namespace posefuse::report {
namespace {

constexpr double kWidth = 900, kHeight = 240;
constexpr double kLeft = 52, kRight = 170, kTop = 26, kBottom = 34;

// The smallest step of `steps` that puts at most `max_ticks` ticks on `span`.
double tick_step(double span, const std::vector<double>& steps, int max_ticks) {
  for (const double step : steps)
    if (span / step <= max_ticks) return step;
  return steps.back() * std::ceil(span / (steps.back() * max_ticks));
}

struct Axes {
  double t0, t1, y0, y1;
  double x(double t) const { return kLeft + (t - t0) / (t1 - t0) * (kWidth - kLeft - kRight); }
  double y(double v) const { return kTop + (y1 - v) / (y1 - y0) * (kHeight - kTop - kBottom); }
};

Axes axes_for(const PlotSpec& spec, double& y_step) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const PlotSeries& s : spec.series) {
    for (const double v : s.value) {
      if (!std::isfinite(v)) continue;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  if (!std::isfinite(lo)) lo = 0, hi = 90;  // no values: an empty plot with a sensible scale
  y_step = tick_step(std::max(hi - lo, 1.0), {5, 10, 15, 30, 45, 90}, 8);
  lo = std::floor(lo / y_step) * y_step;
  hi = std::ceil(hi / y_step) * y_step;
  if (hi - lo < y_step) hi = lo + y_step;
  const double t1 = spec.t1_s > spec.t0_s ? spec.t1_s : spec.t0_s + 1.0;
  return {spec.t0_s, t1, lo, hi};
}

std::string point(const Axes& a, double t, double v) { return fixed(a.x(t), 1) + " " + fixed(a.y(v), 1); }

// One <path> per run of finite values of one confidence state; a run starts at the last point of
// the run before it, so that the line stays continuous where only the state changes.
std::string series_paths(const Axes& a, const PlotSeries& s) {
  std::string out;
  std::string d;
  bool confident = false;
  std::size_t previous = std::numeric_limits<std::size_t>::max();  // last finite index
  const auto flush = [&] {
    if (d.find('L') != std::string::npos)
      out += "<path class=\"line " + std::string(confident ? "confident" : "unconfident") + "\" stroke=\"" +
             html_escape(s.colour) + "\" d=\"" + d + "\"/>\n";
    d.clear();
  };
  for (std::size_t i = 0; i < s.value.size() && i < s.t_s.size(); ++i) {
    if (!std::isfinite(s.value[i])) {
      flush();
      previous = std::numeric_limits<std::size_t>::max();
      continue;
    }
    const bool state = i < s.confidence.size() && s.confidence[i] >= kConfidentAt;
    if (previous == std::numeric_limits<std::size_t>::max()) {
      confident = state;
      d = "M" + point(a, s.t_s[i], s.value[i]);
    } else if (state != confident) {
      flush();
      confident = state;
      d = "M" + point(a, s.t_s[previous], s.value[previous]) + " L" + point(a, s.t_s[i], s.value[i]);
    } else {
      d += " L" + point(a, s.t_s[i], s.value[i]);
    }
    previous = i;
  }
  flush();
  return out;
}

}  // namespace

std::string svg_plot(const PlotSpec& spec) {
  double y_step = 10;
  const Axes a = axes_for(spec, y_step);
  std::string out = "<svg class=\"plot\" id=\"" + html_escape(spec.id) +
                    "\" xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 " + fixed(kWidth, 0) + " " +
                    fixed(kHeight, 0) + "\" role=\"img\" aria-label=\"" + html_escape(spec.title) + "\">\n";
  out += "<text class=\"plot-title\" x=\"" + fixed(kLeft, 0) + "\" y=\"16\">" + html_escape(spec.title) + "</text>\n";
  std::set<std::string> shade_kinds;
  for (const Shade& shade : spec.shades) {
    const double x0 = a.x(std::clamp(shade.t0_s, a.t0, a.t1)), x1 = a.x(std::clamp(shade.t1_s, a.t0, a.t1));
    out += "<rect class=\"shade shade-" + html_escape(shade.kind) + "\" x=\"" + fixed(x0, 1) + "\" y=\"" +
           fixed(kTop, 1) + "\" width=\"" + fixed(std::max(x1 - x0, 1.0), 1) + "\" height=\"" +
           fixed(kHeight - kTop - kBottom, 1) + "\"><title>" + html_escape(shade.kind) + " " +
           fixed(shade.t0_s - a.t0, 2) + "-" + fixed(shade.t1_s - a.t0, 2) + " s</title></rect>\n";
    shade_kinds.insert(shade.kind);
  }
  for (double v = a.y0; v <= a.y1 + 1e-9; v += y_step) {
    out += "<line class=\"grid\" x1=\"" + fixed(kLeft, 1) + "\" x2=\"" + fixed(kWidth - kRight, 1) + "\" y1=\"" +
           fixed(a.y(v), 1) + "\" y2=\"" + fixed(a.y(v), 1) + "\"/><text class=\"tick\" x=\"" + fixed(kLeft - 6, 1) +
           "\" y=\"" + fixed(a.y(v) + 4, 1) + "\" text-anchor=\"end\">" + fixed(v, 0) + "</text>\n";
  }
  const double t_step = tick_step(a.t1 - a.t0, {0.5, 1, 2, 5, 10, 15, 30, 60, 120, 300, 600}, 10);
  for (double t = 0; a.t0 + t <= a.t1 + 1e-9; t += t_step) {
    out += "<text class=\"tick\" x=\"" + fixed(a.x(a.t0 + t), 1) + "\" y=\"" + fixed(kHeight - kBottom + 16, 1) +
           "\" text-anchor=\"middle\">" + fixed(t, t_step < 1 ? 1 : 0) + "</text>\n";
  }
  out += "<text class=\"axis-label\" x=\"" + fixed(kWidth - kRight, 1) + "\" y=\"" + fixed(kHeight - 4, 1) +
         "\" text-anchor=\"end\">time from the first frame (s)</text>\n";
  out += "<text class=\"axis-label\" x=\"4\" y=\"" + fixed(kTop - 8, 1) + "\">deg</text>\n";
  out += "<rect class=\"frame\" x=\"" + fixed(kLeft, 1) + "\" y=\"" + fixed(kTop, 1) + "\" width=\"" +
         fixed(kWidth - kLeft - kRight, 1) + "\" height=\"" + fixed(kHeight - kTop - kBottom, 1) + "\"/>\n";
  for (const PlotSeries& s : spec.series) out += series_paths(a, s);
  double legend_y = kTop + 8;
  for (const PlotSeries& s : spec.series) {
    out += "<line class=\"legend-line\" stroke=\"" + html_escape(s.colour) + "\" x1=\"" +
           fixed(kWidth - kRight + 12, 1) + "\" x2=\"" + fixed(kWidth - kRight + 30, 1) + "\" y1=\"" +
           fixed(legend_y, 1) + "\" y2=\"" + fixed(legend_y, 1) + "\"/><text class=\"legend\" x=\"" +
           fixed(kWidth - kRight + 34, 1) + "\" y=\"" + fixed(legend_y + 4, 1) + "\">" + html_escape(s.label) +
           "</text>\n";
    legend_y += 16;
  }
  for (const std::string& kind : shade_kinds) {
    out += "<rect class=\"shade shade-" + html_escape(kind) + "\" x=\"" + fixed(kWidth - kRight + 12, 1) + "\" y=\"" +
           fixed(legend_y - 6, 1) + "\" width=\"18\" height=\"10\"/><text class=\"legend\" x=\"" +
           fixed(kWidth - kRight + 34, 1) + "\" y=\"" + fixed(legend_y + 4, 1) + "\">" + html_escape(kind) +
           "</text>\n";
    legend_y += 16;
  }
  out += "</svg>\n";
  return out;
}

}  // namespace posefuse::report
