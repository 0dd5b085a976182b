// The body fit's elbow flexion and wrist position on single frames of the simulator's anatomical
// arm poses (sim::BodyPoseAngles: 3-DOF SMPL arms, humeral rotation and supination included),
// the female template's own shape rendered subdivided as posefuse-sim renders it, with the
// simulator's depth errors (sim/depth_noise.hpp) on or off, fitted by FrameFitter's 40-DOF
// no-roll layout from the skeleton-built start of the exact joints. It separates what the
// per-frame fit does from what tracking, the camera skeleton's errors and shape mismatch add.
//
//   bench_elbow_flexion [--noise=all|none|flying|dropout|axial|edge_shift] [--seeds=N] [--option KEY=VALUE]...
//
// --noise: the depth errors applied (one kind alone, or all; default all), each frame with N noise
// seeds (default 3). --option: fit options by their stage keys (fit.silhouette_edge_px=0.7).
// Poses: shoulder abduction 8 and 45 deg, shoulder flexion 0 and 20, humeral rotation -40, 0 and
// 40, supination -60, 0 and 60, elbow flexion 0, 15, 45, 90 and 120; both arms alike.
// Prints per true elbow flexion the fitted flexion's mean and RMS error and the wrists' mean
// vertical (K's y, up) and 3-D errors, then the same for the forearm pointing at the camera
// (abduction 8, flexion 0, humeral rotation 0, elbow 90).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "body/template_generator.hpp"
#include "fit/frame_fitter.hpp"
#include "fit/limb_bend.hpp"
#include "fit/silhouette_cleanup.hpp"
#include "fit/skeleton_pose_init.hpp"
#include "model_frames.hpp"
#include "session/stages/body_fit_options.hpp"
#include "sim/body_pose_angles.hpp"
#include "sim/depth_noise.hpp"
#include "sim/render_model.hpp"

using namespace posefuse;

namespace {

constexpr double kDeg = std::numbers::pi / 180;

double flexion_deg(const Eigen::Matrix3Xd& J, bool left) {
  return left ? fit::limb_bend_deg(J.col(body::kLeftShoulder), J.col(body::kLeftElbow), J.col(body::kLeftWrist))
              : fit::limb_bend_deg(J.col(body::kRightShoulder), J.col(body::kRightElbow), J.col(body::kRightWrist));
}

struct Errors {
  double flexion_sum = 0, flexion_squares = 0, wrist_up_sum = 0, wrist_sum = 0;
  int n = 0;
  void add(double flexion_error, const Eigen::Vector3d& wrist_error) {
    flexion_sum += flexion_error;
    flexion_squares += flexion_error * flexion_error;
    wrist_up_sum += wrist_error.y();
    wrist_sum += wrist_error.norm();
    ++n;
  }
  void print(const char* label) const {
    std::printf("| %s | %d | %+.2f | %.2f | %+.1f | %.1f |\n", label, n, flexion_sum / n,
                std::sqrt(flexion_squares / n), 1e3 * wrist_up_sum / n, 1e3 * wrist_sum / n);
  }
};

sim::DepthNoiseOptions noise_options(const std::string& kind) {
  sim::DepthNoiseOptions all;
  if (kind == "all" || kind == "none") return all;
  sim::DepthNoiseOptions one = all;
  one.flying_pixel_probability = 0;
  one.max_incidence_deg = all.edge_slope_deg - 0.1;  // nothing is grazing enough to drop
  one.axial_sigma_base_m = one.axial_sigma_quadratic_per_m = 0;
  one.max_edge_shift_px = 0;
  if (kind == "flying") {
    one.flying_pixel_probability = all.flying_pixel_probability;
  } else if (kind == "dropout") {
    one.max_incidence_deg = all.max_incidence_deg;
  } else if (kind == "axial") {
    one.axial_sigma_base_m = all.axial_sigma_base_m;
    one.axial_sigma_quadratic_per_m = all.axial_sigma_quadratic_per_m;
  } else if (kind == "edge_shift") {
    one.max_edge_shift_px = all.max_edge_shift_px;
  } else {
    std::fprintf(stderr, "--noise=%s: expected all, none, flying, dropout, axial or edge_shift\n", kind.c_str());
    std::exit(2);
  }
  return one;
}

}  // namespace

int main(int argc, char** argv) {
  std::string noise = "all";
  int seeds = 3;
  v1::SessionHeader header;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--noise=", 0) == 0) {
      noise = arg.substr(8);
    } else if (arg.rfind("--seeds=", 0) == 0) {
      seeds = std::max(1, std::atoi(arg.c_str() + 8));
    } else if (arg == "--option" && i + 1 < argc) {
      const std::string item = argv[++i];
      const std::size_t eq = item.find('=');
      if (eq == std::string::npos) {
        std::fprintf(stderr, "--option %s: expected KEY=VALUE\n", item.c_str());
        return 2;
      }
      (*header.mutable_options())[item.substr(0, eq)] = item.substr(eq + 1);
    } else {
      std::fprintf(stderr, "usage: bench_elbow_flexion [--noise=KIND] [--seeds=N] [--option KEY=VALUE]...\n");
      return 2;
    }
  }
  const fit::FitOptions options = session::read_body_fit_options(header).fit;
  if (noise == "none") seeds = 1;
  const sim::DepthNoiseOptions noise_model = noise_options(noise);

  const auto model = body::make_template(body::Sex::kFemale);
  const Eigen::VectorXd beta = Eigen::VectorXd::Zero(model->num_betas());
  sim::ClothingOptions bare;
  bare.enabled = false;  // the subdivided template without offsets: the fitted shape exactly
  const std::shared_ptr<const body::SmplModel> rendered_model = sim::make_render_model(*model, beta, bare, 1).model;
  const body::PoseLayout all_joints = body::PoseLayout::all_joints();
  const body::PoseLayout layout = body::PoseLayout::upper_body();
  const raycast::DepthCamera camera{raycast::DepthIntrinsics{}};
  const auto room = sim::simple_room(1.0, 4.0);
  fit::FrameFitter fitter(model, layout, camera.intrinsics(), options);
  fit::SkeletonPoseInitializer initializer(model, layout, beta);
  body::BodyEvaluator fitted(model, layout);
  body::BodyEvaluator posed(rendered_model, all_joints);

  std::map<int, Errors> by_flexion;
  Errors at_camera;
  std::int64_t frame_index = 0;
  for (double abduction : {8.0, 45.0})
    for (double shoulder_flexion : {0.0, 20.0})
      for (double humeral : {-40.0, 0.0, 40.0})
        for (double supination : {-60.0, 0.0, 60.0})
          for (double elbow : {0.0, 15.0, 45.0, 90.0, 120.0}) {
            sim::BodyPoseAngles angles;
            for (sim::ArmAngles* arm : {&angles.left_arm, &angles.right_arm}) {
              arm->shoulder_abduction_rad = abduction * kDeg;
              arm->shoulder_flexion_rad = shoulder_flexion * kDeg;
              arm->humeral_rotation_rad = humeral * kDeg;
              arm->elbow_flexion_rad = elbow * kDeg;
              arm->supination_rad = supination * kDeg;
            }
            // Facing the camera, the pelvis where posefuse-sim's sessions have it.
            Eigen::VectorXd truth = sim::all_joints_theta(angles);
            truth[sim::all_joints_rotation_index(body::kPelvis) + 1] = std::numbers::pi;
            posed.evaluate(beta, truth, body::Derivatives::kNone);
            truth.head<3>() += Eigen::Vector3d(0, -0.11, 2.5) - posed.joints().col(body::kPelvis);
            const auto clean = fit::testing::render_model_frame(rendered_model, all_joints, beta, truth, camera);
            for (int seed = 0; seed < seeds; ++seed) {
              auto frame = clean.frame;
              if (noise != "none") {
                sim::composite_room(camera, room, frame.depth_mm);
                const sim::NoisyDepth noisy = sim::apply_depth_noise(camera, frame.depth_mm, frame.body_index,
                                                                     noise_model, 1 + seed, frame_index++);
                frame.depth_mm = noisy.depth_mm;
                frame.body_index = noisy.body_index;
                fit::remove_off_body_depth(frame, fit::TrackedSkeleton::all_tracked(clean.skeleton_K), {}, &camera);
              }
              const fit::FrameObservation observation =
                  fit::prepare_observation(frame, camera, clean.skeleton_K, options);
              const auto start = initializer.initialise(fit::TrackedSkeleton::all_tracked(clean.skeleton_K), {});
              const fit::FitResult result = fitter.fit(observation, start.theta, beta);
              fitted.evaluate(beta, result.theta, body::Derivatives::kNone);
              for (bool left : {true, false}) {
                const int wrist = left ? body::kLeftWrist : body::kRightWrist;
                const double error = flexion_deg(fitted.joints(), left) - flexion_deg(clean.joints_K, left);
                const Eigen::Vector3d wrist_error = fitted.joints().col(wrist) - clean.joints_K.col(wrist);
                by_flexion[static_cast<int>(elbow)].add(error, wrist_error);
                if (abduction == 8.0 && shoulder_flexion == 0.0 && humeral == 0.0 && elbow == 90.0)
                  at_camera.add(error, wrist_error);
              }
            }
          }
  std::printf("noise %s, %d noise seed(s) per pose, fit.silhouette_edge_px %.2g\n\n", noise.c_str(), seeds,
              options.silhouette_edge_px);
  std::printf(
      "| true elbow flexion (deg) | arms | flexion error mean (deg) | RMS (deg) | wrist too high, mean (mm) | "
      "wrist error, mean (mm) |\n|---|---|---|---|---|---|\n");
  for (const auto& [flexion, errors] : by_flexion) errors.print(std::to_string(flexion).c_str());
  at_camera.print("90, forearm at the camera");
  return 0;
}
