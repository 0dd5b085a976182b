#include "forearm/live_gap.hpp"

#include <cmath>
#include <string>

#include <Eigen/Dense>

#include "common/error.hpp"

namespace posefuse::forearm {

LiveGapEstimator::LiveGapEstimator(const ForearmModel& model, const Quat& K_from_W, const LiveGapOptions& options)
    : model_(model), gravity_K_(K_from_W * Vec3(0.0, 0.0, kGravity)), options_(options) {
  if (!(options.boundary_window_s > 0.0)) throw_invalid("options.boundary_window_s", "must be > 0");
  if (!(options.velocity_time_constant_s > 0.0)) {
    throw_invalid("options.velocity_time_constant_s", "must be > 0");
  }
}

void LiveGapEstimator::begin(const std::vector<TrackSample>& track, const std::vector<ArmSample>& arm,
                             std::int64_t t_start_us) {
  const auto window_us = static_cast<std::int64_t>(std::llround(options_.boundary_window_s * 1e6));
  const std::int64_t lo = t_start_us - window_us;
  // Net acceleration (eq. 12) at the arm samples in the window, then q(t): its double integral
  // from the first of them (q = q' = 0 there), trapezoidal.
  std::vector<double> t_s;
  std::vector<Vec3> acc;
  for (std::size_t i = 0; i < arm.size(); ++i) {
    const ArmSample& s = arm[i];
    if (s.t_us < lo || s.t_us > t_start_us) continue;
    if (!s.specific_force_A.allFinite() || !s.K_from_A.coeffs().allFinite()) {
      throw_invalid("arm[" + std::to_string(i) + "]", "not finite");
    }
    if (!t_s.empty() && static_cast<double>(s.t_us) * 1e-6 <= t_s.back()) {
      throw_invalid("arm[" + std::to_string(i) + "].t_us", "not increasing");
    }
    t_s.push_back(static_cast<double>(s.t_us) * 1e-6);
    acc.push_back(net_acceleration(s.K_from_A.normalized(), s.specific_force_A, gravity_K_));
  }
  if (t_s.size() < 2) throw_precondition("arm", "fewer than 2 arm samples in the window before the gap");
  std::vector<Vec3> q(t_s.size(), Vec3::Zero()), dq(t_s.size(), Vec3::Zero());
  for (std::size_t i = 1; i < t_s.size(); ++i) {
    const double dt = t_s[i] - t_s[i - 1];
    dq[i] = dq[i - 1] + 0.5 * (acc[i - 1] + acc[i]) * dt;
    q[i] = q[i - 1] + 0.5 * (dq[i - 1] + dq[i]) * dt;
  }
  auto q_at = [&](double t) -> Vec3 {  // linear between arm samples, held at the ends
    if (t <= t_s.front()) return q.front();
    for (std::size_t i = 1; i < t_s.size(); ++i) {
      if (t <= t_s[i]) {
        const double u = (t - t_s[i - 1]) / (t_s[i] - t_s[i - 1]);
        return (1.0 - u) * q[i - 1] + u * q[i];
      }
    }
    return q.back() + dq.back() * (t - t_s.back());
  };
  // Line through (visible position - q): what the accelerations do not explain.
  const double t0 = static_cast<double>(t_start_us) * 1e-6;
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  Eigen::Matrix<double, 2, 3> rhs = Eigen::Matrix<double, 2, 3>::Zero();
  int count = 0;
  for (std::size_t i = 0; i < track.size(); ++i) {
    const TrackSample& s = track[i];
    if (!s.visible || s.t_us < lo || s.t_us > t_start_us) continue;
    if (!s.p_K.allFinite()) throw_invalid("track[" + std::to_string(i) + "].p_K", "not finite");
    const double t = static_cast<double>(s.t_us) * 1e-6;
    const Eigen::Vector2d row(1.0, t - t0);
    normal += row * row.transpose();
    rhs += row * (s.p_K - q_at(t)).transpose();
    ++count;
  }
  if (count < 2 || normal.determinant() <= 1e-12) {
    throw_precondition("track.before_gap",
                       std::to_string(count) + " visible samples in the window before the gap; need 2");
  }
  const Eigen::Matrix<double, 2, 3> line = normal.ldlt().solve(rhs);
  const Vec3 dq_end = dq.back() + acc.back() * (t0 - t_s.back());
  p_K_ = line.row(0).transpose() + q_at(t0);
  v_K_ = line.row(1).transpose() + dq_end;
  a_K_ = acc.back();
  t_us_ = t_start_us;
  active_ = true;
}

Vec3 LiveGapEstimator::update(const ArmSample& sample, const Vec3& shoulder_K) {
  if (!active_) throw_precondition("gap", "update() before begin()");
  if (sample.t_us <= t_us_) throw_invalid("sample.t_us", "not after the previous sample");
  if (!sample.specific_force_A.allFinite()) throw_invalid("sample.specific_force_A", "not finite");
  if (!sample.K_from_A.coeffs().allFinite()) throw_invalid("sample.K_from_A", "not finite");
  if (!shoulder_K.allFinite()) throw_invalid("shoulder_K", "not finite");
  const Quat K_from_A = sample.K_from_A.normalized();
  const Vec3 a = net_acceleration(K_from_A, sample.specific_force_A, gravity_K_);  // eq. 12
  const double dt = static_cast<double>(sample.t_us - t_us_) * 1e-6;
  const Vec3 v_next = (v_K_ + 0.5 * (a_K_ + a) * dt) * std::exp(-dt / options_.velocity_time_constant_s);
  p_K_ += 0.5 * (v_K_ + v_next) * dt;
  v_K_ = v_next;
  a_K_ = a;
  t_us_ = sample.t_us;
  if (options_.use_shoulder_sphere) {
    const Quat K_from_F = K_from_A * model_.F_from_A.conjugate();     // eq. 11
    const Vec3 centre = sphere_centre(shoulder_K, K_from_F, model_);  // eq. 13
    p_K_ = snap_to_sphere(p_K_, centre, model_.d_ul_m);
    const Vec3 radial = p_K_ - centre;
    if (radial.norm() > 1e-9) {
      const Vec3 n = radial.normalized();
      v_K_ -= v_K_.dot(n) * n;
    }
  }
  return p_K_;
}

void LiveGapEstimator::correct(const Vec3& p_K, double gain) {
  if (!active_) throw_precondition("gap", "correct() before begin()");
  if (!p_K.allFinite()) throw_invalid("p_K", "not finite");
  if (!(gain >= 0.0 && gain <= 1.0)) throw_invalid("gain", "not in [0, 1]");
  p_K_ += gain * (p_K - p_K_);
}

Vec3 imu_position_from_elbow(const Vec3& elbow_K, const Quat& K_from_F, const ForearmModel& model) {
  return elbow_K + K_from_F.normalized() * Vec3(model.r_m, model.d_se_m, 0.0);
}

Vec3 elbow_from_imu_position(const Vec3& imu_K, const Quat& K_from_F, const ForearmModel& model) {
  return imu_K - K_from_F.normalized() * Vec3(model.r_m, model.d_se_m, 0.0);
}

RecoveredGap recover_gap_live(const GapRecoveryInput& input, const GapSpan& gap, const LiveGapOptions& options) {
  const ArmTimeline arm = checked_gap_timeline(input, gap);
  LiveGapEstimator live(input.model, input.K_from_W, options);
  live.begin(input.track, input.arm, gap.t_start_us);
  RecoveredGap out;
  out.span = gap;
  out.t_us.push_back(gap.t_start_us);
  out.p_K.push_back(live.position_K());
  for (const ArmSample& s : input.arm) {
    if (s.t_us <= gap.t_start_us || s.t_us >= gap.t_end_us) continue;
    out.t_us.push_back(s.t_us);
    out.p_K.push_back(live.update(s, arm.shoulder_K(static_cast<double>(s.t_us))));
  }
  // At t_end the gap closes: the live estimate there is the extrapolation to that time.
  out.t_us.push_back(gap.t_end_us);
  out.p_K.push_back(live.position_K() +
                    live.velocity_K() * (static_cast<double>(gap.t_end_us - out.t_us[out.t_us.size() - 2]) * 1e-6));
  return out;
}

}  // namespace posefuse::forearm
