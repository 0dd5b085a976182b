#pragma once
// Forearm orientation K_from_F for every arm IMU sample (paper 1, eq. 11) and the
// pronation/supination angle, which the camera SDK cannot give (paper 1, I and IV-A).
//
// Pronation is the forearm's roll about its own long axis y_F. We measure it relative to the
// calibration pose (II-H: forearm up, palm facing the camera, upper arm and forearm in the
// coronal plane), which is anatomical neutral (the thumb points towards the shoulder): the
// rotation F_ref_from_F = (K_from_F_ref)^-1 * K_from_F is split into a swing about an axis
// perpendicular to y and a twist about y (F_ref_from_F = swing * twist); the twist angle, signed
// per arm, is the pronation angle. For a right arm supination turns the thumb outwards, a
// positive rotation about +y_F, so pronation = -twist; for a left arm pronation = +twist
// (F keeps x dorsal and y distal on both arms). Caveat: with the forearm far from its reference
// direction the swing-twist split is the minimal-swing convention, not a clinical goniometer.
#include "forearm/forearm_types.hpp"

namespace posefuse::forearm {

enum class Side { kLeft, kRight };

// Twist angle of q about its own y axis, in (-pi, pi] (q = swing * twist).
double twist_about_y(const Quat& q);

// Pronation (+) / supination (-) angle in (-pi, pi] of K_from_F relative to K_from_F_reference.
double pronation_angle(const Quat& K_from_F_reference, const Quat& K_from_F, Side side);

// F in the calibration pose from the skeleton alone (paper 1, II-H: upper arm and forearm in the
// coronal plane, the palm facing the camera): y_F along elbow -> wrist, x_F (back of the hand)
// the normal of the shoulder-elbow-wrist plane on the side away from the camera, z_F = x_F x y_F.
// Throws posefuse::Error kInvalidArgument naming the joint when one is not finite,
// "shoulder_K/elbow_K/wrist_K" when the elbow is straighter than 160 degrees (the plane is
// undefined) or the plane contains the camera ray (the side is undefined).
Quat K_from_F_calibration_pose(const Vec3& shoulder_K, const Vec3& elbow_K, const Vec3& wrist_K);

// eq. 11 for one sample with the IMU mounting (F_from_A, the paper's ^A_F q from eq. 9).
struct ForearmSample {
  Quat K_from_A = Quat::Identity();
  Quat K_from_F = Quat::Identity();
  double pronation_rad = 0.0;
};
ForearmSample forearm_sample(const Quat& K_from_W, const Quat& W_from_A, const Quat& F_from_A,
                             const Quat& K_from_F_reference, Side side);

}  // namespace posefuse::forearm
