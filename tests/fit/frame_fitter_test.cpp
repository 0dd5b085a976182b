// FrameFitter (paper 2, II-F): a frame rendered from a known pose and shape is fitted back from a
// perturbed start; degenerate inputs give posefuse::Error.
#include "fit/frame_fitter.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <numbers>
#include <random>

#include "body/template_generator.hpp"
#include "model_frames.hpp"
#include "synthetic_frames.hpp"

namespace posefuse::fit {
namespace {

constexpr double kDeg = std::numbers::pi / 180;

struct Scene {
  std::shared_ptr<const body::SmplModel> model = body::make_template(body::Sex::kMale);
  body::PoseLayout layout = body::PoseLayout::upper_body();
  raycast::DepthCamera camera{raycast::DepthIntrinsics{}};
  Eigen::VectorXd beta = Eigen::VectorXd::Constant(10, 0.2);
};

// Start pose: the truth with every DOF moved by a random amount (rotations up to max_rad,
// translation up to max_m per axis).
Eigen::VectorXd perturbed(const body::PoseLayout& layout, const Eigen::VectorXd& truth, double max_rad, double max_m,
                          unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1, 1);
  Eigen::VectorXd theta = truth;
  for (int d = 0; d < layout.size(); ++d)
    theta[d] += (layout.dof(d).kind == body::DofKind::kTranslation ? max_m : max_rad) * uni(rng);
  return theta;
}

// Largest angle between the model's and the truth's bones (upper arms, forearms, spine to neck,
// shoulder girdle).
double worst_bone_angle_rad(const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b) {
  const int bones[][2] = {{body::kLeftShoulder, body::kLeftElbow},
                          {body::kLeftElbow, body::kLeftWrist},
                          {body::kRightShoulder, body::kRightElbow},
                          {body::kRightElbow, body::kRightWrist},
                          {body::kPelvis, body::kNeck},
                          {body::kLeftShoulder, body::kRightShoulder}};
  double worst = 0;
  for (const auto& bone : bones) {
    const Eigen::Vector3d da = (a.col(bone[1]) - a.col(bone[0])).normalized();
    const Eigen::Vector3d db = (b.col(bone[1]) - b.col(bone[0])).normalized();
    worst = std::max(worst, std::acos(std::clamp(da.dot(db), -1.0, 1.0)));
  }
  return worst;
}

// The joints of paper 2's evaluation (shoulders, elbows, wrists; Fig. 4) and the pelvis and hips.
// The spine's inner joints, neck, head and collars are left out of the worst case: several spine
// and neck DOFs bend the torso surface almost alike, so the fit may split a bend differently
// between them (up to ~1 cm at spine3 or the head joint in bench_fit_frame) with the surface and
// the limbs in place; they count in the mean over all 16.
constexpr int kReportedJoints[] = {body::kPelvis,       body::kLeftHip,       body::kRightHip,
                                   body::kLeftShoulder, body::kRightShoulder, body::kLeftElbow,
                                   body::kRightElbow,   body::kLeftWrist,     body::kRightWrist};

double worst_joint_error_m(const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b) {
  double worst = 0;
  for (int j : kReportedJoints) worst = std::max(worst, (a.col(j) - b.col(j)).norm());
  return worst;
}

double mean_joint_error_m(const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b) {
  double sum = 0;
  for (int j : kBgJoints) sum += (a.col(j) - b.col(j)).norm();
  return sum / kBgJointCount;
}

// Fits three rendered poses back from starts perturbed by up to 3 deg / 2 cm per DOF and checks the
// bounds of docs/fitting.md ("Tests"); returns the mean iteration count.
double expect_fits_rendered_frames_back(const FitOptions& options) {
  Scene s;
  FrameFitter fitter(s.model, s.layout, s.camera.intrinsics(), options);
  int iterations = 0;
  body::BodyEvaluator eval(s.model, s.layout);
  for (int variant = 0; variant < 3; ++variant) {
    const Eigen::VectorXd truth = testing::facing_pose(s.layout, 2.2, variant);
    const testing::ModelFrame rendered = testing::render_model_frame(s.model, s.layout, s.beta, truth, s.camera);
    ForearmDirections imu{testing::forearm_direction(rendered.joints_K, true),
                          testing::forearm_direction(rendered.joints_K, false)};
    const FrameObservation observation =
        prepare_observation(rendered.frame, s.camera, rendered.skeleton_K, fitter.options(), imu);
    const Eigen::VectorXd start = perturbed(s.layout, truth, 3 * kDeg, 0.02, 200 + variant);
    eval.evaluate(s.beta, start, body::Derivatives::kNone);
    const double start_error = worst_joint_error_m(eval.joints(), rendered.joints_K);
    const FitResult result = fitter.fit(observation, start, s.beta);
    eval.evaluate(s.beta, result.theta, body::Derivatives::kNone);
    const double joint_error = worst_joint_error_m(eval.joints(), rendered.joints_K);
    const double mean_error = mean_joint_error_m(eval.joints(), rendered.joints_K);
    const double bone_angle = worst_bone_angle_rad(eval.joints(), rendered.joints_K);
    std::printf(
        "variant %d: start %.1f mm -> worst %.2f mm, mean of 16 %.2f mm, bones %.2f deg, %d iterations (%d rejected), "
        "E %.4g -> %.4g "
        "(data %.4g bg %.4g bgJoint %.4g float %.4g limit %.4g imu %.4g), %s\n",
        variant, 1e3 * start_error, 1e3 * joint_error, 1e3 * mean_error, bone_angle / kDeg, result.iterations,
        result.rejected_steps, result.initial_energy.total(), result.energy.total(), result.energy.data,
        result.energy.bg, result.energy.bg_joint, result.energy.float_term, result.energy.limit, result.energy.imu,
        fit_status_name(result.status));
    EXPECT_GT(start_error, 0.03);
    EXPECT_LT(joint_error, 0.005) << "variant " << variant;
    // The mean includes the spine's inner joints, neck, head and collars (see kReportedJoints).
    EXPECT_LT(mean_error, 0.006) << "variant " << variant;
    EXPECT_LT(bone_angle, 2 * kDeg) << "variant " << variant;
    EXPECT_LT(result.energy.total(), result.initial_energy.total());
    iterations += result.iterations;
  }
  return iterations / 3.0;
}

TEST(FrameFitter, FitsARenderedFrameBackFromAPerturbedStart) { expect_fits_rendered_frames_back(FitOptions{}); }

// Held DOFs keep the start's values exactly while the others are fitted: here the left elbow,
// started 10 deg off, stays there and the fit moves the rest.
TEST(FrameFitter, HeldDofsKeepTheStartsValues) {
  Scene s;
  FrameFitter fitter(s.model, s.layout, s.camera.intrinsics());
  const Eigen::VectorXd truth = testing::facing_pose(s.layout, 2.2, 0);
  const testing::ModelFrame rendered = testing::render_model_frame(s.model, s.layout, s.beta, truth, s.camera);
  const FrameObservation observation = prepare_observation(rendered.frame, s.camera, rendered.skeleton_K, {});
  Eigen::VectorXd start = perturbed(s.layout, truth, 3 * kDeg, 0.02, 300);
  const std::vector<int>& held = s.layout.dofs_of_joint(body::kLeftElbow);
  for (int d : held) start[d] = truth[d] + 10 * kDeg;
  const FitResult result = fitter.fit(observation, start, s.beta, held);
  for (int d : held) EXPECT_EQ(result.theta[d], start[d]) << s.layout.dof(d).name;
  const int right_elbow = s.layout.dofs_of_joint(body::kRightElbow).front();
  EXPECT_NE(result.theta[right_elbow], start[right_elbow]);
  EXPECT_LT(result.energy.total(), result.initial_energy.total());
  // The next fit without held DOFs moves the left elbow back.
  const FitResult free = fitter.fit(observation, start, s.beta);
  for (int d : held) EXPECT_LT(std::abs(free.theta[d] - truth[d]), 3 * kDeg) << s.layout.dof(d).name;
}

// The full-body layout with its knees and ankles held is paper 2's upper-body fit: the same pose,
// energy and iterations from the same start, up to rounding (the larger system sums in another
// order).
TEST(FrameFitter, HeldLegsOfTheFullBodyFitAsTheUpperBody) {
  Scene s;
  const body::PoseLayout full = body::PoseLayout::full_body();
  FrameFitter upper_fitter(s.model, s.layout, s.camera.intrinsics());
  FrameFitter full_fitter(s.model, full, s.camera.intrinsics());
  std::vector<int> legs;
  for (int joint : {body::kLeftKnee, body::kRightKnee, body::kLeftAnkle, body::kRightAnkle})
    for (int d : full.dofs_of_joint(joint)) legs.push_back(d);
  for (int variant = 0; variant < 2; ++variant) {
    const Eigen::VectorXd truth = testing::facing_pose(s.layout, 2.2, variant);
    const testing::ModelFrame rendered = testing::render_model_frame(s.model, s.layout, s.beta, truth, s.camera);
    const FrameObservation observation = prepare_observation(rendered.frame, s.camera, rendered.skeleton_K, {});
    const Eigen::VectorXd start = perturbed(s.layout, truth, 3 * kDeg, 0.02, 400 + variant);
    Eigen::VectorXd full_start = Eigen::VectorXd::Zero(full.size());
    full_start.head(s.layout.size()) = start;
    const FitResult upper = upper_fitter.fit(observation, start, s.beta);
    const FitResult held = full_fitter.fit(observation, full_start, s.beta, legs);
    EXPECT_EQ(held.iterations, upper.iterations) << "variant " << variant;
    EXPECT_NEAR(held.energy.total(), upper.energy.total(), 1e-6 * upper.energy.total()) << "variant " << variant;
    EXPECT_LT((held.theta.head(s.layout.size()) - upper.theta).cwiseAbs().maxCoeff(), 1e-5) << "variant " << variant;
    EXPECT_TRUE(held.theta.tail(full.size() - s.layout.size()).isZero()) << "variant " << variant;
  }
}

// A camera whose image ends above the hips (rows below 300 of 424 cut off, as when it looks up or
// stands close): the image shows nothing of the legs and pelvis below its edge, so the silhouette
// term must not pull them into the view. The same bounds as a whole body in view.
TEST(FrameFitter, ABodyCutByTheImageEdgeIsNotPulledIntoTheView) {
  Scene s;
  raycast::DepthIntrinsics cut;
  cut.height = 300;
  const raycast::DepthCamera camera(cut);
  FrameFitter fitter(s.model, s.layout, camera.intrinsics(), FitOptions{});
  body::BodyEvaluator eval(s.model, s.layout);
  for (int variant = 0; variant < 3; ++variant) {
    const Eigen::VectorXd truth = testing::facing_pose(s.layout, 2.2, variant);
    const testing::ModelFrame rendered = testing::render_model_frame(s.model, s.layout, s.beta, truth, camera);
    const FrameObservation observation =
        prepare_observation(rendered.frame, camera, rendered.skeleton_K, fitter.options(), ForearmDirections{});
    const FitResult result = fitter.fit(observation, perturbed(s.layout, truth, 3 * kDeg, 0.02, 300 + variant), s.beta);
    eval.evaluate(s.beta, result.theta, body::Derivatives::kNone);
    const double joint_error = worst_joint_error_m(eval.joints(), rendered.joints_K);
    const double bone_angle = worst_bone_angle_rad(eval.joints(), rendered.joints_K);
    std::printf("cut variant %d: worst %.2f mm, bones %.2f deg\n", variant, 1e3 * joint_error, bone_angle / kDeg);
    EXPECT_LT(joint_error, 0.005) << "variant " << variant;
    EXPECT_LT(bone_angle, 2 * kDeg) << "variant " << variant;
  }
}

// The stopping rule of issue 7 (U_bg frozen after freeze_contour_after iterations, so that the
// joint-step test can fire): it stops these converged fits earlier than re-selecting U_bg at every
// iteration, and only once the joints are within the same bounds.
TEST(FrameFitter, FrozenContourStopsAConvergedFitEarlyOnlyOnceTheJointsAreClose) {
  FitOptions reselect;
  reselect.freeze_contour_after = 0;
  const double reselect_iterations = expect_fits_rendered_frames_back(reselect);
  FitOptions frozen;
  frozen.freeze_contour_after = 4;
  const double frozen_iterations = expect_fits_rendered_frames_back(frozen);
  std::printf("mean iterations: %.1f re-selecting U_bg, %.1f frozen after 4\n", reselect_iterations, frozen_iterations);
  EXPECT_LT(frozen_iterations, reselect_iterations);
}

// With bg, bgJoint and float linearised as distances (FitOptions::linearise_distances) the fit
// brings the rendered frames back within the same bounds, and re-selecting U_bg no longer keeps
// its stopping tests from firing on these noise-free frames: it stops within an iteration of the
// frozen fit (with the offsets, the test above: 11.0 iterations against 8.0).
TEST(FrameFitter, WithDistancesLinearisedReselectingTheContourStopsAboutAsSoonAsFreezingIt) {
  FitOptions reselect;
  reselect.linearise_distances = true;
  reselect.freeze_contour_after = 0;
  const double reselect_iterations = expect_fits_rendered_frames_back(reselect);
  FitOptions frozen = reselect;
  frozen.freeze_contour_after = 4;
  const double frozen_iterations = expect_fits_rendered_frames_back(frozen);
  std::printf("distances: mean iterations %.1f re-selecting U_bg, %.1f frozen after 4\n", reselect_iterations,
              frozen_iterations);
  EXPECT_LE(reselect_iterations, frozen_iterations + 1.0);
}

// The joint-step stop (FitOptions::min_joint_step_m) after a step shrunk by damping. Behind the back
// on paper 1's protocol the undamped step raised the energy, gamma went from 0.01 to ~160 before a
// step was accepted, and that step, well under 1 mm, ended the fit: the arm stood still for a second
// at a time. Here a start damped at 1000 stands in for it: the first step is then a small fraction
// of the Gauss-Newton step, under 1 mm from a 3 deg / 2 cm start (measured: 51.2 -> 51.1 mm, and
// the stop after any step ends the fit there; with the default the damping comes down over ~10
// accepted steps and the fit ends 3.4 mm off in 20 iterations).
TEST(FrameFitter, AStepShrunkByDampingIsNotTakenForConvergence) {
  Scene s;
  const Eigen::VectorXd truth = testing::facing_pose(s.layout, 2.2, 0);
  const testing::ModelFrame rendered = testing::render_model_frame(s.model, s.layout, s.beta, truth, s.camera);
  const ForearmDirections imu{testing::forearm_direction(rendered.joints_K, true),
                              testing::forearm_direction(rendered.joints_K, false)};
  const Eigen::VectorXd start = perturbed(s.layout, truth, 3 * kDeg, 0.02, 200);
  body::BodyEvaluator eval(s.model, s.layout);
  eval.evaluate(s.beta, start, body::Derivatives::kNone);
  const double start_error = worst_joint_error_m(eval.joints(), rendered.joints_K);
  const auto fit_with = [&](double joint_step_stop_max_damping) {
    FitOptions options;
    options.initial_damping = 1e3;
    options.max_iterations = 40;
    options.joint_step_stop_max_damping = joint_step_stop_max_damping;
    FrameFitter fitter(s.model, s.layout, s.camera.intrinsics(), options);
    const FrameObservation observation =
        prepare_observation(rendered.frame, s.camera, rendered.skeleton_K, fitter.options(), imu);
    const FitResult result = fitter.fit(observation, start, s.beta);
    eval.evaluate(s.beta, result.theta, body::Derivatives::kNone);
    const double error = worst_joint_error_m(eval.joints(), rendered.joints_K);
    std::printf("joint-step stop up to gamma %.3g: start %.1f mm -> %.2f mm, %d iterations, E %.4g -> %.4g\n",
                joint_step_stop_max_damping, 1e3 * start_error, 1e3 * error, result.iterations,
                result.initial_energy.total(), result.energy.total());
    return std::make_pair(error, result.iterations);
  };
  const auto [stopped_error, stopped_iterations] = fit_with(FitOptions{}.max_damping);  // the stop after any step
  const auto [error, iterations] = fit_with(FitOptions{}.joint_step_stop_max_damping);
  EXPECT_GT(start_error, 0.03);
  EXPECT_GT(stopped_error, 0.01) << "the damped first step already ended near the truth: the test shows nothing";
  EXPECT_LE(stopped_iterations, 2);
  EXPECT_LT(error, 0.005);
  EXPECT_GT(iterations, stopped_iterations);
}

namespace posefuse::fit {
namespace {

struct DegenerateInputs : ::testing::Test {
  Scene s;
  Eigen::VectorXd truth = testing::facing_pose(s.layout, 2.2, 0);
  testing::ModelFrame rendered = testing::render_model_frame(s.model, s.layout, s.beta, truth, s.camera);
  FitOptions options;
};

ErrorCode code_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.code();
  }
  return ErrorCode::kInternal;
}

TEST_F(DegenerateInputs, EmptySilhouetteIsRefusedWithTheFieldNamed) {
  DepthFrame frame = rendered.frame;
  std::fill(frame.body_index.begin(), frame.body_index.end(), kNoBody);
  const auto prepare = [&] { prepare_observation(frame, s.camera, rendered.skeleton_K, options); };
  EXPECT_EQ(testing::error_field(prepare), "frame.body_index");
  EXPECT_EQ(code_of(prepare), ErrorCode::kFailedPrecondition);
}

TEST_F(DegenerateInputs, DepthWithoutAnyReadingIsRefused) {
  // The Kinect marks missing depth with 0 (uint16 has no NaN): a silhouette without readings.
  DepthFrame frame = rendered.frame;
  std::fill(frame.depth_mm.begin(), frame.depth_mm.end(), kNoDepth);
  EXPECT_EQ(testing::error_field([&] { prepare_observation(frame, s.camera, rendered.skeleton_K, options); }),
            "frame.body_index");
}

TEST_F(DegenerateInputs, MissingOrNonFiniteSkeletonIsRefused) {
  const auto missing = [&] { prepare_observation(rendered.frame, s.camera, std::nullopt, options); };
  EXPECT_EQ(testing::error_field(missing), "skeleton");
  EXPECT_EQ(code_of(missing), ErrorCode::kFailedPrecondition);
  KinectSkeleton nan_skeleton = rendered.skeleton_K;
  nan_skeleton[5].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(testing::error_field([&] { prepare_observation(rendered.frame, s.camera, nan_skeleton, options); }),
            "skeleton[5]");
}

TEST_F(DegenerateInputs, BadObservationPoseShapeAndOptionsAreRefused) {
  FrameFitter fitter(s.model, s.layout, s.camera.intrinsics());
  const FrameObservation good = prepare_observation(rendered.frame, s.camera, rendered.skeleton_K, options);
  FrameObservation nan_points = good;
  nan_points.points_K[3].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(testing::error_field([&] { fitter.fit(nan_points, truth, s.beta); }), "observation.points_K[3]");
  FrameObservation no_samples = good;
  no_samples.points_K.clear();
  no_samples.normals_K.clear();
  EXPECT_EQ(testing::error_field([&] { fitter.fit(no_samples, truth, s.beta); }), "observation.points_K");
  FrameObservation bad_imu = good;
  bad_imu.forearm.left_K = Eigen::Vector3d(0, 0, 2);
  EXPECT_EQ(testing::error_field([&] { fitter.fit(bad_imu, truth, s.beta); }), "observation.forearm.left_K");
  for (const double weight : {-0.1, 1.5, std::numeric_limits<double>::quiet_NaN()}) {
    FrameObservation bad_weight = good;
    bad_weight.forearm.right_weight = weight;
    EXPECT_EQ(testing::error_field([&] { fitter.fit(bad_weight, truth, s.beta); }), "observation.forearm.right_weight");
  }
  Eigen::VectorXd nan_theta = truth;
  nan_theta[7] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(testing::error_field([&] { fitter.fit(good, nan_theta, s.beta); }), "theta[7]");
  EXPECT_EQ(testing::error_field([&] { fitter.fit(good, truth.head(12), s.beta); }), "theta");
  EXPECT_EQ(testing::error_field([&] { fitter.fit(good, truth, Eigen::VectorXd::Zero(14)); }), "beta");
  const std::vector<int> out_of_range = {3, s.layout.size()}, repeated = {5, 5};
  EXPECT_EQ(testing::error_field([&] { fitter.fit(good, truth, s.beta, out_of_range); }), "held_dofs");
  EXPECT_EQ(testing::error_field([&] { fitter.fit(good, truth, s.beta, repeated); }), "held_dofs");
  FitOptions bad = options;
  bad.sigma_p_m = 0;
  EXPECT_EQ(testing::error_field([&] { FrameFitter(s.model, s.layout, s.camera.intrinsics(), bad); }),
            "fit_options.sigma_p_m");
  bad = options;
  bad.limit_projection_margin_rad = -0.1;
  EXPECT_EQ(testing::error_field([&] { FrameFitter(s.model, s.layout, s.camera.intrinsics(), bad); }),
            "fit_options.limit_projection_margin_rad");
  bad = options;
  bad.joint_step_stop_max_damping = 0;
  EXPECT_EQ(testing::error_field([&] { FrameFitter(s.model, s.layout, s.camera.intrinsics(), bad); }),
            "fit_options.joint_step_stop_max_damping");
  bad = options;
  bad.lambda_imu = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(testing::error_field([&] { FrameFitter(s.model, s.layout, s.camera.intrinsics(), bad); }),
            "fit_options.lambda_imu");
  // After refusing, the fitter still fits.
  const FitResult result = fitter.fit(good, truth, s.beta);
  EXPECT_TRUE(result.theta.allFinite());
}

TEST(FrameFitterEnergy, ImuTermPullsTheForearmTowardsTheImuDirectionByItsWeight) {
  // Same frame, the left forearm IMU says the forearm points 20 degrees elsewhere: with the imu
  // term the fitted forearm turns towards it, the more the larger the direction's weight
  // (forearm_direction_weight); without it (lambda_imu = 0, or weight 0) it does not.
  Scene s;
  const Eigen::VectorXd truth = testing::facing_pose(s.layout, 2.2, 0);
  const testing::ModelFrame rendered = testing::render_model_frame(s.model, s.layout, s.beta, truth, s.camera);
  const Eigen::Vector3d true_direction = testing::forearm_direction(rendered.joints_K, true);
  const Eigen::Vector3d axis = true_direction.unitOrthogonal();
  const Eigen::Vector3d imu_direction = Eigen::AngleAxisd(20 * kDeg, axis) * true_direction;
  body::BodyEvaluator eval(s.model, s.layout);
  const auto angle_to_imu = [&](double lambda_imu, double weight) {
    FitOptions options;
    options.lambda_imu = lambda_imu;
    FrameFitter fitter(s.model, s.layout, s.camera.intrinsics(), options);
    ForearmDirections imu{imu_direction, std::nullopt};
    imu.left_weight = weight;
    const FrameObservation observation =
        prepare_observation(rendered.frame, s.camera, rendered.skeleton_K, options, imu);
    const FitResult result = fitter.fit(observation, truth, s.beta);
    if (lambda_imu == 0 || weight == 0) {
      EXPECT_EQ(result.energy.imu, 0.0);
    }
    eval.evaluate(s.beta, result.theta, body::Derivatives::kNone);
    return std::acos(std::clamp(testing::forearm_direction(eval.joints(), true).dot(imu_direction), -1.0, 1.0));
  };
  const double without = angle_to_imu(0, 1), quarter = angle_to_imu(15, 0.25), full = angle_to_imu(15, 1);
  EXPECT_NEAR(angle_to_imu(15, 0), without, 1e-9);
  EXPECT_LT(quarter, without - 1 * kDeg);
  EXPECT_LT(full, quarter - 1 * kDeg);
}

// A direction confident at 99 % within 15 degrees (RMS up to 6.99 degrees) has the full weight;
// beyond, the weight falls as the inverse of its variance; an unknown error gives none.
TEST(ForearmDirectionWeight, FullWhereConfidentThenInverseToTheVariance) {
  const double confident_rms = 15 * kDeg / 2.146;
  EXPECT_EQ(forearm_direction_weight(0.0), 1.0);
  EXPECT_EQ(forearm_direction_weight(0.999 * confident_rms), 1.0);
  EXPECT_NEAR(forearm_direction_weight(2 * confident_rms), 0.25, 1e-3);
  EXPECT_NEAR(forearm_direction_weight(14 * kDeg), std::pow(confident_rms / (14 * kDeg), 2), 1e-12);
  EXPECT_EQ(forearm_direction_weight(std::numeric_limits<double>::quiet_NaN()), 0.0);
  EXPECT_EQ(forearm_direction_weight(-1.0), 0.0);
}

}  // namespace
}  // namespace posefuse::fit

// Paper 1's protocol (issue 7) turns the upper arm about itself by ~90 deg or more, which the
// layout without arm roll (paper 2, II-B) can only express through the elbow's swing: the
// calibration pose (upper arm sideways, forearm vertical) and the forearm behind the back, where
// the depth image shows nothing of it and only the IMU direction and the elbow place it. Both
// rendered from the upper-body model and fitted back from a perturbed start with the true IMU
// directions. With the anatomical elbow range (z within +-30 deg, body::kLimits) the true poses
// cost a limit energy of 645 and 224 and the fit ended 77-86 and 116-119 mm off at the wrists
// (docs/fitting.md, "Paper 1's protocol").
namespace protocol {

Eigen::VectorXd calibration_pose(const body::PoseLayout& layout) {
  Eigen::VectorXd theta = testing::facing_pose(layout, 2.2, 0);
  for (const char* dof :
       {"left_shoulder_y", "left_shoulder_z", "right_shoulder_y", "right_shoulder_z", "left_elbow_y", "right_elbow_y"})
    theta[layout.index_of(dof)] = 0;
  theta[layout.index_of("left_elbow_z")] = 90 * kDeg;  // forearms up, palms to the camera
  theta[layout.index_of("right_elbow_z")] = -90 * kDeg;
  return theta;
}

// The left forearm across the lower back (as the fits of paper 1's protocol find it); the right
// arm as in facing_pose.
Eigen::VectorXd left_forearm_behind_back(const body::PoseLayout& layout) {
  Eigen::VectorXd theta = testing::facing_pose(layout, 2.2, 0);
  theta[layout.index_of("left_shoulder_y")] = 37 * kDeg;
  theta[layout.index_of("left_shoulder_z")] = -57 * kDeg;
  theta[layout.index_of("left_elbow_y")] = 40 * kDeg;
  theta[layout.index_of("left_elbow_z")] = -70 * kDeg;
  return theta;
}

struct ProtocolFit {
  double limit_energy_at_truth = 0;
  double wrist_error_m[2] = {0, 0};  // left, right
  double elbow_error_m[2] = {0, 0};
};

// From a tracking-like start (every DOF moved by up to 1 deg / 5 mm, as between frames at 30 Hz):
// from 3 deg / 2 cm about one start in ten ends in a local minimum with a visible arm 2 cm off
// (docs/fitting.md, "Not done yet"), which is not what these tests are about.
ProtocolFit fit_protocol_pose(const Scene& s, const Eigen::VectorXd& truth, unsigned seed,
                              const testing::ModelFrame& rendered) {
  FrameFitter fitter(s.model, s.layout, s.camera.intrinsics(), FitOptions{});
  const FrameObservation observation =
      prepare_observation(rendered.frame, s.camera, rendered.skeleton_K, fitter.options(),
                          ForearmDirections{testing::forearm_direction(rendered.joints_K, true),
                                            testing::forearm_direction(rendered.joints_K, false)});
  ProtocolFit out;
  out.limit_energy_at_truth = fitter.energy(observation, truth, s.beta).limit;
  const FitResult result = fitter.fit(observation, perturbed(s.layout, truth, 1 * kDeg, 0.005, seed), s.beta);
  body::BodyEvaluator eval(s.model, s.layout);
  eval.evaluate(s.beta, result.theta, body::Derivatives::kNone);
  for (int side = 0; side < 2; ++side) {
    const int wrist = side == 0 ? body::kLeftWrist : body::kRightWrist,
              elbow = side == 0 ? body::kLeftElbow : body::kRightElbow;
    out.wrist_error_m[side] = (eval.joints().col(wrist) - rendered.joints_K.col(wrist)).norm();
    out.elbow_error_m[side] = (eval.joints().col(elbow) - rendered.joints_K.col(elbow)).norm();
  }
  std::printf("limit energy at the truth %.3g; wrists %.1f / %.1f mm, elbows %.1f / %.1f mm; E %.4g, %d iterations\n",
              out.limit_energy_at_truth, 1e3 * out.wrist_error_m[0], 1e3 * out.wrist_error_m[1],
              1e3 * out.elbow_error_m[0], 1e3 * out.elbow_error_m[1], result.energy.total(), result.iterations);
  return out;
}

}  // namespace protocol

TEST(FrameFitterProtocol, CalibrationPoseWithTheForearmsUpIsFittedBack) {
  Scene s;
  const Eigen::VectorXd truth = protocol::calibration_pose(s.layout);
  const testing::ModelFrame rendered = testing::render_model_frame(s.model, s.layout, s.beta, truth, s.camera);
  // The forearms really point up (K's y) with the upper arms sideways.
  for (const bool left : {true, false}) EXPECT_GT(testing::forearm_direction(rendered.joints_K, left).y(), 0.95);
  for (unsigned seed : {301u, 302u}) {
    const protocol::ProtocolFit fit = protocol::fit_protocol_pose(s, truth, seed, rendered);
    EXPECT_EQ(fit.limit_energy_at_truth, 0.0);
    for (int side = 0; side < 2; ++side) {
      EXPECT_LT(fit.wrist_error_m[side], 0.01) << "seed " << seed << " side " << side;
      EXPECT_LT(fit.elbow_error_m[side], 0.01) << "seed " << seed << " side " << side;
    }
  }
}

TEST(FrameFitterProtocol, HiddenForearmBehindTheBackIsFittedBackFromItsImuDirection) {
  Scene s;
  const Eigen::VectorXd truth = protocol::left_forearm_behind_back(s.layout);
  const testing::ModelFrame rendered = testing::render_model_frame(s.model, s.layout, s.beta, truth, s.camera);
  // The left wrist and the forearm's middle are hidden: the depth there is the torso, in front.
  for (const double along : {0.75, 1.0}) {
    const Eigen::Vector3d p =
        rendered.joints_K.col(body::kLeftElbow) +
        along * (rendered.joints_K.col(body::kLeftWrist) - rendered.joints_K.col(body::kLeftElbow));
    const auto px = s.camera.project(p);
    ASSERT_TRUE(px);
    const size_t i =
        static_cast<size_t>(std::lround(px->y())) * s.camera.width() + static_cast<size_t>(std::lround(px->x()));
    ASSERT_NE(rendered.frame.body_index[i], kNoBody);
    EXPECT_LT(rendered.frame.depth_mm[i] * 1e-3, p.z() - 0.05) << "at " << along << " of the forearm";
  }
  for (unsigned seed : {311u, 312u}) {
    const protocol::ProtocolFit fit = protocol::fit_protocol_pose(s, truth, seed, rendered);
    EXPECT_EQ(fit.limit_energy_at_truth, 0.0);
    EXPECT_LT(fit.elbow_error_m[0], 0.01) << "seed " << seed;
    EXPECT_LT(fit.wrist_error_m[0], 0.01) << "seed " << seed;
    EXPECT_LT(fit.wrist_error_m[1], 0.01) << "seed " << seed;
  }
}

// FitOptions::project_steps_onto_limits: with the left forearm behind the back (the data hardly
// constrain it) no LM step may take a limited DOF more than limit_projection_margin_rad beyond its
// range, where eq. 8's penalty is zero and so unseen by the Gauss-Newton model (behind the back
// on paper 1's protocol those steps crossed the limits by radians and were all rejected). This
// rendered frame's fits end inside the limits with the projection off too (printed), so the
// protocol's numbers (docs/fitting.md, "Steps projected onto the pose limits") show the effect;
// this test holds the bound.
TEST(FrameFitterProtocol, StepsStayWithinTheLimitsWidenedByTheMargin) {
  Scene s;
  const Eigen::VectorXd truth = protocol::left_forearm_behind_back(s.layout);
  const testing::ModelFrame rendered = testing::render_model_frame(s.model, s.layout, s.beta, truth, s.camera);
  const ForearmDirections imu{testing::forearm_direction(rendered.joints_K, true),
                              testing::forearm_direction(rendered.joints_K, false)};
  for (const bool project : {true, false}) {
    FitOptions options;
    options.project_steps_onto_limits = project;
    FrameFitter fitter(s.model, s.layout, s.camera.intrinsics(), options);
    const FrameObservation observation =
        prepare_observation(rendered.frame, s.camera, rendered.skeleton_K, fitter.options(), imu);
    for (unsigned seed : {311u, 312u, 313u}) {
      const Eigen::VectorXd start = perturbed(s.layout, truth, 5 * kDeg, 0.02, seed);
      const FitResult result = fitter.fit(observation, start, s.beta);
      double worst_excess_rad = 0;
      for (int d = 0; d < s.layout.size(); ++d) {
        const body::Dof& dof = s.layout.dof(d);
        if (!dof.limited) continue;
        const double start_excess = std::max(dof.min_rad - start[d], start[d] - dof.max_rad);
        const double excess = std::max(dof.min_rad - result.theta[d], result.theta[d] - dof.max_rad);
        if (project && start_excess <= options.limit_projection_margin_rad) {
          EXPECT_LE(excess, options.limit_projection_margin_rad + 1e-12) << dof.name << " seed " << seed;
        }
        worst_excess_rad = std::max(worst_excess_rad, excess);
      }
      std::printf(
          "projection %s, seed %u: worst excess beyond a limit %.3f rad, %d iterations (%d rejected), E %.4g, limit "
          "%.4g\n",
          project ? "on" : "off", seed, worst_excess_rad, result.iterations, result.rejected_steps,
          result.energy.total(), result.energy.limit);
      EXPECT_LT(result.energy.total(), result.initial_energy.total());
    }
  }
}

}  // namespace
}  // namespace posefuse::fit
