#pragma once
// Writes a SimTruth as the gt/ directory of a simulated session (docs/simulator.md).
//
// The files a fit also produces use session::ResultFiles, i.e. the client's result layout and
// columns exactly (source GROUND_TRUTH, confidence 1):
//   smpl_joints.csv, camera_joints.csv, forearms.csv, imu_positions.csv,
//   imu_orientations/<device_id>.csv (true W_from_A for every sample the device took, lost ones
//   included, device clock), calibration.json (true CalibrationReport).
// Files only the simulator knows:
//   occlusion.csv                t_us,arm,forearm_visible_fraction,forearm_occluded,strap_visible
//   imu_samples/<device_id>.csv  t_device_us,t_camera_us,lost,bias_gx,bias_gy,bias_gz
//   truth.json                   frames, clocks, mountings, IMU error draws, sync truth
// Also in the result layout: joint_angles.csv and repetitions.csv (sim/angle_truth.hpp: the true
// angles from the true joints, vertical and forearm frames).
#include <filesystem>

#include "sim/sim_session.hpp"

namespace posefuse::sim {

// Creates `directory` (kFailedPrecondition when it exists and is not empty).
// Minimal JSON building (truth files): numbers in the shortest exact form; quaternions [w, x, y, z].
std::string json_vec(const Vec3& v);
std::string json_quat(const Quat& q);

void write_ground_truth(const SimTruth& truth, const std::filesystem::path& directory);

}  // namespace posefuse::sim
