#include "gltf/body_animation.hpp"

#include <map>
#include <optional>

#include "common/error.hpp"

namespace posefuse::gltf {

BodyAnimation body_animation(const session::ResultDirectory& results) {
  if (results.smpl_joint_rotations.empty())
    throw_precondition("smpl_joint_rotations.csv",
                       "the results have no fitted joint rotations (was the body fit on? fit.enabled)");
  std::map<std::int64_t, Eigen::Vector3d> pelvis_K;
  for (const session::JointRow& row : results.smpl_joints)
    if (row.joint == body::kPelvis) pelvis_K[row.t_us] = row.p_K;

  // Rows of one frame share t_us; t_us never goes back, so frames arrive in order.
  std::map<std::int64_t, std::array<std::optional<Eigen::Quaterniond>, body::kNumJoints>> global;
  for (const session::JointRotationRow& row : results.smpl_joint_rotations)
    global[row.t_us][static_cast<size_t>(row.joint)] = row.K_from_joint;

  BodyAnimation out;
  for (const auto& [t_us, rotations] : global) {
    const auto pelvis = pelvis_K.find(t_us);
    bool complete = pelvis != pelvis_K.end();
    for (const auto& q : rotations) complete = complete && q.has_value();
    if (!complete) {
      ++out.incomplete_frames;
      continue;
    }
    if (out.frames.empty()) out.t0_us = t_us;
    BodyPose pose;
    pose.t_s = static_cast<double>(t_us - out.t0_us) * 1e-6;
    pose.pelvis_K = pelvis->second;
    for (int j = 0; j < body::kNumJoints; ++j) {
      const int parent = body::kSmplParents[static_cast<size_t>(j)];
      const Eigen::Quaterniond& q = *rotations[static_cast<size_t>(j)];
      pose.local[static_cast<size_t>(j)] =
          (parent < 0 ? q : rotations[static_cast<size_t>(parent)]->conjugate() * q).normalized();
    }
    out.frames.push_back(pose);
  }
  if (out.frames.empty())
    throw_precondition("smpl_joints.csv", "no fitted frame has both its 24 joint rotations and the pelvis position");
  return out;
}

}  // namespace posefuse::gltf
