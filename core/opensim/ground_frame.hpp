#pragma once
// The ground frame G of a session's OpenSim files (docs/exports.md, "Ground"): OpenSim's axes, y
// up, x the subject's forward (facing the camera), z to the subject's right, as the thorax angles'
// global frame (measures::K_from_G); origin on the floor (the lowest joint centre of the session)
// below the first frame's pelvis.
#include <Eigen/Core>
#include <optional>
#include <vector>

#include "session/result_reader.hpp"

namespace posefuse::opensim {

struct GroundFrame {
  Eigen::Matrix3d G_from_K = Eigen::Matrix3d::Identity();
  Eigen::Vector3d origin_K = Eigen::Vector3d::Zero();  // G's origin, in K
  // Up from the calibration's K_from_W (the world's z in the camera); false: the camera's y
  // taken as up (a level camera), which the files say in their headers.
  bool vertical_measured = false;

  Eigen::Vector3d point_G(const Eigen::Vector3d& p_K) const { return G_from_K * (p_K - origin_K); }
};

// The calibration's K_from_W, or nullopt where the report has none (all zero) or no report.
std::optional<Eigen::Matrix3d> K_from_W(const session::ResultDirectory& results);

// The joints the markers come from: smpl_joints.csv where the body fit ran, else camera_joints.csv.
const std::vector<session::JointRow>& marker_joints(const session::ResultDirectory& results);

// Without joints the origin stays at the camera. Throws posefuse::Error (kFailedPrecondition)
// "calibration.json" when K_from_W puts the vertical along the camera's axis (no front).
GroundFrame ground_frame(const session::ResultDirectory& results);

}  // namespace posefuse::opensim
