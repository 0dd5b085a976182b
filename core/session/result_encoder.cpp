#include "session/result_encoder.hpp"

#include <cmath>

#include "forearm/orientation_uncertainty.hpp"
#include "session/stages/proto_values.hpp"

namespace posefuse::session {

namespace {

void encode(const ImuOrientations& value, v1::FitResult& result) {
  v1::ImuOrientationBatch& batch = *result.mutable_imu_orientations();
  batch.set_device_id(value.device_id);
  batch.mutable_t_us()->Reserve(static_cast<int>(value.samples.size()));
  batch.mutable_w_from_a()->Reserve(4 * static_cast<int>(value.W_from_A.size()));
  for (std::size_t i = 0; i < value.samples.size() && i < value.W_from_A.size(); ++i) {
    batch.add_t_us(value.samples[i].t_us);
    for (const double v : geometry::to_wxyz(value.W_from_A[i])) batch.add_w_from_a(v);
    const double beyond_steady_rad = i < value.uncertainty_rad.size() ? value.uncertainty_rad[i] : 0.0;
    const double rms_rad = forearm::imu_orientation_rms_rad(beyond_steady_rad);
    batch.add_uncertainty_rad(rms_rad);
    batch.add_confidence(forearm::confidence_from_rms_rad(rms_rad));
  }
}

void encode(const ForearmOrientations& value, v1::FitResult& result) {
  v1::ForearmOrientationBatch& batch = *result.mutable_forearm_orientations();
  batch.set_device_id(value.device_id);
  batch.set_arm(value.arm);
  batch.set_offline(value.offline);
  for (std::size_t i = 0; i < value.t_us.size(); ++i) {
    batch.add_t_us(value.t_us[i]);
    for (const double v : geometry::to_wxyz(value.K_from_F[i])) batch.add_k_from_f(v);
    batch.add_pronation_rad(value.pronation_rad[i]);
    batch.add_uncertainty_rad(value.orientation_rms_rad[i]);
    batch.add_confidence(forearm::confidence_from_rms_rad(value.orientation_rms_rad[i]));
  }
}

void encode(const RecoveredSegment& value, v1::FitResult& result) {
  v1::RecoveredSegment& segment = *result.mutable_recovered_segment();
  segment.set_arm(value.arm);
  segment.set_device_id(value.device_id);
  segment.set_method(value.segment.method == forearm::RecoveryMethod::kPaper ? v1::RecoveredSegment::PAPER
                                                                             : v1::RecoveredSegment::SMOOTHER);
  segment.set_t_start_us(value.segment.t_start_us);
  segment.set_t_end_us(value.segment.t_end_us);
  for (const forearm::RecoveredGapSample& s : value.segment.samples) {
    v1::RecoveredSegment::Sample& out = *segment.add_samples();
    out.set_t_us(s.t_us);
    *out.mutable_imu_m() = to_proto(s.imu_K);
    *out.mutable_elbow_m() = to_proto(s.elbow_K);
    *out.mutable_wrist_m() = to_proto(s.wrist_K);
    *out.mutable_k_from_f() = to_proto(s.K_from_F);
  }
}

void encode_joint(const JointEstimate& joint, v1::JointEstimate& out) {
  *out.mutable_position_m() = to_proto(joint.p_K);
  out.set_source(joint.source);
  out.set_confidence(joint.confidence);
}

void encode(const FrameEstimate& value, v1::FitResult& result) {
  v1::FrameResult& frame = *result.mutable_frame();
  frame.set_t_us(value.t_us);
  for (const JointEstimate& joint : value.smpl_joints) encode_joint(joint, *frame.add_smpl_joints());
  for (const JointEstimate& joint : value.camera_joints) encode_joint(joint, *frame.add_camera_joints());
  for (const ForearmEstimate& f : value.forearms) {
    v1::ForearmOrientation& out = *frame.add_forearms();
    out.set_arm(f.arm);
    *out.mutable_k_from_f() = to_proto(f.K_from_F);
    out.set_pronation_rad(f.pronation_rad);
    out.set_source(f.source);
    out.set_confidence(f.confidence);
  }
  for (const ImuPositionEstimate& p : value.imu_positions) {
    v1::ImuPosition& out = *frame.add_imu_positions();
    out.set_device_id(p.device_id);
    *out.mutable_position_m() = to_proto(p.p_K);
    out.set_source(p.source);
  }
  frame.set_fit_energy(value.fit_energy);
  for (const geometry::Quat& q : value.smpl_rotations) *frame.add_smpl_joint_rotations() = to_proto(q);
}

// measures::Angle i is JointAngleKind i + 1 (results.proto keeps the same order).
v1::JointAngleKind angle_kind(measures::Angle angle) {
  return static_cast<v1::JointAngleKind>(static_cast<int>(angle) + 1);
}

void encode(const FrameAngles& value, v1::FitResult& result) {
  v1::FrameAngles& frame = *result.mutable_joint_angles();
  frame.set_t_us(value.t_us);
  for (int i = 0; i < measures::kAngleCount; ++i) {
    const measures::AngleValue& a = value.angles[static_cast<std::size_t>(i)];
    v1::JointAngle& out = *frame.add_angles();
    out.set_kind(angle_kind(static_cast<measures::Angle>(i)));
    out.set_defined(a.defined);
    out.set_held(a.held);
    if (a.defined) out.set_deg(a.deg);
    out.set_confidence(a.defined ? a.confidence : 0.0);
    out.set_source(a.source == measures::AngleSource::kBodyModelAndImu ? v1::FUSED
                   : a.source == measures::AngleSource::kBodyModel     ? value.joints_source
                                                                       : v1::SOURCE_UNSPECIFIED);
  }
}

std::int64_t to_us(double t_s) { return std::llround(t_s * 1e6); }

void encode(const Repetitions& value, v1::FitResult& result) {
  v1::RepetitionSummary& out = *result.mutable_repetitions();
  const measures::RepetitionSummary& s = value.repetitions.summary;
  out.set_angle(angle_kind(value.repetitions.angle));
  out.set_angle_detected(value.repetitions.detected);
  for (const measures::Repetition& r : s.repetitions) {
    v1::Repetition& rep = *out.add_repetitions();
    rep.set_t_start_us(to_us(r.t_start_s));
    rep.set_t_peak_us(to_us(r.t_peak_s));
    rep.set_t_end_us(to_us(r.t_end_s));
    rep.set_min_deg(r.min_deg);
    rep.set_max_deg(r.max_deg);
    rep.set_range_deg(r.range_deg);
    rep.set_peak_speed_deg_s(r.peak_speed_deg_s);
    rep.set_duration_s(r.duration_s);
    rep.set_partial(r.partial);
    rep.set_confidence(r.confidence);
    rep.set_may_hold_repetition(r.may_hold_repetition);
    rep.set_cut_ambiguity_deg(r.cut_ambiguity_deg);
  }
  out.set_count(static_cast<std::uint32_t>(s.count));
  out.set_mean_range_deg(s.mean_range_deg);
  out.set_range_spread_deg(s.range_spread_deg);
  out.set_mean_duration_s(s.mean_duration_s);
  out.set_duration_spread_s(s.duration_spread_s);
  out.set_mean_peak_speed_deg_s(s.mean_peak_speed_deg_s);
  out.set_confident_fraction(s.confident_fraction);
  out.set_uncertain_count(static_cast<std::uint32_t>(s.uncertain_count));
}

}  // namespace

const char* value_kind_name(ValueKind kind) {
  switch (kind) {
    case ValueKind::kImuOrientations: return "imu_orientations";
    case ValueKind::kForearmOrientations: return "forearm_orientations";
    case ValueKind::kArmTrackStart: return "arm_track_start";
    case ValueKind::kArmTrack: return "arm_track";
    case ValueKind::kFittedFrame: return "fitted_frame";
    case ValueKind::kArmFrameEstimates: return "arm_frame_estimates";
    case ValueKind::kRecoveredSegment: return "recovered_segment";
    case ValueKind::kFramesDone: return "frames_done";
    case ValueKind::kFrameEstimate: return "frame_estimate";
    case ValueKind::kFrameAngles: return "frame_angles";
    case ValueKind::kRepetitions: return "repetitions";
  }
  return "(unknown value kind)";
}

std::optional<v1::FitResult> encode_value(const StageValue& value) {
  v1::FitResult result;
  bool for_client = true;
  std::visit(
      [&](const auto& v) {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, ImuOrientations> || std::is_same_v<T, ForearmOrientations> ||
                      std::is_same_v<T, RecoveredSegment> || std::is_same_v<T, FrameEstimate> ||
                      std::is_same_v<T, FrameAngles> || std::is_same_v<T, Repetitions>) {
          encode(v, result);
        } else {
          for_client = false;  // between stages only
        }
      },
      value);
  if (!for_client) return std::nullopt;
  return result;
}

}  // namespace posefuse::session
