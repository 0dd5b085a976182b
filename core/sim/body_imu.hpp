#pragma once
// IMU pose trajectories driven by the simulated body: the arm IMU on the forearm strap of the
// posed model (forearm_strap.hpp) and the base IMU fixed on the camera (paper 1, II-A). Both
// are SensorTrajectory grids in W that SensorKinematics, synthesize_imu and
// simulate_imu_device consume.
//
// The arm IMU: the motion's theta is sampled every dt_s (1 ms), the skeleton posed
// (skeleton_pose.hpp, joints only, no mesh) and the strap pose taken from the elbow joint;
// W_from_A = W_from_R * R_from_A, p_W = W_from_R * p_R. The motion must itself be smooth (the
// scripted exercises are C2; bvh_motion smooths and splines the mocap), because the IMU's
// specific force is its second derivative.
#include <Eigen/Geometry>

#include "sim/body_motion.hpp"
#include "sim/forearm_strap.hpp"
#include "sim/sensor_trajectory.hpp"

namespace posefuse::sim {

// Grid t0 = -2 dt_s .. duration + 2 dt_s (BodyMotion continues smoothly there), so that
// SensorKinematics' valid range is exactly [0, duration]. rest_joints: the subject's
// (template_rest_joints). Throws posefuse::Error for bad input, naming the field.
SensorTrajectory forearm_imu_trajectory(const BodyMotion& motion, const Eigen::Matrix3Xd& rest_joints,
                                        const ForearmStrap& strap, const Quat& W_from_R, double dt_s = 1e-3);

// Where the base IMU sits on the camera: its origin and orientation in K.
struct BaseImuMount {
  Vec3 p_K_m = Vec3(0.0, 0.08, 0.0);  // on top of the camera
  Quat K_from_B = Quat::Identity();
};

// A still sensor on the camera over [t_begin_s, t_end_s] (SensorKinematics' valid range):
// W_from_B = W_from_R * R_from_K * K_from_B. K_from_R is the camera session's K_from_W.
SensorTrajectory base_imu_trajectory(const Eigen::Isometry3d& K_from_R, const Quat& W_from_R, const BaseImuMount& mount,
                                     double t_begin_s, double t_end_s, double dt_s = 0.01);

}  // namespace posefuse::sim
