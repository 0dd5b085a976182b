#include "table1_errors.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace posefuse::bench {

namespace {

using geometry::Quat;
using geometry::Vec3;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Kinect v2 JointType: ElbowLeft 5, WristLeft 6, ElbowRight 9, WristRight 10.
int sdk_elbow(v1::Arm arm) { return arm == v1::LEFT ? 5 : 9; }

Vec3 vec(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }
Quat quat(const v1::Quaternion& q) { return {q.w(), q.x(), q.y(), q.z()}; }

// Index of the frame with exactly this time, or -1.
long frame_index(const std::vector<std::int64_t>& frame_t_us, std::int64_t t_us) {
  const auto it = std::lower_bound(frame_t_us.begin(), frame_t_us.end(), t_us);
  return it != frame_t_us.end() && *it == t_us ? static_cast<long>(it - frame_t_us.begin()) : -1;
}

// Fills `positions` (per frame) from one method's recovered segments, linear between samples.
void fill_from_segments(const std::vector<const v1::RecoveredSegment*>& segments,
                        const std::vector<std::int64_t>& frame_t_us, std::vector<Vec3>& positions,
                        std::vector<bool>& filled) {
  for (const v1::RecoveredSegment* s : segments) {
    const auto& samples = s->samples();
    for (int i = 0; i + 1 < samples.size(); ++i) {
      const std::int64_t a = samples[i].t_us(), b = samples[i + 1].t_us();
      if (b <= a) continue;
      for (auto it = std::lower_bound(frame_t_us.begin(), frame_t_us.end(), a); it != frame_t_us.end() && *it <= b;
           ++it) {
        if (*it <= s->t_start_us() || *it >= s->t_end_us()) continue;  // strictly inside the gap
        const double w = static_cast<double>(*it - a) / static_cast<double>(b - a);
        const std::size_t f = static_cast<std::size_t>(it - frame_t_us.begin());
        positions[f] = (1.0 - w) * vec(samples[i].imu_m()) + w * vec(samples[i + 1].imu_m());
        filled[f] = true;
      }
    }
  }
}

}  // namespace

Table1Series table1_series(const Table1Truth& session, const std::vector<v1::FitResult>& results, const Table1Arm& arm,
                           double hold_begin_s, double hold_end_s) {
  const std::size_t n = session.frame_t_us.size();
  const Vec3 nan3 = Vec3::Constant(kNaN);
  const int elbow_joint = sdk_elbow(arm.arm), wrist_joint = elbow_joint + 1;

  // SDK per frame.
  std::vector<Vec3> sdk_position(n, nan3);
  std::vector<Quat> sdk_K_from_wrist(n, Quat(0, 0, 0, 0));
  for (const v1::SkeletonFrame& skeleton : session.sdk) {
    const long f = frame_index(session.frame_t_us, skeleton.t_us());
    if (f < 0 || skeleton.joints_size() <= wrist_joint) continue;
    const v1::SkeletonJoint& elbow = skeleton.joints(elbow_joint);
    const v1::SkeletonJoint& wrist = skeleton.joints(wrist_joint);
    sdk_position[static_cast<std::size_t>(f)] =
        eval::sdk_imu_position(vec(elbow.position_m()), vec(wrist.position_m()), arm.d_se_m, arm.d_sw_m);
    sdk_K_from_wrist[static_cast<std::size_t>(f)] = quat(wrist.orientation());
  }
  Eigen::Vector4d sum = Eigen::Vector4d::Zero();
  for (std::size_t f = 0; f < n; ++f) {
    const double t = static_cast<double>(session.frame_t_us[f]) * 1e-6;
    if (t < hold_begin_s || t > hold_end_s || sdk_K_from_wrist[f].norm() < 0.5) continue;
    const Quat offset = sdk_K_from_wrist[f].normalized().conjugate() * session.forearm[f].K_from_F;
    const Eigen::Vector4d v(offset.w(), offset.x(), offset.y(), offset.z());
    sum += sum.dot(v) < 0.0 ? -v : v;
  }
  const Quat wrist_from_F = sum.norm() > 0.0 ? Quat(sum(0), sum(1), sum(2), sum(3)).normalized() : Quat::Identity();

  // Fusion per frame, from the stage's results.
  std::vector<Quat> fusion_K_from_F(n, Quat(0, 0, 0, 0));
  std::vector<Vec3> visual(n, nan3), live(n, nan3), paper(n, nan3), smoother(n, nan3);
  std::vector<bool> paper_filled(n, false), smoother_filled(n, false);
  std::map<int, std::vector<const v1::RecoveredSegment*>> segments;
  for (const v1::FitResult& r : results) {
    if (r.has_recovered_segment() && r.recovered_segment().arm() == arm.arm) {
      segments[r.recovered_segment().method()].push_back(&r.recovered_segment());
    }
    if (!r.has_frame()) continue;
    const long f = frame_index(session.frame_t_us, r.frame().t_us());
    if (f < 0) continue;
    // The frame result's orientation: the forearm stage's (the IMU's, eq. 11) by the frame merge's
    // rule (frame_merge.hpp).
    for (const v1::ForearmOrientation& o : r.frame().forearms()) {
      if (o.arm() == arm.arm) {
        fusion_K_from_F[static_cast<std::size_t>(f)] = quat(o.k_from_f());
      }
    }
    for (const v1::ImuPosition& p : r.frame().imu_positions()) {
      if (p.device_id() != arm.device_id) continue;
      (p.source() == v1::VISUAL ? visual : live)[static_cast<std::size_t>(f)] = vec(p.position_m());
    }
  }
  fill_from_segments(segments[v1::RecoveredSegment::PAPER], session.frame_t_us, paper, paper_filled);
  fill_from_segments(segments[v1::RecoveredSegment::SMOOTHER], session.frame_t_us, smoother, smoother_filled);

  Table1Series s;
  const auto error = [](const Vec3& estimate, const Vec3& truth) {
    return estimate.allFinite() ? (estimate - truth).norm() : kNaN;
  };
  for (std::size_t f = 0; f < n; ++f) {
    const sim::ForearmTruth& truth = session.forearm[f];
    s.t_s.push_back(static_cast<double>(session.frame_t_us[f]) * 1e-6);
    s.occluded.push_back(truth.occluded);
    s.stage_visible.push_back(visual[f].allFinite());
    const bool has_sdk_orientation = sdk_K_from_wrist[f].norm() > 0.5;
    if (!has_sdk_orientation) ++s.sdk_orientation_missing;
    s.sdk_orientation_deg.push_back(
        has_sdk_orientation ? eval::paper_orientation_error_deg(sdk_K_from_wrist[f] * wrist_from_F, truth.K_from_F)
                            : kNaN);
    s.fusion_orientation_deg.push_back(
        fusion_K_from_F[f].norm() > 0.5 ? eval::paper_orientation_error_deg(fusion_K_from_F[f], truth.K_from_F) : kNaN);
    const Vec3 paper_f = paper_filled[f] ? paper[f] : visual[f];
    const Vec3 smoother_f = smoother_filled[f] ? smoother[f] : visual[f];
    const Vec3 live_f = visual[f].allFinite() ? visual[f] : live[f];
    s.sdk_position_m.push_back(error(sdk_position[f], truth.imu_K_m));
    s.paper_position_m.push_back(error(paper_f, truth.imu_K_m));
    s.smoother_position_m.push_back(error(smoother_f, truth.imu_K_m));
    s.live_position_m.push_back(error(live_f, truth.imu_K_m));
    s.true_x_m.push_back(truth.imu_K_m.x());
    s.sdk_x_m.push_back(sdk_position[f].x());
    s.paper_x_m.push_back(paper_f.x());
    s.smoother_x_m.push_back(smoother_f.x());
  }
  return s;
}

}  // namespace posefuse::bench
