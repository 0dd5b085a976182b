#pragma once
// Sparse sampling of N_s depth pixels (paper 2, II-H): silhouette pixels are put into zones by
// the nearest bone of the projected Kinect skeleton, and each zone is sampled to a quota so that
// small segments (arms, head) get enough samples and every zone gives near-edge pixels.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "fit/depth_frame.hpp"
#include "geometry/kinect_joints.hpp"
#include "raycast/depth_camera.hpp"

namespace posefuse::fit {

using geometry::kKinectJointCount;                                      // geometry/kinect_joints.hpp order
using KinectSkeleton = std::array<Eigen::Vector3d, kKinectJointCount>;  // joint positions in K, metres

enum class BodyZone : int {
  kHead,
  kTorso,
  kLeftUpperArm,
  kLeftForearm,  // with the hand
  kRightUpperArm,
  kRightForearm,
  kLeftLeg,
  kRightLeg,
};
inline constexpr int kBodyZoneCount = 8;
const char* body_zone_name(BodyZone zone);

using enum geometry::KinectJoint;

// A bone of the camera skeleton (Kinect joints) and the zone its pixels belong to.
struct ZoneBone {
  int from, to;
  BodyZone zone;
};

inline constexpr ZoneBone kZoneBones[] = {
    {kSpineShoulder, kNeck, BodyZone::kHead},
    {kNeck, kHead, BodyZone::kHead},
    {kSpineBase, kSpineMid, BodyZone::kTorso},
    {kSpineMid, kSpineShoulder, BodyZone::kTorso},
    {kSpineShoulder, kShoulderLeft, BodyZone::kTorso},
    {kSpineShoulder, kShoulderRight, BodyZone::kTorso},
    {kSpineBase, kHipLeft, BodyZone::kTorso},
    {kSpineBase, kHipRight, BodyZone::kTorso},
    {kShoulderLeft, kElbowLeft, BodyZone::kLeftUpperArm},
    {kElbowLeft, kWristLeft, BodyZone::kLeftForearm},
    {kWristLeft, kHandLeft, BodyZone::kLeftForearm},
    {kHandLeft, kHandTipLeft, BodyZone::kLeftForearm},
    {kShoulderRight, kElbowRight, BodyZone::kRightUpperArm},
    {kElbowRight, kWristRight, BodyZone::kRightForearm},
    {kWristRight, kHandRight, BodyZone::kRightForearm},
    {kHandRight, kHandTipRight, BodyZone::kRightForearm},
    {kHipLeft, kKneeLeft, BodyZone::kLeftLeg},
    {kKneeLeft, kAnkleLeft, BodyZone::kLeftLeg},
    {kAnkleLeft, kFootLeft, BodyZone::kLeftLeg},
    {kHipRight, kKneeRight, BodyZone::kRightLeg},
    {kKneeRight, kAnkleRight, BodyZone::kRightLeg},
    {kAnkleRight, kFootRight, BodyZone::kRightLeg},
};

struct ZoneSamplingParams {
  int num_samples = 250;  // N_s (paper 2, IV-C)
  // Share of N_s per zone (indexed by BodyZone); must sum to 1. Arms and head get more than their
  // area so that the fit sees them (paper 2, II-H); legs little, the tracker is upper-body.
  std::array<double, kBodyZoneCount> zone_share = {0.14, 0.34, 0.10, 0.10, 0.10, 0.10, 0.06, 0.06};
  // Part of each zone's quota drawn from near-edge pixels: within edge_band_px (quasi-Euclidean)
  // of a pixel outside the silhouette.
  double edge_share = 0.3;
  float edge_band_px = 3.0f;
  uint64_t seed = 1;
};

struct DepthSample {
  int col = 0;
  int row = 0;
  BodyZone zone = BodyZone::kTorso;
  bool near_edge = false;
  Eigen::Vector3f p_K = Eigen::Vector3f::Zero();
};

// Zone of every cloud pixel (-1 outside the cloud), by the nearest projected bone segment (the
// first of equally near ones in the bone order), as nearest_bone_zone gives per pixel.
std::vector<int8_t> assign_zones(const PointCloud& cloud, const KinectSkeleton& skeleton_K,
                                 const raycast::DepthCamera& camera);
// The zone of the projected bone nearest to one pixel, testing every bone (the reference for
// assign_zones, which skips bones that cannot be nearest).
BodyZone nearest_bone_zone(const Eigen::Vector2d& pixel, const KinectSkeleton& skeleton_K,
                           const raycast::DepthCamera& camera);

// Deterministic for a given seed. Zones with fewer pixels than their quota give all they have and
// the shortfall goes to the other zones in proportion to their shares; the result holds
// min(num_samples, cloud.count) distinct pixels. Throws posefuse::Error for bad params
// ("zone_params.*"), a non-finite joint ("skeleton[i]") or a skeleton with no bone in front of
// the camera ("skeleton").
std::vector<DepthSample> sample_depth_pixels(const PointCloud& cloud, const KinectSkeleton& skeleton_K,
                                             const raycast::DepthCamera& camera, const ZoneSamplingParams& params = {});

}  // namespace posefuse::fit
