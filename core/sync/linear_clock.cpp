#include "sync/linear_clock.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/Dense>

#include "common/error.hpp"

namespace posefuse::sync {

double LinearClock::to_reference_us(double device_us) const {
  return device_us + offset_us + drift * (device_us - anchor_device_us);
}

double LinearClock::sigma_us(double device_us) const {
  const Eigen::Vector2d j(1.0, device_us - anchor_device_us);
  return std::sqrt(std::max(0.0, j.dot(covariance * j)));
}

LinearClock compose(const LinearClock& outer, const LinearClock& inner) {
  LinearClock c;
  c.anchor_device_us = inner.anchor_device_us;
  const double mid_at_anchor = inner.to_reference_us(inner.anchor_device_us);
  c.offset_us = outer.to_reference_us(mid_at_anchor) - c.anchor_device_us;
  c.drift = (1.0 + inner.drift) * (1.0 + outer.drift) - 1.0;
  // Jacobian of (offset, drift) with respect to (inner offset, inner drift, outer offset,
  // outer drift).
  Eigen::Matrix<double, 2, 4> jac;
  jac << 1.0 + outer.drift, 0.0, 1.0, mid_at_anchor - outer.anchor_device_us, 0.0, 1.0 + outer.drift, 0.0,
      1.0 + inner.drift;
  Eigen::Matrix4d cov = Eigen::Matrix4d::Zero();
  cov.topLeftCorner<2, 2>() = inner.covariance;
  cov.bottomRightCorner<2, 2>() = outer.covariance;
  c.covariance = jac * cov * jac.transpose();
  return c;
}

namespace {

double median_of(std::vector<double> v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

void validate(const std::vector<ClockObservation>& obs, const ClockFitOptions& o) {
  if (obs.empty()) throw_invalid("observations", "no clock observations");
  for (std::size_t i = 0; i < obs.size(); ++i) {
    const std::string at = "observations[" + std::to_string(i) + "].";
    if (!std::isfinite(obs[i].device_us)) throw_invalid(at + "device_us", "not finite");
    if (!std::isfinite(obs[i].reference_us)) throw_invalid(at + "reference_us", "not finite");
    if (!std::isfinite(obs[i].sigma_us) || obs[i].sigma_us < 0.0) {
      throw_invalid(at + "sigma_us", "must be finite and >= 0, got " + std::to_string(obs[i].sigma_us));
    }
  }
  if (!(o.drift_prior_sigma > 0.0) || !(o.outlier_sigmas > 0.0) || !(o.min_sigma_us > 0.0) || o.max_iterations < 1) {
    throw_invalid("options", "drift_prior_sigma, outlier_sigmas, min_sigma_us and max_iterations must be > 0");
  }
}

// Median of slopes between observations half the set apart in device time: robust start.
double pairwise_slope_median(const std::vector<ClockObservation>& obs) {
  std::vector<std::size_t> order(obs.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return obs[a].device_us < obs[b].device_us; });
  const std::size_t half = order.size() / 2;
  std::vector<double> slopes;
  for (std::size_t i = 0; i + half < order.size() && half > 0; ++i) {
    const ClockObservation& a = obs[order[i]];
    const ClockObservation& b = obs[order[i + half]];
    const double dx = b.device_us - a.device_us;
    if (dx <= 0.0) continue;
    slopes.push_back(((b.reference_us - b.device_us) - (a.reference_us - a.device_us)) / dx);
  }
  return slopes.empty() ? 0.0 : median_of(slopes);
}

}  // namespace

ClockFit fit_linear_clock(const std::vector<ClockObservation>& obs, const ClockFitOptions& o) {
  validate(obs, o);
  const std::size_t n = obs.size();
  double anchor = 0.0;
  for (const auto& ob : obs) anchor += ob.device_us / static_cast<double>(n);

  auto sigma_of = [&](std::size_t i) { return std::max(obs[i].sigma_us, o.min_sigma_us); };
  auto residual = [&](std::size_t i, double offset, double drift) {
    return (obs[i].reference_us - obs[i].device_us) - offset - drift * (obs[i].device_us - anchor);
  };

  double drift = pairwise_slope_median(obs);
  std::vector<double> start(n);
  for (std::size_t i = 0; i < n; ++i) start[i] = residual(i, 0.0, drift);
  double offset = median_of(start);

  ClockFit fit;
  fit.inlier.assign(n, true);
  Eigen::Matrix2d info = Eigen::Matrix2d::Zero();
  for (int iteration = 0; iteration < o.max_iterations; ++iteration) {
    // Robust spread of the normalised residuals; never reject tighter than the sigmas claim.
    std::vector<double> z(n), abs_dev(n);
    for (std::size_t i = 0; i < n; ++i) z[i] = residual(i, offset, drift) / sigma_of(i);
    const double z_median = median_of(z);
    for (std::size_t i = 0; i < n; ++i) abs_dev[i] = std::abs(z[i] - z_median);
    const double spread = std::max(1.0, 1.4826 * median_of(abs_dev));
    std::vector<bool> inlier(n);
    for (std::size_t i = 0; i < n; ++i) inlier[i] = std::abs(z[i]) <= o.outlier_sigmas * spread;

    info = Eigen::Matrix2d::Zero();
    info(1, 1) = 1.0 / (o.drift_prior_sigma * o.drift_prior_sigma);  // prior: drift ~ N(0, s^2)
    Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
    for (std::size_t i = 0; i < n; ++i) {
      if (!inlier[i]) continue;
      const double w = 1.0 / (sigma_of(i) * sigma_of(i));
      const Eigen::Vector2d j(1.0, obs[i].device_us - anchor);
      info += w * j * j.transpose();
      rhs += w * j * (obs[i].reference_us - obs[i].device_us);
    }
    const Eigen::Vector2d solution = info.ldlt().solve(rhs);
    offset = solution[0];
    drift = solution[1];
    const bool settled = inlier == fit.inlier && iteration > 0;
    fit.inlier = inlier;
    if (settled) break;
  }

  double chi2 = 0.0, sum_sq = 0.0;
  fit.inlier_count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!fit.inlier[i]) continue;
    const double r = residual(i, offset, drift);
    chi2 += r * r / (sigma_of(i) * sigma_of(i));
    sum_sq += r * r;
    ++fit.inlier_count;
  }
  // Scatter beyond the claimed sigmas widens the covariance (never narrows it).
  const int dof = fit.inlier_count - 2;
  const double inflation = dof > 0 ? std::max(1.0, chi2 / dof) : 1.0;
  fit.clock.anchor_device_us = anchor;
  fit.clock.offset_us = offset;
  fit.clock.drift = drift;
  fit.clock.covariance = inflation * info.inverse();
  fit.residual_rms_us = fit.inlier_count > 0 ? std::sqrt(sum_sq / fit.inlier_count) : 0.0;
  return fit;
}

}  // namespace posefuse::sync
