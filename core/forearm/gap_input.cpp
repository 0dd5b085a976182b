#include "forearm/gap_input.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/Dense>

#include "common/error.hpp"

namespace posefuse::forearm {

namespace {

std::string at(const char* series, std::size_t i, const char* field) {
  return std::string(series) + "[" + std::to_string(i) + "]." + field;
}

template <typename Sample>
void check_times(const std::vector<Sample>& samples, const char* series) {
  if (samples.empty()) throw_invalid(series, "no samples");
  for (std::size_t i = 1; i < samples.size(); ++i) {
    if (samples[i].t_us <= samples[i - 1].t_us) {
      throw_invalid(at(series, i, "t_us"), "timestamp " + std::to_string(samples[i].t_us) +
                                               " is not after the previous one (" +
                                               std::to_string(samples[i - 1].t_us) + ")");
    }
  }
}

bool finite_unit(const Quat& q) { return q.coeffs().allFinite() && std::abs(q.norm() - 1.0) < 1e-3; }

}  // namespace

void validate(const GapRecoveryInput& in) {
  check_times(in.track, "track");
  check_times(in.arm, "arm");
  check_times(in.shoulder, "shoulder");
  if (!in.elbow_anchor.empty()) check_times(in.elbow_anchor, "elbow_anchor");
  if (!in.second_elbow_anchor.empty()) check_times(in.second_elbow_anchor, "second_elbow_anchor");
  for (std::size_t i = 0; i < in.track.size(); ++i) {
    if (in.track[i].visible && !in.track[i].p_K.allFinite()) {
      throw_invalid(at("track", i, "p_K"), "visible sample is not finite");
    }
  }
  for (std::size_t i = 0; i < in.arm.size(); ++i) {
    if (!finite_unit(in.arm[i].K_from_A)) throw_invalid(at("arm", i, "K_from_A"), "not a finite unit quaternion");
    if (!in.arm[i].specific_force_A.allFinite()) throw_invalid(at("arm", i, "specific_force_A"), "not finite");
  }
  for (std::size_t i = 0; i < in.shoulder.size(); ++i) {
    if (!in.shoulder[i].p_K.allFinite()) throw_invalid(at("shoulder", i, "p_K"), "not finite");
  }
  for (const auto& [anchor, name] :
       {std::pair{&in.elbow_anchor, "elbow_anchor"}, std::pair{&in.second_elbow_anchor, "second_elbow_anchor"}}) {
    for (std::size_t i = 0; i < anchor->size(); ++i) {
      if (!(*anchor)[i].p_K.allFinite()) throw_invalid(at(name, i, "p_K"), "not finite");
      if (!((*anchor)[i].sigma_scale >= 1.0) || !std::isfinite((*anchor)[i].sigma_scale)) {
        throw_invalid(at(name, i, "sigma_scale"), "must be finite and >= 1");
      }
    }
  }
  const ForearmModel& m = in.model;
  if (!std::isfinite(m.r_m) || m.r_m < 0.0) throw_invalid("model.r_m", "must be finite and >= 0");
  if (!std::isfinite(m.d_se_m) || m.d_se_m <= 0.0) throw_invalid("model.d_se_m", "must be > 0");
  if (!std::isfinite(m.d_sw_m) || m.d_sw_m < 0.0) throw_invalid("model.d_sw_m", "must be >= 0");
  if (!std::isfinite(m.d_ul_m) || m.d_ul_m <= 0.0) throw_invalid("model.d_ul_m", "must be > 0");
  if (!finite_unit(m.F_from_A)) throw_invalid("model.F_from_A", "not a finite unit quaternion");
  if (!finite_unit(in.K_from_W)) throw_invalid("K_from_W", "not a finite unit quaternion");
}

std::vector<GapSpan> find_gaps(const std::vector<TrackSample>& track) {
  std::vector<GapSpan> gaps;
  std::size_t i = 0;
  while (i < track.size()) {
    if (track[i].visible) {
      ++i;
      continue;
    }
    GapSpan g;
    g.first_occluded = i;
    while (i < track.size() && !track[i].visible) ++i;
    g.last_occluded = i - 1;
    if (g.first_occluded > 0) g.t_start_us = track[g.first_occluded - 1].t_us;
    if (i < track.size()) g.t_end_us = track[i].t_us;
    gaps.push_back(g);
  }
  return gaps;
}

int visible_samples_after(const std::vector<TrackSample>& track, std::int64_t t_us, double window_s) {
  const auto window_us = static_cast<std::int64_t>(std::llround(window_s * 1e6));
  int count = 0;
  for (const TrackSample& s : track) count += s.visible && s.t_us >= t_us && s.t_us <= t_us + window_us;
  return count;
}

void occlude_inside(std::vector<TrackSample>& track, std::int64_t t_start_us, std::int64_t t_end_us) {
  for (TrackSample& s : track) {
    if (s.t_us > t_start_us && s.t_us < t_end_us) s.visible = false;
  }
}

BoundaryState fit_boundary_line(const std::vector<TrackSample>& track, std::int64_t t_at_us, int side,
                                double window_s) {
  const auto window_us = static_cast<std::int64_t>(std::llround(window_s * 1e6));
  const std::int64_t lo = side < 0 ? t_at_us - window_us : t_at_us;
  const std::int64_t hi = side < 0 ? t_at_us : t_at_us + window_us;
  // Least squares p(t) = p + v (t - t_at) over the visible samples in [lo, hi].
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  Eigen::Matrix<double, 2, 3> rhs = Eigen::Matrix<double, 2, 3>::Zero();
  BoundaryState state;
  for (const TrackSample& s : track) {
    if (!s.visible || s.t_us < lo || s.t_us > hi) continue;
    const Eigen::Vector2d row(1.0, static_cast<double>(s.t_us - t_at_us) * 1e-6);
    normal += row * row.transpose();
    rhs += row * s.p_K.transpose();
    ++state.sample_count;
  }
  const char* field = side < 0 ? "track.before_gap" : "track.after_gap";
  if (state.sample_count < 2 || normal.determinant() <= 1e-12) {
    throw_precondition(field, std::to_string(state.sample_count) + " visible samples within " +
                                  std::to_string(window_s) + " s of t=" + std::to_string(t_at_us) +
                                  " us; a boundary fit needs at least 2");
  }
  const Eigen::Matrix<double, 2, 3> solution = normal.ldlt().solve(rhs);
  state.p_K = solution.row(0).transpose();
  state.v_K = solution.row(1).transpose();
  return state;
}

Vec3 net_acceleration(const Quat& K_from_A, const Vec3& specific_force_A, const Vec3& gravity_K) {
  return K_from_A * specific_force_A - gravity_K;  // eq. 12
}

Vec3 sphere_centre(const Vec3& shoulder_K, const Quat& K_from_F, const ForearmModel& m) {
  return shoulder_K - K_from_F * Vec3(-m.r_m, -m.d_se_m, 0.0);  // eq. 13
}

Vec3 snap_to_sphere(const Vec3& p, const Vec3& centre, double radius) {
  const Vec3 out = p - centre;
  const double norm = out.norm();
  if (norm < 1e-12) return p;
  return centre + out * (radius / norm);
}

ArmTimeline::ArmTimeline(const GapRecoveryInput& input)
    : input_(input), gravity_K_(input.K_from_W * Vec3(0.0, 0.0, kGravity)) {
  net_acc_K_.reserve(input.arm.size());
  for (const ArmSample& s : input.arm) {
    net_acc_K_.push_back(net_acceleration(s.K_from_A, s.specific_force_A, gravity_K_));
  }
}

void ArmTimeline::require_coverage(std::int64_t t0, std::int64_t t1, const char* field) const {
  const auto& arm = input_.arm;
  const auto& sh = input_.shoulder;
  if (arm.front().t_us > t0 || arm.back().t_us < t1) {
    throw_precondition(field, "arm samples [" + std::to_string(arm.front().t_us) + ", " +
                                  std::to_string(arm.back().t_us) + "] us do not cover [" + std::to_string(t0) + ", " +
                                  std::to_string(t1) + "] us");
  }
  if (sh.front().t_us > t0 || sh.back().t_us < t1) {
    throw_precondition(field,
                       "shoulder samples do not cover [" + std::to_string(t0) + ", " + std::to_string(t1) + "] us");
  }
}

std::size_t ArmTimeline::arm_index_before(double t) const {
  const auto& arm = input_.arm;
  const auto it = std::upper_bound(
      arm.begin(), arm.end(), t, [](double value, const ArmSample& s) { return value < static_cast<double>(s.t_us); });
  const auto after = static_cast<std::size_t>(it - arm.begin());
  return std::min(after == 0 ? 0 : after - 1, arm.size() >= 2 ? arm.size() - 2 : 0);
}

Quat ArmTimeline::K_from_A(double t) const {
  const auto& arm = input_.arm;
  if (arm.size() == 1) return arm[0].K_from_A;
  const std::size_t i = arm_index_before(t);
  const double span = static_cast<double>(arm[i + 1].t_us - arm[i].t_us);
  const double u = std::clamp((t - static_cast<double>(arm[i].t_us)) / span, 0.0, 1.0);
  return arm[i].K_from_A.slerp(u, arm[i + 1].K_from_A).normalized();
}

Vec3 ArmTimeline::net_acceleration_K(double t) const {
  const auto& arm = input_.arm;
  if (arm.size() == 1) return net_acc_K_[0];
  const std::size_t i = arm_index_before(t);
  const double span = static_cast<double>(arm[i + 1].t_us - arm[i].t_us);
  const double u = std::clamp((t - static_cast<double>(arm[i].t_us)) / span, 0.0, 1.0);
  return (1.0 - u) * net_acc_K_[i] + u * net_acc_K_[i + 1];
}

Vec3 ArmTimeline::shoulder_K(double t) const {
  const auto& sh = input_.shoulder;
  if (sh.size() == 1 || t <= static_cast<double>(sh.front().t_us)) return sh.front().p_K;
  if (t >= static_cast<double>(sh.back().t_us)) return sh.back().p_K;
  const auto it = std::upper_bound(sh.begin(), sh.end(), t, [](double value, const ShoulderSample& s) {
    return value < static_cast<double>(s.t_us);
  });
  const ShoulderSample& b = *it;
  const ShoulderSample& a = *(it - 1);
  const double u = (t - static_cast<double>(a.t_us)) / static_cast<double>(b.t_us - a.t_us);
  return (1.0 - u) * a.p_K + u * b.p_K;  // II-K.4: linear interpolation
}

Vec3 ArmTimeline::sphere_centre_K(double t) const {
  const Quat K_from_F = K_from_A(t) * input_.model.F_from_A.conjugate();  // eq. 11
  return sphere_centre(shoulder_K(t), K_from_F, input_.model);
}

std::vector<std::int64_t> ArmTimeline::arm_times_between(std::int64_t t0, std::int64_t t1) const {
  std::vector<std::int64_t> out;
  for (const ArmSample& s : input_.arm) {
    if (s.t_us > t0 && s.t_us < t1) out.push_back(s.t_us);
  }
  return out;
}

ArmTimeline checked_gap_timeline(const GapRecoveryInput& input, const GapSpan& gap) {
  validate(input);
  if (gap.t_start_us < 0) {
    throw_precondition("track.before_gap", "the gap starts the track: no visible sample before it");
  }
  if (gap.t_end_us < 0) {
    throw_precondition("track.after_gap", "the gap ends the track: no visible sample after it");
  }
  ArmTimeline arm(input);
  arm.require_coverage(gap.t_start_us, gap.t_end_us, "arm");
  return arm;
}

Vec3 position_at(const RecoveredGap& gap, std::int64_t t) {
  if (gap.t_us.empty() || t < gap.t_us.front() || t > gap.t_us.back()) {
    throw Error(ErrorCode::kOutOfRange, "t_us", std::to_string(t) + " is outside the recovered gap");
  }
  const auto it = std::lower_bound(gap.t_us.begin(), gap.t_us.end(), t);
  const auto i = static_cast<std::size_t>(it - gap.t_us.begin());
  if (gap.t_us[i] == t) return gap.p_K[i];
  const double u = static_cast<double>(t - gap.t_us[i - 1]) / static_cast<double>(gap.t_us[i] - gap.t_us[i - 1]);
  return (1.0 - u) * gap.p_K[i - 1] + u * gap.p_K[i];
}

}  // namespace posefuse::forearm
