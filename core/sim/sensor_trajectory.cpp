#include "sim/sensor_trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.hpp"
#include "sim/option_checks.hpp"

namespace posefuse::sim {
namespace {

constexpr std::size_t kMargin = 2;  // grid points each end that the 5-point stencil needs
// Largest turn over the stencil's half-width that log() still reads correctly, with a margin
// for rounding near pi.
constexpr double kMaxStencilTurn_rad = 3.0;
// Faster than any body segment turns (a baseball pitch's upper arm peaks near 160 rad/s): a
// trajectory turning faster carries a glitch of its input, whose rate would be made up.
constexpr double kMaxRate_rad_s = 200.0;

bool finite(const Vec3& v) { return v.allFinite(); }

}  // namespace

SensorKinematics::SensorKinematics(SensorTrajectory trajectory) : trajectory_(std::move(trajectory)) {
  const SensorTrajectory& t = trajectory_;
  require_positive(t.dt_s, "trajectory.dt_s");
  require_finite(t.t0_s, "trajectory.t0_s");
  const std::size_t n = t.p_W_m.size();
  if (t.W_from_A.size() != n) {
    throw_invalid("trajectory.W_from_A",
                  std::to_string(t.W_from_A.size()) + " orientations for " + std::to_string(n) + " positions");
  }
  if (n < 2 * kMargin + 2) {
    throw_invalid("trajectory.p_W_m", "needs at least 6 poses, got " + std::to_string(n));
  }
  for (std::size_t k = 0; k < n; ++k) {
    if (!finite(t.p_W_m[k])) throw_invalid("trajectory.p_W_m[" + std::to_string(k) + "]", "not finite");
    const double norm = t.W_from_A[k].norm();
    if (!std::isfinite(norm) || std::abs(norm - 1.0) > 1e-6) {
      throw_invalid("trajectory.W_from_A[" + std::to_string(k) + "]",
                    "not a unit quaternion (norm " + std::to_string(norm) + ")");
    }
    trajectory_.W_from_A[k].normalize();
  }
  // The stencil reads each turn over up to kMargin steps through the logarithm, which is
  // unambiguous below pi: a faster turn would alias (2 pi - x reads as -x).
  for (std::size_t k = 1; k < n; ++k) {
    const double step = geometry::angle_between(t.W_from_A[k - 1], t.W_from_A[k]);
    if (step > kMaxRate_rad_s * t.dt_s) {
      throw_invalid("trajectory.W_from_A[" + std::to_string(k) + "]",
                    "turns " + std::to_string(step) + " rad in one step of " + std::to_string(t.dt_s) + " s (" +
                        std::to_string(step / t.dt_s) + " rad/s, faster than any body segment, limit " +
                        std::to_string(kMaxRate_rad_s) + " rad/s); a glitch in the motion it was made from?");
    }
  }
  for (std::size_t k = kMargin; k < n; ++k) {
    const double turn = geometry::angle_between(t.W_from_A[k - kMargin], t.W_from_A[k]);
    if (turn > kMaxStencilTurn_rad) {
      throw_invalid("trajectory.W_from_A[" + std::to_string(k) + "]",
                    "turns " + std::to_string(turn) + " rad in " + std::to_string(kMargin) + " steps of " +
                        std::to_string(t.dt_s) + " s (" + std::to_string(turn / (kMargin * t.dt_s)) +
                        " rad/s); the rate is ambiguous from " + std::to_string(kMaxStencilTurn_rad) +
                        " rad on; sample the trajectory more densely");
    }
  }

  omega_A_.assign(n, Vec3::Zero());
  a_W_.assign(n, Vec3::Zero());
  const double dt = t.dt_s;
  for (std::size_t k = kMargin; k + kMargin < n; ++k) {
    const Quat A_k_from_W = t.W_from_A[k].conjugate();
    auto r = [&](std::size_t j) { return geometry::rotation_vector_from_quat(A_k_from_W * t.W_from_A[j]); };
    omega_A_[k] = (r(k - 2) - 8.0 * r(k - 1) + 8.0 * r(k + 1) - r(k + 2)) / (12.0 * dt);
    a_W_[k] = (-t.p_W_m[k - 2] + 16.0 * t.p_W_m[k - 1] - 30.0 * t.p_W_m[k] + 16.0 * t.p_W_m[k + 1] - t.p_W_m[k + 2]) /
              (12.0 * dt * dt);
  }
}

double SensorKinematics::t_begin_s() const {
  return trajectory_.t0_s + static_cast<double>(kMargin) * trajectory_.dt_s;
}

double SensorKinematics::t_end_s() const {
  return trajectory_.t0_s + static_cast<double>(trajectory_.p_W_m.size() - 1 - kMargin) * trajectory_.dt_s;
}

SensorMotion SensorKinematics::at(double t_s) const {
  // A rounding tolerance keeps the exact end points inside.
  const double tolerance = 1e-9 * trajectory_.dt_s;
  if (!(t_s >= t_begin_s() - tolerance && t_s <= t_end_s() + tolerance)) {
    throw Error(ErrorCode::kOutOfRange, "t_s",
                std::to_string(t_s) + " s is outside the trajectory's valid range [" + std::to_string(t_begin_s()) +
                    ", " + std::to_string(t_end_s()) + "] s");
  }
  const std::size_t last_interval = trajectory_.p_W_m.size() - 2 - kMargin;
  const double u = (t_s - trajectory_.t0_s) / trajectory_.dt_s;
  std::size_t i = static_cast<std::size_t>(std::max(0.0, std::floor(u)));
  i = std::clamp(i, kMargin, last_interval);
  const double f = std::clamp(u - static_cast<double>(i), 0.0, 1.0);

  SensorMotion m;
  m.W_from_A = trajectory_.W_from_A[i].slerp(f, trajectory_.W_from_A[i + 1]).normalized();
  m.p_W_m = (1.0 - f) * trajectory_.p_W_m[i] + f * trajectory_.p_W_m[i + 1];
  m.omega_A_rad_s = (1.0 - f) * omega_A_[i] + f * omega_A_[i + 1];
  m.a_W_m_s2 = (1.0 - f) * a_W_[i] + f * a_W_[i + 1];
  return m;
}

}  // namespace posefuse::sim
