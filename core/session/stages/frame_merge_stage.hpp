#pragma once
// Pipeline stage, the last: one FrameResult per camera frame that any stage estimated something
// for, by the frame merge's rule (frame_merge.hpp). A thin adapter over FrameMerger: it collects
// the body fit's FittedFrames, the forearm gaps' ArmFrameEstimates and SMOOTHER segments, and
// hands a frame on (the client gets it as a FrameResult) once every contributing stage's
// FramesDone has passed it. Warning MERGE_FRAME_INCOMPLETE: frames sent after kMaxHoldS without
// every part.
// Holds: the frames not complete yet, about 3 kB each (the fit's joints and the arms' estimates):
// with the fit's default fit.imu_wait_s of 30 s at most about 2.7 MB.
#include "session/frame_merge.hpp"
#include "session/pipeline_stage.hpp"

namespace posefuse::session {

class FrameMergeStage : public Stage {
 public:
  std::string_view name() const override { return "frame_merge"; }
  std::string_view description() const override;
  std::vector<ValueKind> consumes() const override {
    return {ValueKind::kFittedFrame, ValueKind::kArmFrameEstimates, ValueKind::kRecoveredSegment,
            ValueKind::kFramesDone};
  }
  std::vector<ValueKind> produces() const override { return {ValueKind::kFrameEstimate}; }
  void start(const v1::SessionHeader& header, StageOutput& out) override;
  void on_value(const StageValue& value, StageOutput& out) override;
  // Frames leave here, after every earlier stage has seen the camera frame (a stage's
  // FramesDone for it has come by then).
  void on_camera_frame(const CameraFrame& frame, StageOutput& out) override;
  void finish(StageOutput& out) override;
  std::size_t held_bytes() const override { return merger_.held_bytes(); }

 private:
  FrameMerger merger_;
};

}  // namespace posefuse::session
