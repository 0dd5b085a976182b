#pragma once
// Pipeline stage: the forearm through its occlusion gaps (paper 1, II-K and II-L), after the body
// fit. A thin adapter over forearm::GapTracker (gap_tracker.hpp), one per tracked arm.
//
// Consumes the forearm stage's ArmTrackStart (which arms are tracked, with their forearm model)
// and ArmTrack (settled IMU samples, tracked camera frames), and the body fit's FittedFrames
// (their elbows anchor the gap smoother and take the SDK elbow's bias out of the live estimate,
// with forearm.gap_anchor = auto). Hands on per arm and frame the IMU position (VISUAL or, in a
// gap, PREDICTED: ArmFrameEstimates) and per gap two RecoveredSegments (PAPER, SMOOTHER) once
// the boundary window after it has been seen (and the fit's frames up to there have come, at
// most FitAnchorOptions::max_wait_s of camera time).
// Warnings: FOREARM_GAP_NOT_RECOVERED, FOREARM_GAP_OPEN, FOREARM_NO_LIVE_ESTIMATE.
// Holds (docs/architecture.md, "Pipeline stages"): every settled IMU sample of a tracked arm
// (about 100 B each: 35 MB per arm-hour at 100 Hz), its frames' track samples and elbow anchors,
// the fit's elbows, and the fit's elbows that come before an arm's calibration for at most
// kEarlyElbowS of camera time.
#include <map>
#include <memory>
#include <vector>

#include "forearm/gap_tracker.hpp"
#include "session/pipeline_stage.hpp"

namespace posefuse::session {

class ForearmGapsStage : public Stage {
 public:
  static constexpr double kEarlyElbowS = 30.0;

  std::string_view name() const override { return "forearm_gaps"; }
  std::string_view description() const override;
  std::vector<ValueKind> consumes() const override {
    return {ValueKind::kArmTrackStart, ValueKind::kArmTrack, ValueKind::kFittedFrame};
  }
  std::vector<ValueKind> produces() const override {
    return {ValueKind::kArmFrameEstimates, ValueKind::kRecoveredSegment};
  }
  void start(const v1::SessionHeader& header, StageOutput& out) override;
  void on_value(const StageValue& value, StageOutput& out) override;
  void finish(StageOutput& out) override;
  std::size_t held_bytes() const override;

 private:
  struct Arm {
    std::string device_id;
    v1::Arm arm = v1::ARM_UNSPECIFIED;
    std::unique_ptr<forearm::GapTracker> tracker;  // none: refused (no calibration)
  };
  void start_arm(const ArmTrackStart& start, StageOutput& out);
  void add_track(const ArmTrack& track, StageOutput& out);
  void add_fit(const FittedFrame& frame, StageOutput& out);
  void hand_on(Arm& arm, std::vector<forearm::RecoveredGapSegment>&& segments, StageOutput& out);

  std::vector<Arm> arms_;
  // The fit's elbows per arm (v1::Arm) before that arm's ArmTrackStart.
  std::map<int, std::vector<forearm::FitElbow>> early_elbows_;
};

}  // namespace posefuse::session
