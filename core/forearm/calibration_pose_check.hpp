#pragma once
// Is a camera frame paper 1's calibration pose (II-H, Fig. 3b)? The forearm is raised to about
// head level, palm to the camera, upper arm and forearm in the coronal plane: the forearm points
// up, the elbow is flexed (the simulator's pose: 90 degrees, the upper arm horizontal to the
// side) and stays at about the shoulder's height or below it. Each test allows the same
// tolerance, kCalibrationPoseToleranceRad, since a person's pose varies.
//
// Without these tests the still hold of the calibration could be any still arm, and eq. 9 would
// then build A_from_F from a pose whose forearm frame the skeleton cannot give: an arm hanging at
// rest through the whole calibration window (the demo's resting left arm came out 130-150
// degrees off), or an arm raised overhead, straight, which the SDK shows bent by 30-40 degrees
// with the elbow near the shoulder (arm raising's top, seed 52: 26 degrees off). Eq. 9's frame is
// the plane of upper arm and forearm, which a straight arm does not have.
#include "forearm/forearm_types.hpp"

namespace posefuse::forearm {

inline constexpr double kCalibrationPoseToleranceRad = 45.0 * 3.14159265358979323846 / 180.0;

// Up to max_tilt_rad between elbow -> wrist and up. up_K: the upward vertical in K
// (K_from_W * z_W). False for non-finite input.
bool forearm_raised_for_calibration(const Vec3& elbow_K, const Vec3& wrist_K, const Vec3& up_K,
                                    double max_tilt_rad = kCalibrationPoseToleranceRad);

// The upper arm (shoulder -> elbow) rises at most max_rise_rad above horizontal: it points
// sideways or down. False for non-finite input.
bool upper_arm_lowered_for_calibration(const Vec3& shoulder_K, const Vec3& elbow_K, const Vec3& up_K,
                                       double max_rise_rad = kCalibrationPoseToleranceRad);

// The elbow flexed by at least min_flexion_rad: the angle between shoulder -> elbow and
// elbow -> wrist (0 for a straight arm). False for non-finite input.
bool elbow_flexed_for_calibration(const Vec3& shoulder_K, const Vec3& elbow_K, const Vec3& wrist_K,
                                  double min_flexion_rad = kCalibrationPoseToleranceRad);

}  // namespace posefuse::forearm
