#include "session/stages/measures_stage.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "common/error.hpp"
#include "fit/arm_roll.hpp"
#include "session/stages/body_fit_options.hpp"
#include "session/stages/proto_values.hpp"
#include "session/text_fields.hpp"

namespace posefuse::session {
namespace {

// An arm's SMPL joints.
struct ArmJoints {
  int shoulder, elbow, wrist;
};
ArmJoints arm_joints(bool left) { return left ? ArmJoints{16, 18, 20} : ArmJoints{17, 19, 21}; }

std::optional<measures::PronationInput> pronation_of(const FrameEstimate& frame, v1::Arm arm, double min_flexion_deg) {
  const bool left = arm == v1::LEFT;
  for (const ForearmEstimate& forearm : frame.forearms) {
    if (forearm.arm != arm || forearm.source == v1::SOURCE_UNSPECIFIED) continue;
    const auto& J = frame.smpl_joints;
    const auto [shoulder, elbow, wrist] = arm_joints(left);
    const geometry::Vec3 thumb_K =
        forearm.K_from_F * fit::thumb_axis_F(left ? fit::ArmSide::kLeft : fit::ArmSide::kRight);
    const std::optional<double> rad =
        measures::pronation_rad(J[shoulder].p_K, J[elbow].p_K, J[wrist].p_K, thumb_K, left, min_flexion_deg);
    if (!rad) return std::nullopt;
    return measures::PronationInput{*rad, forearm.confidence};
  }
  return std::nullopt;
}

// A series time as a warning quotes it: seconds to a tenth.
std::string seconds_text(double t_s) { return format_double(std::round(10 * t_s) / 10); }

}  // namespace

std::string_view MeasuresStage::description() const {
  return "ISB joint angles of the fitted body per frame and the repetitions of the dominant angle";
}

const OptionTable& MeasuresStage::options() const { return measures_option_table(); }

void MeasuresStage::start(const v1::SessionHeader& header, StageOutput& /*out*/) {
  options_ = read_measures_options(header);
  fit_enabled_ = body_fit_enabled(header);
  series_ = measures::AngleSeries(options_.repetition_angle);
  // Without a fit there are no angles, so no vertical to look for; without a depth camera, no floor.
  if (fit_enabled_ && header.has_depth_intrinsics()) {
    depth_camera_ = session_cameras(header).depth;
    geometry::validate(*depth_camera_, "header.depth_intrinsics");
  }
}

void MeasuresStage::on_camera_frame(const CameraFrame& frame, StageOutput& /*out*/) {
  if (!depth_camera_ || frame.depth_mm.empty() || !vertical_.wants_floor(frame.t_us)) return;
  const geometry::PinholeCamera& camera = *depth_camera_;
  // A frame of another size is the body fit's to report (FIT_FRAME); it has no floor to give.
  if (frame.depth_mm.type() != CV_16UC1 || frame.body_index.type() != CV_8UC1 || frame.depth_mm.cols != camera.width ||
      frame.depth_mm.rows != camera.height || frame.body_index.size() != frame.depth_mm.size())
    return;
  // Row by row: a cv::Mat need not be continuous.
  std::vector<std::uint16_t> depth;
  std::vector<std::uint8_t> body;
  for (int row = 0; row < camera.height; ++row) {
    const auto* d = frame.depth_mm.ptr<std::uint16_t>(row);
    const auto* b = frame.body_index.ptr<std::uint8_t>(row);
    depth.insert(depth.end(), d, d + camera.width);
    body.insert(body.end(), b, b + camera.width);
  }
  vertical_.add_floor(frame.t_us, measures::floor_vertical(depth, body, camera));
}

void MeasuresStage::on_value(const StageValue& value, StageOutput& out) {
  if (const auto* start = std::get_if<ArmTrackStart>(&value)) {
    // W is z up (docs/architecture.md, "Frames"); every tracked arm carries the same K_from_W.
    if (start->tracked) vertical_.add_imu_up(start->K_from_W * geometry::Vec3::UnitZ());
  } else if (const auto* frame = std::get_if<FrameEstimate>(&value)) {
    add_frame(*frame, out);
  }
}

void MeasuresStage::add_frame(const FrameEstimate& frame, StageOutput& out) {
  if (frame.smpl_joints.size() != 24) return;  // no body fit at this frame
  measures::PosedUpperBody body;
  body.smpl_joints_K.resize(3, 24);
  for (int j = 0; j < 24; ++j) {
    body.smpl_joints_K.col(j) = frame.smpl_joints[static_cast<std::size_t>(j)].p_K;
    body.joint_confidence[static_cast<std::size_t>(j)] = frame.smpl_joints[static_cast<std::size_t>(j)].confidence;
  }
  const measures::Vertical& vertical = vertical_.current();
  body.up_K = vertical.up_K;
  body.up_confidence = vertical.confidence;
  if (vertical.source == measures::VerticalSource::kAssumed && !warned_vertical_) {
    out.warn("MEASURES_VERTICAL_ASSUMED", "joint_angles.thorax",
             "no vertical measured yet (no floor in the depth frames, no calibrated arm IMU): the thorax angles take "
             "the camera's y as vertical, at confidence " +
                 format_double(vertical.confidence));
    warned_vertical_ = true;
  }
  const double min_flexion = options_.angles.min_elbow_flexion_deg;
  body.left_pronation = pronation_of(frame, v1::LEFT, min_flexion);
  body.right_pronation = pronation_of(frame, v1::RIGHT, min_flexion);

  FrameAngles angles;
  angles.t_us = frame.t_us;
  angles.joints_source = frame.smpl_joints.front().source;
  try {
    angles.angles = measures::joint_angles(body, options_.angles, previous_ ? &*previous_ : nullptr);
  } catch (const Error& e) {
    // A fit whose joints span no segment frame: that frame has no angles; the session goes on.
    if (skipped_frames_++ == 0) first_skip_ = std::to_string(frame.t_us) + " us: " + e.what();
    return;
  }
  previous_ = angles.angles;
  count_length_limited_elbows(body, angles.angles);
  count_thorax_limited_elevations(body, angles.angles);
  count_tilt_limited_thorax(body, angles.angles);

  series_.add(static_cast<double>(frame.t_us) * 1e-6, angles.angles);  // the merge sends frames in time order
  out.hand_on(std::move(angles));
}

void MeasuresStage::count_length_limited_elbows(const measures::PosedUpperBody& body,
                                                const measures::JointAngles& angles) {
  for (const bool left : {true, false}) {
    const ArmJoints j = arm_joints(left);
    const auto& c = body.joint_confidence;
    const double joints = std::min({c[j.shoulder], c[j.elbow], c[j.wrist]});
    const auto angle = left ? measures::Angle::kLeftElbowFlexion : measures::Angle::kRightElbowFlexion;
    ++arm_values_;
    if (joints >= measures::kConfidentAt && angles[static_cast<int>(angle)].confidence < measures::kConfidentAt)
      ++length_limited_elbows_;
  }
}

void MeasuresStage::count_thorax_limited_elevations(const measures::PosedUpperBody& body,
                                                    const measures::JointAngles& angles) {
  const auto& c = body.joint_confidence;
  const double thorax = measures::thorax_joint_confidence(body);
  for (const bool left : {true, false}) {
    const ArmJoints j = arm_joints(left);
    const double joints = std::min({thorax, c[j.shoulder], c[j.elbow]});
    const auto angle = left ? measures::Angle::kLeftElevation : measures::Angle::kRightElevation;
    if (joints >= measures::kConfidentAt && angles[static_cast<int>(angle)].confidence < measures::kConfidentAt)
      ++thorax_limited_elevations_;
  }
}

void MeasuresStage::count_tilt_limited_thorax(const measures::PosedUpperBody& body,
                                              const measures::JointAngles& angles) {
  ++thorax_values_;
  const double sources = std::min(measures::thorax_joint_confidence(body), body.up_confidence);
  if (sources >= measures::kConfidentAt &&
      angles[static_cast<int>(measures::Angle::kThoraxFlexion)].confidence < measures::kConfidentAt)
    ++tilt_limited_thorax_;
}

void MeasuresStage::finish(StageOutput& out) {
  if (fit_enabled_) report_vertical(out);
  if (length_limited_elbows_ > 0) {
    out.warn("MEASURES_ELBOW_FLEXION_UNCERTAIN", "joint_angles.elbow_flexion",
             std::to_string(length_limited_elbows_) + " of " + std::to_string(arm_values_) +
                 " elbow flexion values are below confidence 0.5 though their joints are tracked: with arm lengths "
                 "uncertain by " +
                 format_double(100 * options_.angles.arm_length_uncertainty) +
                 " % (measures.arm_length_uncertainty) a fit near full extension bends by tens of degrees "
                 "(docs/measures.md, \"Elbow flexion near full extension\")");
  }
  if (thorax_limited_elevations_ > 0) {
    out.warn(
        "MEASURES_ELEVATION_UNCERTAIN", "joint_angles.elevation",
        std::to_string(thorax_limited_elevations_) + " of " + std::to_string(arm_values_) +
            " elevation values are below confidence 0.5 though no joint they are read from is: a thorax joint "
            "the camera did not track (spine2, the neck or a collar; confidence 0.5, a 15 degree bound) adds "
            "its error to the humerus' own; the planes of elevation and the humerus' axial rotations there are "
            "not confident either (docs/measures.md, \"The elevation, the plane of elevation and the humerus' axial "
            "rotation\")");
  }
  if (tilt_limited_thorax_ > 0) {
    out.warn("MEASURES_THORAX_TILTED", "joint_angles.thorax",
             std::to_string(tilt_limited_thorax_) + " of " + std::to_string(thorax_values_) +
                 " frames have their thorax flexion and axial rotation below confidence 0.5 though the thorax's "
                 "joints and the vertical are not: the trunk tilted far to the side, where ISB's Z-X-Y sequence nears "
                 "its gimbal lock and the two angles take the thorax's error over the cosine of the tilt "
                 "(docs/measures.md, \"Gimbal lock of the thorax's Z-X-Y\")");
  }
  if (skipped_frames_ > 0) {
    out.warn("MEASURES_FRAME_SKIPPED", "joint_angles",
             std::to_string(skipped_frames_) + " fitted frames have no joint angles; the first at " + first_skip_);
  }
  if (series_.frames() == 0) {
    // With the fit off there are no angles by design (docs/measures.md); say so only when it was on.
    if (fit_enabled_)
      out.warn("MEASURES_NO_BODY_FIT", "joint_angles",
               "fit.enabled is true but no frame had a fitted body: no joint angles or repetitions");
    return;
  }
  if (auto repetitions = series_.repetitions(options_.repetitions)) {
    warn_uncertain_repetitions(*repetitions, out);
    out.hand_on(Repetitions{std::move(*repetitions)});
  }
}

void MeasuresStage::warn_uncertain_repetitions(const measures::SessionRepetitions& repetitions, StageOutput& out) {
  const measures::RepetitionSummary& s = repetitions.summary;
  const std::string angle(measures::angle_name(repetitions.angle));
  const std::string confident_at = format_double(measures::kConfidentAt);
  for (const measures::Repetition& r : s.repetitions) {
    if (!r.may_hold_repetition) continue;
    out.warn("MEASURES_START_AMBIGUOUS", "repetitions",
             angle +
                 " starts out of rest, comes back to it and then crosses to the other side before its first "
                 "return (" +
                 seconds_text(r.t_start_s) + "-" + seconds_text(r.t_end_s) +
                 " s, partial): a start that settled (the subject, or the fit, coming to rest) and a swing already "
                 "under way look the same, so the count may be one short and the repetitions after it may run "
                 "from one swing's second side to the next one's first (docs/measures.md, \"Angles that swing "
                 "about their zero\")");
  }
  if (!s.troughs_near_middle_t_s.empty()) {
    std::string times;
    for (std::size_t i = 0; i < s.troughs_near_middle_t_s.size() && i < 5; ++i)
      times += (i ? ", " : "") + seconds_text(s.troughs_near_middle_t_s[i]);
    if (s.troughs_near_middle_t_s.size() > 5) times += ", ...";
    out.warn("MEASURES_REST_AMBIGUOUS", "repetitions",
             std::to_string(s.troughs_near_middle_t_s.size()) + " of " + angle +
                 "'s turns lie within measures.hysteresis_deg of the middle of its range, the bound below which a "
                 "turn ends a repetition (at " +
                 times +
                 " s): whether they end one turns on a few degrees, so the repetitions and their ranges may be cut "
                 "elsewhere than the motion's own (docs/measures.md, \"Repetitions\")");
  }
  if (s.confident_fraction < 0.5) {
    out.warn("MEASURES_REPETITIONS_UNCERTAIN", "repetitions",
             "only " + format_double(std::round(100 * s.confident_fraction)) + " % of " + angle +
                 "'s defined frames are at confidence " + confident_at +
                 " or above: its repetitions' count and ranges rest on values not to act on");
  } else if (s.uncertain_count > 0) {
    out.warn("MEASURES_REPETITION_RANGE_UNCERTAIN", "repetitions",
             std::to_string(s.uncertain_count) + " of " + std::to_string(s.count) + " counted repetitions of " + angle +
                 " have a range below confidence " + confident_at +
                 " (an extreme where the angle is not confident, or a cut at a turn near the middle of the range)");
  }
}

void MeasuresStage::report_vertical(StageOutput& out) const {
  constexpr double kDeg = 180.0 / std::numbers::pi;
  const measures::Vertical& vertical = vertical_.current();
  v1::CameraVertical& report = *out.calibration().mutable_vertical();
  switch (vertical.source) {
    case measures::VerticalSource::kFloor: report.set_source(v1::CameraVertical::FLOOR); break;
    case measures::VerticalSource::kImu: report.set_source(v1::CameraVertical::IMU); break;
    case measures::VerticalSource::kAssumed: report.set_source(v1::CameraVertical::ASSUMED); break;
  }
  const geometry::Vec3& up = vertical.up_K;
  *report.mutable_up_k() = to_proto(up);
  report.set_confidence(vertical.confidence);
  report.set_camera_pitch_deg(std::asin(std::clamp(-up.z(), -1.0, 1.0)) * kDeg);
  report.set_camera_roll_deg(std::atan2(-up.x(), up.y()) * kDeg);
  if (const auto& floor = vertical_.floor()) {
    report.set_floor_spread_deg(floor->spread_rad * kDeg);
    report.set_camera_height_m(floor->camera_height_m);
    report.set_floor_points(static_cast<std::uint32_t>(floor->points));
  }
  report.set_floor_imu_angle_deg(vertical_.disagreement_rad() ? *vertical_.disagreement_rad() * kDeg : -1.0);
}

}  // namespace posefuse::session
