#include "measures/joint_angles.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "common/error.hpp"
#include "forearm/orientation_uncertainty.hpp"
#include "geometry/axis_angles.hpp"

namespace posefuse::measures {
namespace {

// SMPL joint order (body/smpl_model.hpp); measures sits below body in the layers, so the few
// indices it reads are named here.
constexpr int kSpine2 = 6, kNeck = 12, kLeftCollar = 13, kRightCollar = 14, kLeftShoulder = 16, kRightShoulder = 17,
              kLeftElbow = 18, kRightElbow = 19, kLeftWrist = 20, kRightWrist = 21;

constexpr double kDegPerRad = 180.0 / std::numbers::pi;
constexpr double kBound99OverRms = 2.576;  // two-sided 99 % of a normal error

using geometry::angle_between;
using geometry::perpendicular;
using geometry::signed_angle;

AngleValue defined_value(double rad, double confidence, AngleSource source = AngleSource::kBodyModel) {
  return AngleValue{rad * kDegPerRad, true, false, confidence, source};
}

// A right-handed frame whose columns are x, y, z; `y` and `z_hint` need not be orthogonal.
Eigen::Matrix3d frame_from_y_and_z(const Eigen::Vector3d& y, const Eigen::Vector3d& z_hint) {
  Eigen::Matrix3d frame;
  frame.col(1) = y.normalized();
  frame.col(2) = perpendicular(z_hint, frame.col(1));
  frame.col(0) = frame.col(1).cross(frame.col(2));
  return frame;
}

struct Thorax {
  Eigen::Matrix3d K_from_T;  // ISB thorax: x forward, y up (spine2 -> neck), z to the right
  double confidence = 0.0;
};

}  // namespace

Eigen::Matrix3d K_from_G(const Eigen::Vector3d& up_K, const Eigen::Vector3d& front_K) {
  const Eigen::Vector3d up = up_K.normalized();
  Eigen::Matrix3d axes;  // columns: G's x, y, z in K
  axes.col(0) = perpendicular(front_K, up);
  axes.col(1) = up;
  axes.col(2) = axes.col(0).cross(up);
  return axes;
}

namespace {

Thorax thorax_frame(const PosedUpperBody& body) {
  const auto& J = body.smpl_joints_K;
  const Eigen::Vector3d up = J.col(kNeck) - J.col(kSpine2);
  const Eigen::Vector3d right = J.col(kRightCollar) - J.col(kLeftCollar);
  if (up.norm() < 1e-6 || right.norm() < 1e-6 || perpendicular(right, up.normalized()).isZero())
    throw_invalid("smpl_joints_K", "spine2, neck and the collars span no thorax frame");
  return {frame_from_y_and_z(up, right), thorax_joint_confidence(body)};
}

void thorax_angles(const PosedUpperBody& body, const Thorax& thorax, const JointAngleOptions& options,
                   JointAngles& out) {
  const Eigen::Matrix3d R = K_from_G(body.up_K, body.front_K).transpose() * thorax.K_from_T;
  // ISB Z-X-Y: R = Rz(a) Rx(b) Ry(c).
  const double a = std::atan2(-R(0, 1), R(1, 1));
  const double b = std::asin(std::clamp(R(2, 1), -1.0, 1.0));
  const double c = std::atan2(-R(2, 0), R(2, 2));
  // The smallest, as for every angle's joints: each bounds how far the angle can be trusted.
  const double confidence = std::min(thorax.confidence, std::clamp(body.up_confidence, 0.0, 1.0));
  // A joint position error e turns the thorax by about e / l about each axis (l: spine2 -> neck).
  // Z-X-Y passes that on to the lateral tilt as it is and to the flexion and the axial rotation
  // over cos(b): tilted towards 90 degrees the first and third axes meet (gimbal lock) and only
  // their sum is defined (docs/measures.md, "Gimbal lock of the thorax's Z-X-Y").
  const auto& J = body.smpl_joints_K;
  const double turn_rad = options.joint_position_uncertainty_m / (J.col(kNeck) - J.col(kSpine2)).norm();
  const double cos_tilt = std::cos(b);
  const double locked_turn_rad = cos_tilt > 0 ? turn_rad / cos_tilt : std::numbers::pi;
  const double tilt_confidence = std::min(confidence, angle_confidence_from_rms_rad(turn_rad));
  const double locked_confidence = std::min(confidence, angle_confidence_from_rms_rad(locked_turn_rad));
  out[static_cast<int>(Angle::kThoraxFlexion)] = defined_value(-a, locked_confidence);  // +Z turns y backwards
  out[static_cast<int>(Angle::kThoraxLateralTilt)] = defined_value(b, tilt_confidence);
  out[static_cast<int>(Angle::kThoraxAxialRotation)] = defined_value(c, locked_confidence);
}

struct ArmAngleIds {
  Angle plane, elevation, axial, elbow, pronation, girdle;
};

ArmAngleIds arm_ids(bool left) {
  if (left)
    return {Angle::kLeftPlaneOfElevation, Angle::kLeftElevation, Angle::kLeftHumerusAxialRotation,
            Angle::kLeftElbowFlexion,     Angle::kLeftPronation, Angle::kLeftGirdleElevation};
  return {Angle::kRightPlaneOfElevation, Angle::kRightElevation, Angle::kRightHumerusAxialRotation,
          Angle::kRightElbowFlexion,     Angle::kRightPronation, Angle::kRightGirdleElevation};
}

void arm_angles(const PosedUpperBody& body, const Thorax& thorax, bool left, const JointAngleOptions& options,
                const JointAngles* previous, JointAngles& out) {
  const auto& J = body.smpl_joints_K;
  const auto& c = body.joint_confidence;
  const int collar = left ? kLeftCollar : kRightCollar, shoulder = left ? kLeftShoulder : kRightShoulder;
  const int elbow = left ? kLeftElbow : kRightElbow, wrist = left ? kLeftWrist : kRightWrist;
  const ArmAngleIds id = arm_ids(left);
  const Eigen::Vector3d z_t = thorax.K_from_T.col(2);
  // ISB defines the right side; the left arm is mirrored through the thorax's sagittal plane so
  // that every sign means the same anatomical motion on both sides.
  const auto mirrored = [&](const Eigen::Vector3d& d) -> Eigen::Vector3d {
    return left ? Eigen::Vector3d(d - 2.0 * d.dot(z_t) * z_t) : d;
  };
  const Eigen::Vector3d upper = mirrored(J.col(elbow) - J.col(shoulder));
  const Eigen::Vector3d fore = mirrored(J.col(wrist) - J.col(elbow));
  const Eigen::Vector3d clavicle = mirrored(J.col(shoulder) - J.col(collar));
  if (upper.norm() < 1e-6 || fore.norm() < 1e-6 || clavicle.norm() < 1e-6)
    throw_invalid("smpl_joints_K", std::string(left ? "left" : "right") + " arm joints coincide");

  const double girdle_confidence =
      std::min({thorax.confidence, c[collar], c[shoulder],
                angle_confidence_from_rms_rad(options.girdle_elevation_uncertainty_deg / kDegPerRad)});
  out[static_cast<int>(id.girdle)] = defined_value(
      std::asin(std::clamp(clavicle.normalized().dot(thorax.K_from_T.col(1)), -1.0, 1.0)), girdle_confidence);

  const double flexion = angle_between(upper, fore);
  const double flexion_spread =
      elbow_flexion_spread_rad(upper.norm(), fore.norm(), (upper + fore).norm(), options.arm_length_uncertainty);
  const double elbow_confidence =
      std::min({c[shoulder], c[elbow], c[wrist], angle_confidence_from_rms_rad(flexion_spread)});
  out[static_cast<int>(id.elbow)] = defined_value(flexion, elbow_confidence);

  // Humerus, ISB's second frame: y from the elbow to the shoulder, z perpendicular to the plane
  // of the upper arm and the forearm (to the right), x forward.
  const Eigen::Vector3d y_h = -upper.normalized();
  const Eigen::Vector3d y_f = -fore.normalized();
  const bool has_plane = flexion >= options.min_elbow_flexion_deg / kDegPerRad;
  const double humerus_confidence = std::min({thorax.confidence, c[shoulder], c[elbow]});

  // Thorax -> humerus, Y-X-Y: R = Ry(a) Rx(b) Ry(c) with b = -elevation. The elevation and the
  // plane need only y_h (R's middle column); the axial rotation needs the humerus' plane.
  const Eigen::Vector3d y_in_T = thorax.K_from_T.transpose() * y_h;
  const double elevation = std::acos(std::clamp(y_in_T.y(), -1.0, 1.0));
  // A joint position error e turns a segment of length l by about e / l (the elevation's own
  // spread); an angle about an axis that a second direction makes with it by that over the sine
  // of their angle (JointAngleOptions::joint_position_uncertainty_m).
  const auto direction_spread_rad = [&](double segment_m) { return options.joint_position_uncertainty_m / segment_m; };
  const auto plane_spread_rad = [&](double segment_m, double angle_rad) {
    const double s = std::sin(angle_rad);
    return s > 0 ? direction_spread_rad(segment_m) / s : std::numbers::pi;
  };
  // These angles are read in the thorax frame, so its own error (at most what its confidence
  // allows) is theirs too; independent errors add in quadrature, a smallest confidence would
  // claim either error alone.
  const double thorax_rms = angle_rms_rad_from_confidence(thorax.confidence);
  const auto with_thorax_confidence = [&](double own_rms_rad) {
    return angle_confidence_from_rms_rad(std::hypot(thorax_rms, own_rms_rad));
  };
  const double plane_confidence =
      std::min(humerus_confidence, with_thorax_confidence(plane_spread_rad(upper.norm(), elevation)));
  const double elevation_confidence =
      std::min(humerus_confidence, with_thorax_confidence(direction_spread_rad(upper.norm())));
  out[static_cast<int>(id.elevation)] = defined_value(elevation, elevation_confidence);
  const double plane = std::atan2(-y_in_T.x(), -y_in_T.z());
  const double lock = options.min_elevation_for_plane_deg / kDegPerRad;
  const bool plane_locked = elevation < lock || elevation > std::numbers::pi - lock;

  AngleValue& plane_out = out[static_cast<int>(id.plane)];
  if (!plane_locked) {
    plane_out = defined_value(plane, plane_confidence);
  } else {
    const AngleValue* last = previous ? &(*previous)[static_cast<int>(id.plane)] : nullptr;
    plane_out = AngleValue{last && last->defined ? last->deg : 0.0, true, true, 0.0, AngleSource::kBodyModel};
  }

  AngleValue& axial_out = out[static_cast<int>(id.axial)];
  if (!has_plane) {
    axial_out = AngleValue{};
  } else {
    Eigen::Matrix3d K_from_H;
    K_from_H.col(1) = y_h;
    K_from_H.col(2) = y_h.cross(y_f).normalized();
    K_from_H.col(0) = K_from_H.col(1).cross(K_from_H.col(2));
    const Eigen::Matrix3d R = thorax.K_from_T.transpose() * K_from_H;
    double axial = std::atan2(-R(1, 0), R(1, 2));
    if (plane_locked) {
      // Only a + c (near 0 elevation) or c - a (near 180) is defined: keep that sum with the
      // held plane so the humerus' turn about the vertical stays whole.
      const double held = plane_out.deg / kDegPerRad;
      axial = elevation < lock ? plane + axial - held : axial - plane + held;
      axial = std::remainder(axial, 2.0 * std::numbers::pi);
    }
    // Near the lock the plane of elevation and the axial rotation trade off (only their sum is
    // well conditioned): tilting the humerus moves the plane by the tilt over sin(elevation) and
    // the axial rotation by cos(elevation) times that. In the lock the value depends on which
    // plane was held, i.e. on the session's history, not on this pose: it claims nothing.
    const double tilt_spread = plane_spread_rad(upper.norm(), elevation) * std::abs(std::cos(elevation));
    const double axial_spread = std::hypot(plane_spread_rad(fore.norm(), flexion), tilt_spread);
    const double axial_confidence =
        plane_locked ? 0.0 : std::min({humerus_confidence, c[wrist], with_thorax_confidence(axial_spread)});
    axial_out = defined_value(axial, axial_confidence);
  }

  const auto& pronation = left ? body.left_pronation : body.right_pronation;
  AngleValue& pronation_out = out[static_cast<int>(id.pronation)];
  if (pronation && has_plane && std::isfinite(pronation->rad))
    pronation_out =
        defined_value(pronation->rad, std::clamp(pronation->confidence, 0.0, 1.0), AngleSource::kBodyModelAndImu);
  else pronation_out = AngleValue{};
}

void check_reference(const Eigen::Vector3d& v, const char* field) {
  if (!v.allFinite() || v.norm() < 1e-9) throw_invalid(field, "must be a finite non-zero vector");
}

}  // namespace

std::string_view angle_name(Angle angle) {
  switch (angle) {
    case Angle::kThoraxFlexion: return "thorax_flexion";
    case Angle::kThoraxLateralTilt: return "thorax_lateral_tilt";
    case Angle::kThoraxAxialRotation: return "thorax_axial_rotation";
    case Angle::kLeftPlaneOfElevation: return "left_plane_of_elevation";
    case Angle::kLeftElevation: return "left_elevation";
    case Angle::kLeftHumerusAxialRotation: return "left_humerus_axial_rotation";
    case Angle::kLeftElbowFlexion: return "left_elbow_flexion";
    case Angle::kLeftPronation: return "left_pronation";
    case Angle::kLeftGirdleElevation: return "left_girdle_elevation";
    case Angle::kRightPlaneOfElevation: return "right_plane_of_elevation";
    case Angle::kRightElevation: return "right_elevation";
    case Angle::kRightHumerusAxialRotation: return "right_humerus_axial_rotation";
    case Angle::kRightElbowFlexion: return "right_elbow_flexion";
    case Angle::kRightPronation: return "right_pronation";
    case Angle::kRightGirdleElevation: return "right_girdle_elevation";
    case Angle::kCount: break;
  }
  return "unknown";
}

double elbow_flexion_spread_rad(double upper_arm_m, double forearm_m, double reach_m, double relative_length_error) {
  const auto flexion = [&](double scale) {
    const double a = scale * upper_arm_m, b = scale * forearm_m;
    return std::acos(std::clamp((reach_m * reach_m - a * a - b * b) / (2 * a * b), -1.0, 1.0));
  };
  const double fitted = flexion(1.0);
  return std::max(std::abs(flexion(1.0 + relative_length_error) - fitted),
                  std::abs(flexion(1.0 - relative_length_error) - fitted));
}

JointAngleOptions exact_joint_options(JointAngleOptions options) {
  options.arm_length_uncertainty = 0.0;
  options.joint_position_uncertainty_m = 0.0;
  options.girdle_elevation_uncertainty_deg = 0.0;
  return options;
}

double angle_confidence_from_rms_rad(double rms_rad) {
  return forearm::confidence_from_bound99_rad(kBound99OverRms * rms_rad);
}

double angle_rms_rad_from_confidence(double confidence) {
  return forearm::bound99_rad_from_confidence(confidence) / kBound99OverRms;
}

double thorax_joint_confidence(const PosedUpperBody& body) {
  const auto& c = body.joint_confidence;
  return std::min({c[kSpine2], c[kNeck], c[kLeftCollar], c[kRightCollar]});
}

JointAngles joint_angles(const PosedUpperBody& body, const JointAngleOptions& options, const JointAngles* previous) {
  if (body.smpl_joints_K.cols() != 24 || !body.smpl_joints_K.allFinite())
    throw_invalid("smpl_joints_K", "needs 24 finite joints, got " + std::to_string(body.smpl_joints_K.cols()));
  check_reference(body.up_K, "up_K");
  check_reference(body.front_K, "front_K");
  if (perpendicular(body.front_K, body.up_K.normalized()).isZero())
    throw_invalid("front_K", "lies along up_K: no horizontal front");
  if (!(options.min_elbow_flexion_deg >= 0 && options.min_elbow_flexion_deg < 90))
    throw_invalid("joint_angle_options.min_elbow_flexion_deg", "must be in [0, 90)");
  if (!(options.min_elevation_for_plane_deg > 0 && options.min_elevation_for_plane_deg < 90))
    throw_invalid("joint_angle_options.min_elevation_for_plane_deg", "must be in (0, 90)");
  if (!(options.arm_length_uncertainty >= 0 && options.arm_length_uncertainty < 0.5))
    throw_invalid("joint_angle_options.arm_length_uncertainty", "must be in [0, 0.5)");
  if (!(options.joint_position_uncertainty_m >= 0 && options.joint_position_uncertainty_m <= 0.2))
    throw_invalid("joint_angle_options.joint_position_uncertainty_m", "must be in [0, 0.2]");
  if (!(options.girdle_elevation_uncertainty_deg >= 0 && options.girdle_elevation_uncertainty_deg <= 90))
    throw_invalid("joint_angle_options.girdle_elevation_uncertainty_deg", "must be in [0, 90]");

  JointAngles out{};
  const Thorax thorax = thorax_frame(body);
  thorax_angles(body, thorax, options, out);
  arm_angles(body, thorax, true, options, previous, out);
  arm_angles(body, thorax, false, options, previous, out);
  return out;
}

std::optional<double> pronation_rad(const Eigen::Vector3d& shoulder_K, const Eigen::Vector3d& elbow_K,
                                    const Eigen::Vector3d& wrist_K, const Eigen::Vector3d& thumb_K, bool left_arm,
                                    double min_elbow_flexion_deg) {
  const Eigen::Vector3d forearm = wrist_K - elbow_K, upper = elbow_K - shoulder_K;
  if (forearm.norm() < 1e-6 || upper.norm() < 1e-6) return std::nullopt;
  const Eigen::Vector3d a = forearm.normalized();
  if (angle_between(upper, a) < min_elbow_flexion_deg / kDegPerRad) return std::nullopt;
  const Eigen::Vector3d neutral_thumb = perpendicular(-upper, a);
  const Eigen::Vector3d thumb = perpendicular(thumb_K, a);
  if (thumb.isZero()) return std::nullopt;
  // A positive turn about the forearm axis moves the left thumb medially (pronation) and the
  // right thumb laterally (supination).
  return (left_arm ? 1.0 : -1.0) * signed_angle(neutral_thumb, thumb, a);
}

}  // namespace posefuse::measures
