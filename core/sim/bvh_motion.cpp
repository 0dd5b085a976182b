#include "sim/bvh_motion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "common/error.hpp"
#include "sim/body_pose_angles.hpp"
#include "sim/bvh_retarget.hpp"
#include "sim/option_checks.hpp"
#include "sim/skeleton_pose.hpp"
#include "sim/smoothing_spline.hpp"
#include "sim/uniform_cubic_spline.hpp"

namespace posefuse::sim {
namespace {

constexpr int kQuatValues = 4 * body::kNumJoints;  // then 3 translation values

double lowest_foot_y(const Eigen::Matrix3Xd& joints) {
  double lowest = std::numeric_limits<double>::infinity();
  for (int j : {body::kLeftAnkle, body::kRightAnkle, body::kLeftFoot, body::kRightFoot}) {
    lowest = std::min(lowest, joints(1, j));
  }
  return lowest;
}

}  // namespace

BodyMotion bvh_motion(const BvhClip& clip, const BvhMotionOptions& options, BvhPlacement* placement) {
  require_non_negative(options.smoothing_s, "smoothing_s");
  require_positive(clip.frame_time_s, "clip.frame_time_s");
  if (clip.frame_count() < 2)
    throw_invalid("clip.frames", "needs at least 2 frames, got " + std::to_string(clip.frame_count()));
  const Eigen::Matrix3Xd rest_joints = template_rest_joints(options.sex, options.betas);
  const BvhRetargetMap map = make_bvh_retarget_map(clip.skeleton, rest_joints, options.joint_map);

  std::vector<RetargetedFrame> frames;
  frames.reserve(clip.frames.size());
  for (const BvhLocalPose& pose : clip.frames) frames.push_back(retarget_frame(clip.skeleton, map, pose));

  BvhPlacement place;
  place.scale = map.leg_length_ratio;
  if (options.face_front) {
    const Vec3 front = frames[0].global[body::kPelvis] * Vec3::UnitZ();
    if (std::hypot(front.x(), front.z()) > 1e-6) {
      place.R_from_bvh = Quat(Eigen::AngleAxisd(-std::atan2(front.x(), front.z()), Vec3::UnitY()));
    }
  }
  const Vec3 start = place.scale * (place.R_from_bvh * frames[0].hips_R_units);
  place.offset_R_m = Vec3(-start.x(), 0.0, -start.z());

  // theta per frame before the vertical shift; rotations as quaternion components.
  const body::PoseLayout layout = body::PoseLayout::all_joints();
  std::vector<Eigen::VectorXd> values(frames.size(), Eigen::VectorXd(kQuatValues + 3));
  double lowest = std::numeric_limits<double>::infinity();
  for (std::size_t f = 0; f < frames.size(); ++f) {
    Eigen::VectorXd& v = values[f];
    Eigen::VectorXd theta = layout.zero();
    for (int j = 0; j < body::kNumJoints; ++j) {
      Quat q = frames[f].parent_from_joint[static_cast<std::size_t>(j)];
      if (j == body::kPelvis) q = place.R_from_bvh * q;
      if (f > 0) {
        const Eigen::Vector4d& prev = values[f - 1].segment<4>(4 * j);
        q = geometry::same_hemisphere(q.normalized(), Quat(prev[0], prev[1], prev[2], prev[3]));
      }
      v.segment<4>(4 * j) << q.w(), q.x(), q.y(), q.z();
      theta.segment<3>(all_joints_rotation_index(j)) = geometry::rotation_vector_from_quat(q);
    }
    const Vec3 translation =
        place.scale * (place.R_from_bvh * frames[f].hips_R_units) + place.offset_R_m - rest_joints.col(body::kPelvis);
    v.tail<3>() = translation;
    theta.head<3>() = translation;
    lowest = std::min(lowest, lowest_foot_y(pose_skeleton(rest_joints, layout, theta).joints));
  }
  const double lift = lowest_foot_y(rest_joints) - lowest;
  place.offset_R_m.y() += lift;
  for (Eigen::VectorXd& v : values) v[kQuatValues + 1] += lift;
  if (placement != nullptr) *placement = place;

  auto spline = std::make_shared<const UniformCubicSpline>(
      0.0, clip.frame_time_s,
      options.smoothing == BvhSmoothing::kNoiseLevel
          ? smooth_by_noise_level(values, clip.frame_time_s)
          : gaussian_smooth(values, options.smoothing_s / clip.frame_time_s));
  BodyMotion motion;
  motion.duration_s = clip.duration_s();
  motion.poses = [spline](double t_s) {
    const Eigen::VectorXd v = spline->at_extended(t_s);
    Eigen::VectorXd theta(3 + 3 * body::kNumJoints);
    theta.head<3>() = v.tail<3>();
    for (int j = 0; j < body::kNumJoints; ++j) {
      const Quat q = Quat(v[4 * j], v[4 * j + 1], v[4 * j + 2], v[4 * j + 3]).normalized();
      theta.segment<3>(all_joints_rotation_index(j)) = geometry::rotation_vector_from_quat(q);
    }
    return theta;
  };
  return motion;
}

}  // namespace posefuse::sim
