#pragma once
// Is a camera frame paper 1's calibration pose (II-H, Fig. 3b)? The forearm is raised to about
// head level, so it points up. Without this test the still hold of the calibration could be
// any still arm, e.g. one hanging at rest through the whole calibration window, and eq. 9 would
// then build A_from_F from a pose whose forearm frame the skeleton cannot give (the demo's
// resting left arm came out 130-150 degrees off).
#include "forearm/forearm_types.hpp"

namespace posefuse::forearm {

// Up to this angle between elbow -> wrist and up counts as "raised". The simulated pose holds
// the forearm vertical; a person's varies, and a hanging arm is ~180 degrees off.
inline constexpr double kCalibrationForearmMaxTiltRad = 45.0 * 3.14159265358979323846 / 180.0;

// up_K: the upward vertical in K (K_from_W * z_W). False for non-finite input.
bool forearm_raised_for_calibration(const Vec3& elbow_K, const Vec3& wrist_K, const Vec3& up_K,
                                    double max_tilt_rad = kCalibrationForearmMaxTiltRad);

}  // namespace posefuse::forearm
