#pragma once
// Transformations between the sensing systems (paper 1, II-F): mocap (E) -> camera (K) from the
// panel seen by both (eqs. 4-6), and the base IMU in the camera frame (K_from_B, eq. 8) from a
// panel carrying an IMU, which then gives K_from_W = K_from_B * (W_from_B)^-1 (eq. 7).
#include <vector>

#include "calib/panel.hpp"
#include "calib/panel_in_camera.hpp"

namespace posefuse::calib {

// eq. 6: p_K = E_origin_K + K_from_E * p_E.
struct MocapToCamera {
  Quat K_from_E = Quat::Identity();
  Vec3 E_origin_K = Vec3::Zero();
  Vec3 to_K(const Vec3& p_E) const { return E_origin_K + K_from_E * p_E; }
  double marker_residual_px = 0.0;  // mocap markers mapped by eq. 6 and projected, vs the IR points (RMS)
  int poses = 0;
};

// One panel pose seen by both systems: eq. 4 K_from_E = K_from_P * (E_from_P)^-1 and eq. 5
// E_origin_K = P_origin_K - K_from_E * P_origin_E. The residual uses the panel's marker
// positions in E as the mocap measured them (markers_E) and the camera's bright points.
// Throws what panel_pose_from_markers throws, and kFailedPrecondition "mocap.markers" when the
// mapped markers reproject more than max_residual_px from the bright points (RMS).
MocapToCamera mocap_to_camera(const std::array<Vec3, 4>& markers_E, const PanelInCamera& seen_by_camera,
                              const PinholeCamera& camera, const PanelGeometry& panel, double max_residual_px = 3.0);

// Several panel poses combined: rotations averaged (chordal mean), origins averaged; the residual
// is recomputed for every pose. Throws kInvalidArgument "poses" when empty or sizes differ, and
// kFailedPrecondition "mocap.poses" when single-pose results disagree by more than
// max_spread_rad / max_spread_m (the panel or a marker moved between the systems' readings).
MocapToCamera mocap_to_camera(const std::vector<std::array<Vec3, 4>>& markers_E,
                              const std::vector<PanelInCamera>& seen_by_camera, const PinholeCamera& camera,
                              const PanelGeometry& panel, double max_spread_rad = 0.02, double max_spread_m = 0.01);

// One reading of the panel with an IMU on it (IMU axes aligned with P): the panel seen by the
// camera (K_from_P), the panel IMU's filter output (W_from_P) and the base IMU's (W_from_B).
struct PanelImuReading {
  Quat K_from_P = Quat::Identity();
  Quat W_from_P = Quat::Identity();
  Quat W_from_B = Quat::Identity();
};

struct BaseImuAlignment {
  Quat K_from_B = Quat::Identity();
  double spread_rad = 0.0;  // RMS angle of the per-reading eq. 8 results from their mean
  int readings = 0;
};

// eq. 8 per reading, K_from_B = K_from_P * (W_from_P)^-1 * W_from_B, then the chordal mean.
// Throws kInvalidArgument "readings" when empty, "readings[i].<field>" for a non-unit or
// non-finite quaternion; kFailedPrecondition "readings" when the spread exceeds max_spread_rad
// (the IMU slipped on the panel, or a magnetic disturbance near one of the IMUs).
BaseImuAlignment base_imu_in_camera(const std::vector<PanelImuReading>& readings, double max_spread_rad = 0.035);

// eq. 7: K_from_W = K_from_B * (W_from_B)^-1.
Quat K_from_W_from_base(const Quat& K_from_B, const Quat& W_from_B);

}  // namespace posefuse::calib
