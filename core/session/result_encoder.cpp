#include "session/result_encoder.hpp"

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
  }
}

void encode(const ForearmOrientations& value, v1::FitResult& result) {
  v1::ForearmOrientationBatch& batch = *result.mutable_forearm_orientations();
  batch.set_device_id(value.device_id);
  batch.set_arm(value.arm);
  for (std::size_t i = 0; i < value.t_us.size(); ++i) {
    batch.add_t_us(value.t_us[i]);
    for (const double v : geometry::to_wxyz(value.K_from_F[i])) batch.add_k_from_f(v);
    batch.add_pronation_rad(value.pronation_rad[i]);
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
                      std::is_same_v<T, RecoveredSegment> || std::is_same_v<T, FrameEstimate>) {
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
