#pragma once
// ISB joint angles (Wu et al. 2005, J Biomech 38:981) of one posed upper body: thorax relative to
// vertical, humerothoracic Y-X-Y per arm, elbow flexion, forearm pronation / supination relative
// to the humerus, shoulder girdle elevation. docs/measures.md, "Joint angles" gives every
// segment frame's construction (with a figure), the zero and sign of every angle and how the
// Y-X-Y gimbal lock is handled.
//
// The segment frames come from the 24 SMPL joints alone: the body model has no roll DOF in the
// arms (docs/fitting.md), so the humerus' axial rotation is read from the plane of the upper arm
// and the forearm (ISB's second humerus frame), and pronation from the wrist IMU's thumb axis.
// Where the geometry cannot give an angle (elbow nearly straight: no plane; arm nearly down: no
// plane of elevation) the angle is marked undefined or held, with confidence 0, never guessed.
#include <Eigen/Core>
#include <array>
#include <optional>
#include <string_view>

namespace posefuse::measures {

enum class Angle : int {
  kThoraxFlexion,        // forward flexion +, about the thorax's lateral axis (ISB Z-X-Y, 1st)
  kThoraxLateralTilt,    // to the right +                                          (2nd)
  kThoraxAxialRotation,  // to the left +                                           (3rd)
  kLeftPlaneOfElevation,
  kLeftElevation,
  kLeftHumerusAxialRotation,
  kLeftElbowFlexion,
  kLeftPronation,
  kLeftGirdleElevation,
  kRightPlaneOfElevation,      // humerothoracic Y-X-Y 1st: 0 abduction, 90 forward flexion
  kRightElevation,             // 2nd, as a positive angle: 0 arm down, 90 horizontal, 180 overhead
  kRightHumerusAxialRotation,  // 3rd: internal rotation +
  kRightElbowFlexion,          // 0 straight
  kRightPronation,             // 0 neutral (thumb to the shoulder side), pronation +
  kRightGirdleElevation,       // clavicle line above the thorax's transverse plane, elevation +
  kCount
};
inline constexpr int kAngleCount = static_cast<int>(Angle::kCount);

// Stable snake_case names (CSV columns, proto enum names), e.g. "right_elbow_flexion".
std::string_view angle_name(Angle angle);

// Where an angle's inputs came from.
enum class AngleSource { kNone, kBodyModel, kBodyModelAndImu };

struct AngleValue {
  double deg = 0.0;
  bool defined = false;     // false: the geometry gives no value (deg is meaningless)
  bool held = false;        // the plane of elevation kept from the last frame (gimbal lock)
  double confidence = 0.0;  // 0..1
  AngleSource source = AngleSource::kNone;
};

using JointAngles = std::array<AngleValue, kAngleCount>;

// A value at or above this confidence is one to act on: the bound of a confident forearm sample
// (docs/forearm.md), used by the report's plots and posefuse-score's confident errors.
inline constexpr double kConfidentAt = 0.5;

// One arm's pronation from the forearm IMU (fit/arm_roll.hpp) with its confidence.
struct PronationInput {
  double rad = 0.0;
  double confidence = 0.0;
};

struct PosedUpperBody {
  Eigen::Matrix3Xd smpl_joints_K;                   // 3 x 24, SMPL order
  std::array<double, 24> joint_confidence{};        // 0..1 per SMPL joint
  Eigen::Vector3d up_K = Eigen::Vector3d::UnitY();  // against gravity, in K
  double up_confidence = 1.0;                       // the vertical's; the thorax angles' is at most this
  // The subject's reference front: the horizontal direction the thorax's axial rotation is
  // measured from. Default: facing the camera (K's -z).
  Eigen::Vector3d front_K = -Eigen::Vector3d::UnitZ();
  std::optional<PronationInput> left_pronation, right_pronation;
};

struct JointAngleOptions {
  // Below this elbow flexion the upper arm and forearm span no plane: no humerus axial rotation
  // (and no pronation, fit/arm_roll.hpp uses the same bound).
  double min_elbow_flexion_deg = 15.0;
  // Below this elevation (or above 180 minus it) the Y-X-Y plane of elevation is gimbal locked:
  // it is held at its last defined value and the axial rotation takes the whole turn about y (at
  // confidence 0: that value depends on the held plane, not on the pose).
  double min_elevation_for_plane_deg = 15.0;
  // Relative RMS error of the fitted arms' segment lengths. Near full extension the elbow
  // flexion of a fit is set by them more than by the image: at the same shoulder-wrist distance
  // an arm 1 % too long must bend about 16 degrees (law of cosines), one too short stays
  // straight. The flexion's confidence carries the spread this error gives
  // (elbow_flexion_spread_rad). 0.057: the RMS error of a personalised shape's upper arms and
  // forearms over 336 simulated subjects (bench_fig4 seed bases 0-55); the template's measured
  // 4.6 % there, so one value serves both (docs/measures.md, "Elbow flexion near full extension").
  double arm_length_uncertainty = 0.057;
  // RMS error of a fitted joint's position, m. An angle read from a segment's direction (the
  // elevation) turns by about this over the segment's length, and one read from a plane of two
  // segments by that over the sine of their angle: the humerus' axial rotation (the upper arm and
  // forearm's plane) near a straight elbow, the plane of elevation near the gimbal lock. Their
  // confidence carries that spread, and the thorax's error in quadrature. The thorax angles take
  // it over spine2 -> neck, the flexion and axial rotation over the cosine of the lateral tilt
  // (Z-X-Y's gimbal lock at 90 degrees of tilt). 0.02: the body fit's
  // mean error on the arm joints at 30 Hz (20.5 mm, docs/benchmarks.md, "Paper 2, Fig. 4"), not
  // chosen on the sessions the angles are reported on.
  double joint_position_uncertainty_m = 0.02;
  // RMS error of the fitted girdle elevation, degrees; its confidence is at most what this allows.
  // The collars have no camera joint (docs/fitting.md, "Joint confidence"): the model's shape and
  // the surface around the shoulders place them, and over a clavicle of about 9 cm a joint error
  // of a centimetre or two turns the line by 6-13 degrees. 8.4: the girdle elevation's RMS error
  // on the joint-angle bench's design sessions (seeds 61 and 62), checked on later seeds
  // (docs/benchmarks.md, "The girdle elevation's own error").
  double girdle_elevation_uncertainty_deg = 8.4;
};

// `options` for exact joints (a simulator's truth, a skeleton built from known angles): no fit
// uncertainty lowers any angle's confidence.
JointAngleOptions exact_joint_options(JointAngleOptions options);

// The global frame G of the thorax angles (and of the OpenSim exports' ground): y along up_K,
// x the part of front_K perpendicular to it, z = x cross y (to the subject's right). The caller
// checks that the two are not parallel (joint_angles does, naming them).
Eigen::Matrix3d K_from_G(const Eigen::Vector3d& up_K, const Eigen::Vector3d& front_K);

// `previous`: the last frame's angles of the same session (for the held plane of elevation), or
// null. Throws posefuse::Error (kInvalidArgument) "smpl_joints_K" for a wrong size or non-finite
// joints, "up_K" / "front_K" for zero, non-finite or parallel references, "joint_angle_options.*".
JointAngles joint_angles(const PosedUpperBody& body, const JointAngleOptions& options = {},
                         const JointAngles* previous = nullptr);

// How far an elbow flexion moves when both arm segments (upper_arm_m, forearm_m) are
// `relative_length_error` longer or shorter at the same shoulder-wrist distance `reach_m`: the
// larger of the two changes, rad. An arm that cannot reach bends to 0; one that is too long bends
// as reach^2 = a^2 + b^2 + 2 a b cos(flexion) requires.
double elbow_flexion_spread_rad(double upper_arm_m, double forearm_m, double reach_m, double relative_length_error);

// Confidence of an angle from its 1-sigma error, rad: 0.5 where the 99 % bound of a normal error
// (2.576 sigma) reaches 15 degrees, the bound of a confident forearm sample (docs/forearm.md).
double angle_confidence_from_rms_rad(double rms_rad);
// Its inverse: the 1-sigma error a confidence allows at most, rad (0 at 1, infinite at 0).
double angle_rms_rad_from_confidence(double confidence);

// The thorax frame's confidence: the smallest of the joints it is built from (spine2, the neck
// and the collars). The thorax angles take it, and the humerothoracic ones its error.
double thorax_joint_confidence(const PosedUpperBody& body);

// Pronation (+) / supination (-) of a forearm from the neutral position, in which the thumb
// points to the shoulder side of the elbow's flexion plane (thumb up with the upper arm hanging
// and the elbow bent 90 degrees); nullopt where the elbow is straighter than
// `min_elbow_flexion_deg` (no flexion plane). `thumb_K`: the forearm's radial (thumb) direction.
std::optional<double> pronation_rad(const Eigen::Vector3d& shoulder_K, const Eigen::Vector3d& elbow_K,
                                    const Eigen::Vector3d& wrist_K, const Eigen::Vector3d& thumb_K, bool left_arm,
                                    double min_elbow_flexion_deg);

}  // namespace posefuse::measures
