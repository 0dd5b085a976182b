#include "sim/bvh_retarget.hpp"

#include <algorithm>
#include <vector>

#include "common/error.hpp"

namespace posefuse::sim {
namespace {

using namespace body;

// The SMPL joint each joint's bone points to (-1 for the ends).
constexpr std::array<int, kNumJoints> kAimChild = {
    kSpine1,    kLeftKnee,     kRightKnee,     kSpine2,    kLeftAnkle, kRightAnkle,
    kSpine3,    kLeftFoot,     kRightFoot,     kNeck,      -1,         -1,
    kHead,      kLeftShoulder, kRightShoulder, -1,         kLeftElbow, kRightElbow,
    kLeftWrist, kRightWrist,   kLeftHand,      kRightHand, -1,         -1};

bool is_bvh_ancestor(const BvhSkeleton& skeleton, int ancestor, int joint) {
  for (int j = skeleton.joints[static_cast<std::size_t>(joint)].parent; j >= 0;
       j = skeleton.joints[static_cast<std::size_t>(j)].parent) {
    if (j == ancestor) return true;
  }
  return false;
}

int nearest_mapped_ancestor(const BvhRetargetMap& map, int j) {
  for (int a = kSmplParents[static_cast<std::size_t>(j)]; a >= 0; a = kSmplParents[static_cast<std::size_t>(a)]) {
    if (map.bvh_joint[static_cast<std::size_t>(a)] >= 0) return a;
  }
  return -1;
}

// Columns: a, then b made orthogonal to a, then a x b (all unit).
Eigen::Matrix3d frame_of(const Vec3& a, const Vec3& b) {
  Eigen::Matrix3d m;
  m.col(0) = a.normalized();
  m.col(1) = (b - b.dot(m.col(0)) * m.col(0)).normalized();
  m.col(2) = m.col(0).cross(m.col(1));
  return m;
}

BvhLocalPose rest_pose(const BvhSkeleton& skeleton) {
  BvhLocalPose pose;
  pose.parent_from_joint.assign(skeleton.joints.size(), Quat::Identity());
  pose.translation.assign(skeleton.joints.size(), Vec3::Zero());
  return pose;
}

// World rotations and positions of every BVH joint in the file's own world (R's axes, file
// units): forward_kinematics in W, taken back through W_from_M.
void bvh_world(const BvhSkeleton& skeleton, const BvhLocalPose& pose, std::vector<Quat>& rotation,
               std::vector<Vec3>& position) {
  const BvhWorldPose world = forward_kinematics(skeleton, pose, 1.0);
  const Quat M_from_W = W_from_bvh_world().conjugate();
  rotation.resize(world.W_from_joint.size());
  position.resize(world.p_W_m.size());
  for (std::size_t i = 0; i < rotation.size(); ++i) {
    rotation[i] = (M_from_W * world.W_from_joint[i]).normalized();
    position[i] = M_from_W * world.p_W_m[i];
  }
}

std::string joint_label(int smpl) {
  return std::string("SMPL joint '") + smpl_joint_names()[static_cast<std::size_t>(smpl)] + "'";
}

}  // namespace

std::vector<Vec3> bvh_joint_positions(const BvhSkeleton& skeleton, const BvhLocalPose& pose) {
  std::vector<Quat> rotation;
  std::vector<Vec3> position;
  bvh_world(skeleton, pose, rotation, position);
  return position;
}

BvhRetargetMap make_bvh_retarget_map(const BvhSkeleton& skeleton, const Eigen::Matrix3Xd& rest_joints,
                                     const BvhJointMap& joints) {
  if (rest_joints.cols() != kNumJoints || !rest_joints.allFinite()) {
    throw_invalid("rest_joints", "must be 3 x 24 and finite");
  }
  if (skeleton.joints.empty()) throw_invalid("bvh.joints", "the skeleton has no joints");
  BvhRetargetMap map;
  map.bvh_joint.fill(-1);
  map.aim_joint.fill(-1);
  map.rest_bone.fill(Vec3::Zero());
  map.rest_correction.fill(Quat::Identity());
  map.aim_posed.fill(false);

  const BvhJointMatch match = match_bvh_joint_map(joints, skeleton);
  map.bvh_joint = match.bvh_joint;
  for (int j = 1; j < kNumJoints; ++j) {
    const int b = map.bvh_joint[static_cast<std::size_t>(j)];
    const int a = nearest_mapped_ancestor(map, j);
    if (b < 0 || a < 0) continue;
    const int ab = map.bvh_joint[static_cast<std::size_t>(a)];
    if (!is_bvh_ancestor(skeleton, ab, b)) {
      throw_invalid(bvh_joint_map_field(joints, match.line[static_cast<std::size_t>(j)]),
                    "'" + skeleton.joints[static_cast<std::size_t>(b)].name + "' (" + joint_label(j) +
                        ") is not below '" + skeleton.joints[static_cast<std::size_t>(ab)].name + "' (" +
                        joint_label(a) + ") in the BVH hierarchy");
    }
  }

  std::vector<Quat> rest_rotation;
  std::vector<Vec3> P0;
  bvh_world(skeleton, rest_pose(skeleton), rest_rotation, P0);
  double extent = 0.0;
  for (const Vec3& p : P0) extent = std::max(extent, (p - P0[0]).norm());
  const double eps = 1e-6 * std::max(extent, 1e-9);
  auto bvh_at = [&](int smpl) { return P0[static_cast<std::size_t>(map.bvh_joint[static_cast<std::size_t>(smpl)])]; };

  for (int j = 0; j < kNumJoints; ++j) {
    const auto ju = static_cast<std::size_t>(j);
    if (map.bvh_joint[ju] < 0) continue;
    int c = kAimChild[ju];
    while (c >= 0 && (map.bvh_joint[static_cast<std::size_t>(c)] < 0 || (bvh_at(c) - bvh_at(j)).norm() < eps)) {
      c = kAimChild[static_cast<std::size_t>(c)];
    }
    if (c >= 0) {
      map.aim_joint[ju] = c;
      map.rest_bone[ju] = (rest_joints.col(c) - rest_joints.col(j)).normalized();
      const Vec3 u = (bvh_at(c) - bvh_at(j)).normalized();
      map.rest_correction[ju] = Quat::FromTwoVectors(map.rest_bone[ju], u);
      map.aim_posed[ju] = j != kPelvis;  // the pelvis turns with the hips segment alone
      if (j == kPelvis) {
        // Spine direction and hip axis (right hip -> left hip) fix the whole pelvis rotation.
        const Vec3 s_axis = rest_joints.col(kLeftHip) - rest_joints.col(kRightHip);
        const Vec3 u_axis = bvh_at(kLeftHip) - bvh_at(kRightHip);
        if (u_axis.cross(u).norm() > eps && s_axis.cross(map.rest_bone[ju]).norm() > 1e-9) {
          map.rest_correction[ju] = Quat(frame_of(u, u_axis) * frame_of(map.rest_bone[ju], s_axis).transpose());
        }
      }
    } else if (const int a = nearest_mapped_ancestor(map, j); a >= 0) {
      const Vec3 s = rest_joints.col(j) - rest_joints.col(a);
      const Vec3 u = bvh_at(j) - bvh_at(a);
      if (s.norm() > 1e-9 && u.norm() > eps) map.rest_correction[ju] = Quat::FromTwoVectors(s, u);
    }
  }

  const double smpl_leg = (rest_joints.col(kLeftKnee) - rest_joints.col(kLeftHip)).norm() +
                          (rest_joints.col(kLeftAnkle) - rest_joints.col(kLeftKnee)).norm();
  const double bvh_leg =
      (bvh_at(kLeftKnee) - bvh_at(kLeftHip)).norm() + (bvh_at(kLeftAnkle) - bvh_at(kLeftKnee)).norm();
  if (!(bvh_leg > eps)) throw_invalid("bvh.joints", "the left leg has zero length in the rest pose");
  map.leg_length_ratio = smpl_leg / bvh_leg;
  return map;
}

RetargetedFrame retarget_frame(const BvhSkeleton& skeleton, const BvhRetargetMap& map, const BvhLocalPose& pose) {
  std::vector<Quat> D;
  std::vector<Vec3> p;
  bvh_world(skeleton, pose, D, p);
  RetargetedFrame out;
  for (int j = 0; j < kNumJoints; ++j) {
    const auto ju = static_cast<std::size_t>(j);
    const int parent = kSmplParents[ju];
    const Quat G_parent = parent < 0 ? Quat::Identity() : out.global[static_cast<std::size_t>(parent)];
    const int b = map.bvh_joint[ju];
    if (b < 0) {
      out.global[ju] = G_parent;
    } else {
      Quat G = (D[static_cast<std::size_t>(b)] * map.rest_correction[ju]).normalized();
      if (map.aim_posed[ju]) {
        const int c = map.bvh_joint[static_cast<std::size_t>(map.aim_joint[ju])];
        const Vec3 target = p[static_cast<std::size_t>(c)] - p[static_cast<std::size_t>(b)];
        if (target.norm() > 0) G = (Quat::FromTwoVectors(G * map.rest_bone[ju], target) * G).normalized();
      }
      out.global[ju] = G;
    }
    out.parent_from_joint[ju] = (G_parent.conjugate() * out.global[ju]).normalized();
  }
  out.hips_R_units = p[static_cast<std::size_t>(map.bvh_joint[kPelvis])];
  return out;
}

}  // namespace posefuse::sim
