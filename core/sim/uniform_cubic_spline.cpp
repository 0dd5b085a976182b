#include "sim/uniform_cubic_spline.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.hpp"
#include "sim/option_checks.hpp"

namespace posefuse::sim {

UniformCubicSpline::UniformCubicSpline(double t0_s, double dt_s, std::vector<Eigen::VectorXd> values)
    : t0_s_(t0_s), dt_s_(dt_s), values_(std::move(values)) {
  require_finite(t0_s, "spline.t0_s");
  require_positive(dt_s, "spline.dt_s");
  const std::size_t n = values_.size();
  if (n < 2) throw_invalid("spline.values", "needs at least 2 values, got " + std::to_string(n));
  const Eigen::Index dim = values_[0].size();
  for (std::size_t k = 0; k < n; ++k) {
    if (values_[k].size() != dim || !values_[k].allFinite()) {
      throw_invalid("spline.values[" + std::to_string(k) + "]", "wrong size or not finite");
    }
  }
  // Tridiagonal system M_{k-1} + 4 M_k + M_{k+1} = 6 (y_{k+1} - 2 y_k + y_{k-1}) / dt^2 for the
  // interior second derivatives, M_0 = M_{n-1} = 0; Thomas algorithm.
  second_derivatives_.assign(n, Eigen::VectorXd::Zero(dim));
  if (n < 3) return;
  std::vector<double> c(n, 0.0);
  std::vector<Eigen::VectorXd> d(n, Eigen::VectorXd::Zero(dim));
  const double scale = 6.0 / (dt_s * dt_s);
  for (std::size_t k = 1; k + 1 < n; ++k) {
    const Eigen::VectorXd rhs = scale * (values_[k + 1] - 2.0 * values_[k] + values_[k - 1]);
    const double denominator = 4.0 - (k > 1 ? c[k - 1] : 0.0);
    c[k] = 1.0 / denominator;
    d[k] = (rhs - (k > 1 ? d[k - 1] : Eigen::VectorXd::Zero(dim))) / denominator;
  }
  for (std::size_t k = n - 2; k >= 1; --k) {
    second_derivatives_[k] = d[k] - c[k] * second_derivatives_[k + 1];
  }
}

Eigen::VectorXd UniformCubicSpline::at(double t_s) const {
  const double u = std::clamp((t_s - t0_s_) / dt_s_, 0.0, static_cast<double>(values_.size() - 1));
  const std::size_t i = std::min(static_cast<std::size_t>(u), values_.size() - 2);
  const double b = u - static_cast<double>(i);  // weight of the right point
  const double a = 1.0 - b;
  const double h2 = dt_s_ * dt_s_ / 6.0;
  return a * values_[i] + b * values_[i + 1] +
         h2 * ((a * a * a - a) * second_derivatives_[i] + (b * b * b - b) * second_derivatives_[i + 1]);
}

Eigen::VectorXd UniformCubicSpline::at_extended(double t_s) const {
  const std::size_t last = values_.size() - 1;
  // End slopes of the cubic pieces (second derivative zero at the ends).
  if (t_s < t_begin_s()) {
    const Eigen::VectorXd slope = (values_[1] - values_[0]) / dt_s_ - dt_s_ / 6.0 * second_derivatives_[1];
    return values_[0] + (t_s - t_begin_s()) * slope;
  }
  if (t_s > t_end_s()) {
    const Eigen::VectorXd slope =
        (values_[last] - values_[last - 1]) / dt_s_ + dt_s_ / 6.0 * second_derivatives_[last - 1];
    return values_[last] + (t_s - t_end_s()) * slope;
  }
  return at(t_s);
}

std::vector<Eigen::VectorXd> gaussian_smooth(const std::vector<Eigen::VectorXd>& frames, double sigma_frames) {
  if (!(sigma_frames > 0) || frames.size() < 2) return frames;
  const auto radius = static_cast<std::ptrdiff_t>(std::ceil(3.0 * sigma_frames));
  const auto n = static_cast<std::ptrdiff_t>(frames.size());
  const auto at = [&](std::ptrdiff_t j) -> const Eigen::VectorXd& {
    return frames[static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(j, 0, n - 1))];
  };
  // Beyond the ends the sequence is continued by point reflection about the end value
  // (x_{-k} = 2 x_0 - x_k), which keeps a linear trend linear: a truncated kernel would pull
  // the end values towards the interior and bend a steady motion there.
  const auto extended = [&](std::ptrdiff_t j) -> Eigen::VectorXd {
    if (j < 0) return 2.0 * at(0) - at(-j);
    if (j >= n) return 2.0 * at(n - 1) - at(2 * (n - 1) - j);
    return at(j);
  };
  std::vector<Eigen::VectorXd> out(frames.size());
  for (std::ptrdiff_t k = 0; k < n; ++k) {
    Eigen::VectorXd sum = Eigen::VectorXd::Zero(frames[0].size());
    double weight_sum = 0.0;
    for (std::ptrdiff_t j = k - radius; j <= k + radius; ++j) {
      const double x = static_cast<double>(j - k) / sigma_frames;
      const double w = std::exp(-0.5 * x * x);
      sum += w * extended(j);
      weight_sum += w;
    }
    out[static_cast<std::size_t>(k)] = sum / weight_sum;
  }
  return out;
}

}  // namespace posefuse::sim
