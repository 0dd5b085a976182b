// Speed and accuracy of the fitter's starting pose and rough personalisation (paper 2, II-G and
// III-A; issue 7) on the simulator's camera skeleton with its default error model (biases of
// 5-10 cm on the upper limbs, 2-4 cm elsewhere, 4 mm jitter, jumps; no occlusion here).
//   1. SkeletonPoseInitializer::initialise on random upper-body poses: time per frame, and the
//      mean error of shoulders, elbows and wrists of the built pose against the truth, beside the
//      camera skeleton's own error for the same joints.
//   2. estimate_rough_shape on 30 frames of the controlled pose: time, segment and beta errors.
// Single-threaded; medians of thread CPU time.
#include <algorithm>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "bench_clock.hpp"
#include "body/template_generator.hpp"
#include "fit/joint_kinematics.hpp"
#include "fit/rough_shape.hpp"
#include "fit/skeleton_pose_init.hpp"
#include "sim/camera_skeleton.hpp"

using namespace posefuse;

namespace {

constexpr double kDeg = std::numbers::pi / 180;

struct Frame {
  fit::JointPose truth;
  fit::TrackedSkeleton skeleton;
  Eigen::Matrix3Xd true_camera_joints;
};

Frame simulate(const sim::CameraSkeletonSimulator& simulator, const raycast::DepthCamera& camera,
               const Eigen::Matrix3Xd& rest, const body::PoseLayout& layout, const Eigen::VectorXd& theta, int index) {
  Frame f;
  f.truth = fit::pose_joints(rest, layout, theta);
  sim::SmplJointsK smpl{f.truth.positions_K, f.truth.K_from_joint};
  f.true_camera_joints = sim::camera_joints_from_smpl(smpl);
  const std::vector<uint16_t> no_depth(static_cast<size_t>(camera.width()) * camera.height(), 0);
  const std::vector<std::int32_t> no_face(no_depth.size(), -1);
  const v1::SkeletonFrame frame = simulator.simulate(smpl, no_depth, no_face, index, index * 33'333, 1);
  for (int j = 0; j < fit::kKinectJointCount; ++j) {
    const auto& joint = frame.joints(j);
    f.skeleton.positions_K[j] = {joint.position_m().x(), joint.position_m().y(), joint.position_m().z()};
    f.skeleton.tracking[j] = joint.state() == v1::SkeletonJoint::TRACKED    ? fit::JointTracking::kTracked
                             : joint.state() == v1::SkeletonJoint::INFERRED ? fit::JointTracking::kInferred
                                                                            : fit::JointTracking::kNotTracked;
  }
  return f;
}

Eigen::VectorXd facing(const body::PoseLayout& layout, double depth_m) {
  Eigen::VectorXd theta = layout.zero();
  theta[layout.index_of("translation_y")] = -0.9;
  theta[layout.index_of("translation_z")] = depth_m;
  theta[layout.index_of("pelvis_y")] = std::numbers::pi;
  return theta;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main() {
  const raycast::DepthCamera camera{raycast::DepthIntrinsics{}};
  const auto model = body::make_template(body::Sex::kMale);
  const sim::CameraSkeletonSimulator simulator(camera, sim::CameraSkeletonOptions{}, 42, *model);
  Eigen::VectorXd beta = Eigen::VectorXd::Zero(10);
  beta << 0.5, 0.3, -0.4, 0.6, 0.5, -0.3, 0, 0, 0, 0.2;
  const Eigen::Matrix3Xd rest = fit::rest_joints(*model, beta);

  // 1. Starting pose.
  const body::PoseLayout layout = body::PoseLayout::upper_body();
  const fit::SkeletonPoseInitializer init(model, layout, beta);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const int frames = 300;
  std::vector<double> cpu_us;
  // Per joint kind (shoulders, elbows, wrists): sums of the errors of both sides.
  double init_error[3] = {}, skeleton_error[3] = {};
  Eigen::VectorXd previous;
  for (int i = 0; i < frames; ++i) {
    Eigen::VectorXd theta = facing(layout, 2.0 + 1.0 * (uniform(rng) + 1) / 2);
    for (int d = 6; d < layout.size(); ++d)
      if (layout.dof(d).limited)
        theta[d] = 0.5 * (layout.dof(d).min_rad + layout.dof(d).max_rad) +
                   0.35 * uniform(rng) * (layout.dof(d).max_rad - layout.dof(d).min_rad);
    theta[layout.index_of("pelvis_y")] += 20 * kDeg * uniform(rng);
    const Frame f = simulate(simulator, camera, rest, layout, theta, i);
    const double start = bench::thread_cpu_seconds();
    const fit::SkeletonInitResult result = init.initialise(f.skeleton, previous);
    cpu_us.push_back(1e6 * (bench::thread_cpu_seconds() - start));
    previous = result.theta;
    const fit::JointPose built = fit::pose_joints(rest, layout, result.theta);
    const std::pair<int, int> pairs[] = {
        {body::kLeftShoulder, geometry::kShoulderLeft}, {body::kRightShoulder, geometry::kShoulderRight},
        {body::kLeftElbow, geometry::kElbowLeft},       {body::kRightElbow, geometry::kElbowRight},
        {body::kLeftWrist, geometry::kWristLeft},       {body::kRightWrist, geometry::kWristRight}};
    for (int k = 0; k < 6; ++k) {
      const auto [smpl, kinect] = pairs[k];
      init_error[k / 2] += (built.positions_K.col(smpl) - f.truth.positions_K.col(smpl)).norm();
      skeleton_error[k / 2] += (f.skeleton.positions_K[kinect] - f.true_camera_joints.col(kinect)).norm();
    }
  }
  std::printf("Starting pose from the camera skeleton (%d random upper-body poses, 40 DOF)\n", frames);
  std::printf("  initialise: median %.1f us per frame (thread CPU)\n", median(cpu_us));
  std::printf("  mean position error, mm  %10s %10s %10s %10s\n", "shoulders", "elbows", "wrists", "all");
  const double per_kind = 2.0 * frames / 1e3;
  std::printf("  camera skeleton          %10.1f %10.1f %10.1f %10.1f\n", skeleton_error[0] / per_kind,
              skeleton_error[1] / per_kind, skeleton_error[2] / per_kind,
              (skeleton_error[0] + skeleton_error[1] + skeleton_error[2]) / (3 * per_kind));
  std::printf("  built starting pose      %10.1f %10.1f %10.1f %10.1f\n", init_error[0] / per_kind,
              init_error[1] / per_kind, init_error[2] / per_kind,
              (init_error[0] + init_error[1] + init_error[2]) / (3 * per_kind));

  // 2. Rough shape on the controlled pose.
  const body::PoseLayout full = body::PoseLayout::full_body();
  const Eigen::Matrix3Xd full_rest = fit::rest_joints(*model, beta);
  Eigen::VectorXd pose = facing(full, 3.2);
  pose[full.index_of("left_shoulder_z")] = -30 * kDeg;
  pose[full.index_of("right_shoulder_z")] = 30 * kDeg;
  std::vector<fit::TrackedSkeleton> calibration;
  for (int i = 0; i < 30; ++i)
    calibration.push_back(simulate(simulator, camera, full_rest, full, pose, 1000 + i).skeleton);
  const double start = bench::thread_cpu_seconds();
  const fit::RoughShapeResult r = fit::estimate_rough_shape(*model, calibration, &camera);
  const double ms = 1e3 * (bench::thread_cpu_seconds() - start);
  const fit::SegmentLengths truth = fit::ModelSegmentLengths(*model, 0.09).lengths(beta);
  std::printf("Rough shape (30 frames of the controlled pose): %.1f ms, %d iterations, stop: %s\n", ms, r.iterations,
              fit::rough_shape_stop_name(r.stop));
  std::printf("  %-20s %10s %10s %10s\n", "segment", "truth mm", "skeleton", "fitted");
  for (int s = 0; s < fit::kBodySegmentCount; ++s)
    std::printf("  %-20s %10.1f %10.1f %10.1f\n", fit::body_segment_name(fit::BodySegment(s)), 1e3 * truth[s],
                1e3 * r.measured[s], 1e3 * r.model[s]);
  std::printf("  beta truth :");
  for (int b = 0; b < 10; ++b) std::printf(" %6.2f", beta[b]);
  std::printf("\n  beta fitted:");
  for (int b = 0; b < 10; ++b) std::printf(" %6.2f", r.beta[b]);
  std::printf("\n");
  return 0;
}
