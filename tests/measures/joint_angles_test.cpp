// ISB joint angles: exact on constructed skeletons (every angle set and read back, a tilted
// camera, the left side mirrored), on the built-in template posed by its own DOFs, the gimbal lock
// and the straight elbow, and bad input.
#include "measures/joint_angles.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <numbers>
#include <random>
#include <set>
#include <string>

#include "body/pose_parameters.hpp"
#include "body/template_generator.hpp"
#include "common/error.hpp"
#include "constructed_skeleton.hpp"
#include "fit/joint_kinematics.hpp"

namespace posefuse::measures {
namespace {

using testing::ArmPose;
using testing::build;
using testing::Built;
using testing::kRad;
using testing::Rx;
using testing::Ry;
using testing::Rz;

double deg(const JointAngles& a, Angle angle) { return a[static_cast<int>(angle)].deg; }

// The elevation's confidence with every joint tracked: the default 2 cm joint error over the
// constructed skeleton's 0.3 m upper arm (constructed_skeleton.hpp).
double tracked_elevation_confidence() { return angle_confidence_from_rms_rad(0.02 / 0.3); }
bool defined(const JointAngles& a, Angle angle) { return a[static_cast<int>(angle)].defined; }

void expect_arm(const JointAngles& a, bool left, const ArmPose& want, double tolerance_deg) {
  const int base = static_cast<int>(left ? Angle::kLeftPlaneOfElevation : Angle::kRightPlaneOfElevation);
  const char* side = left ? "left" : "right";
  EXPECT_NEAR(a[base + 0].deg, want.plane_deg, tolerance_deg) << side << " plane";
  EXPECT_NEAR(a[base + 1].deg, want.elevation_deg, tolerance_deg) << side << " elevation";
  EXPECT_NEAR(a[base + 2].deg, want.axial_deg, tolerance_deg) << side << " axial";
  EXPECT_NEAR(a[base + 3].deg, want.elbow_deg, tolerance_deg) << side << " elbow";
  EXPECT_NEAR(a[base + 5].deg, want.girdle_deg, tolerance_deg) << side << " girdle";
}

TEST(JointAngles, EveryAngleReadBackOnConstructedSkeletons) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Matrix3d K_from_G =
        Eigen::Quaterniond(Eigen::Vector4d::NullaryExpr([&](Eigen::Index) { return u(rng) - 0.5; }).normalized())
            .toRotationMatrix();
    const auto random_arm = [&] {
      return ArmPose{-60 + 180 * u(rng), 20 + 140 * u(rng),  -80 + 160 * u(rng),
                     20 + 120 * u(rng),  -80 + 160 * u(rng), -10 + 40 * u(rng)};
    };
    const ArmPose left = random_arm(), right = random_arm();
    const double flexion = -20 + 80 * u(rng), tilt = -30 + 60 * u(rng), axial = -40 + 80 * u(rng);
    Built b = build(K_from_G, flexion, tilt, axial, left, right);
    const auto& J = b.body.smpl_joints_K;
    b.body.left_pronation =
        PronationInput{*pronation_rad(J.col(16), J.col(18), J.col(20), b.left_thumb_K, true, 15), 1};
    b.body.right_pronation =
        PronationInput{*pronation_rad(J.col(17), J.col(19), J.col(21), b.right_thumb_K, false, 15), 1};
    // The skeleton's own exact joints: every angle as confident as they are.
    const JointAngles a = joint_angles(b.body, exact_joint_options({}));
    SCOPED_TRACE(trial);
    EXPECT_NEAR(deg(a, Angle::kThoraxFlexion), flexion, 1e-6);
    EXPECT_NEAR(deg(a, Angle::kThoraxLateralTilt), tilt, 1e-6);
    EXPECT_NEAR(deg(a, Angle::kThoraxAxialRotation), axial, 1e-6);
    expect_arm(a, true, left, 1e-6);
    expect_arm(a, false, right, 1e-6);
    EXPECT_NEAR(deg(a, Angle::kLeftPronation), left.pronation_deg, 1e-6);
    EXPECT_NEAR(deg(a, Angle::kRightPronation), right.pronation_deg, 1e-6);
    for (const AngleValue& v : a) {
      EXPECT_TRUE(v.defined);
      EXPECT_FALSE(v.held);
      EXPECT_DOUBLE_EQ(v.confidence, 1.0);
    }
    EXPECT_EQ(a[static_cast<int>(Angle::kRightPronation)].source, AngleSource::kBodyModelAndImu);
    EXPECT_EQ(a[static_cast<int>(Angle::kRightElbowFlexion)].source, AngleSource::kBodyModel);
  }
}

// The built-in template posed through its own DOFs (SMPL T-pose: arms along x, palms down), facing
// the camera: the analytic poses.
struct TemplatePose {
  PosedUpperBody body;
  fit::JointPose joints;
};

TemplatePose pose_template(std::initializer_list<std::pair<const char*, double>> degrees) {
  static const auto model = body::make_template(body::Sex::kFemale);
  static const Eigen::Matrix3Xd rest = fit::rest_joints(*model, Eigen::VectorXd());
  const body::PoseLayout layout = body::PoseLayout::all_joints();
  Eigen::VectorXd theta = layout.zero();
  theta[layout.index_of("translation_z")] = 2.5;
  theta[layout.index_of("pelvis_y")] = std::numbers::pi;  // face the camera (K: z away from it)
  for (const auto& [name, d] : degrees) theta[layout.index_of(name)] += d * kRad;
  TemplatePose out;
  out.joints = fit::pose_joints(rest, layout, theta);
  out.body.smpl_joints_K = out.joints.positions_K;
  out.body.joint_confidence.fill(1.0);
  return out;
}

TEST(JointAngles, TemplateElbowAt90WithTheArmHanging) {
  // Right arm lowered from the T-pose to hang, elbow bent 90 degrees, forearm forward.
  const TemplatePose p = pose_template({{"right_shoulder_z", 90}, {"right_elbow_y", 90}});
  const JointAngles a = joint_angles(p.body);
  EXPECT_NEAR(deg(a, Angle::kRightElbowFlexion), 90, 0.5);
  EXPECT_NEAR(deg(a, Angle::kRightElevation), 0, 0.5);
  EXPECT_NEAR(deg(a, Angle::kRightHumerusAxialRotation), 0, 0.5);
  EXPECT_TRUE(a[static_cast<int>(Angle::kRightPlaneOfElevation)].held);  // gimbal lock at 0 elevation
  EXPECT_NEAR(deg(a, Angle::kThoraxFlexion), 0, 0.5);
  EXPECT_NEAR(deg(a, Angle::kThoraxLateralTilt), 0, 0.5);
  EXPECT_NEAR(deg(a, Angle::kThoraxAxialRotation), 0, 0.5);
  // The untouched left arm is in the T-pose: abducted 90 in the frontal plane, elbow straight.
  EXPECT_NEAR(deg(a, Angle::kLeftElevation), 90, 0.5);
  EXPECT_NEAR(deg(a, Angle::kLeftPlaneOfElevation), 0, 0.5);
  EXPECT_NEAR(deg(a, Angle::kLeftElbowFlexion), 0, 0.5);
  EXPECT_FALSE(defined(a, Angle::kLeftHumerusAxialRotation));  // straight elbow: no humerus plane
}

TEST(JointAngles, TemplateShoulderAbducted90InTheScapularPlane) {
  // 30 degrees forward of the frontal plane, elbow bent 90 with the forearm horizontal.
  const TemplatePose p = pose_template({{"right_shoulder_y", 30}, {"right_elbow_y", 90}});
  const JointAngles a = joint_angles(p.body);
  EXPECT_NEAR(deg(a, Angle::kRightPlaneOfElevation), 30, 0.5);
  EXPECT_NEAR(deg(a, Angle::kRightElevation), 90, 0.5);
  EXPECT_NEAR(deg(a, Angle::kRightHumerusAxialRotation), 0, 0.5);
  EXPECT_NEAR(deg(a, Angle::kRightElbowFlexion), 90, 0.5);
  // The same on the left (mirrored DOF signs) reads the same angles.
  const TemplatePose q = pose_template({{"left_shoulder_y", -30}, {"left_elbow_y", -90}});
  const JointAngles b = joint_angles(q.body);
  EXPECT_NEAR(deg(b, Angle::kLeftPlaneOfElevation), 30, 0.5);
  EXPECT_NEAR(deg(b, Angle::kLeftElevation), 90, 0.5);
  EXPECT_NEAR(deg(b, Angle::kLeftHumerusAxialRotation), 0, 0.5);
  EXPECT_NEAR(deg(b, Angle::kLeftElbowFlexion), 90, 0.5);
}

TEST(JointAngles, TemplateForearmPronated60) {
  const TemplatePose p = pose_template({{"right_shoulder_z", 90}, {"right_elbow_y", 90}});
  const auto& J = p.body.smpl_joints_K;
  // Neutral thumb up (towards the shoulder side); pronation turns the right thumb medially (to
  // the subject's left, K's -x for a subject facing the camera).
  const Eigen::Vector3d fore = (J.col(21) - J.col(19)).normalized();
  const Eigen::Vector3d thumb = Eigen::AngleAxisd(60 * kRad, -fore) * Eigen::Vector3d::UnitY();
  EXPECT_LT(thumb.x(), 0);  // medial
  const std::optional<double> pronation = pronation_rad(J.col(17), J.col(19), J.col(21), thumb, false, 15);
  ASSERT_TRUE(pronation.has_value());
  EXPECT_NEAR(*pronation / kRad, 60, 0.5);
}

TEST(JointAngles, GimbalLockHoldsThePlaneAndKeepsTheTurnAboutVertical) {
  const Eigen::Matrix3d K_from_G = Eigen::Matrix3d::Identity();
  ArmPose right{40, 60, 10, 90, 0, 0};
  const Built moving = build(K_from_G, 0, 0, 0, right, right);
  const JointAngles before = joint_angles(moving.body);
  ASSERT_NEAR(deg(before, Angle::kRightPlaneOfElevation), 40, 1e-6);

  // Arm down to 5 degrees: the plane is held at 40, the humerus' turn about the vertical (plane
  // + axial = 55) is kept whole.
  ArmPose low{15, 5, 40, 90, 0, 0};
  const Built locked = build(K_from_G, 0, 0, 0, low, low);
  const JointAngles a = joint_angles(locked.body, {}, &before);
  const AngleValue& plane = a[static_cast<int>(Angle::kRightPlaneOfElevation)];
  EXPECT_TRUE(plane.held);
  EXPECT_DOUBLE_EQ(plane.deg, 40);
  EXPECT_DOUBLE_EQ(plane.confidence, 0);
  EXPECT_NEAR(deg(a, Angle::kRightHumerusAxialRotation), 15, 1e-6);  // 15 + 40 - 40
  // That value depends on the plane held from an earlier frame, not on this pose: it claims nothing.
  EXPECT_DOUBLE_EQ(a[static_cast<int>(Angle::kRightHumerusAxialRotation)].confidence, 0);
  EXPECT_NEAR(deg(a, Angle::kRightElevation), 5, 1e-6);
  // Without a previous frame the plane is held at 0.
  const JointAngles first = joint_angles(locked.body);
  EXPECT_DOUBLE_EQ(first[static_cast<int>(Angle::kRightPlaneOfElevation)].deg, 0);
  EXPECT_NEAR(deg(first, Angle::kRightHumerusAxialRotation), 55, 1e-6);
}

TEST(JointAngles, StraightElbowLeavesAxialRotationAndPronationUndefined) {
  ArmPose straight{20, 70, 30, 5, 0, 0};
  Built b = build(Eigen::Matrix3d::Identity(), 0, 0, 0, straight, straight);
  b.body.right_pronation = PronationInput{0.3, 1.0};
  const JointAngles a = joint_angles(b.body);
  EXPECT_FALSE(defined(a, Angle::kRightHumerusAxialRotation));
  EXPECT_FALSE(defined(a, Angle::kRightPronation));
  EXPECT_DOUBLE_EQ(a[static_cast<int>(Angle::kRightPronation)].confidence, 0);
  EXPECT_NEAR(deg(a, Angle::kRightElevation), 70, 1e-6);
  EXPECT_NEAR(deg(a, Angle::kRightPlaneOfElevation), 20, 1e-6);
  const auto& J = b.body.smpl_joints_K;
  EXPECT_FALSE(pronation_rad(J.col(17), J.col(19), J.col(21), Eigen::Vector3d::UnitY(), false, 15).has_value());
}

TEST(JointAngles, ConfidenceFollowsTheJointsAndTheVertical) {
  Built b = build(Eigen::Matrix3d::Identity(), 0, 0, 0, ArmPose{0, 45, 0, 45, 0, 0}, ArmPose{0, 45, 0, 45, 0, 0});
  b.body.joint_confidence[21] = 0.5;  // right wrist inferred
  b.body.up_confidence = 0.5;         // vertical assumed
  JointAngleOptions exact_lengths;
  exact_lengths.arm_length_uncertainty = 0;  // the arm lengths' share has its own tests below
  const JointAngles a = joint_angles(b.body, exact_lengths);
  EXPECT_DOUBLE_EQ(a[static_cast<int>(Angle::kRightElbowFlexion)].confidence, 0.5);
  EXPECT_DOUBLE_EQ(a[static_cast<int>(Angle::kLeftElbowFlexion)].confidence, 1.0);
  EXPECT_DOUBLE_EQ(a[static_cast<int>(Angle::kThoraxFlexion)].confidence, 0.5);
  EXPECT_DOUBLE_EQ(a[static_cast<int>(Angle::kRightElevation)].confidence, tracked_elevation_confidence());
  // The smallest of the thorax's joints and the vertical, not their product: an inferred spine2
  // (0.5) under a floor measured to a fraction of a degree (0.99) stays at 0.5.
  b.body.joint_confidence[21] = 1.0;
  b.body.joint_confidence[6] = 0.5;  // spine2
  b.body.up_confidence = 0.99;
  const JointAngles measured = joint_angles(b.body, exact_lengths);
  EXPECT_DOUBLE_EQ(measured[static_cast<int>(Angle::kThoraxFlexion)].confidence, 0.5);
  b.body.joint_confidence[6] = 1.0;
  JointAngleOptions exact_joints = exact_lengths;
  exact_joints.joint_position_uncertainty_m = 0;  // the thorax's own spread has its own test below
  EXPECT_DOUBLE_EQ(joint_angles(b.body, exact_joints)[static_cast<int>(Angle::kThoraxLateralTilt)].confidence, 0.99);
}

// The thorax turns by about e / l (2 cm over the constructed skeleton's 0.25 m spine2 -> neck) about
// each axis; Z-X-Y passes that on to the lateral tilt as it is and to the flexion and the axial
// rotation over cos(tilt), whose first and third axes meet at 90 degrees of tilt.
TEST(JointAngles, ThoraxFlexionAndAxialRotationCarryTheirGimbalLock) {
  const double turn_rad = 0.02 / 0.25;
  const auto confidence = [](const JointAngles& a, Angle angle) { return a[static_cast<int>(angle)].confidence; };
  const JointAngles upright = joint_angles(
      build(Eigen::Matrix3d::Identity(), 10, 0, 20, ArmPose{0, 45, 0, 45, 0, 0}, ArmPose{0, 45, 0, 45, 0, 0}).body);
  for (const Angle angle : {Angle::kThoraxFlexion, Angle::kThoraxLateralTilt, Angle::kThoraxAxialRotation})
    EXPECT_NEAR(confidence(upright, angle), angle_confidence_from_rms_rad(turn_rad), 1e-12);
  EXPECT_GT(confidence(upright, Angle::kThoraxFlexion), 0.5);

  const Built tilted =
      build(Eigen::Matrix3d::Identity(), 10, 60, 20, ArmPose{0, 45, 0, 45, 0, 0}, ArmPose{0, 45, 0, 45, 0, 0});
  const JointAngles a = joint_angles(tilted.body);
  EXPECT_NEAR(deg(a, Angle::kThoraxFlexion), 10, 1e-6);
  EXPECT_NEAR(deg(a, Angle::kThoraxLateralTilt), 60, 1e-6);
  EXPECT_NEAR(deg(a, Angle::kThoraxAxialRotation), 20, 1e-6);
  EXPECT_NEAR(confidence(a, Angle::kThoraxLateralTilt), angle_confidence_from_rms_rad(turn_rad), 1e-12);
  for (const Angle angle : {Angle::kThoraxFlexion, Angle::kThoraxAxialRotation}) {
    EXPECT_NEAR(confidence(a, angle), angle_confidence_from_rms_rad(turn_rad / std::cos(60 * kRad)), 1e-12);
    EXPECT_LT(confidence(a, angle), 0.5);
  }
  // Exact joints: no spread to pass on, however tilted.
  const JointAngles exact = joint_angles(tilted.body, exact_joint_options({}));
  EXPECT_DOUBLE_EQ(confidence(exact, Angle::kThoraxFlexion), 1.0);
}

// The girdle elevation carries its own error (the collars have no camera joint): with every
// joint tracked it is below confidence 0.5 at the default 8.4 deg RMS (99 % bound 22 deg), at what
// the option allows, and as confident as its joints with exact joints.
TEST(JointAngles, GirdleElevationCarriesItsOwnError) {
  const Built b = build(Eigen::Matrix3d::Identity(), 0, 0, 0, ArmPose{0, 45, 0, 45, 0, 0}, ArmPose{0, 45, 0, 45, 0, 0});
  const auto girdle_confidence = [&](const JointAngleOptions& options) {
    return joint_angles(b.body, options)[static_cast<int>(Angle::kRightGirdleElevation)].confidence;
  };
  const double by_default = girdle_confidence({});
  EXPECT_LT(by_default, 0.5);
  EXPECT_DOUBLE_EQ(by_default, angle_confidence_from_rms_rad(8.4 * kRad));
  JointAngleOptions sharper;
  sharper.girdle_elevation_uncertainty_deg = 2.0;
  EXPECT_GT(girdle_confidence(sharper), 0.5);
  EXPECT_DOUBLE_EQ(girdle_confidence(exact_joint_options({})), 1.0);
  // The other arm angles do not take it.
  EXPECT_DOUBLE_EQ(joint_angles(b.body)[static_cast<int>(Angle::kRightElevation)].confidence,
                   tracked_elevation_confidence());
}

TEST(JointAngles, ElbowFlexionSpreadFollowsTheLawOfCosines) {
  const double a = 0.26, b = 0.23;
  const auto reach = [&](double flexion_deg) {
    return std::sqrt(a * a + b * b + 2 * a * b * std::cos(flexion_deg * kRad));
  };
  // Straight: segments 5 % too long bend to acos((d^2 - 1.05^2 (a^2 + b^2)) / (2 1.05^2 a b));
  // 5 % too short cannot reach and stay straight.
  const double longer = std::acos((reach(0) * reach(0) - 1.1025 * (a * a + b * b)) / (2 * 1.1025 * a * b));
  EXPECT_NEAR(elbow_flexion_spread_rad(a, b, reach(0), 0.05), longer, 1e-12);
  EXPECT_NEAR(longer / kRad, 35.6, 0.1);
  // At 90 degrees the change is nearly linear: about 6 degrees either way.
  EXPECT_NEAR(elbow_flexion_spread_rad(a, b, reach(90), 0.05) / kRad, 6.2, 0.1);
  EXPECT_DOUBLE_EQ(elbow_flexion_spread_rad(a, b, reach(40), 0.0), 0.0);
  // The sqrt-like growth near extension: 1 % already moves a straight arm by 16 degrees.
  EXPECT_NEAR(elbow_flexion_spread_rad(a, b, reach(0), 0.01) / kRad, 16.2, 0.1);
}

TEST(JointAngles, ElbowFlexionNearFullExtensionIsNotConfident) {
  Built straight = build(Eigen::Matrix3d::Identity(), 0, 0, 0, ArmPose{0, 30, 0, 3, 0, 0}, ArmPose{0, 30, 0, 3, 0, 0});
  Built bent = build(Eigen::Matrix3d::Identity(), 0, 0, 0, ArmPose{0, 30, 0, 90, 0, 0}, ArmPose{0, 30, 0, 90, 0, 0});
  const double straight_confidence =
      joint_angles(straight.body)[static_cast<int>(Angle::kRightElbowFlexion)].confidence;
  const double bent_confidence = joint_angles(bent.body)[static_cast<int>(Angle::kRightElbowFlexion)].confidence;
  EXPECT_LT(straight_confidence, 0.01);
  EXPECT_GT(bent_confidence, 0.3);
  EXPECT_GT(bent_confidence, straight_confidence);
  // Known arm lengths: both are as confident as their joints.
  JointAngleOptions exact_lengths;
  exact_lengths.arm_length_uncertainty = 0;
  EXPECT_DOUBLE_EQ(joint_angles(straight.body, exact_lengths)[static_cast<int>(Angle::kLeftElbowFlexion)].confidence,
                   1.0);
  // The angle itself does not change, only what it claims.
  EXPECT_DOUBLE_EQ(deg(joint_angles(bent.body, exact_lengths), Angle::kRightElbowFlexion),
                   deg(joint_angles(bent.body), Angle::kRightElbowFlexion));
  // The other arm angles do not take it.
  EXPECT_DOUBLE_EQ(joint_angles(straight.body)[static_cast<int>(Angle::kRightElevation)].confidence,
                   tracked_elevation_confidence());
}

TEST(JointAngles, AxialRotationNearAStraightElbowAndThePlaneNearItsLockAreNotConfident) {
  // 2 cm of joint error over a 25 cm forearm turns the arm's plane by 4.6 degrees / sin(flexion):
  // 13 degrees at 20 degrees of flexion, 4.6 at 90; the plane of elevation likewise with the
  // elevation.
  Built low = build(Eigen::Matrix3d::Identity(), 0, 0, 0, ArmPose{30, 20, 10, 20, 0, 0}, ArmPose{30, 20, 10, 20, 0, 0});
  Built high =
      build(Eigen::Matrix3d::Identity(), 0, 0, 0, ArmPose{30, 90, 10, 90, 0, 0}, ArmPose{30, 90, 10, 90, 0, 0});
  const JointAngles a_low = joint_angles(low.body), a_high = joint_angles(high.body);
  const auto confidence = [](const JointAngles& a, Angle angle) { return a[static_cast<int>(angle)].confidence; };
  EXPECT_LT(confidence(a_low, Angle::kRightHumerusAxialRotation), 0.5);
  EXPECT_GT(confidence(a_high, Angle::kRightHumerusAxialRotation), 0.5);
  EXPECT_LT(confidence(a_low, Angle::kRightPlaneOfElevation), 0.5);
  EXPECT_GT(confidence(a_high, Angle::kRightPlaneOfElevation), 0.5);
  EXPECT_LT(confidence(a_low, Angle::kLeftHumerusAxialRotation), 0.5);
  // Near the gimbal lock the axial rotation trades off against the plane of elevation: with the
  // elbow at 90 degrees it is confident with the arm horizontal, not at 25 degrees of elevation.
  Built near_lock =
      build(Eigen::Matrix3d::Identity(), 0, 0, 0, ArmPose{30, 25, 10, 90, 0, 0}, ArmPose{30, 25, 10, 90, 0, 0});
  EXPECT_LT(confidence(joint_angles(near_lock.body), Angle::kRightHumerusAxialRotation), 0.5);
  // The elevation's own spread does not depend on the elevation; the values do not change, only
  // what they claim; exact joints claim their own confidence.
  EXPECT_DOUBLE_EQ(confidence(a_low, Angle::kRightElevation), tracked_elevation_confidence());
  EXPECT_DOUBLE_EQ(confidence(a_high, Angle::kRightElevation), tracked_elevation_confidence());
  JointAngleOptions exact_joints;
  exact_joints.joint_position_uncertainty_m = 0;
  const JointAngles exact = joint_angles(low.body, exact_joints);
  EXPECT_DOUBLE_EQ(confidence(exact, Angle::kRightHumerusAxialRotation), 1.0);
  EXPECT_DOUBLE_EQ(confidence(exact, Angle::kRightPlaneOfElevation), 1.0);
  EXPECT_DOUBLE_EQ(confidence(exact, Angle::kRightElevation), 1.0);
  EXPECT_DOUBLE_EQ(deg(exact, Angle::kRightHumerusAxialRotation), deg(a_low, Angle::kRightHumerusAxialRotation));
  EXPECT_DOUBLE_EQ(deg(exact, Angle::kRightPlaneOfElevation), deg(a_low, Angle::kRightPlaneOfElevation));
}

// The humerothoracic angles are read in the thorax frame: the thorax's error adds to their own in
// quadrature. An inferred spine2 (thorax confidence 0.5, a 15 degree bound) takes all three below
// 0.5, where the smallest of the two confidences kept them at 0.5 while claiming only one of the
// errors.
TEST(JointAngles, AnglesInTheThoraxFrameAddTheThoraxError) {
  Built b = build(Eigen::Matrix3d::Identity(), 0, 0, 0, ArmPose{30, 90, 10, 90, 0, 0}, ArmPose{30, 90, 10, 90, 0, 0});
  const auto confidence = [](const JointAngles& a, Angle angle) { return a[static_cast<int>(angle)].confidence; };
  const JointAngles tracked = joint_angles(b.body);
  ASSERT_GT(confidence(tracked, Angle::kRightPlaneOfElevation), 0.5);
  ASSERT_GT(confidence(tracked, Angle::kRightHumerusAxialRotation), 0.5);
  ASSERT_GT(confidence(tracked, Angle::kRightElevation), 0.5);
  b.body.joint_confidence[6] = 0.5;  // spine2 inferred
  const JointAngles inferred = joint_angles(b.body);
  for (const Angle angle : {Angle::kRightPlaneOfElevation, Angle::kRightHumerusAxialRotation, Angle::kRightElevation,
                            Angle::kLeftPlaneOfElevation, Angle::kLeftHumerusAxialRotation, Angle::kLeftElevation}) {
    SCOPED_TRACE(std::string(angle_name(angle)));
    const double own_rms = angle_rms_rad_from_confidence(confidence(tracked, angle));
    EXPECT_LT(confidence(inferred, angle), 0.5);
    EXPECT_NEAR(confidence(inferred, angle),
                angle_confidence_from_rms_rad(std::hypot(angle_rms_rad_from_confidence(0.5), own_rms)), 1e-12);
    EXPECT_DOUBLE_EQ(deg(inferred, angle), deg(tracked, angle));  // only the claim changes
  }
  // Exact joints have no error of their own: the thorax's alone.
  JointAngleOptions exact_joints;
  exact_joints.joint_position_uncertainty_m = 0;
  EXPECT_NEAR(confidence(joint_angles(b.body, exact_joints), Angle::kRightPlaneOfElevation), 0.5, 1e-12);
  EXPECT_NEAR(confidence(joint_angles(b.body, exact_joints), Angle::kRightElevation), 0.5, 1e-12);
}

TEST(JointAngles, AngleConfidenceIsHalfWhereThe99PercentBoundReaches15Degrees) {
  EXPECT_DOUBLE_EQ(angle_confidence_from_rms_rad(0), 1.0);
  EXPECT_NEAR(angle_confidence_from_rms_rad(15 * kRad / 2.576), 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(angle_confidence_from_rms_rad(std::nan("")), 0.0);
  EXPECT_DOUBLE_EQ(angle_confidence_from_rms_rad(-1), 0.0);
  // and back
  EXPECT_DOUBLE_EQ(angle_rms_rad_from_confidence(1.0), 0.0);
  EXPECT_NEAR(angle_rms_rad_from_confidence(0.5), 15 * kRad / 2.576, 1e-12);
  for (const double rms_deg : {0.5, 3.0, 5.8, 12.0})
    EXPECT_NEAR(angle_rms_rad_from_confidence(angle_confidence_from_rms_rad(rms_deg * kRad)), rms_deg * kRad, 1e-9);
  EXPECT_TRUE(std::isinf(angle_rms_rad_from_confidence(0.0)));
  EXPECT_TRUE(std::isinf(angle_rms_rad_from_confidence(std::nan(""))));
}

TEST(JointAngles, BadInputNamesTheField) {
  Built b = build(Eigen::Matrix3d::Identity(), 0, 0, 0, ArmPose{0, 45, 0, 45, 0, 0}, ArmPose{0, 45, 0, 45, 0, 0});
  const auto field_of = [](const PosedUpperBody& body, const JointAngleOptions& options = {}) {
    try {
      joint_angles(body, options);
    } catch (const Error& e) {
      return e.field();
    }
    return std::string("no error");
  };
  PosedUpperBody short_body = b.body;
  short_body.smpl_joints_K.conservativeResize(3, 23);
  EXPECT_EQ(field_of(short_body), "smpl_joints_K");
  PosedUpperBody nan_body = b.body;
  nan_body.smpl_joints_K(0, 19) = std::nan("");
  EXPECT_EQ(field_of(nan_body), "smpl_joints_K");
  PosedUpperBody flat = b.body;
  flat.front_K = flat.up_K;
  EXPECT_EQ(field_of(flat), "front_K");
  PosedUpperBody zero_up = b.body;
  zero_up.up_K.setZero();
  EXPECT_EQ(field_of(zero_up), "up_K");
  PosedUpperBody collapsed = b.body;
  collapsed.smpl_joints_K.col(19) = collapsed.smpl_joints_K.col(17);
  EXPECT_EQ(field_of(collapsed), "smpl_joints_K");
  JointAngleOptions bad;
  bad.min_elevation_for_plane_deg = 0;
  EXPECT_EQ(field_of(b.body, bad), "joint_angle_options.min_elevation_for_plane_deg");
  JointAngleOptions bad_lengths;
  bad_lengths.arm_length_uncertainty = 0.5;
  EXPECT_EQ(field_of(b.body, bad_lengths), "joint_angle_options.arm_length_uncertainty");
  bad_lengths.arm_length_uncertainty = std::nan("");
  EXPECT_EQ(field_of(b.body, bad_lengths), "joint_angle_options.arm_length_uncertainty");
  JointAngleOptions bad_positions;
  bad_positions.joint_position_uncertainty_m = -0.01;
  EXPECT_EQ(field_of(b.body, bad_positions), "joint_angle_options.joint_position_uncertainty_m");
  bad_positions.joint_position_uncertainty_m = std::nan("");
  EXPECT_EQ(field_of(b.body, bad_positions), "joint_angle_options.joint_position_uncertainty_m");
  JointAngleOptions bad_girdle;
  bad_girdle.girdle_elevation_uncertainty_deg = -1;
  EXPECT_EQ(field_of(b.body, bad_girdle), "joint_angle_options.girdle_elevation_uncertainty_deg");
}

TEST(JointAngles, NamesAreUniqueSnakeCase) {
  std::set<std::string> names;
  for (int i = 0; i < kAngleCount; ++i) {
    const std::string name(angle_name(static_cast<Angle>(i)));
    EXPECT_EQ(name.find_first_not_of("abcdefghijklmnopqrstuvwxyz_"), std::string::npos) << name;
    names.insert(name);
  }
  EXPECT_EQ(names.size(), static_cast<size_t>(kAngleCount));
}

}  // namespace
}  // namespace posefuse::measures
