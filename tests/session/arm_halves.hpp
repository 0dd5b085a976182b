#pragma once
// One arm through both halves of the forearm fusion as the pipeline joins them: ForearmTrack
// (the forearm stage) then GapTracker (the forearm_gaps stage), the per-frame estimates merged
// by the frame merge's rule and every value written as the client receives it, so the tests of
// the gap logic read FitResults (frames with IMU positions, recovered segments) as before.
#include <optional>
#include <string>
#include <vector>

#include "forearm/forearm_track.hpp"
#include "forearm/gap_tracker.hpp"
#include "forearm/orientation_uncertainty.hpp"
#include "session/frame_merge.hpp"
#include "session/pipeline_stage.hpp"

namespace posefuse::session::testing {

class ArmHalves {
 public:
  ArmHalves(std::string device_id, forearm::Side side, const forearm::ForearmModel& model, bool has_model,
            const forearm::Quat& K_from_W, const forearm::Quat& K_from_F_reference,
            const forearm::GapSmootherOptions& smoother = {}, double live_elbow_time_constant_s = 0.05)
      : device_id_(std::move(device_id)),
        arm_(side == forearm::Side::kLeft ? v1::LEFT : v1::RIGHT),
        track_(side, model, has_model, K_from_W, K_from_F_reference, forearm::kPoseCalibrationRmsRad),
        gaps_(device_id_, model, has_model, K_from_W, smoother, live_elbow_time_constant_s) {}

  void use_axis_correction(const forearm::VisualAxisCorrectionOptions& options) { track_.use_axis_correction(options); }
  void use_fit_anchor(const forearm::FitAnchorOptions& options) { gaps_.use_fit_anchor(options); }
  void add_imu(const std::vector<std::int64_t>& t_us, const std::vector<forearm::Quat>& W_from_A,
               const std::vector<forearm::Vec3>& specific_force_A, StageOutput& out) {
    track_.add_imu(t_us, W_from_A, specific_force_A);
    process(false, out);
  }
  void add_frame(const forearm::ArmFrame& frame) { track_.add_frame(frame); }
  void process(bool all, StageOutput& out) {
    forearm::ForearmTrackOutput tracked = track_.process(all);
    if (!tracked.samples.empty()) {
      out.hand_on(forearm_orientations_of(device_id_, arm_, tracked.samples));
    }
    gaps_.add_samples(tracked.samples);
    for (const forearm::TrackedArmFrame& frame : tracked.frames) {
      FrameParts parts;
      parts.t_us = frame.frame.t_us;
      parts.arms.push_back({device_id_, arm_, gaps_.add_frame(frame)});
      out.hand_on(merge_frame(parts));
    }
    hand_on(gaps_.recover_ready(false), out);
  }
  void add_fit_elbow(std::int64_t t_us, const forearm::Vec3& elbow_K, double energy, StageOutput& out) {
    gaps_.add_fit_elbow({t_us, elbow_K, energy});
    hand_on(gaps_.recover_ready(false), out);
  }
  // End of session before the fit's last elbows: the last frames, the gaps that do not wait for
  // the fit, a gap still open reported. finish_late: the fit has finished, every gap recovered.
  void finish(StageOutput& out) {
    process(true, out);
    hand_on(gaps_.finish(), out);
  }
  void finish_late(StageOutput& out) {
    gaps_.fit_finished();
    hand_on(gaps_.recover_ready(true), out);
  }

  forearm::AxisCorrection axis_correction() const { return track_.axis_correction(); }
  std::uint64_t axis_correction_frames() const { return track_.axis_correction_frames(); }
  std::uint64_t visible_frames() const { return track_.visible_frames(); }
  std::uint64_t lone_detections() const { return track_.lone_detections(); }
  std::uint64_t gaps() const { return gaps_.gaps(); }

 private:
  void hand_on(std::vector<forearm::RecoveredGapSegment>&& segments, StageOutput& out) {
    for (forearm::RecoveredGapSegment& s : segments) out.hand_on(RecoveredSegment{device_id_, arm_, std::move(s)});
    for (const forearm::ForearmWarning& w : gaps_.take_warnings()) out.warn(w.code, w.field, w.message);
  }

  std::string device_id_;
  v1::Arm arm_;
  forearm::ForearmTrack track_;
  forearm::GapTracker gaps_;
};

}  // namespace posefuse::session::testing
